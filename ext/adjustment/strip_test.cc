// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/strip.h"

#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/table_tie_points.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/random.h"
#include "ext/eval/sparse_eval.h"
#include "ext/synth/workspace_writer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <random>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

struct Workspace {
  std::string path;
  SyntheticTruth truth;
};

// 16 stations on a ring of 10 m around 900 points, with control.
Workspace MakeWorkspace(const std::string& name,
                        int num_control_points = 6,
                        bool levelling_bar = false) {
  Workspace ws;
  ws.path = testing::TempDir(name) + "/ws";
  PointsSceneOptions scene;
  scene.num_points = 900;
  scene.seed = 4;
  ws.truth = SynthesizePointsScene(scene);
  SyntheticControlOptions control;
  control.num_control_points = num_control_points;
  control.num_check_points = 2;
  control.levelling_bar = levelling_bar;
  SyntheticWorkspaceExtras extras;
  extras.control = SynthesizeControl(ws.truth, scene, control);
  WriteSyntheticWorkspace(ws.truth, ws.path, false, extras);
  return ws;
}

// Turns every relative orientation by `angle_deg` about a random axis and
// tilts its base, as a relative orientation from noisy points would be; with
// `drop_pose` the pose columns are removed so that E must be decomposed.
void DisturbRelativeOrientations(const std::string& database_path,
                                 double angle_deg,
                                 bool drop_pose) {
  Database database(database_path, Database::Mode::kReadWrite);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 1);
  auto transaction = database.BeginTransaction();
  for (auto& [pair_id, geometry] : database.ReadAllTwoViewGeometries()) {
    const auto [id1, id2] = ImageIdsFromPairId(pair_id);
    const Eigen::Vector3d axis = RandomVector<3>(noise, rng).normalized();
    const Eigen::Quaterniond turn(
        Eigen::AngleAxisd(angle_deg * M_PI / 180.0, axis));
    const Eigen::Vector4d& q = *geometry.qvec;
    const Eigen::Quaterniond rotation =
        turn * Eigen::Quaterniond(q(0), q(1), q(2), q(3));
    const Eigen::Vector3d t = (*geometry.tvec + 0.5 * angle_deg * M_PI / 180.0 *
                                                    RandomVector<3>(noise, rng))
                                  .normalized();
    Eigen::Matrix3d skew;
    skew << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
    geometry.E = skew * rotation.toRotationMatrix();
    if (drop_pose) {
      geometry.qvec.reset();
      geometry.tvec.reset();
    } else {
      geometry.qvec = Eigen::Vector4d(
          rotation.w(), rotation.x(), rotation.y(), rotation.z());
      geometry.tvec = t;
    }
    database.WriteTwoViewGeometry(id1, id2, geometry);
  }
  transaction.Commit();
}

TEST(Strip, ClosedRingWithControlIsCloseToTheTruth) {
  const Workspace ws = MakeWorkspace("strip_ring");
  DisturbRelativeOrientations(ws.path + "/database.db", 0.3, false);
  StripOptions options;
  options.num_threads = 1;
  const StripResult result =
      RunStrip(ws.path + "/database.db", ws.path + "/control", options);
  EXPECT_EQ(result.model.images.size(), 16u);
  EXPECT_TRUE(result.unoriented_images.empty());
  EXPECT_TRUE(result.closed_ring);
  // The disturbed orientations leave a closure error, which is reported.
  EXPECT_GT(result.closure_rotation_deg, 0.05);
  EXPECT_GT(result.model.points3D.size(), 800u);
  ASSERT_TRUE(result.has_control);
  EXPECT_EQ(result.datum.type, DatumType::kControl);
  EXPECT_EQ(result.datum.similarity_residuals.size(), 6u);
  // After the strip adjustment and the similarity, in the truth's system.
  SparseEvaluationOptions evaluation_options;
  evaluation_options.align = false;
  const SparseEvaluation evaluation =
      EvaluateSparse(result.model, ws.truth.scene, evaluation_options);
  EXPECT_EQ(evaluation.num_registered, 16);
  EXPECT_LT(evaluation.center_rms_relative, 0.005);
  EXPECT_LT(evaluation.rotation_rms_deg, 0.1);
  EXPECT_LT(result.sigma0_px, 0.5);
  // 2D points are the database keypoints, tracks point at them.
  Database database(ws.path + "/database.db", Database::Mode::kReadOnly);
  for (const auto& [id, image] : result.model.images) {
    EXPECT_EQ(static_cast<Eigen::Index>(image.points2D.size()),
              database.ReadKeypoints(id).rows());
  }
  result.model.CheckConsistency("strip");
}

