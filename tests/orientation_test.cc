// SPDX-License-Identifier: BSD-3-Clause
//
// The automated relative orientation chain end to end (issue 4): bayon
// features, match, relative and disparity on the real temple ring, judged
// against its calibrated cameras, and stock `colmap mapper` on the result;
// bayon's whole chain to the bundle on the temple and on fountain-P11
// (issue 6).
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/table_matches.h"
#include "ext/colmap/table_relative.h"
#include "ext/core/errors.h"
#include "ext/eval/ground_truth_import.h"
#include "ext/eval/sparse_eval.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// The temple ring's calibration (templeSR_par.txt) as the importer reads
// it, in COLMAP pixels: x = K [R | t] X.
struct TrueCamera {
  Eigen::Matrix3d K, R;
  Eigen::Vector3d t;
};

std::map<std::string, TrueCamera> ReadTempleCameras() {
  GroundTruthImportOptions options;
  options.format = GroundTruthFormat::kMiddlebury;
  std::map<std::string, TrueCamera> cameras;
  for (const GroundTruthView& view : ReadMiddleburyCameras(
           testing::DataPath("temple-ring/templeSR_par.txt"), options)) {
    TrueCamera camera;
    camera.K = view.K;
    camera.R = view.cam_from_world.rotation.toRotationMatrix();
    camera.t = view.cam_from_world.translation;
    cameras[view.name] = camera;
  }
  EXPECT_EQ(cameras.size(), 16u);
  return cameras;
}

// Distance of the COLMAP pixel x2 from the true epipolar line of x1.
double TrueEpipolarDistance(const TrueCamera& a,
                            const TrueCamera& b,
                            const Eigen::Vector2d& x1,
                            const Eigen::Vector2d& x2) {
  const Eigen::Matrix3d R = b.R * a.R.transpose();
  const Eigen::Vector3d t = b.t - R * a.t;
  Eigen::Matrix3d tx;
  tx << 0, -t(2), t(1), t(2), 0, -t(0), -t(1), t(0), 0;
  const Eigen::Matrix3d F = b.K.inverse().transpose() * tx * R * a.K.inverse();
  const Eigen::Vector3d line = F * x1.homogeneous();
  return std::abs(x2.homogeneous().dot(line)) / line.head<2>().norm();
}

// Angle between the two stations as seen from the object, degrees.
double StationAngleDeg(const TrueCamera& a, const TrueCamera& b) {
  const Eigen::Vector3d object(-0.02, 0.1, 0.025);  // bounding box centre
  const Eigen::Vector3d ca = -a.R.transpose() * a.t - object;
  const Eigen::Vector3d cb = -b.R.transpose() * b.t - object;
  return std::acos(
             std::clamp(ca.normalized().dot(cb.normalized()), -1.0, 1.0)) *
         180.0 / M_PI;
}

void Run(const std::vector<std::string>& args) {
  const testing::CommandResult result = testing::RunBayon(args);
  ASSERT_EQ(result.exit_code, 0) << result.output;
}

// A database of `images` with one PINHOLE camera of the calibrated
// `params` (fx fy cx cy, the focal length marked as known), bayon's Moravec
// points and correlation matches (`pairing` arguments of bayon match), or
// what `features` arguments ask for.
void MatchWithCalibratedCamera(const std::string& images,
                               const std::string& db,
                               const std::vector<double>& params,
                               const std::vector<std::string>& pairing,
                               const std::vector<std::string>& features = {}) {
  Run({"import",
       "--image_path",
       images,
       "--database_path",
       db,
       "--single_camera",
       "1",
       "--camera_model",
       "PINHOLE",
       "--camera_params",
       testing::CommaSeparated(params)});
  std::vector<std::string> extract = {
      "features", "--database_path", db, "--image_path", images};
  extract.insert(extract.end(), features.begin(), features.end());
  Run(extract);
  std::vector<std::string> match = {
      "match", "--database_path", db, "--image_path", images};
  match.insert(match.end(), pairing.begin(), pairing.end());
  match.insert(match.end(), {"--num_threads", "2"});
  Run(match);
}

