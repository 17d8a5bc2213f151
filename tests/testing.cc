// SPDX-License-Identifier: BSD-3-Clause
#include "tests/testing.h"

#include "ext/core/file_util.h"

#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace bayon {
namespace testing {

namespace {

// $name, or the default compiled in by tests/CMakeLists.txt.
std::string Setting(const char* name, const char* fallback) {
  const char* env = std::getenv(name);
  return env && *env ? env : fallback;
}

}  // namespace

bool StrictTests() { return Setting("BAYON_TEST_STRICT", "") == "1"; }

std::string BayonBin() { return Setting("BAYON_BIN", BAYON_DEFAULT_BIN); }

std::string DataDir() {
  const std::string dir = Setting("BAYON_DATA_DIR", BAYON_DEFAULT_DATA_DIR);
  if (dir.empty() || !fs::is_directory(dir)) return std::string();
  return fs::canonical(dir).string();
}

std::string DataPath(const std::string& relative) {
  const std::string dir = DataDir();
  if (dir.empty()) return std::string();
  const fs::path path = fs::path(dir) / relative;
  return fs::exists(path) ? path.string() : std::string();
}

std::string ConfigPath(const std::string& name) {
  return (fs::path(BAYON_DEFAULT_SOURCE_DIR) / "configs" / name).string();
}

std::string TempDir(const std::string& name) {
  const char* env = std::getenv("BAYON_TEST_TMP");
  const fs::path root =
      env && *env ? fs::path(env) : fs::temp_directory_path() / "bayon-tests";
  const fs::path dir = root / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string CommandResult::LastLine() const {
  size_t end = output.find_last_not_of("\n ");
  if (end == std::string::npos) return std::string();
  const size_t start = output.rfind('\n', end);
  return output.substr(start == std::string::npos ? 0 : start + 1,
                       end - (start == std::string::npos ? 0 : start + 1) + 1);
}

CommandResult RunCommand(const std::vector<std::string>& argv) {
  CommandResult result;
  int pipe_fds[2];
  if (::pipe(pipe_fds) != 0) return result;
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(pipe_fds[1], STDOUT_FILENO);
    ::dup2(pipe_fds[1], STDERR_FILENO);
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    std::vector<char*> args;
    for (const auto& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  ::close(pipe_fds[1]);
  char buffer[4096];
  ssize_t n;
  while ((n = ::read(pipe_fds[0], buffer, sizeof(buffer))) > 0) {
    result.output.append(buffer, n);
  }
  ::close(pipe_fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  result.exit_code =
      WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

CommandResult RunBayon(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {BayonBin()};
  argv.insert(argv.end(), args.begin(), args.end());
  return RunCommand(argv);
}

CommandResult RunColmap(const std::vector<std::string>& args) {
  const char* bin = std::getenv("BAYON_COLMAP");
  std::vector<std::string> argv = {bin && *bin ? bin : "colmap"};
  argv.insert(argv.end(), args.begin(), args.end());
  return RunCommand(argv);
}

std::map<std::string, uint64_t> HashTree(const std::string& path) {
  std::map<std::string, uint64_t> hashes;
  if (fs::is_regular_file(path)) {
    hashes[fs::path(path).filename().string()] = FileHash(path);
    return hashes;
  }
  for (const std::string& file : ListFilesRecursive(path)) {
    hashes[file] = FileHash(path + "/" + file);
  }
  return hashes;
}

std::string SharedFixture(
    const std::string& name,
    const std::function<void(const std::string&)>& build) {
  std::error_code ec;
  const long long stamp = static_cast<long long>(
      fs::last_write_time(BayonBin(), ec).time_since_epoch().count());
  const char* env = std::getenv("BAYON_TEST_TMP");
  const fs::path root =
      (env && *env ? fs::path(env)
                   : fs::temp_directory_path() / "bayon-tests") /
      "fixtures";
  fs::create_directories(root, ec);
  const fs::path dir = root / (name + "-" + std::to_string(stamp));
  const fs::path done = dir / ".done";
  const std::string lock_path = (root / (name + ".lock")).string();
  const int lock_fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT, 0644);
  ::flock(lock_fd, LOCK_EX);
  if (!fs::exists(done)) {
    fs::remove_all(dir, ec);
    fs::create_directories(dir);
    build(dir.string());
    std::ofstream(done.string()) << "ok\n";
  }
  ::flock(lock_fd, LOCK_UN);
  ::close(lock_fd);
  return dir.string();
}

std::string CommaSeparated(const std::vector<double>& values) {
  std::ostringstream text;
  text << std::setprecision(17);
  for (size_t i = 0; i < values.size(); ++i) {
    text << (i > 0 ? "," : "") << values[i];
  }
  return text.str();
}

void CopyTree(const std::string& from, const std::string& to) {
  fs::copy(from,
           to,
           fs::copy_options::recursive | fs::copy_options::overwrite_existing);
}

}  // namespace testing
}  // namespace bayon