// Turns the stored relative rotation of the pair (id1, id2) by `angle_rad`
// about the y axis, as a false relative orientation would be.
void TurnStoredRotation(Database* database,
                        image_t id1,
                        image_t id2,
                        double angle_rad) {
  TwoViewGeometry geometry = database->ReadTwoViewGeometry(id1, id2);
  ASSERT_TRUE(geometry.qvec.has_value());
  const Eigen::Vector4d& q = *geometry.qvec;
  const Eigen::Quaterniond turned = Eigen::Quaterniond(Eigen::AngleAxisd(
                                        angle_rad, Eigen::Vector3d::UnitY())) *
                                    Eigen::Quaterniond(q(0), q(1), q(2), q(3));
  geometry.qvec =
      Eigen::Vector4d(turned.w(), turned.x(), turned.y(), turned.z());
  database->WriteTwoViewGeometry(id1, id2, geometry);
}

// Every image of the truth oriented, the rotations within `max_rms_deg`
// (RMS) in the control's system.
void ExpectEveryImageWithin(const StripResult& result,
                            const Scene& truth,
                            double max_rms_deg) {
  SparseEvaluationOptions evaluation_options;
  evaluation_options.align = false;
  const SparseEvaluation evaluation =
      EvaluateSparse(result.model, truth, evaluation_options);
  EXPECT_EQ(evaluation.num_registered, static_cast<int>(truth.images.size()));
  EXPECT_LT(evaluation.rotation_rms_deg, max_rms_deg);
}

// A false relative orientation (chance matches between photographs that do
// not overlap would give one) is left out for its loops, and the strip is
// as good as without it.
TEST(Strip, APairThatDisagreesWithItsLoopsIsDropped) {
  const Workspace ws = MakeWorkspace("strip_loops");
  const std::string db = ws.path + "/database.db";
  DisturbRelativeOrientations(db, 0.3, false);
  std::string name1, name2;
  int num_pairs = 0;
  {
    Database database(db, Database::Mode::kReadWrite);
    std::map<image_t, std::string> names;
    for (const DatabaseImage& image : database.ReadAllImages()) {
      names[image.image_id] = image.name;
    }
    // Images 5 and 6 (neighbours on the ring): turned by 60 deg.
    TurnStoredRotation(&database, 5, 6, M_PI / 3);
    name1 = names.at(5);
    name2 = names.at(6);
    num_pairs = static_cast<int>(database.ReadAllTwoViewGeometries().size());
  }
  StripOptions options;
  options.num_threads = 1;
  const StripResult result = RunStrip(db, ws.path + "/control", options);
  ASSERT_EQ(result.dropped_pairs.size(), 1u) << num_pairs << " pairs";
  EXPECT_EQ(result.dropped_pairs[0].rfind(name1 + " - " + name2 + ": ", 0), 0u)
      << result.dropped_pairs[0];
  ExpectEveryImageWithin(result, ws.truth.scene, 0.1);
}

// A false pair that lies on no triangle, only on longer loops (a
// doppelganger between alike faces of a symmetric object): the ring keeps
// its neighbours and the chords three places on, which form no triangle,
// and one chord is turned by 90 deg. The longer loops leave it out.
TEST(Strip, AFalsePairOnLongerLoopsOnlyIsDropped) {
  const Workspace ws = MakeWorkspace("strip_long_loops");
  const std::string db = ws.path + "/database.db";
  DisturbRelativeOrientations(db, 0.3, false);
  std::string name1, name2;
  {
    Database database(db, Database::Mode::kReadWrite);
    std::map<image_t, std::string> names;
    for (const DatabaseImage& image : database.ReadAllImages()) {
      names[image.image_id] = image.name;
    }
    const int n = static_cast<int>(names.size());
    for (const auto& [pair_id, geometry] :
         database.ReadAllTwoViewGeometries()) {
      const auto [id1, id2] = ImageIdsFromPairId(pair_id);
      const int step = (static_cast<int>(id2) - static_cast<int>(id1) + n) % n;
      if (step != 1 && step != n - 1 && step != 3 && step != n - 3) {
        database.DeleteTwoViewGeometry(id1, id2);
      }
    }
    TurnStoredRotation(&database, 5, 8, M_PI / 2);
    name1 = names.at(5);
    name2 = names.at(8);
  }
  StripOptions options;
  options.num_threads = 1;
  const StripResult result = RunStrip(db, ws.path + "/control", options);
  ASSERT_EQ(result.dropped_pairs.size(), 1u);
  EXPECT_EQ(
      result.dropped_pairs[0].rfind(
          name1 + " - " + name2 + ": its rotation disagrees with a loop", 0),
      0u)
      << result.dropped_pairs[0];
  ExpectEveryImageWithin(result, ws.truth.scene, 0.1);
}

