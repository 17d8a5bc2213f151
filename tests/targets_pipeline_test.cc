// SPDX-License-Identifier: BSD-3-Clause
//
// Coded targets through `bayon pipeline` on the rendered tower (16
// photographs of 1800 x 1200 around it, 50 targets of 0.2 m, a third of
// them surveyed): the targets stage finds them, they match pairs by name
// and orient the pairs that repetitive masonry defeats, and the surveyed
// ones are control and check points of the bundle. Judged against the
// truth: every image oriented, the check points within three standard
// deviations, sigma0 as the weights state, the calibration within 2.5
// standard deviations of the truth. Then the survey as a gcp_list.txt in
// UTM, through import_control.
#include "ext/colmap/control_io.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "tests/testing.h"

namespace bayon {
namespace {

nlohmann::json ReadJson(const std::string& path) {
  return nlohmann::json::parse(ReadFileToString(path));
}

Eigen::Vector3d ReadGeoFrameOrigin(const std::string& path) {
  const nlohmann::json origin = ReadJson(path)["origin"];
  return Eigen::Vector3d(origin[0], origin[1], origin[2]);
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
  // Measured: 16 of 16, 0.030 deg, 1.36 mm; 2.01.
  EXPECT_EQ(sparse["num_registered"].get<int>(), 16);
  EXPECT_LT(sparse["rotation_rms_deg"].get<double>(), 0.1);
  EXPECT_LT(
      evaluation["calibration"][0]["max_abs_error_over_sigma"].get<double>(),
      2.5);

  // The same survey as OpenDroneMap's gcp_list.txt in UTM zone 48 N (the
  // tower's frame shifted to near the Bayon's grid coordinates), through
  // import_control and adjust: the check points as before, the model's
  // frame stated beside it.
  const Eigen::Vector3d utm_offset(372000, 1486000, 20);
  std::map<std::string, ControlPoint> given;
  std::string check_names;
  for (const ControlPoint& point :
       ReadControlPoints(ws + "/control/points.txt")) {
    given[point.name] = point;
    if (point.type == ControlPointType::kCheck && !surveyed.count(point.name)) {
      check_names += (check_names.empty() ? "" : ",") + point.name;
    }
  }
  std::ostringstream gcp_list;
  gcp_list.precision(12);
  gcp_list << "WGS84 UTM 48N\n";
  for (const ImageMeasurement& m :
       ReadImageMeasurements(ws + "/control/observations.txt")) {
    if (!given.count(m.point_name)) continue;  // the levelling bar's
    // OpenSfM's pixels: the upper-left pixel's centre at (0, 0).
    const Eigen::Vector3d xyz = given[m.point_name].xyz + utm_offset;
    gcp_list << xyz.x() << " " << xyz.y() << " " << xyz.z() << " "
             << m.xy.x() - 0.5 << " " << m.xy.y() - 0.5 << " " << m.image_name
             << " " << m.point_name << "\n";
  }
  WriteFileAtomically(dir + "/gcp_list.txt", gcp_list.str());
  result = testing::RunBayon({"import_control",
                              "--format",
                              "odm",
                              "--input_path",
                              dir + "/gcp_list.txt",
                              "--output_path",
                              dir + "/control_utm",
                              "--image_path",
                              ws + "/images",
                              "--check_names",
                              check_names,
                              "--sigma_m",
                              "0.002"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  result = testing::RunBayon({"adjust",
                              "--database_path",
                              ws + "/database.db",
                              "--input_path",
                              ws + "/sparse/initial",
                              "--output_path",
                              dir + "/adjusted_utm",
                              "--control_path",
                              dir + "/control_utm"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json utm = ReadJson(dir + "/adjusted_utm/adjustment.json");
  const nlohmann::json& utm_checks = utm["check_points"];
  std::cout << "in UTM: " << utm_checks["num"] << " check points, RMS "
            << utm_checks["rms_mm"] << " mm per axis, largest |d|/s "
            << utm_checks["max_normalized_difference"] << "\n";
  // Measured: 3 check points, 1.5 / 1.7 / 1.9 mm, 1.06.
  EXPECT_EQ(utm_checks["num"].get<int>(), 3);
  for (int k = 0; k < 3; ++k) EXPECT_LT(utm_checks["rms_mm"][k], 5.0);
  EXPECT_LT(utm_checks["max_normalized_difference"].get<double>(), 3.0);
  EXPECT_EQ(utm["georeference"]["crs"], "EPSG:32648");
  EXPECT_EQ(ReadGeoFrameOrigin(dir + "/adjusted_utm/crs.json"),
            Eigen::Vector3d(372000, 1486000, 22));

  // A GCP in a photograph that is not the project's: one line naming the
  // file, nothing written.
  WriteFileAtomically(dir + "/gcp_bad.txt",
                      "EPSG:32648\n372001 1486002 21 10 20 missing.png G1\n");
  result = testing::RunBayon({"import_control",
                              "--input_path",
                              dir + "/gcp_bad.txt",
                              "--output_path",
                              dir + "/control_bad",
                              "--image_path",
                              ws + "/images"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("missing.png"), std::string::npos)
      << result.LastLine();
  EXPECT_NE(result.LastLine().find("gcp_bad.txt"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir + "/control_bad/points.txt"));
}

}  // namespace
}  // namespace bayon
