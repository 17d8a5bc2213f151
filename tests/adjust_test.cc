// SPDX-License-Identifier: BSD-3-Clause
//
// bayon adjust end to end on synthetic workspaces with known truth (control
// points, check points and a levelling bar from `bayon synth`), and on a
// stock `colmap mapper` model hosted in its database; bad input.
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/table_tie_points.h"
#include "ext/core/alignment.h"
#include "ext/core/file_util.h"
#include "ext/core/random.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <map>
#include <random>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

void RunOk(const std::vector<std::string>& args) {
  const testing::CommandResult result = testing::RunBayon(args);
  ASSERT_EQ(result.exit_code, 0) << result.output;
}

// A ring of 16 stations (every other one turned 90 degrees) around 900
// points, 0.3 px noise, the nominal camera in the database, 8 control and 4
// check points and a levelling bar; sparse/initial is the truth with its
// poses and points disturbed (what strip would give).
std::string SyntheticWorkspace() {
  return testing::SharedFixture(
             "adjust_synthetic",
             [](const std::string& dir) {
               const std::string ws = dir + "/ws";
               RunOk({"synth", "--output_path",
                      ws,      "--num_points",
                      "900",   "--ring_radius_m",
                      "6",     "--alternate_roll_deg",
                      "90",    "--max_view_angle_deg",
                      "75",    "--num_control_points",
                      "8",     "--num_check_points",
                      "4",     "--levelling_bar",
                      "1",     "--nominal_calibration",
                      "1",     "--seed",
                      "3"});
               Scene scene = ReadModel(ws + "/gt/sparse");
               std::mt19937 rng(5);
               std::normal_distribution<double> noise(0, 1);
               for (auto& [id, point] : scene.points3D) {
                 point.xyz += 0.01 * RandomVector<3>(noise, rng);
               }
               for (auto& [id, image] : scene.images) {
                 const Eigen::Vector3d center =
                     image.cam_from_world.Center() +
                     0.03 * RandomVector<3>(noise, rng);
                 image.cam_from_world.translation =
                     -(image.cam_from_world.rotation * center);
               }
               fs::create_directories(ws + "/sparse/initial");
               WriteModel(scene, ws + "/sparse/initial", ModelFormat::kBinary);
             }) +
         "/ws";
}

nlohmann::json ReadJson(const std::string& path) {
  return nlohmann::json::parse(ReadFileToString(path));
}

