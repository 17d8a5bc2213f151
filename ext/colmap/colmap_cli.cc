// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/colmap_cli.h"

#include "ext/colmap/sqlite.h"
#include "ext/core/errors.h"

#include <glog/logging.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;

namespace bayon {
namespace {

std::string Executable(const ColmapRunOptions& options) {
  if (!options.executable.empty()) return options.executable;
  if (const char* env = std::getenv("BAYON_COLMAP"); env && *env) return env;
  return "colmap";
}

std::string ShellQuote(const std::string& arg) {
  if (!arg.empty() && arg.find_first_not_of(
                          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                          "0123456789_-./=:+,") == std::string::npos) {
    return arg;
  }
  std::string quoted = "'";
  for (char c : arg) {
    if (c == '\'') {
      quoted += "'\\''";
    } else {
      quoted += c;
    }
  }
  return quoted + "'";
}

// Runs argv with stdout and stderr appended to log_path. Returns the exit
// code, 127 if the binary could not be started, 128 + signal if killed.
int Spawn(const std::vector<std::string>& argv, const std::string& log_path) {
  const pid_t pid = ::fork();
  if (pid < 0) return 127;
  if (pid == 0) {
    const int fd =
        ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      ::dup2(fd, STDOUT_FILENO);
      ::dup2(fd, STDERR_FILENO);
      ::close(fd);
    }
    const int null_fd = ::open("/dev/null", O_RDONLY);
    if (null_fd >= 0) {
      ::dup2(null_fd, STDIN_FILENO);
      ::close(null_fd);
    }
    std::vector<char*> args;
    for (const std::string& arg : argv)
      args.push_back(const_cast<char*>(arg.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return 127;
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return 127;
}

std::string LastLines(const std::string& path, int max_lines) {
  std::ifstream file(path);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(file, line)) {
    if (!line.empty()) lines.push_back(line);
    if (static_cast<int>(lines.size()) > max_lines) lines.erase(lines.begin());
  }
  std::string tail;
  for (const std::string& l : lines) tail += (tail.empty() ? "" : " | ") + l;
  return tail;
}

}  // namespace

ColmapResult RunColmap(const ColmapCall& call,
                       const ColmapRunOptions& options) {
  ColmapResult result;
  std::vector<std::string> argv = {Executable(options), call.command};
  for (const auto& [flag, value] : call.options) {
    argv.push_back(flag);
    argv.push_back(value);
  }
  for (const std::string& arg : argv) {
    result.command_line +=
        (result.command_line.empty() ? "" : " ") + ShellQuote(arg);
  }
  result.log_path =
      options.log_path.empty()
          ? (fs::temp_directory_path() /
             ("bayon-colmap-" + std::to_string(::getpid()) + ".log"))
                .string()
          : options.log_path;
  {
    std::ofstream log(result.log_path, std::ios::app);
    log << "$ " << result.command_line << "\n";
  }
  LOG(INFO) << "Running: " << result.command_line;
  const auto start = std::chrono::steady_clock::now();
  result.exit_code = Spawn(argv, result.log_path);
  result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  if (result.exit_code == 127) {
    ThrowInputError("cannot run '",
                    argv[0],
                    "': is COLMAP installed? (apt install colmap, or set "
                    "$BAYON_COLMAP)");
  }
  if (result.exit_code != 0) {
    result.message = "colmap " + call.command + " exited with code " +
                     std::to_string(result.exit_code) + ": " +
                     LastLines(result.log_path, 2);
    return result;
  }
  for (const std::string& output : call.expected_outputs) {
    std::error_code ec;
    if (!fs::exists(output, ec)) {
      result.message = "colmap " + call.command +
                       " exited 0 but did not write " + output + ": " +
                       LastLines(result.log_path, 2);
      return result;
    }
  }
  result.success = true;
  return result;
}

std::string ColmapVersion(const ColmapRunOptions& options) {
  const std::string log =
      (fs::temp_directory_path() /
       ("bayon-colmap-version-" + std::to_string(::getpid()) + ".txt"))
          .string();
  std::error_code ec;
  fs::remove(log, ec);
  const int code = Spawn({Executable(options), "-h"}, log);
  std::string version;
  if (code == 0 || code == 1) {
    std::ifstream file(log);
    std::string line;
    while (std::getline(file, line)) {
      if (line.rfind("COLMAP", 0) == 0) {
        version = line;
        break;
      }
    }
  }
  fs::remove(log, ec);
  return version;
}

void CopyDatabaseForColmap(const std::string& database_path,
                           const std::string& copy_path) {
  CopySqliteDatabase(database_path, copy_path);
}

std::string LargestModel(const std::string& mapper_output) {
  std::vector<fs::path> folders;
  for (const auto& entry : fs::directory_iterator(mapper_output)) {
    const fs::path& folder = entry.path();
    if (entry.is_directory() && fs::is_regular_file(folder / "cameras.bin") &&
        fs::is_regular_file(folder / "images.bin") &&
        fs::is_regular_file(folder / "points3D.bin")) {
      folders.push_back(folder);
    }
  }
  std::sort(folders.begin(), folders.end());
  std::string best;
  uint64_t best_count = 0;
  for (const fs::path& folder : folders) {
    // images.bin begins with the number of registered images (uint64).
    uint64_t count = 0;
    std::ifstream((folder / "images.bin").string(), std::ios::binary)
        .read(reinterpret_cast<char*>(&count), sizeof(count));
    if (count > best_count) {
      best = folder.string();
      best_count = count;
    }
  }
  return best;
}

}  // namespace bayon
