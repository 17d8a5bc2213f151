// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon targets` end to end on a small synthetic tower with coded targets
// (`bayon synth --coded_targets`): every target the truth counts as visible
// found, every measurement at its target's true projection (no wrong
// identity), centres within a tenth of a pixel RMS; and its bad input.
#include "ext/colmap/control_io.h"
#include "ext/colmap/model_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "tests/testing.h"

namespace bayon {
namespace {

// A coarse tower (13.5 mm GSD) with 30 coded targets of 0.4 m, about 30 px
// in the photographs.
std::string TowerWithCodedTargets(const std::string& dir) {
  const std::string ws = dir + "/ws";
  const testing::CommandResult result = testing::RunBayon(
      {"synth", "--scene",          "tower", "--output_path",
       ws,      "--num_views",      "6",     "--image_width",
       "900",   "--mesh_spacing_m", "0.08",  "--texel_size_m",
       "0.02",  "--supersampling",  "2",     "--seed",
       "3",     "--coded_targets",  "30",    "--coded_target_side_m",
       "0.4"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return ws;
}

TEST(Targets, FindsTheTowersCodedTargetsAtTheirTrueProjections) {
  const std::string ws = TowerWithCodedTargets(testing::TempDir("targets"));
  const std::string found_path = ws + "/targets.txt";
  const testing::CommandResult result = testing::RunBayon({"targets",
                                                           "--database_path",
                                                           ws + "/database.db",
                                                           "--image_path",
                                                           ws + "/images",
                                                           "--output_path",
                                                           found_path});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::cout << result.LastLine() << "\n";

  // The truth: the coded targets' exact projections where synth counts
  // them visible, and their object points for all the others.
  std::set<std::pair<std::string, std::string>> visible;
  std::map<std::pair<std::string, std::string>, Eigen::Vector2d> truth;
  for (const ImageMeasurement& m :
       ReadImageMeasurements(ws + "/gt/control/observations.txt")) {
    if (m.point_name.rfind("CT", 0) != 0) continue;
    visible.insert({m.image_name, m.point_name});
    truth[{m.image_name, m.point_name}] = m.xy;
  }
  ASSERT_GE(visible.size(), 40u);
  std::map<std::string, Eigen::Vector3d> points;
  for (const ControlPoint& point :
       ReadControlPoints(ws + "/gt/control/points.txt")) {
    points[point.name] = point.xyz;
  }
  const Scene model = ReadModel(ws + "/gt/sparse");

  int num_visible_found = 0;
  double error_sq = 0;
  for (const ImageMeasurement& m : ReadImageMeasurements(found_path)) {
    EXPECT_GT(m.sigma_px, 0);
    const auto key = std::make_pair(m.image_name, m.point_name);
    // Every measurement, counted visible or not, lies at the true
    // projection of the target its code names.
    ASSERT_TRUE(points.count(m.point_name)) << m.point_name;
    const Image* image = model.FindImageByName(m.image_name);
    ASSERT_NE(image, nullptr);
    Eigen::Vector2d projected;
    ASSERT_TRUE(model.Project(*image, points.at(m.point_name), &projected));
    EXPECT_LT((m.xy - projected).norm(), 1.0)
        << m.point_name << " in " << m.image_name;
    if (visible.count(key) == 0) continue;
    ++num_visible_found;
    error_sq += (m.xy - truth.at(key)).squaredNorm();
  }
  const double rms = std::sqrt(error_sq / num_visible_found);
  std::cout << num_visible_found << " of " << visible.size()
            << " visible targets found, centre RMS " << rms << " px\n";
  // Measured: 48 of 48, 0.032 px.
  EXPECT_GE(num_visible_found, 0.99 * visible.size());
  EXPECT_LT(rms, 0.1);
}

TEST(Targets, BadInputGetsOneLine) {
  const std::string dir = testing::TempDir("targets_bad");
  const std::string ws = TowerWithCodedTargets(dir);
  // A photograph the database names is missing: nothing is written.
  const std::string images = dir + "/images";
  testing::CopyTree(ws + "/images", images);
  std::filesystem::remove(images + "/image_003.png");
  testing::CommandResult result = testing::RunBayon({"targets",
                                                     "--database_path",
                                                     ws + "/database.db",
                                                     "--image_path",
                                                     images,
                                                     "--output_path",
                                                     dir + "/targets.txt"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("image_003.png"), std::string::npos)
      << result.LastLine();
  EXPECT_FALSE(std::filesystem::exists(dir + "/targets.txt"));
  // An unknown dictionary, before any work.
  result = testing::RunBayon({"targets",
                              "--database_path",
                              ws + "/database.db",
                              "--image_path",
                              ws + "/images",
                              "--output_path",
                              dir + "/targets.txt",
                              "--dictionary",
                              "aruco_3x3"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("aruco_3x3"), std::string::npos)
      << result.LastLine();
  // The sheet, and a code the dictionary does not have.
  result = testing::RunBayon(
      {"targets", "--print", dir + "/sheet.svg", "--codes", "0-5,9"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_TRUE(std::filesystem::exists(dir + "/sheet.svg"));
  result = testing::RunBayon(
      {"targets", "--print", dir + "/sheet2.svg", "--codes", "48-51"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("code 50"), std::string::npos)
      << result.LastLine();
}

}  // namespace
}  // namespace bayon
