// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/file_util.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

TEST(FileUtil, JoinPathPutsOneSeparatorBetween) {
  EXPECT_EQ(JoinPath("ws", "dense/points.ply"), "ws/dense/points.ply");
  EXPECT_EQ(JoinPath("ws/", "mesh"), "ws/mesh");
  EXPECT_EQ(JoinPath("", "mesh"), "mesh");
}

TEST(FileUtil, AtomicWriteLeavesNoTemporaryFiles) {
  const std::string dir = testing::TempDir("file_util");
  WriteFileAtomically(dir + "/a.txt", "hello");
  EXPECT_EQ(ReadFileToString(dir + "/a.txt"), "hello");
  EXPECT_EQ(ListFilesRecursive(dir), std::vector<std::string>{"a.txt"});
}

TEST(FileUtil, OutputDirectoryRefusesExistingWithoutOverwrite) {
  const std::string dir = testing::TempDir("file_util_out");
  fs::create_directories(dir + "/model");
  WriteFileAtomically(dir + "/model/old.txt", "old");
  EXPECT_THROW(OutputDirectory(dir + "/model", false), InputError);
  {
    OutputDirectory output(dir + "/model", true);
    WriteFileAtomically(output.File("new.txt"), "new");
    // Not committed yet: the old folder is still complete.
    EXPECT_TRUE(fs::exists(dir + "/model/old.txt"));
    output.Commit();
  }
  EXPECT_EQ(ListFilesRecursive(dir), std::vector<std::string>{"model/new.txt"});
}

TEST(FileUtil, UncommittedOutputDirectoryDisappears) {
  const std::string dir = testing::TempDir("file_util_abort");
  {
    OutputDirectory output(dir + "/model", false);
    WriteFileAtomically(output.File("x.bin"), "partial");
  }
  EXPECT_TRUE(ListFilesRecursive(dir).empty());
  EXPECT_FALSE(fs::exists(dir + "/model"));
}

TEST(FileUtil, KilledWritersTemporariesAreRemovedByTheNextWrite) {
  const std::string dir = testing::TempDir("file_util_stale");
  // A pid that no longer runs: a child that has exited and been reaped.
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ::waitpid(child, nullptr, 0);
  const std::string dead = std::to_string(child);
  const std::string live = std::to_string(::getpid());
  // What kill -9 leaves: a file's temporary, a database's journal, an
  // output folder being filled, an old folder moved aside by Commit().
  WriteFileAtomically(dir + "/a.txt.tmp-" + dead + "-0", "partial");
  WriteFileAtomically(dir + "/a.txt.tmp-" + dead + "-0-journal", "j");
  fs::create_directories(dir + "/model.tmp-" + dead + "-1");
  WriteFileAtomically(dir + "/model.tmp-" + dead + "-1/x.bin", "partial");
  fs::create_directories(dir + "/model.old.tmp-" + dead + "-2");
  // A running process's temporary, and names that only look alike.
  WriteFileAtomically(dir + "/a.txt.tmp-" + live + "-7", "in progress");
  WriteFileAtomically(dir + "/a.txt.tmp-notapid", "kept");
  WriteFileAtomically(dir + "/b.txt.tmp-" + dead + "-0", "another file's");

  WriteFileAtomically(dir + "/a.txt", "complete");
  {
    OutputDirectory output(dir + "/model", false);
    WriteFileAtomically(output.File("x.bin"), "complete");
    output.Commit();
  }
  EXPECT_EQ(ListFilesRecursive(dir),
            (std::vector<std::string>{"a.txt",
                                      "a.txt.tmp-" + live + "-7",
                                      "a.txt.tmp-notapid",
                                      "b.txt.tmp-" + dead + "-0",
                                      "model/x.bin"}));
  EXPECT_FALSE(fs::exists(dir + "/model.old.tmp-" + dead + "-2"));
}

// flock is held per open file, so a second FileLock in the same process is
// refused as another process's would be; the pid in the message is the
// holder's, and the lock is free again once the holder is gone.
TEST(FileUtil, FileLockRefusesASecondHolderUntilTheFirstIsGone) {
  const std::string path = testing::TempDir("file_lock") + "/lock";
  {
    const FileLock first(path, "the workspace");
    try {
      const FileLock second(path, "the workspace");
      FAIL() << "expected an InputError";
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what())
                    .find(StrCat("the workspace is in use by another process "
                                 "(pid ",
                                 ::getpid(),
                                 ")")),
                std::string::npos)
          << error.what();
    }
  }
  EXPECT_NO_THROW(FileLock(path, "the workspace"));
  // A lock file that cannot be made: one line naming it.
  EXPECT_THROW(FileLock(path + "/not_a_folder/lock", "x"), InputError);
}

}  // namespace
}  // namespace bayon