TEST(Adjust, SyntheticBlockWithControl) {
  const std::string ws = SyntheticWorkspace();
  const std::string out = testing::TempDir("adjust_control") + "/adjusted";
  const testing::CommandResult result =
      testing::RunBayon({"adjust",
                         "--database_path",
                         ws + "/database.db",
                         "--input_path",
                         ws + "/sparse/initial",
                         "--output_path",
                         out,
                         "--control_path",
                         ws + "/control",
                         "--image_sigma_px",
                         "0.3",
                         "--log_path",
                         out + ".log"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  for (const char* file : {"cameras.bin",
                           "images.bin",
                           "points3D.bin",
                           "calibration.json",
                           "adjustment.json",
                           "adjustment.txt"}) {
    EXPECT_TRUE(fs::exists(out + "/" + file)) << file;
  }
  const nlohmann::json report = ReadJson(out + "/adjustment.json");
  const nlohmann::json& s = report["statistics"];
  EXPECT_EQ(report["datum"]["type"], "control");
  // sigma0 within 10 % of the injected 0.3 px noise.
  EXPECT_NEAR(s["sigma0_px"].get<double>(), 0.3, 0.03);
  EXPECT_EQ(s["r"].get<int>(), s["n"].get<int>() - s["u"].get<int>());
  EXPECT_GT(s["r_over_n"].get<double>(), 0.3);
  // The nominal camera's K3 is zero and stays out; dc, K1 are found.
  std::set<std::string> kept;
  for (const auto& p : report["self_calibration"]["parameters"]) {
    kept.insert(p["name"].get<std::string>());
  }
  EXPECT_TRUE(kept.count("K1") && kept.count("dx0")) << report.dump();
  EXPECT_FALSE(kept.count("K3"));
  // Check points within 3 sigma, coordinate by coordinate.
  ASSERT_EQ(report["check_points"]["num"].get<int>(), 4);
  for (const auto& p : report["check_points"]["points"]) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_LT(std::abs(p["difference_mm"][k].get<double>()),
                3 * p["std_dev_mm"][k].get<double>())
          << p.dump();
    }
  }
  // The calibration carries its covariance and the COLMAP fit.
  const nlohmann::json calibration = ReadJson(out + "/calibration.json");
  EXPECT_EQ(calibration["cameras"][0]["model"], "BROWN_BEYER");
  EXPECT_EQ(calibration["cameras"][0]["covariance"].size(), 13u);
  EXPECT_GT(calibration["cameras"][0]["std_devs"]["K1"].get<double>(), 0);
  EXPECT_LT(calibration["cameras"][0]["colmap"]["fit_rms_px"].get<double>(),
            0.1);
  // The model is COLMAP's: its tools read it, and it is in the truth's datum.
  const testing::CommandResult analyzer =
      testing::RunColmap({"model_analyzer", "--path", out});
  EXPECT_EQ(analyzer.exit_code, 0) << analyzer.output;
  const testing::CommandResult evaluation =
      testing::RunBayon({"evaluate",
                         "--input_path",
                         out,
                         "--ground_truth_path",
                         ws + "/gt/sparse",
                         "--align",
                         "0",
                         "--output_path",
                         out + ".eval.json"});
  ASSERT_EQ(evaluation.exit_code, 0) << evaluation.output;
  const nlohmann::json eval = ReadJson(out + ".eval.json");
  EXPECT_LT(eval["sparse"]["center_rms"].get<double>(), 0.01);
  // The printout has the classic sections.
  const std::string text = ReadFileToString(out + "/adjustment.txt");
  for (const char* section : {"STATISTICS",
                              "r/n",
                              "sigma0 a posteriori",
                              "CHECK POINTS",
                              "EXTERIOR ORIENTATIONS",
                              "OBJECT POINTS",
                              "correlation matrix"}) {
    EXPECT_NE(text.find(section), std::string::npos) << section;
  }
}