TEST(Strip, OpenStripFromEssentialMatricesInModelCoordinates) {
  const Workspace ws = MakeWorkspace("strip_open");
  DisturbRelativeOrientations(ws.path + "/database.db", 0.0, true);
  StripOptions options;
  options.ring = RingClosure::kOpen;
  options.num_threads = 1;
  const StripResult result = RunStrip(ws.path + "/database.db", "", options);
  EXPECT_EQ(result.model.images.size(), 16u);
  EXPECT_FALSE(result.closed_ring);
  EXPECT_FALSE(result.has_control);
  // Model coordinates: right up to a similarity.
  const SparseEvaluation evaluation =
      EvaluateSparse(result.model, ws.truth.scene);
  EXPECT_LT(evaluation.center_rms_relative, 0.005);
  EXPECT_LT(evaluation.rotation_rms_deg, 0.1);
}

// Names that do not follow the ring (temple-ring's were photographed out
// of order): the models are connected along the view graph.
TEST(Strip, ImagesOutOfOrderFollowTheViewGraph) {
  Workspace ws = MakeWorkspace("strip_graph");
  std::vector<image_t> ids;
  for (const auto& [id, image] : ws.truth.scene.images) ids.push_back(id);
  std::mt19937 rng(9);
  std::vector<image_t> shuffled = ids;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  std::map<std::string, std::string> renamed;
  for (size_t i = 0; i < ids.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "shot_%02zu.png", i);
    renamed[ws.truth.scene.images.at(shuffled[i]).name] = name;
  }
  {
    Database database(ws.path + "/database.db", Database::Mode::kReadWrite);
    auto transaction = database.BeginTransaction();
    for (DatabaseImage row : database.ReadAllImages()) {
      row.name = renamed.at(row.name) + ".tmp";
      database.UpdateImage(row);
    }
    for (DatabaseImage row : database.ReadAllImages()) {
      row.name = row.name.substr(0, row.name.size() - 4);
      database.UpdateImage(row);
    }
    transaction.Commit();
  }
  for (auto& [id, image] : ws.truth.scene.images) {
    image.name = renamed.at(image.name);
  }
  StripOptions options;
  options.num_threads = 1;
  const StripResult result = RunStrip(ws.path + "/database.db", "", options);
  EXPECT_EQ(result.order, "graph");
  EXPECT_EQ(result.model.images.size(), 16u);
  const SparseEvaluation evaluation =
      EvaluateSparse(result.model, ws.truth.scene);
  EXPECT_LT(evaluation.center_rms_relative, 0.005);
  EXPECT_LT(evaluation.rotation_rms_deg, 0.1);
}

// bayon tiepoints' multi-image points carry the strip across an image that
// has no relative orientation: it is placed by spatial resection, and its
// tie observations follow the keypoints in the model.
TEST(Strip, ImageWithoutRelativeOrientationIsResectedFromTiePoints) {
  const Workspace ws = MakeWorkspace("strip_resection");
  const std::string db = ws.path + "/database.db";
  image_t lost = kInvalidImageId;
  size_t num_tie_observations = 0;
  {
    Database database(db, Database::Mode::kReadWrite);
    std::vector<DatabaseImage> rows = database.ReadAllImages();
    std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
      return a.name < b.name;
    });
    lost = rows[6].image_id;
    auto transaction = database.BeginTransaction();
    for (const auto& [pair_id, geometry] :
         database.ReadAllTwoViewGeometries()) {
      const auto [id1, id2] = ImageIdsFromPairId(pair_id);
      if (id1 == lost || id2 == lost) database.DeleteTwoViewGeometry(id1, id2);
    }
    // The synthetic observations (0.3 px noise) of every point seen in three
    // or more images, as least-squares tie points with that precision.
    std::vector<TiePointRecord> points;
    for (const auto& [id, point] : ws.truth.noisy_scene.points3D) {
      if (point.track.size() < 3) continue;
      TiePointRecord record;
      record.source = "alsm";
      for (const TrackElement& element : point.track) {
        TieObservation observation;
        observation.image_id = element.image_id;
        observation.xy = ws.truth.noisy_scene.images.at(element.image_id)
                             .points2D.at(element.point2D_idx)
                             .xy;
        observation.covariance = 0.09 * Eigen::Matrix2d::Identity();
        record.observations.push_back(observation);
      }
      std::sort(
          record.observations.begin(),
          record.observations.end(),
          [](const auto& a, const auto& b) { return a.image_id < b.image_id; });
      num_tie_observations += record.observations.size();
      points.push_back(std::move(record));
    }
    WriteTiePoints(&database, points);
    transaction.Commit();
  }
  StripOptions options;
  options.num_threads = 1;
  options.ring = RingClosure::kOpen;
  const StripResult result = RunStrip(db, "", options);
  EXPECT_EQ(result.model.images.size(), 16u);
  ASSERT_EQ(result.resected_images.size(), 1u);
  EXPECT_GT(result.resected_images[0].num_inliers, 50);
  EXPECT_LT(result.resected_images[0].rms_px, 1.0);
  EXPECT_GT(result.num_alsm_tie_points, 100);
  const SparseEvaluation evaluation =
      EvaluateSparse(result.model, ws.truth.scene);
  EXPECT_EQ(evaluation.num_registered, 16);
  EXPECT_LT(evaluation.center_rms_relative, 0.005);
  EXPECT_LT(evaluation.rotation_rms_deg, 0.1);
  // Keypoints first, then the tie observations.
  Database database(db, Database::Mode::kReadOnly);
  size_t num_extra = 0;
  for (const auto& [id, image] : result.model.images) {
    const Eigen::Index keypoints = database.ReadKeypoints(id).rows();
    ASSERT_GE(static_cast<Eigen::Index>(image.points2D.size()), keypoints);
    num_extra += image.points2D.size() - keypoints;
  }
  EXPECT_EQ(num_extra, num_tie_observations);
  result.model.CheckConsistency("strip");

  // Without the tie points the image stays out.
  options.tie_points = TiePointSource::kModel;
  const StripResult without = RunStrip(db, "", options);
  EXPECT_EQ(without.model.images.size(), 15u);
}