// The temple ring in a database with its calibrated camera (PINHOLE, with
// the focal length marked as known), bayon's Moravec points and
// correlation matches of every pair.
std::string TempleMatchedFixture() {
  return testing::SharedFixture(
      "temple_bayon_matches", [](const std::string& dir) {
        const std::string images = testing::DataPath("temple-ring");
        const TrueCamera truth = ReadTempleCameras().begin()->second;
        MatchWithCalibratedCamera(
            images,
            dir + "/database.db",
            {truth.K(0, 0), truth.K(1, 1), truth.K(0, 2), truth.K(1, 2)},
            {"--pairing", "exhaustive"});
      });
}

TEST(Orientation, TempleMatchesFollowTheTrueEpipolarGeometry) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir = TempleMatchedFixture();
  const auto truth = ReadTempleCameras();
  Database database(dir + "/database.db", Database::Mode::kReadOnly);
  std::map<image_t, std::string> names;
  for (const DatabaseImage& image : database.ReadAllImages()) {
    names[image.image_id] = image.name;
    EXPECT_GT(database.ReadKeypoints(image.image_id).rows(), 200) << image.name;
  }
  // Stations 12-16 look at the temple upside down (latitude +82 instead of
  // -82 degrees, README.txt): their pairs with the others turn by 180.
  const auto upside_down = [](const std::string& name) {
    return name >= "templeSR0012.png";
  };
  int num_neighbour_pairs = 0, num_close_pairs = 0, num_good_pairs = 0;
  for (image_t id1 = 1; id1 <= 16; ++id1) {
    for (image_t id2 = id1 + 1; id2 <= 16; ++id2) {
      const TrueCamera& a = truth.at(names[id1]);
      const TrueCamera& b = truth.at(names[id2]);
      const double angle = StationAngleDeg(a, b);
      // Ring neighbours (up to 45 degrees apart), without the two stations
      // at the same place (templeSR0001 and templeSR0011).
      if (angle > 45 || angle < 1) continue;
      ++num_neighbour_pairs;
      if (!database.ExistsMatches(id1, id2)) {
        ADD_FAILURE() << "no matches for neighbours " << names[id1] << " "
                      << names[id2];
        continue;
      }
      const FeatureMatches matches = database.ReadMatches(id1, id2);
      const auto record = ReadMatchRecord(&database, id1, id2);
      ASSERT_TRUE(record.has_value());
      ASSERT_EQ(record->xy1.size(), static_cast<size_t>(matches.rows()));
      EXPECT_EQ(record->rotation_deg,
                upside_down(names[id1]) != upside_down(names[id2]) ? 180 : 0)
          << names[id1] << " " << names[id2];
      int on_line = 0;
      for (int k = 0; k < matches.rows(); ++k) {
        on_line += TrueEpipolarDistance(a,
                                        b,
                                        record->xy1[k].cast<double>(),
                                        record->xy2[k].cast<double>()) < 2.0;
      }
      const bool good = on_line >= 20 && on_line >= 0.6 * matches.rows();
      if (angle < 32) {
        ++num_close_pairs;
        num_good_pairs += good;
      }
      std::printf(
          "%s-%s %5.1f deg: %4d of %4d matches on the true epipolar "
          "line%s\n",
          names[id1].c_str(),
          names[id2].c_str(),
          angle,
          on_line,
          static_cast<int>(matches.rows()),
          good ? "" : "  (weak)");
    }
  }
  EXPECT_EQ(num_neighbour_pairs, 22);
  // Pairs up to 32 degrees apart: at least 20 matches, 60 % of them on the
  // true epipolar line (measured 2026-11-25: 15 of 16; wider pairs give few
  // points, as the paper's did, because of the different image scales).
  EXPECT_EQ(num_close_pairs, 16);
  EXPECT_GE(num_good_pairs, 14);
}