TEST(Adjust, MinimumDatumAndFreeNetwork) {
  const std::string ws = SyntheticWorkspace();
  const std::string dir = testing::TempDir("adjust_minimum");
  // The paper's minimum datum: the levelling bar and one more point; every
  // other control point becomes a check point, in the truth's system.
  RunOk({"adjust",
         "--database_path",
         ws + "/database.db",
         "--input_path",
         ws + "/sparse/initial",
         "--output_path",
         dir + "/minimum",
         "--control_path",
         ws + "/control",
         "--datum",
         "minimum",
         "--image_sigma_px",
         "0.3",
         "--log_path",
         dir + "/log"});
  const nlohmann::json minimum = ReadJson(dir + "/minimum/adjustment.json");
  EXPECT_EQ(minimum["datum"]["type"], "minimum");
  EXPECT_EQ(minimum["statistics"]["d"].get<int>(), 0);
  EXPECT_EQ(minimum["check_points"]["num"].get<int>(), 4 + 8 - 1);
  int within = 0, total = 0;
  for (const auto& p : minimum["check_points"]["points"]) {
    for (int k = 0; k < 3; ++k) {
      ++total;
      within += std::abs(p["difference_mm"][k].get<double>()) <
                3 * p["std_dev_mm"][k].get<double>();
    }
  }
  EXPECT_GE(within, total - 1) << minimum["check_points"].dump();

  // A free network: datum defect 7, the same sigma0 (the datum does not
  // change the residuals), precision from inner constraints.
  RunOk({"adjust",
         "--database_path",
         ws + "/database.db",
         "--input_path",
         ws + "/sparse/initial",
         "--output_path",
         dir + "/free",
         "--datum",
         "free",
         "--image_sigma_px",
         "0.3",
         "--log_path",
         dir + "/log"});
  const nlohmann::json free = ReadJson(dir + "/free/adjustment.json");
  EXPECT_EQ(free["datum"]["type"], "free");
  EXPECT_EQ(free["statistics"]["d"].get<int>(), 7);
  EXPECT_NEAR(free["statistics"]["sigma0_px"].get<double>(), 0.3, 0.03);
  const nlohmann::json& rms = free["statistics"]["point_precision_rms_mm"];
  for (int k = 0; k < 3; ++k) EXPECT_GT(rms[k].get<double>(), 0);

  // Upright: z along the truth's vertical (within 5 degrees; the
  // photographs, every other one portrait, are all that tells it), the
  // origin at the object's centre, the scale of the relative orientation.
  EXPECT_EQ(free["datum"]["vertical"],
            "the images' horizontal axes (cameras held level)");
  const Scene truth = ReadModel(ws + "/gt/sparse");
  const Scene adjusted = ReadModel(dir + "/free");
  std::vector<Eigen::Vector3d> true_centres, free_centres;
  for (const auto& [id, image] : adjusted.images) {
    free_centres.push_back(image.cam_from_world.Center());
    const Image* same = truth.FindImageByName(image.name);
    ASSERT_NE(same, nullptr) << image.name;
    true_centres.push_back(same->cam_from_world.Center());
  }
  const std::optional<Sim3d> free_from_true =
      EstimateSim3d(true_centres, free_centres);
  ASSERT_TRUE(free_from_true);
  const Eigen::Vector3d up =
      free_from_true->rotation * Eigen::Vector3d::UnitZ();
  EXPECT_LT(std::acos(up.z()) * 180 / M_PI, 5.0);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& [id, point] : adjusted.points3D) mean += point.xyz;
  mean /= static_cast<double>(adjusted.points3D.size());
  // The ring's radius is 6 m in the truth.
  EXPECT_LT(mean.norm(), 0.1 * 6 * free_from_true->scale);
}

// bayon's own chain: strip (chained models, similarity to the control),
// then adjust.
TEST(Adjust, StripThenAdjust) {
  const std::string ws = SyntheticWorkspace();
  const std::string dir = testing::TempDir("adjust_strip");
  const testing::CommandResult strip = testing::RunBayon({"strip",
                                                          "--database_path",
                                                          ws + "/database.db",
                                                          "--output_path",
                                                          dir + "/initial",
                                                          "--control_path",
                                                          ws + "/control",
                                                          "--log_path",
                                                          dir + "/log"});
  ASSERT_EQ(strip.exit_code, 0) << strip.output;
  EXPECT_NE(strip.output.find("16 images oriented"), std::string::npos)
      << strip.output;
  const nlohmann::json report = ReadJson(dir + "/initial/strip.json");
  EXPECT_TRUE(report["closed_ring"].get<bool>());
  EXPECT_EQ(report["similarity"]["residuals"].size(), 10u);
  RunOk({"adjust",
         "--database_path",
         ws + "/database.db",
         "--input_path",
         dir + "/initial",
         "--output_path",
         dir + "/adjusted",
         "--control_path",
         ws + "/control",
         "--image_sigma_px",
         "0.3",
         "--log_path",
         dir + "/log"});
  const nlohmann::json adjusted = ReadJson(dir + "/adjusted/adjustment.json");
  EXPECT_NEAR(adjusted["statistics"]["sigma0_px"].get<double>(), 0.3, 0.03);
  RunOk({"evaluate",
         "--input_path",
         dir + "/adjusted",
         "--ground_truth_path",
         ws + "/gt/sparse",
         "--align",
         "0",
         "--output_path",
         dir + "/eval.json"});
  const nlohmann::json eval = ReadJson(dir + "/eval.json");
  EXPECT_LT(eval["sparse"]["center_rms"].get<double>(), 0.01);
  // Bad input: an output that exists is refused, nothing changes.
  const auto before = testing::HashTree(dir + "/initial");
  const testing::CommandResult again = testing::RunBayon({"strip",
                                                          "--database_path",
                                                          ws + "/database.db",
                                                          "--output_path",
                                                          dir + "/initial",
                                                          "--log_path",
                                                          dir + "/log"});
  EXPECT_EQ(again.exit_code, 2) << again.output;
  EXPECT_EQ(testing::HashTree(dir + "/initial"), before);
}

