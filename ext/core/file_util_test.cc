// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/file_util.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

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

}  // namespace
}  // namespace bayon
