// SPDX-License-Identifier: BSD-3-Clause
//
// What issue 4 asks the automated relative orientation to show, end to end:
// bayon features, match and relative on the rendered tower judged against
// its true poses (with the true interior orientation, and with distortion
// assumed zero as the paper starts); stock `colmap mapper` on a database
// filled only by bayon (temple ring), evaluated against the truth beside
// stock COLMAP's own SIFT pipeline; and bad pairs in one run. Issue 4's
// figures that are not reached (the tower's pairs within 0.02 deg, the stock
// mapper on bayon's tower database) are `scripts/bench.sh tower_pairs`.
#include "ext/colmap/colmap_cli.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/table_matches.h"
#include "ext/colmap/table_relative.h"
#include "ext/core/file_util.h"
#include "ext/eval/relative_eval.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <filesystem>
#include <map>

#include "tests/temple_fixture.h"
#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

constexpr double kDeg = M_PI / 180.0;

void RunOk(const std::vector<std::string>& args) {
  const testing::CommandResult result = testing::RunBayon(args);
  ASSERT_EQ(result.exit_code, 0) << result.output;
}

// The tower of `bayon synth` (16 stations, seed 1) at 1200 x 800 with the
// true calibration in its database, Moravec points on 8-pixel patches,
// ring matches (two neighbours) and both relative orientations: with the
// true interior orientation (database.db) and with distortion assumed zero
// (zero_distortion.db); and the matches refined and propagated by
// least-squares matching, oriented with the true interior orientation
// (lsm.db).
std::string TowerFixture() {
  return testing::SharedFixture(
      "relative_pipeline_tower", [](const std::string& dir) {
        const std::string ws = dir + "/ws";
        RunOk({"synth",
               "--scene",
               "tower",
               "--output_path",
               ws,
               "--image_width",
               "1200",
               "--supersampling",
               "2",
               "--num_heldout_views",
               "0",
               "--num_threads",
               "2"});
        const std::string db = ws + "/database.db";
        RunOk({"features",
               "--database_path",
               db,
               "--image_path",
               ws + "/images",
               "--patch_size",
               "8",
               "--max_num_features",
               "0",
               "--num_threads",
               "2"});
        const std::string lsm_db = ws + "/lsm.db";
        testing::CopyTree(db, lsm_db);
        for (const std::string& path : {db, lsm_db}) {
          RunOk({"match",
                 "--database_path",
                 path,
                 "--image_path",
                 ws + "/images",
                 "--pairing",
                 "ring",
                 "--lsm_refinement",
                 path == lsm_db ? "1" : "0",
                 "--num_threads",
                 "2"});
        }
        RunOk({"relative", "--database_path", lsm_db, "--num_threads", "2"});
        testing::CopyTree(db, ws + "/zero_distortion.db");
        RunOk({"relative", "--database_path", db, "--num_threads", "2"});
        RunOk({"relative",
               "--database_path",
               ws + "/zero_distortion.db",
               "--assume_zero_distortion",
               "1",
               "--num_threads",
               "2"});
      });
}

// Every adjacent station pair of the ring (image i with i + 1, the last
// with the first) in `db_path` against the true poses, printed (the same
// table as `bayon evaluate --database_path --adjacent_pairs 1`).
RelativeEvaluation JudgeAdjacentPairs(const std::string& db_path,
                                      const Scene& truth,
                                      const std::string& label) {
  Database database(db_path, Database::Mode::kReadOnly);
  RelativeEvaluationOptions options;
  options.adjacent_only = true;
  const RelativeEvaluation evaluation =
      EvaluateRelativeOrientations(&database, truth, options);
  std::printf("%s", RelativeEvaluationTable(label, evaluation).c_str());
  return evaluation;
}