// bayon tiepoints' output in the database: the keypoints of the points seen
// in three or more images (0.3 px noise) as least-squares tie points with
// that precision. strip and adjust take them (auto) beside the tracks, or
// alone (alsm): weighted by their covariance, sigma0 a priori the median
// one, the model's 2D points the keypoints and then the tie observations.
TEST(Adjust, TiePointsFromTheDatabase) {
  const std::string ws = SyntheticWorkspace();
  const std::string dir = testing::TempDir("adjust_tie_points");
  const std::string db = dir + "/database.db";
  fs::copy_file(ws + "/database.db", db);
  std::map<image_t, size_t> num_ties;
  {
    const Scene initial = ReadModel(ws + "/sparse/initial");
    Database database(db, Database::Mode::kReadWrite);
    std::vector<TiePointRecord> points;
    for (const auto& [id, point] : initial.points3D) {
      if (point.track.size() < 3) continue;
      TiePointRecord record;
      record.source = "alsm";
      for (const TrackElement& element : point.track) {
        TieObservation observation;
        observation.image_id = element.image_id;
        observation.xy = KeypointXY(database.ReadKeypoints(element.image_id),
                                    element.point2D_idx);
        observation.covariance = 0.09 * Eigen::Matrix2d::Identity();
        record.observations.push_back(observation);
        ++num_ties[element.image_id];
      }
      std::sort(
          record.observations.begin(),
          record.observations.end(),
          [](const auto& a, const auto& b) { return a.image_id < b.image_id; });
      points.push_back(std::move(record));
    }
    WriteTiePoints(&database, points);
  }
  RunOk({"strip",
         "--database_path",
         db,
         "--output_path",
         dir + "/initial",
         "--control_path",
         ws + "/control",
         "--log_path",
         dir + "/log"});
  const nlohmann::json strip = ReadJson(dir + "/initial/strip.json");
  EXPECT_GT(strip["num_alsm_tie_points"].get<int>(), 300);
  // Alone: sigma0 a priori = the tie points' 0.3 px, variance factor 1.
  RunOk({"adjust",
         "--database_path",
         db,
         "--input_path",
         dir + "/initial",
         "--output_path",
         dir + "/alsm",
         "--control_path",
         ws + "/control",
         "--tie_points",
         "alsm",
         "--log_path",
         dir + "/log"});
  const nlohmann::json report = ReadJson(dir + "/alsm/adjustment.json");
  const nlohmann::json& s = report["statistics"];
  EXPECT_NEAR(s["sigma0_apriori_px"].get<double>(), 0.3, 1e-6);
  EXPECT_NEAR(s["variance_factor"].get<double>(), 1.0, 0.1);
  for (const auto& p : report["check_points"]["points"]) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_LT(std::abs(p["difference_mm"][k].get<double>()),
                3 * p["std_dev_mm"][k].get<double>())
          << p.dump();
    }
  }
  const Scene alsm = ReadModel(dir + "/alsm");
  for (const auto& [id, image] : alsm.images) {
    EXPECT_EQ(image.points2D.size(), num_ties.at(id)) << image.name;
  }
  const testing::CommandResult analyzer =
      testing::RunColmap({"model_analyzer", "--path", dir + "/alsm"});
  EXPECT_EQ(analyzer.exit_code, 0) << analyzer.output;
  // Both (auto), from the tie-point-only model: keypoints first again.
  RunOk({"adjust",
         "--database_path",
         db,
         "--input_path",
         dir + "/alsm",
         "--output_path",
         dir + "/both",
         "--control_path",
         ws + "/control",
         "--log_path",
         dir + "/log"});
  Database database(db, Database::Mode::kReadOnly);
  const Scene both = ReadModel(dir + "/both");
  for (const auto& [id, image] : both.images) {
    EXPECT_EQ(static_cast<Eigen::Index>(image.points2D.size()),
              database.ReadKeypoints(id).rows() +
                  static_cast<Eigen::Index>(num_ties.at(id)))
        << image.name;
  }
  // Without tie points in the database, alsm is refused.
  const testing::CommandResult refused = testing::RunBayon({"adjust",
                                                            "--database_path",
                                                            ws + "/database.db",
                                                            "--input_path",
                                                            dir + "/initial",
                                                            "--output_path",
                                                            dir + "/refused",
                                                            "--tie_points",
                                                            "alsm",
                                                            "--log_path",
                                                            dir + "/log"});
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_FALSE(fs::exists(dir + "/refused"));
}