// The temple fixture oriented by `bayon relative` (a copy per test run).
std::string TempleOrientedCopy(const std::string& name) {
  const std::string dir = testing::TempDir(name);
  testing::CopyTree(TempleMatchedFixture() + "/database.db",
                    dir + "/database.db");
  const testing::CommandResult result = testing::RunBayon({"relative",
                                                           "--database_path",
                                                           dir + "/database.db",
                                                           "--num_threads",
                                                           "2"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return dir;
}

TEST(Orientation, TempleRelativeOrientationsAgreeWithTheCalibration) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir = TempleOrientedCopy("orientation_temple_relative");
  const auto truth = ReadTempleCameras();
  Database database(dir + "/database.db", Database::Mode::kReadOnly);
  std::map<image_t, std::string> names;
  for (const DatabaseImage& image : database.ReadAllImages()) {
    names[image.image_id] = image.name;
  }
  int num_oriented = 0, num_geometries = 0, num_within_3_sigma = 0;
  for (const auto& [pair_id, record] : ReadAllRelativeOrientations(&database)) {
    const auto [id1, id2] = ImageIdsFromPairId(pair_id);
    const TrueCamera& a = truth.at(names[id1]);
    const TrueCamera& b = truth.at(names[id2]);
    // templeSR0001 and templeSR0011 were taken from the same station.
    if (names[id1] == "templeSR0001.png" && names[id2] == "templeSR0011.png") {
      EXPECT_FALSE(record.success);
      EXPECT_NE(record.reason.find("identical images"), std::string::npos)
          << record.reason;
    }
    EXPECT_EQ(database.ExistsTwoViewGeometry(id1, id2), record.success);
    if (!record.success) continue;
    ++num_oriented;
    // Ring neighbours are up to 45 degrees apart (about 50 from the
    // bounding box centre); since the correlation also tries windows shifted
    // by a pixel, pairs a little wider get enough points too (templeSR0001 -
    // templeSR0010, 54 degrees, 0.25 deg rotation error). A false geometry
    // from chance matches, whatever the angle, fails the error bounds below.
    EXPECT_LT(StationAngleDeg(a, b), 60.0) << names[id1] << " " << names[id2];
    const Eigen::Matrix3d R = b.R * a.R.transpose();
    const Eigen::Vector3d t = b.t - R * a.t;
    const double rotation_error =
        Eigen::AngleAxisd(
            record.cam2_from_cam1.rotation.toRotationMatrix().transpose() * R)
            .angle() *
        180 / M_PI;
    const Eigen::Vector3d center = (-R.transpose() * t).normalized();
    const double base_error =
        std::acos(std::min(
            1.0, center.dot(record.cam2_from_cam1.Center().normalized()))) *
        180 / M_PI;
    std::printf(
        "%s-%s: %3d inliers, %3d blunders, sigma0 %.3f px, rotation "
        "error %.3f deg (std %.3f), base error %.3f deg (std %.3f)\n",
        names[id1].c_str(),
        names[id2].c_str(),
        record.num_inliers,
        record.num_blunders,
        record.sigma0_px,
        rotation_error,
        record.std_omega_phi_kappa_deg.norm(),
        base_error,
        record.std_base_deg.norm());
    // The temple's 24-degree field of view makes rotation and base
    // direction hard to separate (standard deviations of 0.2 - 1.7 deg).
    // The errors must be of the size the reported standard deviations
    // admit; correlation of 7 x 7 windows across 20 - 45 degree views adds
    // systematic errors that they do not describe, hence the margin.
    const double std_rotation = record.std_omega_phi_kappa_deg.norm();
    EXPECT_LT(rotation_error, 8 * std_rotation + 0.5);
    EXPECT_LT(base_error, 8 * record.std_base_deg.norm() + 0.5);
    num_within_3_sigma += rotation_error < 3 * std_rotation + 0.2;
    EXPECT_LT(record.sigma0_px, 1.0);
    EXPECT_EQ(record.num_inliers + record.num_blunders, record.num_matches);
    const TwoViewGeometry geometry = database.ReadTwoViewGeometry(id1, id2);
    EXPECT_EQ(geometry.config, TwoViewConfig::kCalibrated);
    EXPECT_EQ(geometry.inlier_matches.rows(), record.num_inliers);
    ASSERT_TRUE(geometry.qvec && geometry.tvec && geometry.E && geometry.F);
    EXPECT_NEAR(geometry.tvec->norm(), 1.0, 1e-9);
    ++num_geometries;
  }
  // Measured 2026-11-25: 16 pairs, all ring neighbours, 12 within 3 sigma.
  EXPECT_GE(num_oriented, 14);
  EXPECT_GE(num_within_3_sigma, 0.7 * num_oriented);
  EXPECT_EQ(database.NumVerifiedPairs(), num_geometries);
}

// disparity, tiepoints, strip and adjust (free network) on an oriented
// database: the adjusted model in dir/adjusted.
void BundleThroughBayonsChain(const std::string& db,
                              const std::string& images,
                              const std::string& dir,
                              const std::string& self_calibration) {
  Run({"disparity", "--database_path", db, "--num_threads", "2"});
  Run({"tiepoints",
       "--database_path",
       db,
       "--image_path",
       images,
       "--num_threads",
       "2"});
  Run({"strip",
       "--database_path",
       db,
       "--output_path",
       dir + "/initial",
       "--num_threads",
       "2"});
  Run({"adjust",
       "--database_path",
       db,
       "--input_path",
       dir + "/initial",
       "--output_path",
       dir + "/adjusted",
       "--datum",
       "free",
       "--self_calibration",
       self_calibration,
       "--num_threads",
       "2"});
}

// Photographs imported with nothing known of the camera (no EXIF, none
// given: import guesses 1.2 x the long side), features, every pair matched
// and oriented (relative estimates the focal length where the pairs fix it).
void OrientPairsWithNothingGiven(const std::string& images,
                                 const std::string& db) {
  Run({"import",
       "--image_path",
       images,
       "--database_path",
       db,
       "--single_camera",
       "1"});
  {
    Database database(db, Database::Mode::kReadOnly);
    ASSERT_FALSE(database.ReadCamera(1).has_prior_focal_length);
  }
  Run({"features", "--database_path", db, "--image_path", images});
  Run({"match",
       "--database_path",
       db,
       "--image_path",
       images,
       "--pairing",
       "exhaustive",
       "--num_threads",
       "2"});
  Run({"relative", "--database_path", db, "--num_threads", "2"});
}

// How far the adjusted model's z is from the truth's vertical `truth_up`
// (in the truth's frame), in degrees: per image, the angle between the two
// as that camera sees them (the frames' similarity cancels), the mean.
double UpErrorDeg(const Scene& adjusted,
                  const Scene& truth,
                  const Eigen::Vector3d& truth_up) {
  double sum = 0;
  int count = 0;
  for (const auto& [id, image] : adjusted.images) {
    const Image* same = truth.FindImageByName(image.name);
    if (same == nullptr) continue;
    const Eigen::Vector3d seen_true = same->cam_from_world.rotation * truth_up;
    const Eigen::Vector3d seen_adjusted =
        image.cam_from_world.rotation * Eigen::Vector3d::UnitZ();
    sum += std::acos(std::clamp(seen_true.dot(seen_adjusted), -1.0, 1.0));
    ++count;
  }
  return count == 0 ? 180 : sum / count * 180 / M_PI;
}

// The Middlebury truth of temple-ring as a COLMAP model in dir/truth.
Scene ImportTempleTruth(const std::string& dir) {
  Run({"import_ground_truth",
       "--format",
       "middlebury",
       "--input_path",
       testing::DataPath("temple-ring/templeSR_par.txt"),
       "--output_path",
       dir + "/truth"});
  return ReadModel(dir + "/truth");
}

// bayon's own chain on the temple ring, free network: relative orientation,
// disparity surfaces, least-squares tie points, strip (with resection),
// bundle adjustment; the adjusted stations against the calibrated cameras
// after a similarity. `self_calibration` as bayon adjust takes it.
SparseEvaluation TempleThroughBayonsChain(const std::string& name,
                                          const std::string& self_calibration) {
  const std::string dir = TempleOrientedCopy(name);
  const std::string db = dir + "/database.db";
  BundleThroughBayonsChain(
      db, testing::DataPath("temple-ring"), dir, self_calibration);
  const Scene adjusted = ReadModel(dir + "/adjusted");
  const Scene truth = ImportTempleTruth(dir);
  const SparseEvaluation evaluation = EvaluateSparse(adjusted, truth);
  // Upright free network (issue 30): the Middlebury frame's vertical is +y,
  // the axis of the gantry's ring (every photograph is portrait, half of
  // them turned each way: the stations above the temple give the sign).
  const double up_error_deg =
      UpErrorDeg(adjusted, truth, Eigen::Vector3d::UnitY());
  std::printf(
      "temple, bayon's chain, free network, self-calibration %s: %d/16 "
      "images, rotation RMS %.3f deg, centre RMS %.3f %% of the distance, "
      "z %.2f deg from the vertical\n",
      self_calibration.c_str(),
      evaluation.num_registered,
      evaluation.rotation_rms_deg,
      100 * evaluation.center_rms_relative,
      up_error_deg);
  EXPECT_LT(up_error_deg, 5.0);
  return evaluation;
}

// Measured 2026-12-02: 0.135 deg, 0.21 % (stock colmap mapper: 13 images,
// 0.8 deg). The bounds hold what is reached; issue 6's 0.1 deg and 0.2 %
// with self-calibration, not reached, are printed by `scripts/bench.sh chain
// significant`.
TEST(Orientation, TempleBundleThroughBayonsChain) {
  BAYON_REQUIRE_DATA("temple-ring");
  const SparseEvaluation evaluation =
      TempleThroughBayonsChain("orientation_temple_bundle", "none");
  EXPECT_EQ(evaluation.num_registered, 16);
  EXPECT_LT(evaluation.rotation_rms_deg, 0.2);
  EXPECT_LT(evaluation.center_rms_relative, 0.003);
}

// Issue 31 part 3: pairs chosen by what the photographs show, not by
// their names. temple-ring's names do not follow the ring (stations 12-16
// look from above); `ring` pairing orients 12 of its pairs. Retrieval with
// 4 neighbours per photograph (forced here; `auto` matches every pair of
// a set this small) finds pairs that close the ring. Measured 2026-12-05
// (12 s): 16/16 images, rotation RMS 0.164 deg; every pair matched: 0.134.
TEST(Orientation, TempleRingFromPairsChosenByRetrieval) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string images = testing::DataPath("temple-ring");
  const std::string dir = testing::TempDir("orientation_temple_retrieval");
  const std::string db = dir + "/database.db";
  const TrueCamera truth = ReadTempleCameras().begin()->second;
  MatchWithCalibratedCamera(
      images,
      db,
      {truth.K(0, 0), truth.K(1, 1), truth.K(0, 2), truth.K(1, 2)},
      {"--pairing", "retrieval", "--retrieval_neighbors", "4"});
  {
    Database database(db, Database::Mode::kReadOnly);
    const int num_pairs = database.NumMatchedPairs();
    EXPECT_GE(num_pairs, 16 * 4 / 2);
    EXPECT_LE(num_pairs, 16 * 4);
  }
  bayon::Run({"relative", "--database_path", db, "--num_threads", "2"});
  BundleThroughBayonsChain(db, images, dir, "none");
  const SparseEvaluation evaluation =
      EvaluateSparse(ReadModel(dir + "/adjusted"), ImportTempleTruth(dir));
  std::printf(
      "temple-ring, retrieval pairs: %d/16 images, rotation RMS "
      "%.3f deg\n",
      evaluation.num_registered,
      evaluation.rotation_rms_deg);
  EXPECT_EQ(evaluation.num_registered, 16);
  EXPECT_LT(evaluation.rotation_rms_deg, 0.2);
}