// Least-squares conjugate points (match --lsm_refinement 1): the peaks'
// bias is gone, so the pairs agree with the truth to about their standard
// deviations, and the median error is a quarter of the correlation peaks'
// (measured 2026-12-02: 0.045 against 0.216 deg; largest 0.50 against 2.35
// deg). The 0.02 deg is below the precision of most of these pairs
// (reported standard deviations 0.02 - 0.3 deg: the tower fills the middle
// third of 1200 x 800 frames): `scripts/bench.sh tower_pairs` prints that
// figure.
TEST(RelativePipeline, LeastSquaresConjugatePointsOrientTheTowerPairs) {
  const std::string ws = TowerFixture() + "/ws";
  const Scene truth = ReadModel(ws + "/gt/sparse");
  const RelativeEvaluation lsm = JudgeAdjacentPairs(
      ws + "/lsm.db", truth, "tower, least-squares conjugate points");
  const RelativeEvaluation peaks = JudgeAdjacentPairs(
      ws + "/database.db", truth, "tower, correlation peaks");
  EXPECT_GE(lsm.num_oriented, 13);
  EXPECT_LT(lsm.median_rotation_error_deg, 0.1);
  EXPECT_LT(lsm.median_rotation_error_deg,
            0.5 * peaks.median_rotation_error_deg);
  EXPECT_LT(lsm.max_rotation_error_deg, 0.5 * peaks.max_rotation_error_deg);
  EXPECT_LT(lsm.max_rotation_ratio, 4.0);
  EXPECT_LT(lsm.max_base_ratio, 4.0);
}

// The paper's start: distortion assumed zero. Reported, not bounded (the
// tower's lens has every Brown/Beyer parameter set), beside the figures
// with the true interior orientation.
TEST(RelativePipeline, TowerWithDistortionAssumedZero) {
  const std::string ws = TowerFixture() + "/ws";
  const Scene truth = ReadModel(ws + "/gt/sparse");
  const RelativeEvaluation pairs = JudgeAdjacentPairs(
      ws + "/zero_distortion.db", truth, "tower, distortion assumed zero");
  EXPECT_GT(pairs.num_oriented, 0);
  Database database(ws + "/zero_distortion.db", Database::Mode::kReadOnly);
  for (const auto& [pair_id, record] : ReadAllRelativeOrientations(&database)) {
    EXPECT_TRUE(record.assume_zero_distortion);
  }
}

// Stock `colmap mapper` on a copy of `db_path` (COLMAP rewrites the pragmas
// of databases it opens); returns the folder of the largest model, or empty.
std::string RunStockMapper(const std::string& db_path,
                           const std::string& image_path,
                           const std::string& dir,
                           const std::vector<std::string>& extra) {
  fs::create_directories(dir + "/sparse");
  CopyDatabaseForColmap(db_path, dir + "/colmap.db");
  std::vector<std::string> args = {"mapper",
                                   "--database_path",
                                   dir + "/colmap.db",
                                   "--image_path",
                                   image_path,
                                   "--output_path",
                                   dir + "/sparse",
                                   "--Mapper.num_threads",
                                   "2"};
  args.insert(args.end(), extra.begin(), extra.end());
  const testing::CommandResult mapper = testing::RunColmap(args);
  WriteFileAtomically(dir + "/mapper.log", mapper.output);
  std::string largest;
  size_t most = 0;
  for (const auto& entry : fs::directory_iterator(dir + "/sparse")) {
    if (!fs::exists(entry.path() / "images.bin")) continue;
    const size_t count = ReadModel(entry.path().string()).images.size();
    if (count > most) {
      most = count;
      largest = entry.path().string();
    }
  }
  return largest;
}

// Registered images of the largest model (0 without one), and `bayon
// evaluate`'s table of it against the truth.
int RegisteredAndEvaluated(const std::string& model,
                           const std::string& truth,
                           const std::string& label) {
  if (model.empty()) {
    std::printf("%-28s no model\n", label.c_str());
    return 0;
  }
  const testing::CommandResult evaluate =
      testing::RunBayon({"evaluate",
                         "--input_path",
                         model,
                         "--ground_truth_path",
                         truth,
                         "--label",
                         label});
  EXPECT_EQ(evaluate.exit_code, 0) << evaluate.output;
  std::printf("%s", evaluate.output.c_str());
  return static_cast<int>(ReadModel(model).images.size());
}

