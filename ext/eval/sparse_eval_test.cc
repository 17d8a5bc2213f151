// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/sparse_eval.h"

#include "ext/core/errors.h"
#include "ext/synth/points_scene.h"

#include <gtest/gtest.h>

namespace bayon {
namespace {

TEST(SparseEval, SimilarityTransformedTruthHasZeroError) {
  PointsSceneOptions options;
  options.num_points = 100;
  const Scene truth = SynthesizePointsScene(options).scene;
  const Sim3d model_from_truth(
      0.3,
      Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitX())),
      Eigen::Vector3d(1, 2, 3));
  Scene model = truth;
  for (auto& [image_id, image] : model.images) {
    image.cam_from_world = model_from_truth.TransformPose(image.cam_from_world);
  }
  model.images.Erase(4);
  const SparseEvaluation evaluation = EvaluateSparse(model, truth);
  EXPECT_EQ(evaluation.num_registered, 15);
  EXPECT_FALSE(evaluation.images[3].registered);
  EXPECT_LT(evaluation.center_max, 1e-9);
  EXPECT_LT(evaluation.rotation_max_deg, 1e-7);
  EXPECT_NEAR(evaluation.mean_camera_distance, 10.0, 1e-9);
  EXPECT_NEAR(evaluation.truth_from_model.scale, 1 / 0.3, 1e-9);
}

TEST(SparseEval, RefusesModelsWithoutCommonImages) {
  PointsSceneOptions options;
  options.num_points = 10;
  const Scene truth = SynthesizePointsScene(options).scene;
  EXPECT_THROW(EvaluateSparse(Scene(), truth), InputError);
}

}  // namespace
}  // namespace bayon