// The Strecha truth of `set` (e.g. "fountain-P11") as a COLMAP model in
// dir/truth.
Scene ImportStrechaTruth(const std::string& set, const std::string& dir) {
  Run({"import_ground_truth",
       "--format",
       "strecha",
       "--input_path",
       testing::DataPath(set + "/gt_dense_cameras"),
       "--output_path",
       dir + "/truth",
       "--image_path",
       testing::DataPath(set + "/images")});
  return ReadModel(dir + "/truth");
}

// Issue 6's real facade: fountain-P11 (11 photographs of 3072 x 2048,
// undistorted by their authors) through bayon's chain with the calibrated
// camera, free network, judged against the Strecha cameras in mm.
// Measured 2026-12-02 (50 s on 2 cores): 11/11, centre RMS 2.82 mm
// (0.060 % of the distance), rotation RMS 0.055 deg; with
// --self_calibration significant 2.90 mm, 0.069 deg. Stock COLMAP (CPU
// SIFT at 2000 px, exhaustive matching, mapper; scripts/bench.sh
// colmap_baseline): 11/11, 6.24 mm (0.134 %), 0.485 deg, most of it its
// fixed principal point. scripts/bench.sh chain prints both side by side.
SparseEvaluation FountainThroughBayonsChain() {
  const std::string images = testing::DataPath("fountain-P11/images");
  const std::string dir = testing::TempDir("orientation_fountain_chain");
  const std::string db = dir + "/database.db";
  const Scene truth = ImportStrechaTruth("fountain-P11", dir);
  MatchWithCalibratedCamera(
      images,
      db,
      truth.cameras.begin()->second.params,
      {"--pairing", "sequential", "--num_neighbors", "3"});
  Run({"relative", "--database_path", db, "--num_threads", "2"});
  BundleThroughBayonsChain(db, images, dir, "none");
  const Scene adjusted = ReadModel(dir + "/adjusted");
  // Upright free network (issue 30): the Strecha frame's vertical is -z
  // (the photographs' x axes lie within 1.2 degrees of its xy plane).
  const double up_error_deg =
      UpErrorDeg(adjusted, truth, -Eigen::Vector3d::UnitZ());
  std::printf("fountain-P11: z %.2f deg from the vertical\n", up_error_deg);
  EXPECT_LT(up_error_deg, 5.0);
  return EvaluateSparse(adjusted, truth);
}