TEST(Strip, MinimumDatumFromTheLevellingBar) {
  const Workspace ws = MakeWorkspace("strip_bar", 2, true);
  StripOptions options;
  options.num_threads = 1;
  // The bar's ends are control points too: auto would take the four.
  options.datum.datum = DatumType::kMinimum;
  const StripResult result =
      RunStrip(ws.path + "/database.db", ws.path + "/control", options);
  ASSERT_TRUE(result.has_control);
  EXPECT_EQ(result.datum.type, DatumType::kMinimum);
  SparseEvaluationOptions evaluation_options;
  evaluation_options.align = false;
  const SparseEvaluation evaluation =
      EvaluateSparse(result.model, ws.truth.scene, evaluation_options);
  EXPECT_LT(evaluation.center_rms_relative, 0.01);
}

TEST(Strip, BadInput) {
  const Workspace ws = MakeWorkspace("strip_bad", 2);
  StripOptions options;
  options.num_threads = 1;
  // Two control points cannot define the similarity.
  try {
    RunStrip(ws.path + "/database.db", ws.path + "/control", options);
    FAIL() << "expected an InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("three control points"),
              std::string::npos)
        << error.what();
  }
  // A camera without a focal length: none in the database and no
  // bayon_calibration.
  const std::string db = testing::TempDir("strip_bad_camera") + "/db.db";
  fs::copy_file(ws.path + "/database.db", db);
  {
    Database database(db, Database::Mode::kReadWrite);
    database.connection()->Execute("DROP TABLE bayon_calibration");
    Camera camera = database.ReadCamera(1);
    camera.has_prior_focal_length = false;
    for (int idx : camera.ModelInfo().focal_idxs) camera.params[idx] = 0;
    database.UpdateCamera(camera);
  }
  try {
    RunStrip(db, "", options);
    FAIL() << "expected an InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("has no calibration"),
              std::string::npos)
        << error.what();
  }
}

// COLMAP's guess of the focal length (no EXIF, no bayon_calibration, not
// estimated by relative): the strip is formed with it, for adjust to
// estimate the focal length (adjustment.h, step 1b).
TEST(Strip, FormsTheStripWithTheGuessedFocalLength) {
  const Workspace ws = MakeWorkspace("strip_guess", 2);
  const std::string db = testing::TempDir("strip_guess_camera") + "/db.db";
  fs::copy_file(ws.path + "/database.db", db);
  Camera guess;
  {
    Database database(db, Database::Mode::kReadWrite);
    database.connection()->Execute("DROP TABLE bayon_calibration");
    guess = database.ReadCamera(1);
    guess.has_prior_focal_length = false;
    for (int idx : guess.ModelInfo().focal_idxs) {
      guess.params[idx] = 1.2 * std::max(guess.width, guess.height);
    }
    database.UpdateCamera(guess);
  }
  StripOptions options;
  options.num_threads = 1;
  const StripResult result = RunStrip(db, "", options);
  EXPECT_EQ(result.model.images.size(), ws.truth.scene.images.size());
  ASSERT_EQ(result.model.cameras.size(), 1u);
  EXPECT_DOUBLE_EQ(result.model.cameras.begin()->second.MeanFocalLengthPx(),
                   guess.MeanFocalLengthPx());
}

}  // namespace
}  // namespace bayon
