// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/file_util.h"

#include "ext/core/errors.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/file.h>
#include <sys/types.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace bayon {

std::string TempSuffix() {
  static std::atomic<int> counter{0};
  return StrCat(".tmp-", ::getpid(), "-", counter++);
}

namespace {

// The writer's pid in a temporary name that starts with `prefix`
// ("<name>.tmp-"), or 0 where the rest is not "<pid>-...".
pid_t TemporaryOwner(const std::string& name, const std::string& prefix) {
  if (name.rfind(prefix, 0) != 0) return 0;
  const size_t begin = prefix.size();
  const size_t end = name.find('-', begin);
  if (end == std::string::npos || end == begin || end - begin > 9) return 0;
  pid_t pid = 0;
  for (size_t i = begin; i < end; ++i) {
    if (name[i] < '0' || name[i] > '9') return 0;
    pid = pid * 10 + (name[i] - '0');
  }
  return pid;
}

}  // namespace

void RemoveStaleTemporaries(const std::string& path) {
  fs::path target = fs::path(path).lexically_normal();
  if (!target.has_filename()) target = target.parent_path();
  const std::string name = target.filename().string();
  if (name.empty()) return;
  fs::path folder = target.parent_path();
  if (folder.empty()) folder = ".";
  std::error_code ec;
  std::vector<fs::path> stale;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string entry_name = entry.path().filename().string();
    for (const std::string& prefix : {name + ".tmp-", name + ".old.tmp-"}) {
      const pid_t pid = TemporaryOwner(entry_name, prefix);
      // Another process's, and that process is gone (kill -9, a crash).
      if (pid > 0 && pid != ::getpid() && ::kill(pid, 0) != 0 &&
          errno == ESRCH) {
        stale.push_back(entry.path());
      }
    }
  }
  for (const fs::path& p : stale) fs::remove_all(p, ec);
}

void WriteFileAtomically(const std::string& path, const std::string& content) {
  RemoveStaleTemporaries(path);
  const std::string temp = path + TempSuffix();
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) {
    ThrowInputError(path, ": cannot write: ", std::strerror(errno));
  }
  size_t written = 0;
  while (written < content.size()) {
    const ssize_t n =
        ::write(fd, content.data() + written, content.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int saved = errno;
      ::close(fd);
      ::unlink(temp.c_str());
      ThrowInputError(path, ": cannot write: ", std::strerror(saved));
    }
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const int saved = errno;
    ::unlink(temp.c_str());
    ThrowInputError(path, ": cannot write: ", std::strerror(saved));
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const int saved = errno;
    ::unlink(temp.c_str());
    ThrowInputError(path, ": cannot rename into place: ", std::strerror(saved));
  }
}

std::string ReadFileToString(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    ThrowInputError(path, ": file not found");
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) ThrowInputError(path, ": cannot open for reading");
  std::ostringstream buffer;
  buffer << file.rdbuf();
  if (file.bad()) ThrowInputError(path, ": read error");
  return buffer.str();
}

OutputDirectory::OutputDirectory(const std::string& path, bool overwrite)
    : path_(fs::path(path).lexically_normal().string()) {
  if (!path_.empty() && path_.back() == '/') path_.pop_back();
  CheckOutputPath(path_, overwrite);
  const fs::path parent = fs::absolute(path_).parent_path();
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) {
    fs::create_directories(parent, ec);
    if (ec) {
      ThrowInputError(
          path_, ": cannot create the parent folder: ", ec.message());
    }
  }
  RemoveStaleTemporaries(path_);
  temp_path_ = path_ + TempSuffix();
  fs::create_directory(temp_path_, ec);
  if (ec)
    ThrowInputError(path_, ": cannot create output folder: ", ec.message());
}

OutputDirectory::~OutputDirectory() {
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(temp_path_, ec);
  }
}

std::string OutputDirectory::File(const std::string& name) const {
  return temp_path_ + "/" + name;
}

