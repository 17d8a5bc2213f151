// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/points_scene.h"

#include "ext/synth/workspace_writer.h"

#include <gtest/gtest.h>

#include "tests/testing.h"

namespace bayon {
namespace {

TEST(PointsScene, TracksAreExactProjections) {
  PointsSceneOptions options;
  options.num_points = 300;
  const SyntheticTruth truth = SynthesizePointsScene(options);
  EXPECT_EQ(truth.scene.images.size(), 16u);
  EXPECT_GT(truth.scene.points3D.size(), 250u);
  const SceneStats stats = truth.scene.Stats();
  EXPECT_LT(stats.mean_reprojection_error_px, 1e-9);
  EXPECT_GT(stats.mean_track_length, 3.0);
  const SceneStats noisy = truth.noisy_scene.Stats();
  EXPECT_NEAR(
      noisy.mean_reprojection_error_px, 0.3 * std::sqrt(M_PI / 2), 0.05);
}

TEST(PointsScene, SameSeedSameScene) {
  PointsSceneOptions options;
  options.num_points = 50;
  const SyntheticTruth a = SynthesizePointsScene(options);
  const SyntheticTruth b = SynthesizePointsScene(options);
  ASSERT_EQ(a.noisy_scene.points3D.size(), b.noisy_scene.points3D.size());
  EXPECT_EQ(a.noisy_scene.images.at(3).points2D.at(0).xy,
            b.noisy_scene.images.at(3).points2D.at(0).xy);
}

}  // namespace
}  // namespace bayon