// Mapper options for bayon's databases: the camera is the calibrated one
// (the true calibration), so it is not refined from the first pair alone.
const std::vector<std::string> kCalibratedMapper = {
    "--Mapper.ba_refine_focal_length",
    "0",
    "--Mapper.ba_refine_principal_point",
    "0",
    "--Mapper.ba_refine_extra_params",
    "0"};

// The mapper accepts an image's pose from 12 correspondences (default 30).
const std::vector<std::string> kWeakPoseMapper = {
    "--Mapper.abs_pose_min_num_inliers", "12"};

// The temple ring: bayon's chain with the calibrated camera against stock
// COLMAP's own chain (SIFT, exhaustive matching, mapper; CPU), both
// evaluated against the calibration (bayon import_ground_truth).
// bayon's conjugate points are refined by least-squares matching with the
// correlation peaks kept beside them (weighted by their precision), which
// orients the link across the ring's widest gap (stations 14 and 2, 43
// degrees, one turned upside down); the mapper then needs to accept a
// pose from 12 correspondences (its default 30: 13 of 16, the three
// stations beyond that gap as a second model below its 10-image minimum).
// Stock SIFT gets the same mapper option (with the default: 13 of 16).
// Measured 2026-12-02: bayon 16/16, centre RMS 1.27 % of the distance,
// rotation RMS 0.95 deg; SIFT 16/16, 3.51 %, 1.02 deg.
TEST(RelativePipeline, StockMapperRegistersTheTempleFromBayonsDatabase) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string images = testing::DataPath("temple-ring");
  const std::string dir = testing::TempDir("relative_pipeline_temple");
  RunOk({"import_ground_truth",
         "--format",
         "middlebury",
         "--input_path",
         images + "/templeSR_par.txt",
         "--output_path",
         dir + "/gt"});
  const Scene truth = ReadModel(dir + "/gt");
  ASSERT_EQ(truth.cameras.size(), 1u);

  // bayon: the calibrated camera, Moravec points on 6-pixel patches (the
  // object covers a small part of the frame), every pair.
  const std::string db = dir + "/database.db";
  RunOk({"import",
         "--image_path",
         images,
         "--database_path",
         db,
         "--single_camera",
         "1",
         "--camera_model",
         "PINHOLE",
         "--camera_params",
         testing::CommaSeparated(truth.cameras.begin()->second.params)});
  RunOk({"features",
         "--database_path",
         db,
         "--image_path",
         images,
         "--patch_size",
         "6",
         "--max_num_features",
         "0"});
  RunOk({"match",
         "--database_path",
         db,
         "--image_path",
         images,
         "--pairing",
         "exhaustive",
         "--lsm_refinement",
         "1",
         "--lsm_keep_unrefined",
         "1",
         "--num_threads",
         "2"});
  RunOk({"relative", "--database_path", db, "--num_threads", "2"});
  std::vector<std::string> mapper_options = kCalibratedMapper;
  mapper_options.insert(
      mapper_options.end(), kWeakPoseMapper.begin(), kWeakPoseMapper.end());
  const std::string bayon_model =
      RunStockMapper(db, images, dir + "/bayon", mapper_options);

  // Stock COLMAP from the images: the tests' one run of its SIFT features
  // and exhaustive matches of the ring (temple_fixture.h).
  const std::string sift_db = testing::TempleColmapFixture().database;
  const std::string sift_model =
      RunStockMapper(sift_db, images, dir + "/sift", kWeakPoseMapper);

  const int bayon_registered = RegisteredAndEvaluated(
      bayon_model, dir + "/gt", "temple: bayon + mapper");
  const int sift_registered =
      RegisteredAndEvaluated(sift_model, dir + "/gt", "temple: colmap SIFT");
  std::printf(
      "temple: stock colmap mapper registered %d of 16 images from bayon's "
      "features, match and relative; %d of 16 from its own SIFT\n",
      bayon_registered,
      sift_registered);
  EXPECT_EQ(bayon_registered, 16) << "see " << dir << "/bayon/mapper.log";
  EXPECT_GE(bayon_registered, sift_registered);
}