TEST(Orientation, FountainBundleThroughBayonsChain) {
  BAYON_REQUIRE_DATA("fountain-P11");
  const SparseEvaluation evaluation = FountainThroughBayonsChain();
  std::printf(
      "fountain-P11, bayon's chain, free network: %d/11 images, centre RMS "
      "%.2f mm (%.3f %% of the distance), rotation RMS %.3f deg\n",
      evaluation.num_registered,
      1000 * evaluation.center_rms,
      100 * evaluation.center_rms_relative,
      evaluation.rotation_rms_deg);
  EXPECT_EQ(evaluation.num_registered, 11);
  // Well inside stock COLMAP's 0.134 % and 0.485 deg.
  EXPECT_LT(evaluation.center_rms_relative, 0.001);
  EXPECT_LT(evaluation.rotation_rms_deg, 0.15);
}

// Issue 31 part 1: nothing given. herz-jesu-P8 (8 photographs of 3072 x
// 2048, no calibration, no EXIF focal length: import guesses 1.2 x the long
// side) through bayon's chain with exhaustive pairs; `relative` estimates
// the focal length from the photographs, the self-calibrating bundle
// refines it with the principal point. Measured 2026-12-05 (about 70 s on
// 2 cores): focal length 2765.2 px after relative and 2757.7 px after
// adjust (truth 2761.8 px: -0.15 %), 8/8, centre RMS 4.27 mm, rotation RMS
// 0.207 deg. The calibrated run (the truth's PINHOLE camera, no
// self-calibration): 3.88 mm, 0.122 deg. The issue asks for at most 1.2
// times those: the centres are (1.10), the rotations are not (1.70). The
// bundle keeps P1 (t = 14.6), which moves the principal point 11 px from
// the truth and the rotations with it; with P1 and P2 held, 0.105 deg. The
// rotation bound below guards what is reached; `scripts/bench.sh
// uncalibrated` prints the comparison.
// Issue 31 part 2: SIFT keypoints matched by descriptor, then the paper's
// chain as for Moravec points. herz-jesu-P8 with the calibrated camera,
// exhaustive pairs, no self-calibration. Measured 2026-12-05 (about 60 s
// on 2 cores): 8/8, centre RMS 3.64 mm, rotation RMS 0.105 deg. Moravec
// points through the same chain: 3.88 mm, 0.122 deg; stock COLMAP with the
// same camera held: 3.75 mm, 0.136 deg (scripts/bench.sh detectors and
// uncalibrated). The bounds hold SIFT below Moravec's figures.
TEST(Orientation, HerzJesuThroughSift) {
  BAYON_REQUIRE_DATA("herz-jesu-P8");
  const std::string images = testing::DataPath("herz-jesu-P8/images");
  const std::string dir = testing::TempDir("orientation_herz_jesu_sift");
  const std::string db = dir + "/database.db";
  const Scene truth = ImportStrechaTruth("herz-jesu-P8", dir);
  MatchWithCalibratedCamera(images,
                            db,
                            truth.cameras.begin()->second.params,
                            {"--pairing", "exhaustive"},
                            {"--detector", "sift"});
  {
    Database database(db, Database::Mode::kReadOnly);
    EXPECT_EQ(database.NumDescriptors(), database.NumKeypoints());
  }
  bayon::Run({"relative", "--database_path", db, "--num_threads", "2"});
  BundleThroughBayonsChain(db, images, dir, "none");
  const SparseEvaluation evaluation =
      EvaluateSparse(ReadModel(dir + "/adjusted"), truth);
  std::printf(
      "herz-jesu-P8, SIFT, calibrated: %d/8 images, centre RMS %.2f mm, "
      "rotation RMS %.3f deg\n",
      evaluation.num_registered,
      1000 * evaluation.center_rms,
      evaluation.rotation_rms_deg);
  EXPECT_EQ(evaluation.num_registered, 8);
  EXPECT_LT(1000 * evaluation.center_rms, 3.80);
  EXPECT_LT(evaluation.rotation_rms_deg, 0.115);
}

