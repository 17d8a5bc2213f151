// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/colmap_comparison.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

TEST(ColmapComparison, AWorkspaceBuiltByHandHasNoPipelineRecord) {
  const fs::path workspace = testing::TempDir("comparison_by_hand");
  const PipelineRecord record = ReadPipelineRecord(workspace);
  EXPECT_FALSE(record.present);
  EXPECT_TRUE(record.stage_seconds.empty());
  EXPECT_TRUE(record.total_seconds.is_null());
  EXPECT_EQ(DefaultImagePath(workspace, record),
            (workspace / "images").string());
}

TEST(ColmapComparison, ThePipelinesRecordGivesTheCameraAndTheSparseTimes) {
  const fs::path workspace = testing::TempDir("comparison_record");
  fs::create_directories(workspace / "pipeline");
  std::ofstream(workspace / "pipeline.json") << R"({
    "image_path": "photographs",
    "stages": [
      {"name": "import", "status": "ran", "seconds": 1.5,
       "command": ["bayon", "import", "--camera_model", "PINHOLE",
                   "--camera_params", "1520,1525,302,246"]},
      {"name": "features", "status": "ran", "seconds": 2.0, "command": []},
      {"name": "dense", "status": "ran", "seconds": 9.0, "command": []},
      {"name": "strip", "status": "skipped", "seconds": 0, "command": []}],
    "total_seconds": 20.0})";
  // A skipped stage's time is that of the run its stamp records.
  std::ofstream(workspace / "pipeline" / "strip.done")
      << R"({"command": [], "seconds": 3.0})";
  const PipelineRecord record = ReadPipelineRecord(workspace);
  EXPECT_TRUE(record.present);
  EXPECT_EQ(record.camera_model, "PINHOLE");
  EXPECT_EQ(record.camera_params, "1520,1525,302,246");
  EXPECT_EQ(record.stage_seconds.size(), 3u);  // not dense's
  EXPECT_EQ(record.stage_seconds["strip"].get<double>(), 3.0);
  EXPECT_EQ(record.total_seconds.get<double>(), 6.5);
  EXPECT_EQ(record.pipeline_total_seconds.get<double>(), 20.0);
  // A relative folder that is not the caller's is the workspace's.
  EXPECT_EQ(DefaultImagePath(workspace, record),
            (workspace / "photographs").string());
}

TEST(ColmapComparison, AnUnreadableRecordIsRefusedNamingIt) {
  const fs::path workspace = testing::TempDir("comparison_unreadable");
  std::ofstream(workspace / "pipeline.json") << "{ not json";
  try {
    ReadPipelineRecord(workspace);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("pipeline.json"),
              std::string::npos);
  }
}

TEST(ColmapComparison, OptionsCheckTheCameraGivenToColmap) {
  CompareColmapOptions options;
  EXPECT_NO_THROW(options.Check());
  options.camera_model = "BROWN_BEYER";  // bayon's own, not COLMAP's
  EXPECT_THROW(options.Check(), InputError);
  options.camera_model = "PINHOLE";
  options.camera_params = "1520,1525,302";  // PINHOLE has four
  EXPECT_THROW(options.Check(), InputError);
  options.camera_params = "1520,1525,302,246";
  EXPECT_NO_THROW(options.Check());
  EXPECT_TRUE(options.calibrated());
  options.num_neighbors = 0;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace bayon