// A COLMAP user's project: stock colmap mapper on the database, then bayon
// adjust with control and self-calibration on that model.
TEST(Adjust, StockColmapModelWithControl) {
  const std::string dir = testing::TempDir("adjust_colmap");
  const std::string ws = dir + "/ws";
  RunOk({"synth",
         "--output_path",
         ws,
         "--num_control_points",
         "6",
         "--num_check_points",
         "4",
         "--seed",
         "2"});
  fs::copy_file(ws + "/database.db", dir + "/colmap.db");
  fs::create_directories(dir + "/mapper");
  const testing::CommandResult mapper =
      testing::RunColmap({"mapper",
                          "--database_path",
                          dir + "/colmap.db",
                          "--image_path",
                          ws + "/images",
                          "--output_path",
                          dir + "/mapper",
                          "--Mapper.ba_refine_extra_params",
                          "0"});
  ASSERT_EQ(mapper.exit_code, 0) << mapper.output;
  RunOk({"adjust",
         "--database_path",
         ws + "/database.db",
         "--input_path",
         dir + "/mapper/0",
         "--output_path",
         dir + "/adjusted",
         "--control_path",
         ws + "/control",
         "--image_sigma_px",
         "0.3",
         "--log_path",
         dir + "/log"});
  const nlohmann::json report = ReadJson(dir + "/adjusted/adjustment.json");
  EXPECT_EQ(report["datum"]["type"], "control");
  // The mapper's model is in its own system: the similarity brings it in.
  EXPECT_GT(
      std::abs(report["datum"]["object_from_model"]["scale"].get<double>() -
               1.0),
      1e-3);
  EXPECT_NEAR(report["statistics"]["sigma0_px"].get<double>(), 0.3, 0.03);
  EXPECT_LT(report["check_points"]["rms_3d_mm"].get<double>(), 10.0);
}

// A "Bundle Adjustment in the Large" problem through import_bal, adjusted in
// its own camera model (the benchmark's set-up, a few iterations).
TEST(Adjust, BalProblem) {
  BAYON_REQUIRE_DATA("bundle/ladybug-49-7776");
  const std::string dir = testing::TempDir("adjust_bal");
  RunOk({"import_bal",
         "--input_path",
         testing::DataPath("bundle/ladybug-49-7776/problem-49-7776-pre.txt"),
         "--output_path",
         dir + "/ws"});
  const Scene scene = ReadModel(dir + "/ws/sparse/0");
  EXPECT_EQ(scene.images.size(), 49u);
  EXPECT_EQ(scene.points3D.size(), 7776u);
  RunOk({"adjust",
         "--database_path",
         dir + "/ws/database.db",
         "--input_path",
         dir + "/ws/sparse/0",
         "--output_path",
         dir + "/adjusted",
         "--camera_model",
         "colmap",
         "--self_calibration",
         "all",
         "--two_steps",
         "0",
         "--blunder_detection",
         "none",
         "--max_num_iterations",
         "10",
         "--log_path",
         dir + "/log"});
  const nlohmann::json report = ReadJson(dir + "/adjusted/adjustment.json");
  // 31843 observations, 31 of them of points behind their camera.
  EXPECT_EQ(report["statistics"]["n"].get<int>(), 2 * (31843 - 31));
  EXPECT_EQ(report["statistics"]["d"].get<int>(), 7);
  // Far below the imported model's 4.9 px after ten iterations.
  EXPECT_LT(report["statistics"]["mean_reprojection_error_px"].get<double>(),
            1.0);
}