// --- Bad input to the chain -------------------------------------------------

// Five images for `relative`'s bad pairs, from two temple stations 23
// degrees apart (a, b): an exact copy of b, b turned on the spot (a pure
// rotation of 4 degrees, warped through the calibrated camera) and an
// almost empty image; with the true camera.
std::string BadPairsWorkspace(const std::string& dir) {
  const std::string temple = testing::DataPath("temple-ring");
  const std::string images = dir + "/images";
  fs::create_directories(images);
  fs::copy_file(temple + "/templeSR0001.png", images + "/a.png");
  fs::copy_file(temple + "/templeSR0002.png", images + "/b.png");
  fs::copy_file(temple + "/templeSR0002.png", images + "/copy.png");
  const cv::Mat b = cv::imread(temple + "/templeSR0002.png");
  // H = K R K^-1 in OpenCV's pixel convention (templeSR_par.txt's).
  cv::Matx33d K(1520.4, 0, 302.32, 0, 1525.9, 246.87, 0, 0, 1);
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(4 * kDeg, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(2 * kDeg, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  cv::Matx33d Rcv;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) Rcv(r, c) = R(r, c);
  }
  cv::Mat turned;
  cv::warpPerspective(b, turned, cv::Mat(K * Rcv * K.inv()), b.size());
  cv::imwrite(images + "/turned.png", turned);
  // Flat grey but for a 16 x 16 piece of texture: a few points at most.
  cv::Mat blank(b.size(), b.type(), cv::Scalar(90, 90, 90));
  b(cv::Rect(300, 230, 16, 16)).copyTo(blank(cv::Rect(300, 230, 16, 16)));
  cv::imwrite(images + "/blank.png", blank);

  const std::string db = dir + "/database.db";
  RunOk({"import",
         "--image_path",
         images,
         "--database_path",
         db,
         "--single_camera",
         "1",
         "--camera_model",
         "PINHOLE",
         "--camera_params",
         "1520.4,1525.9,302.82,247.37"});
  return dir;
}

image_t IdOf(Database* database, const std::string& name) {
  const auto image = database->ReadImageWithName(name);
  if (!image) {
    ADD_FAILURE() << name << " not in the database";
    return kInvalidImageId;
  }
  return image->image_id;
}