TEST(Orientation, HerzJesuWithNothingGiven) {
  BAYON_REQUIRE_DATA("herz-jesu-P8");
  const std::string images = testing::DataPath("herz-jesu-P8/images");
  const std::string dir =
      testing::TempDir("orientation_herz_jesu_uncalibrated");
  const std::string db = dir + "/database.db";
  const Scene truth = ImportStrechaTruth("herz-jesu-P8", dir);
  const double true_focal_px =
      truth.cameras.begin()->second.MeanFocalLengthPx();
  OrientPairsWithNothingGiven(images, db);
  double estimated_px = 0;
  {
    Database database(db, Database::Mode::kReadOnly);
    const Camera camera = database.ReadCamera(1);
    EXPECT_TRUE(camera.has_prior_focal_length);
    estimated_px = camera.MeanFocalLengthPx();
  }
  BundleThroughBayonsChain(db, images, dir, "significant");
  const Scene adjusted = ReadModel(dir + "/adjusted");
  const double adjusted_px =
      adjusted.cameras.begin()->second.MeanFocalLengthPx();
  const SparseEvaluation evaluation = EvaluateSparse(adjusted, truth);
  std::printf(
      "herz-jesu-P8, nothing given: focal length %.1f px after relative, "
      "%.1f px after adjust (truth %.1f); %d/8 images, centre RMS %.2f mm, "
      "rotation RMS %.3f deg\n",
      estimated_px,
      adjusted_px,
      true_focal_px,
      evaluation.num_registered,
      1000 * evaluation.center_rms,
      evaluation.rotation_rms_deg);
  EXPECT_NEAR(estimated_px / true_focal_px, 1, 0.02);
  EXPECT_NEAR(adjusted_px / true_focal_px, 1, 0.005);
  EXPECT_EQ(evaluation.num_registered, 8);
  EXPECT_LT(1000 * evaluation.center_rms, 1.2 * 3.88);
  EXPECT_LT(evaluation.rotation_rms_deg, 0.25);
}