void OutputDirectory::Commit() {
  std::error_code ec;
  std::string old_path;
  if (fs::exists(path_, ec)) {
    old_path = path_ + ".old" + TempSuffix();
    fs::rename(path_, old_path, ec);
    if (ec) ThrowInputError(path_, ": cannot replace: ", ec.message());
  }
  fs::rename(temp_path_, path_, ec);
  if (ec) {
    if (!old_path.empty()) fs::rename(old_path, path_, ec);
    ThrowInputError(path_, ": cannot move output into place: ", ec.message());
  }
  committed_ = true;
  if (!old_path.empty()) fs::remove_all(old_path, ec);
}

TempFileGuard::~TempFileGuard() {
  if (keep_) return;
  std::error_code ec;
  for (const char* suffix : {"", "-journal", "-wal", "-shm"}) {
    fs::remove(path_ + suffix, ec);
  }
}

void CheckFileExists(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (path.empty()) ThrowInputError(what, " is required");
  if (!fs::exists(path, ec)) ThrowInputError(path, ": ", what, " not found");
  if (!fs::is_regular_file(path, ec)) {
    ThrowInputError(path, ": ", what, " is not a regular file");
  }
}

void CheckDirectoryExists(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (path.empty()) ThrowInputError(what, " is required");
  if (!fs::exists(path, ec)) ThrowInputError(path, ": ", what, " not found");
  if (!fs::is_directory(path, ec)) {
    ThrowInputError(path, ": ", what, " is not a folder");
  }
}

void CheckOutputPath(const std::string& path, bool overwrite) {
  std::error_code ec;
  if (path.empty()) ThrowInputError("an output path is required");
  if (fs::exists(path, ec) && !overwrite) {
    ThrowInputError(path, ": exists already; pass --overwrite 1 to replace it");
  }
}

void CheckCanWrite(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (fs::exists(path, ec) && ::access(path.c_str(), W_OK) != 0) {
    ThrowInputError(path, ": cannot write ", what, ": ", std::strerror(errno));
  }
  const fs::path folder = fs::absolute(path, ec).parent_path();
  if (::access(folder.c_str(), W_OK | X_OK) != 0) {
    ThrowInputError(path,
                    ": cannot write ",
                    what,
                    ": the folder ",
                    folder.string(),
                    " is not writable (",
                    std::strerror(errno),
                    ")");
  }
}

uint64_t FileHash(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) ThrowInputError(path, ": cannot open for reading");
  uint64_t hash = 1469598103934665603ull;
  char buffer[1 << 16];
  while (file) {
    file.read(buffer, sizeof(buffer));
    const std::streamsize n = file.gcount();
    for (std::streamsize i = 0; i < n; ++i) {
      hash ^= static_cast<unsigned char>(buffer[i]);
      hash *= 1099511628211ull;
    }
  }
  return hash;
}

std::vector<std::string> ListFilesRecursive(const std::string& folder) {
  std::vector<std::string> files;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(folder, ec);
       !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!name.empty() && name[0] == '.') {
      if (it->is_directory()) it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file()) {
      files.push_back(fs::relative(it->path(), folder).generic_string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

FileLock::FileLock(const std::string& path, const std::string& what) {
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    ThrowInputError(
        path, ": cannot open the lock file (", std::strerror(errno), ")");
  }
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    char holder[32] = {};
    const ssize_t n = ::pread(fd_, holder, sizeof(holder) - 1, 0);
    ::close(fd_);
    fd_ = -1;
    if (error == EWOULDBLOCK) {
      std::string pid(holder, n > 0 ? static_cast<size_t>(n) : 0);
      pid.erase(pid.find_last_not_of(" \n") + 1);
      ThrowInputError(what,
                      " is in use by another process",
                      pid.empty() ? std::string() : StrCat(" (pid ", pid, ")"),
                      "; wait for it to finish or stop it, then run again");
    }
    ThrowInputError(path, ": cannot lock (", std::strerror(error), ")");
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t written =
        ::pwrite(fd_, pid.data(), pid.size(), 0);
  }
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

std::string JoinPath(const std::string& folder, const std::string& name) {
  return (std::filesystem::path(folder) / name).string();
}

}  // namespace bayon
