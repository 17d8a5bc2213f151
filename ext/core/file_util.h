// SPDX-License-Identifier: BSD-3-Clause
//
// Writing outputs so that nothing is lost: every file is written under a
// temporary name and renamed when complete, so a crash never leaves a
// half-written file under the final name; folders are assembled in a
// temporary folder and swapped in as a whole.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace bayon {

// Writes `content` to `path` atomically (temporary file, fsync, rename).
void WriteFileAtomically(const std::string& path, const std::string& content);

// Reads a whole file; throws InputError naming `path` when it cannot.
std::string ReadFileToString(const std::string& path);

// folder/name, as a string (std::filesystem's join).
std::string JoinPath(const std::string& folder, const std::string& name);

// A folder written as a whole. Files go into temp_path(); Commit() renames it
// to the final path, replacing an existing folder only when overwriting was
// allowed (the old one is moved aside first and removed after the swap).
// Without Commit() the temporary folder is removed on destruction.
class OutputDirectory {
 public:
  // Throws InputError if `path` exists and `overwrite` is false, or if its
  // parent folder does not exist or is not writable.
  OutputDirectory(const std::string& path, bool overwrite);
  ~OutputDirectory();
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;

  const std::string& temp_path() const { return temp_path_; }
  const std::string& final_path() const { return path_; }
  // temp_path() + "/" + name
  std::string File(const std::string& name) const;
  void Commit();

 private:
  std::string path_;
  std::string temp_path_;
  bool committed_ = false;
};

// Removes a file (and its SQLite -journal/-wal/-shm companions) when it goes
// out of scope, unless Keep() was called: for outputs built under temporary
// names that must not survive a failure.
class TempFileGuard {
 public:
  explicit TempFileGuard(std::string path) : path_(std::move(path)) {}
  ~TempFileGuard();
  TempFileGuard(const TempFileGuard&) = delete;
  TempFileGuard& operator=(const TempFileGuard&) = delete;
  void Keep() { keep_ = true; }

 private:
  std::string path_;
  bool keep_ = false;
};

// Throws InputError unless `path` is an existing regular file / folder.
// `what` names the role, e.g. "--database_path".
void CheckFileExists(const std::string& path, const std::string& what);
void CheckDirectoryExists(const std::string& path, const std::string& what);
// Throws InputError if `path` exists and `overwrite` is false.
void CheckOutputPath(const std::string& path, bool overwrite);
// Throws InputError unless this process may write `path`: an existing file
// must be writable, and so must its folder (where a new file, a temporary or
// SQLite's journal goes). Run as a user without the rights, or on a
// read-only mount, the message names the path, `what` was to be written
// there and why not ("Permission denied", "Read-only file system"), before
// any work is done.
void CheckCanWrite(const std::string& path, const std::string& what);

// A fast 64-bit content hash (FNV-1a) of a file, for "input unchanged" checks.
uint64_t FileHash(const std::string& path);

// Files in a folder (names relative to it, '/' separators, sorted), recursing
// into subfolders; hidden files are skipped.
std::vector<std::string> ListFilesRecursive(const std::string& folder);

// A unique suffix for temporary names: ".tmp-<pid>-<counter>".
std::string TempSuffix();

// Removes what a killed writer of `path` left beside it: files and folders
// named "<name>.tmp-<pid>-..." or "<name>.old.tmp-<pid>-..." (TempSuffix,
// OutputDirectory::Commit) whose process no longer runs. Temporaries of a
// live process are left alone. WriteFileAtomically and OutputDirectory call
// it, so a rerun after kill -9 leaves no stray temporaries.
void RemoveStaleTemporaries(const std::string& path);

// An exclusive hold on a lock file for as long as the object lives (flock):
// two processes that would write the same workspace do not run at once.
// The kernel releases the hold when the process ends, however it ends, so
// a killed run leaves no stale lock. The file keeps the holder's pid for
// the message of the next one.
class FileLock {
 public:
  // Throws InputError naming `what` and the holder's pid when another
  // process holds `path`, or when the file cannot be opened.
  FileLock(const std::string& path, const std::string& what);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace bayon