// Issue 31 part 1: nothing given on temple-ring. The ring's pairs do not
// fix the focal length in `relative` (its score rises by under 5 % from 1/1.5
// to 1.5 times the best), so strip forms the model with COLMAP's guess, 768
// px for the truth's 1523, and adjust estimates the focal length first,
// alone, then the other parameters. Measured 2026-12-05 (about 25 s on 2
// cores): 16/16, focal length 1536 px (+0.9 %), rotation RMS 0.224 deg,
// centre RMS 0.32 % of the distance. The calibrated run: 0.134 deg, 0.21 %;
// stock COLMAP, nothing given: 13/16 at 0.8-1.0 deg. The 0.5 % and
// 1.2 times the calibrated run are not reached: the bounds below hold what
// is. Holding the guess is refused before any work.
TEST(Orientation, TempleWithNothingGiven) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string images = testing::DataPath("temple-ring");
  const std::string dir = testing::TempDir("orientation_temple_uncalibrated");
  const std::string db = dir + "/database.db";
  const Scene truth = ImportTempleTruth(dir);
  const double true_focal_px =
      truth.cameras.begin()->second.MeanFocalLengthPx();
  OrientPairsWithNothingGiven(images, db);
  {
    Database database(db, Database::Mode::kReadOnly);
    ASSERT_FALSE(database.ReadCamera(1).has_prior_focal_length)
        << "relative now fixes the temple's focal length: this test no "
           "longer tests a guess";
  }
  BundleThroughBayonsChain(db, images, dir, "significant");
  const Scene adjusted = ReadModel(dir + "/adjusted");
  const double adjusted_px =
      adjusted.cameras.begin()->second.MeanFocalLengthPx();
  const SparseEvaluation evaluation = EvaluateSparse(adjusted, truth);
  std::printf(
      "temple-ring, nothing given: focal length %.1f px after adjust (guess "
      "768, truth %.1f); %d/16 images, centre RMS %.3f %%, rotation RMS "
      "%.3f deg\n",
      adjusted_px,
      true_focal_px,
      evaluation.num_registered,
      100 * evaluation.center_rms_relative,
      evaluation.rotation_rms_deg);
  EXPECT_NEAR(adjusted_px / true_focal_px, 1, 0.012);
  EXPECT_EQ(evaluation.num_registered, 16);
  EXPECT_LT(evaluation.center_rms_relative, 0.004);
  EXPECT_LT(evaluation.rotation_rms_deg, 0.3);

  // Holding the guess is refused, whichever camera model adjusts it.
  const auto before = testing::HashTree(dir + "/initial");
  for (const std::string camera_model : {"brown_beyer", "colmap"}) {
    const testing::CommandResult held = testing::RunBayon({"adjust",
                                                           "--database_path",
                                                           db,
                                                           "--input_path",
                                                           dir + "/initial",
                                                           "--output_path",
                                                           dir + "/held",
                                                           "--camera_model",
                                                           camera_model,
                                                           "--self_calibration",
                                                           "none"});
    EXPECT_EQ(held.exit_code, 2) << held.output;
    EXPECT_NE(held.LastLine().find("its focal length is unknown"),
              std::string::npos)
        << camera_model << ": " << held.LastLine();
    EXPECT_FALSE(fs::exists(dir + "/held"));
  }
  EXPECT_EQ(testing::HashTree(dir + "/initial"), before);
}

}  // namespace
}  // namespace bayon