TEST(RelativePipeline, BadPairsAreReportedAndTheOthersOriented) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir =
      BadPairsWorkspace(testing::TempDir("relative_pipeline_bad_pairs"));
  const std::string db = dir + "/database.db";
  RunOk({"features", "--database_path", db, "--image_path", dir + "/images"});
  const testing::CommandResult match = testing::RunBayon({"match",
                                                          "--database_path",
                                                          db,
                                                          "--image_path",
                                                          dir + "/images",
                                                          "--pairing",
                                                          "exhaustive"});
  ASSERT_EQ(match.exit_code, 0) << match.output;
  // The almost empty image: its pairs are reported, not written.
  EXPECT_NE(match.output.find("blank.png: "), std::string::npos);
  EXPECT_NE(match.output.find("-- not written: too few points to match"),
            std::string::npos)
      << match.output;
  {
    Database database(db, Database::Mode::kReadWrite);
    const image_t blank = IdOf(&database, "blank.png");
    for (const DatabaseImage& image : database.ReadAllImages()) {
      if (image.image_id != blank) {
        EXPECT_FALSE(database.ExistsMatches(image.image_id, blank));
      }
    }
    // A pair with too few conjugate points for the orientation (as another
    // matcher might leave it): 10 of a's and copy's matches.
    const image_t a = IdOf(&database, "a.png");
    const image_t copy = IdOf(&database, "copy.png");
    const FeatureMatches matches = database.ReadMatches(a, copy);
    ASSERT_GT(matches.rows(), 10);
    DeletePairResults(&database, a, copy);
    database.WriteMatches(a, copy, matches.topRows(10));
  }
  const testing::CommandResult relative = testing::RunBayon(
      {"relative", "--database_path", db, "--num_threads", "2"});
  ASSERT_EQ(relative.exit_code, 0) << relative.output;

  Database database(db, Database::Mode::kReadOnly);
  const image_t a = IdOf(&database, "a.png"), b = IdOf(&database, "b.png");
  const image_t copy = IdOf(&database, "copy.png");
  const image_t turned = IdOf(&database, "turned.png");
  const auto expect_refused =
      [&](image_t id1, image_t id2, const std::string& reason) {
        const auto record = ReadRelativeOrientation(&database, id1, id2);
        ASSERT_TRUE(record) << id1 << " " << id2;
        EXPECT_FALSE(record->success) << id1 << " " << id2;
        EXPECT_NE(record->reason.find(reason), std::string::npos)
            << id1 << " " << id2 << ": " << record->reason;
        // Reported in the run's output, and nothing half-done.
        EXPECT_NE(relative.output.find(record->reason), std::string::npos);
        EXPECT_FALSE(database.ExistsTwoViewGeometry(id1, id2));
      };
  expect_refused(b, copy, "identical images");
  expect_refused(b, turned, "no base");
  expect_refused(copy, turned, "no base");
  expect_refused(a, copy, "too few conjugate points");
  // The good pairs are still done: a with b, and with b turned.
  for (const image_t other : {b, turned}) {
    const auto record = ReadRelativeOrientation(&database, a, other);
    ASSERT_TRUE(record);
    EXPECT_TRUE(record->success) << record->reason;
    EXPECT_TRUE(database.ExistsTwoViewGeometry(a, other));
  }
}

// Refused before any work: a database without images (match, relative) and
// an image missing on disk (match); nothing changed.
TEST(RelativePipeline, ChainRefusesEmptyDatabasesAndMissingImages) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir = testing::TempDir("relative_pipeline_refused");
  { Database empty(dir + "/empty.db", Database::Mode::kCreate); }
  const auto empty_before = testing::HashTree(dir + "/empty.db");
  fs::create_directories(dir + "/none");
  for (const std::vector<std::string>& args :
       std::vector<std::vector<std::string>>{
           {"match",
            "--database_path",
            dir + "/empty.db",
            "--image_path",
            dir + "/none"},
           {"relative", "--database_path", dir + "/empty.db"}}) {
    const testing::CommandResult result = testing::RunBayon(args);
    EXPECT_EQ(result.exit_code, 2) << result.output;
    EXPECT_NE(result.LastLine().find("empty.db: the database has no images"),
              std::string::npos)
        << result.output;
  }
  EXPECT_EQ(testing::HashTree(dir + "/empty.db"), empty_before);

  const std::string ws = BadPairsWorkspace(dir + "/ws");
  const std::string db = ws + "/database.db";
  RunOk({"features", "--database_path", db, "--image_path", ws + "/images"});
  fs::rename(ws + "/images/turned.png", ws + "/turned.png");
  const auto before = testing::HashTree(db);
  const testing::CommandResult match = testing::RunBayon(
      {"match", "--database_path", db, "--image_path", ws + "/images"});
  EXPECT_EQ(match.exit_code, 2) << match.output;
  EXPECT_NE(match.LastLine().find("turned.png: listed in"), std::string::npos)
      << match.output;
  EXPECT_EQ(testing::HashTree(db), before);
}

}  // namespace
}  // namespace bayon