// Bad input: one line naming the problem, exit code 2, nothing written.
class AdjustBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    ws_ = SyntheticWorkspace();
    dir_ = testing::TempDir(
        std::string("adjust_bad_") +
        ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }

  void ExpectRefused(const std::string& control,
                     const std::vector<std::string>& extra,
                     const std::string& expected,
                     const std::string& input = "") {
    std::vector<std::string> args = {
        "adjust",
        "--database_path",
        ws_ + "/database.db",
        "--input_path",
        input.empty() ? ws_ + "/sparse/initial" : input,
        "--output_path",
        dir_ + "/out",
        "--log_path",
        dir_ + "/log"};
    if (!control.empty()) {
      args.push_back("--control_path");
      args.push_back(control);
    }
    args.insert(args.end(), extra.begin(), extra.end());
    const auto before = testing::HashTree(ws_);
    const testing::CommandResult result = testing::RunBayon(args);
    EXPECT_EQ(result.exit_code, 2) << result.output;
    EXPECT_NE(result.LastLine().find(expected), std::string::npos)
        << "expected '" << expected << "' in: " << result.output;
    EXPECT_FALSE(fs::exists(dir_ + "/out"));
    EXPECT_EQ(testing::HashTree(ws_), before);
  }

  // A copy of the control folder with points.txt replaced.
  std::string Control(const std::string& points) {
    const std::string control = dir_ + "/control";
    testing::CopyTree(ws_ + "/control", control);
    WriteFileAtomically(control + "/points.txt", points);
    return control;
  }

  std::string ws_;
  std::string dir_;
};

TEST_F(AdjustBadInput, DeterminabilityLimitsOutOfRange) {
  ExpectRefused("",
                {"--max_exterior_correlation", "1.5"},
                "max_exterior_correlation must be");
  ExpectRefused(
      "", {"--max_interior_sigma", "0"}, "max_interior_sigma must be");
}

TEST_F(AdjustBadInput, NoControlWhereTheDatumNeedsIt) {
  ExpectRefused("", {"--datum", "control"}, "no control points");
  ExpectRefused("", {"--datum", "minimum"}, "vertical levelling bar");
}

TEST_F(AdjustBadInput, FewerThanThreeControlPoints) {
  ExpectRefused(Control("C01 1.8477590650225735 0.76536686473017956 0.8\n"
                        "C02 0.76536686473017967 1.8477590650225735 3.2\n"),
                {"--datum", "control"},
                "needs three control points");
}

TEST_F(AdjustBadInput, ControlPointSeenInNoImage) {
  ExpectRefused(Control("C01 1.8477590650225735 0.76536686473017956 0.8\n"
                        "NOWHERE 0 0 0\n"),
                {},
                "'NOWHERE' is measured in no image");
}

TEST_F(AdjustBadInput, CollinearControl) {
  // Three control points on one line (coordinates given on a line, whatever
  // the images say).
  ExpectRefused(Control("C01 0 0 1\nC02 0 0 2\nC03 0 0 3\n"),
                {"--datum", "control"},
                "collinear");
}

TEST_F(AdjustBadInput, CameraWithoutCalibration) {
  Scene scene = ReadModel(ws_ + "/sparse/initial");
  for (auto& [id, camera] : scene.cameras) {
    for (int idx : camera.ModelInfo().focal_idxs) camera.params[idx] = 0;
  }
  const std::string model = dir_ + "/model";
  fs::create_directories(model);
  WriteModel(scene, model, ModelFormat::kBinary);
  ExpectRefused("", {}, "has no calibration", model);
}

}  // namespace
}  // namespace bayon
