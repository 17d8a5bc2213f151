// SPDX-License-Identifier: BSD-3-Clause
//
// Coded targets through `bayon pipeline` on the rendered tower (16
// photographs of 1800 x 1200 around it, 50 targets of 0.2 m, a third of
// them surveyed): the targets stage finds them, they match pairs by name
// and orient the pairs that repetitive masonry defeats, and the surveyed
// ones are control and check points of the bundle. Judged against the
// truth: every image oriented, the check points within three standard
// deviations, sigma0 as the weights state, the calibration within 2.5
// standard deviations of the truth.
#include "ext/colmap/control_io.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <set>

#include "tests/testing.h"

namespace bayon {
namespace {

nlohmann::json ReadJson(const std::string& path) {
  return nlohmann::json::parse(ReadFileToString(path));
}

TEST(TargetsPipeline, CodedTargetsOrientAndControlTheTowerRing) {
  const std::string dir = testing::TempDir("targets_pipeline");
  const std::string ws = dir + "/ws";
  testing::CommandResult result = testing::RunBayon({"synth",
                                                     "--scene",
                                                     "tower",
                                                     "--output_path",
                                                     ws,
                                                     "--seed",
                                                     "2",
                                                     "--num_heldout_views",
                                                     "0",
                                                     "--coded_targets",
                                                     "50"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::set<std::string> surveyed;
  for (const ControlPoint& point :
       ReadControlPoints(ws + "/control/points.txt")) {
    if (point.name.rfind("CT", 0) == 0) surveyed.insert(point.name);
  }
  ASSERT_GE(surveyed.size(), 10u);

  result = testing::RunBayon(
      {"pipeline", "--workspace_path", ws, "--to_stage", "adjust"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  // Found in every photograph, and some pair oriented from them first.
  EXPECT_GE(ReadImageMeasurements(ws + "/targets/targets.txt").size(), 180u);
  EXPECT_NE(ReadFileToString(ws + "/logs/relative.log")
                .find("coded targets (oriented from them first)"),
            std::string::npos);

  const nlohmann::json adjustment =
      ReadJson(ws + "/sparse/adjusted/adjustment.json");
  const nlohmann::json& checks = adjustment["check_points"];
  int num_coded_checks = 0;
  for (const nlohmann::json& point : checks["points"]) {
    num_coded_checks += surveyed.count(point["name"].get<std::string>());
  }
  std::cout << checks["num"] << " check points (" << num_coded_checks
            << " coded), largest |d|/s " << checks["max_normalized_difference"]
            << "; variance factor "
            << adjustment["statistics"]["variance_factor"] << "\n";
  EXPECT_GE(num_coded_checks, 3);
  EXPECT_LT(checks["max_normalized_difference"].get<double>(), 3.0);
  // sigma0 within 10 % of the weights' reference.
  const double sigma0_ratio =
      std::sqrt(adjustment["statistics"]["variance_factor"].get<double>());
  EXPECT_GT(sigma0_ratio, 0.9);
  EXPECT_LT(sigma0_ratio, 1.1);

  result = testing::RunBayon({"evaluate",
                              "--ground_truth_path",
                              ws + "/gt",
                              "--input_path",
                              ws + "/sparse/adjusted",
                              "--output_path",
                              dir + "/evaluation.json"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json evaluation = ReadJson(dir + "/evaluation.json");
  const nlohmann::json& sparse = evaluation["sparse"];
  std::cout << sparse["num_registered"] << " of 16 oriented, rotation RMS "
            << sparse["rotation_rms_deg"] << " deg, centre RMS "
            << sparse["center_rms"] << " m; calibration largest |e|/s "
            << evaluation["calibration"][0]["max_abs_error_over_sigma"] << "\n";
  // Measured: 16 of 16, 0.030 deg, 0.96 mm; 2.19.
  EXPECT_EQ(sparse["num_registered"].get<int>(), 16);
  EXPECT_LT(sparse["rotation_rms_deg"].get<double>(), 0.1);
  EXPECT_LT(
      evaluation["calibration"][0]["max_abs_error_over_sigma"].get<double>(),
      2.5);
}

}  // namespace
}  // namespace bayon
