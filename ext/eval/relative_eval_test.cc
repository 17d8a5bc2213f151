// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/relative_eval.h"

#include "ext/colmap/table_relative.h"
#include "ext/core/errors.h"
#include "ext/synth/points_scene.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "tests/testing.h"

namespace bayon {
namespace {

constexpr double kDeg = M_PI / 180.0;

// The true cam2_from_cam1 of two images of the scene.
Rigid3d TruePair(const Scene& truth, image_t id1, image_t id2) {
  return truth.images.at(id2).cam_from_world *
         truth.images.at(id1).cam_from_world.Inverse();
}

// A database with the first four images of the points scene: pair 1-2
// oriented exactly, pair 2-3 with the rotation 0.5 degrees off and the base
// turned by 1 degree, pair 3-4 failed, pair 1-4 never oriented.
class RelativeEvalTest : public ::testing::Test {
 protected:
  void SetUp() override {
    PointsSceneOptions options;
    options.num_points = 10;
    truth_ = SynthesizePointsScene(options).scene;
    // A folder per test: ctest runs the tests of this fixture side by side.
    const std::string name =
        ::testing::UnitTest::GetInstance()->current_test_info()->name();
    database_ = std::make_unique<Database>(
        testing::TempDir("relative_eval_" + name) + "/database.db",
        Database::Mode::kCreate);
    const camera_t camera_id = database_->WriteCamera(
        Camera::Create(CameraModelId::kPinhole, 500, 640, 480));
    for (image_t id = 1; id <= 4; ++id) {
      database_->WriteImage(DatabaseImage{
          kInvalidImageId, truth_.images.at(id).name, camera_id, {}, {}});
    }
    RelativeOrientationRecord exact;
    exact.success = true;
    exact.num_matches = exact.num_inliers = 100;
    exact.std_omega_phi_kappa_deg = Eigen::Vector3d(0.1, 0, 0);
    exact.std_base_deg = Eigen::Vector2d(0.5, 0);
    exact.cam2_from_cam1 = TruePair(truth_, 1, 2);
    WriteRelativeOrientation(database_.get(), 1, 2, exact);

    RelativeOrientationRecord off = exact;
    const Rigid3d pair = TruePair(truth_, 2, 3);
    const Eigen::Vector3d base = pair.Center();
    const Eigen::Vector3d axis = base.unitOrthogonal();
    const Eigen::Vector3d turned_base =
        Eigen::AngleAxisd(1 * kDeg, axis) * base;
    off.cam2_from_cam1.rotation =
        pair.rotation * Eigen::AngleAxisd(0.5 * kDeg, Eigen::Vector3d::UnitZ());
    off.cam2_from_cam1.translation =
        -(off.cam2_from_cam1.rotation * turned_base);
    WriteRelativeOrientation(database_.get(), 2, 3, off);

    RelativeOrientationRecord failed;
    failed.reason = "too few matches";
    WriteRelativeOrientation(database_.get(), 3, 4, failed);
  }

  Scene truth_;
  std::unique_ptr<Database> database_;
};

TEST_F(RelativeEvalTest, ErrorsOfRotationAndBaseDirection) {
  const RelativeEvaluation evaluation =
      EvaluateRelativeOrientations(database_.get(), truth_);
  ASSERT_EQ(evaluation.num_pairs, 3);
  EXPECT_EQ(evaluation.num_oriented, 2);
  const PairEvaluation& exact = evaluation.pairs[0];
  EXPECT_EQ(exact.name1, truth_.images.at(1).name);
  EXPECT_TRUE(exact.oriented);
  EXPECT_NEAR(exact.rotation_error_deg, 0, 1e-6);
  EXPECT_NEAR(exact.base_error_deg, 0, 1e-6);
  const PairEvaluation& off = evaluation.pairs[1];
  EXPECT_NEAR(off.rotation_error_deg, 0.5, 1e-6);
  EXPECT_NEAR(off.base_error_deg, 1.0, 1e-6);
  EXPECT_FALSE(evaluation.pairs[2].oriented);
  EXPECT_EQ(evaluation.pairs[2].reason, "too few matches");
  EXPECT_NEAR(evaluation.max_rotation_error_deg, 0.5, 1e-6);
  EXPECT_NEAR(evaluation.max_rotation_ratio, 5.0, 1e-5);
  EXPECT_NEAR(evaluation.max_base_ratio, 2.0, 1e-5);
  // Median(): the upper of the middle two.
  EXPECT_NEAR(evaluation.median_rotation_error_deg, 0.5, 1e-6);
  const std::string table = RelativeEvaluationTable("test", evaluation);
  EXPECT_NE(table.find("2 of 3 pairs oriented"), std::string::npos) << table;
  EXPECT_NE(table.find("not oriented (too few matches)"), std::string::npos);
}

TEST_F(RelativeEvalTest, AdjacentPairsCloseTheRing) {
  RelativeEvaluationOptions options;
  options.adjacent_only = true;
  const RelativeEvaluation evaluation =
      EvaluateRelativeOrientations(database_.get(), truth_, options);
  ASSERT_EQ(evaluation.num_pairs, 4);  // 1-2, 2-3, 3-4, 4-1
  EXPECT_EQ(evaluation.num_oriented, 2);
  EXPECT_EQ(evaluation.pairs[3].name1, truth_.images.at(1).name);
  EXPECT_EQ(evaluation.pairs[3].name2, truth_.images.at(4).name);
  EXPECT_EQ(evaluation.pairs[3].reason, "no orientation");
}

TEST_F(RelativeEvalTest, RefusesImagesThatTheTruthLacks) {
  Scene truth = truth_;
  truth.images.Erase(3);
  EXPECT_THROW(EvaluateRelativeOrientations(database_.get(), truth),
               InputError);
}

}  // namespace
}  // namespace bayon
