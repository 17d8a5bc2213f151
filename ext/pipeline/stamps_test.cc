// SPDX-License-Identifier: BSD-3-Clause
#include "ext/pipeline/stamps.h"

#include "ext/core/file_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// A stage with one output and one input outside the chain, in a fresh
// workspace; the output and input exist, the stamp does not yet.
struct StageFixture {
  explicit StageFixture(const std::string& name) {
    workspace = testing::TempDir(name);
    fs::create_directories(workspace + "/pipeline");
    fs::create_directories(workspace + "/images");
    stage.name = "relative";
    stage.program = "bayon";
    stage.command = "relative";
    stage.options = {{"database_path", workspace + "/database.db"}};
    stage.outputs = {workspace + "/database.db"};
    stage.inputs = {workspace + "/images"};
    Touch(workspace + "/database.db");
    Touch(workspace + "/images/a.png");
    words = CommandWords(stage, true);
    stamp = StampPath(workspace, stage.name);
  }

  static void Touch(const std::string& path) { std::ofstream(path) << "x"; }

  // Sets a file's time `seconds` after the stamp's.
  void After(const std::string& path, int seconds) const {
    fs::last_write_time(
        path, fs::last_write_time(stamp) + std::chrono::seconds(seconds));
  }

  std::string Why(const std::optional<fs::file_time_type>& previous = {}) {
    return WhyRun(stage, words, stamp, previous);
  }

  std::string workspace, stamp;
  Stage stage;
  std::vector<std::string> words;
};

TEST(PipelineStamps, StampPathIsInThePipelineFolder) {
  EXPECT_EQ(StampPath("/w", "dense"), "/w/pipeline/dense.done");
}

TEST(PipelineStamps, AStageWithoutAStampRuns) {
  StageFixture f("stamps_none");
  EXPECT_EQ(f.Why(), "not run yet");
}

TEST(PipelineStamps, AStampedStageIsUpToDate) {
  StageFixture f("stamps_done");
  WriteStamp(f.stamp, f.words, 1.5);
  f.After(f.workspace + "/images/a.png", -10);
  f.After(f.workspace + "/images", -10);
  EXPECT_EQ(f.Why(), "");
  // An earlier stage stamped before this one leaves it up to date.
  EXPECT_EQ(f.Why(fs::last_write_time(f.stamp) - std::chrono::seconds(5)), "");
}

TEST(PipelineStamps, ChangedOptionsRunTheStageAgain) {
  StageFixture f("stamps_options");
  WriteStamp(f.stamp, f.words, 1.0);
  SetStageOption(&f.stage.options, "num_samples", "2048");
  EXPECT_EQ(WhyRun(f.stage, CommandWords(f.stage, true), f.stamp, {}),
            "its options changed");
}

TEST(PipelineStamps, AMissingOutputRunsTheStageAgain) {
  StageFixture f("stamps_output");
  WriteStamp(f.stamp, f.words, 1.0);
  fs::remove(f.workspace + "/database.db");
  EXPECT_EQ(f.Why(), f.workspace + "/database.db is missing");
}

TEST(PipelineStamps, AnEarlierStageThatRanSinceRunsThisOneAgain) {
  StageFixture f("stamps_earlier");
  WriteStamp(f.stamp, f.words, 1.0);
  f.After(f.workspace + "/images/a.png", -10);
  f.After(f.workspace + "/images", -10);
  EXPECT_EQ(f.Why(fs::last_write_time(f.stamp) + std::chrono::seconds(5)),
            "an earlier stage ran since");
}

TEST(PipelineStamps, AnInputChangedSinceRunsTheStageAgain) {
  StageFixture f("stamps_input");
  WriteStamp(f.stamp, f.words, 1.0);
  f.After(f.workspace + "/images", -10);
  // A photograph replaced inside the folder counts, not only the folder.
  f.After(f.workspace + "/images/a.png", 10);
  EXPECT_EQ(f.Why(), f.workspace + "/images changed since");
}

TEST(PipelineStamps, AnUnreadableStampRunsTheStageAgain) {
  StageFixture f("stamps_unreadable");
  std::ofstream(f.stamp) << "{ not json";
  EXPECT_EQ(f.Why(), "its stamp is unreadable");
}

TEST(PipelineStamps, NewestTimeLooksIntoFolders) {
  StageFixture f("stamps_newest");
  const std::string folder = f.workspace + "/images";
  fs::create_directories(folder + "/sub");
  StageFixture::Touch(folder + "/sub/b.png");
  const fs::file_time_type late =
      fs::last_write_time(folder) + std::chrono::hours(1);
  fs::last_write_time(folder + "/sub/b.png", late);
  EXPECT_EQ(NewestTime(folder), late);
  EXPECT_FALSE(NewestTime(f.workspace + "/nothing").has_value());
}

TEST(PipelineStamps, StaleTemporariesOfTheOutputsAreRemoved) {
  StageFixture f("stamps_temporaries");
  const std::string temp = f.workspace + "/database.db.tmp-123-4";
  const std::string other = f.workspace + "/other.tmp-123-4";
  StageFixture::Touch(temp);
  StageFixture::Touch(other);
  RemoveStaleTemporaries(f.stage);
  EXPECT_FALSE(fs::exists(temp));
  EXPECT_TRUE(fs::exists(other));
  EXPECT_TRUE(fs::exists(f.workspace + "/database.db"));
}

}  // namespace
}  // namespace bayon
