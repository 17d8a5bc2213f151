// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon synth_cloud`, `bayon edit` and `bayon mesh` end to end: a synthetic
// dense cloud with known surface and blunders, edited and meshed through the
// command line, the outputs read back and judged against the truth; and bad
// input refused with one line, nothing written.
#include "ext/colmap/ply_io.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// A small tower cloud (and its true surface) shared by the tests of one
// build.
std::string TowerCloud() {
  return testing::SharedFixture("edit_mesh_tower", [](const std::string& dir) {
    const testing::CommandResult result =
        testing::RunBayon({"synth_cloud",
                           "--shape",
                           "box_tower",
                           "--num_points",
                           "30000",
                           "--output_path",
                           dir + "/points.ply",
                           "--truth_path",
                           dir + "/surface.ply"});
    ASSERT_EQ(result.exit_code, 0) << result.output;
  });
}

size_t CountBlunders(const PointCloud& cloud) {
  const PointAttribute* flags = cloud.FindAttribute("blunder");
  EXPECT_NE(flags, nullptr);
  size_t count = 0;
  for (double f : flags->values) count += f != 0;
  return count;
}

// Runs bayon, expects exit code 2 with one line naming `expected`, the
// inputs unchanged and none of `outputs` created.
void ExpectRefusedWithoutOutput(const std::vector<std::string>& args,
                                const std::string& expected,
                                const std::string& input,
                                const std::vector<std::string>& outputs) {
  const auto before = testing::HashTree(input);
  const testing::CommandResult result = testing::RunBayon(args);
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("error: "), std::string::npos)
      << result.output;
  EXPECT_NE(result.LastLine().find(expected), std::string::npos)
      << "expected '" << expected << "' in: " << result.output;
  EXPECT_EQ(testing::HashTree(input), before);
  for (const std::string& output : outputs) {
    EXPECT_FALSE(fs::exists(output)) << output << " was written";
  }
}

TEST(EditCommand, RemovesTheBlundersOfASyntheticTower) {
  const std::string fixture = TowerCloud();
  const std::string ws = testing::TempDir("edit_tower");
  fs::create_directories(ws + "/dense");
  fs::copy_file(fixture + "/points.ply", ws + "/dense/points.ply");
  const testing::CommandResult result =
      testing::RunBayon({"edit",
                         "--input_path",
                         ws + "/dense/points.ply",
                         "--output_path",
                         ws + "/dense/points_edited.ply",
                         "--removed_path",
                         ws + "/dense/removed.ply",
                         "--report_path",
                         ws + "/dense/edit.json"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("iteration 2:"), std::string::npos);
  EXPECT_TRUE(fs::exists(ws + "/logs/edit.log"));
  EXPECT_TRUE(fs::exists(ws + "/logs/edit.options"));

  const PointCloud input = ReadPointCloudPly(ws + "/dense/points.ply");
  const PointCloud edited = ReadPointCloudPly(ws + "/dense/points_edited.ply");
  const PointCloud removed = ReadPointCloudPly(ws + "/dense/removed.ply");
  EXPECT_EQ(edited.size() + removed.size(), input.size());
  const size_t blunders = CountBlunders(input);
  EXPECT_EQ(blunders, 600u);                        // 2 % of 30000
  EXPECT_LE(CountBlunders(edited), blunders / 20);  // >= 95 % removed
  const size_t good_removed = removed.size() - CountBlunders(removed);
  EXPECT_LT(good_removed, (input.size() - blunders) / 100);
  // Sigmas and flags travel with the kept points; the removed carry why.
  EXPECT_NE(edited.FindAttribute("sx"), nullptr);
  ASSERT_NE(removed.FindAttribute("edit_reason"), nullptr);
  EXPECT_EQ(removed.FindAttribute("edit_reason")->values[0], 1.0);

  std::ifstream report_file(ws + "/dense/edit.json");
  const nlohmann::json report = nlohmann::json::parse(report_file);
  EXPECT_EQ(report["num_removed"].get<size_t>(), removed.size());
  EXPECT_TRUE(report["used_point_precision"].get<bool>());
  EXPECT_GE(report["iterations"].size(), 2u);

  // PCL's statistical outlier removal through the same command.
  const testing::CommandResult statistical =
      testing::RunBayon({"edit",
                         "--input_path",
                         ws + "/dense/points.ply",
                         "--output_path",
                         ws + "/dense/statistical.ply",
                         "--method",
                         "statistical"});
  ASSERT_EQ(statistical.exit_code, 0) << statistical.output;
  EXPECT_NE(statistical.output.find("statistical outlier"), std::string::npos);
}

TEST(EditCommand, BadInput) {
  const std::string dir = testing::TempDir("edit_bad");
  const std::string out = dir + "/out.ply";

  // An empty cloud.
  WritePointCloudPly(PointCloud(), dir + "/empty.ply");
  ExpectRefusedWithoutOutput(
      {"edit", "--input_path", dir + "/empty.ply", "--output_path", out},
      "empty.ply: the cloud has no points",
      dir + "/empty.ply",
      {out});

  // All points on one line.
  PointCloud line;
  for (int i = 0; i < 200; ++i) line.positions.emplace_back(i, 0.5 * i, 1);
  WritePointCloudPly(line, dir + "/line.ply");
  ExpectRefusedWithoutOutput(
      {"edit", "--input_path", dir + "/line.ply", "--output_path", out},
      "line.ply: all 200 points lie on one line",
      dir + "/line.ply",
      {out});

  // A NaN coordinate (ASCII, as another program might write it).
  WriteFileAtomically(dir + "/nan.ply",
                      "ply\nformat ascii 1.0\nelement vertex 3\n"
                      "property float x\nproperty float y\nproperty float z\n"
                      "end_header\n0 0 0\n1 nan 0\n0 1 0\n");
  ExpectRefusedWithoutOutput(
      {"edit", "--input_path", dir + "/nan.ply", "--output_path", out},
      "nan.ply: point 1 has a coordinate that is not a finite number",
      dir + "/nan.ply",
      {out});

  // A bad option value and a bad method name.
  ExpectRefusedWithoutOutput({"edit",
                              "--input_path",
                              dir + "/line.ply",
                              "--output_path",
                              out,
                              "--num_iterations",
                              "0"},
                             "--num_iterations must be in [1, 20] (got 0)",
                             dir + "/line.ply",
                             {out});
  ExpectRefusedWithoutOutput({"edit",
                              "--input_path",
                              dir + "/line.ply",
                              "--output_path",
                              out,
                              "--method",
                              "median"},
                             "median",
                             dir + "/line.ply",
                             {out});
}

}  // namespace
}  // namespace bayon
