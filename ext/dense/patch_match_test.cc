// SPDX-License-Identifier: BSD-3-Clause
#include "ext/dense/patch_match.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "tests/plane_scene_testing.h"

namespace bayon {
namespace {

using testing::PlaneScene;

struct PinholeScene {
  std::vector<PinholeView> views;
  std::vector<const PinholeView*> sources;
  PinholeScene(const PlaneScene& scene, int downscale) {
    for (size_t j = 0; j < scene.poses.size(); ++j) {
      views.push_back(MakePinholeView(scene.camera,
                                      nullptr,
                                      scene.poses[j],
                                      scene.images[j],
                                      cv::Mat(),
                                      downscale));
    }
    for (size_t j = 1; j < views.size(); ++j) sources.push_back(&views[j]);
  }
  // The true depth (z in the master's camera) and normal at a pinhole
  // pixel of the master.
  float TrueDepth(int x, int y) const {
    const PinholeView& master = views[0];
    const Eigen::Vector3d ray =
        master.K.inverse() * Eigen::Vector3d(x + 0.5, y + 0.5, 1);
    const Rigid3d world_from_cam = master.cam_from_world.Inverse();
    const Eigen::Vector3d c = world_from_cam.translation;
    const Eigen::Vector3d d = world_from_cam.rotation * ray;
    return static_cast<float>(-c.z() / d.z());
  }
  Eigen::Vector3f TrueNormal() const {
    Eigen::Vector3f n =
        (views[0].cam_from_world.rotation * Eigen::Vector3d::UnitZ())
            .cast<float>();
    return n.z() > 0 ? -n : n;
  }
};

TEST(PatchMatch, PinholeViewRemovesTheDistortion) {
  // A point of the plane lands where the pinhole camera puts it.
  const PlaneScene scene(0.0);
  const PinholeScene pinhole(scene, 1);
  const PinholeView& view = pinhole.views[1];
  int compared = 0;
  double sum_sq = 0;
  for (int y = 40; y < 200; y += 20) {
    for (int x = 40; x < 280; x += 20) {
      const Eigen::Vector3d ray =
          view.K.inverse() * Eigen::Vector3d(x + 0.5, y + 0.5, 1);
      const Eigen::Vector2d distorted = scene.camera.ImgFromCam(ray);
      const float expected = scene.images[1].at<float>(
          static_cast<int>(distorted.y()), static_cast<int>(distorted.x()));
      (void)expected;
      const auto point = scene.OnPlane(scene.poses[1], distorted);
      ASSERT_TRUE(point.has_value());
      const double truth =
          scene.texture.Value(point->head<2>() / PlaneScene::kTexel);
      sum_sq += std::pow(view.gray.at<float>(y, x) - truth, 2);
      ++compared;
    }
  }
  // Bilinear interpolation of a texture of about a pixel's detail: a few
  // grey values.
  EXPECT_LT(std::sqrt(sum_sq / compared), 8.0);
}

TEST(PatchMatch, TheTruePlaneCostsLeast) {
  const PlaneScene scene(1.0);
  const PinholeScene pinhole(scene, 1);
  const PatchMatchOptions options;
  const int x = 160, y = 120;
  const float depth = pinhole.TrueDepth(x, y);
  const Eigen::Vector3f normal = pinhole.TrueNormal();
  const std::vector<float> at_truth = PlaneCosts(
      pinhole.views[0], pinhole.sources, x, y, depth, normal, options);
  const std::vector<float> off = PlaneCosts(
      pinhole.views[0], pinhole.sources, x, y, depth * 1.01f, normal, options);
  ASSERT_EQ(at_truth.size(), 4u);
  for (size_t j = 0; j < at_truth.size(); ++j) {
    EXPECT_LT(at_truth[j], 0.15) << "view " << j;
    EXPECT_GT(off[j], at_truth[j] + 0.2) << "view " << j;
  }
}

void ExpectPlaneRecovered(int downscale, double max_rms_percent) {
  const PlaneScene scene(2.0);
  const PinholeScene pinhole(scene, downscale);
  PatchMatchOptions options;
  const DepthMap map = EstimateDepthMap(
      pinhole.views[0], pinhole.sources, 3.0, 5.5, {}, options, 2);
  ASSERT_EQ(map.width, pinhole.views[0].width());
  const Eigen::Vector3f true_normal = pinhole.TrueNormal();
  int interior = 0, within = 0, normals_within = 0;
  double sum_sq = 0;
  const int margin = 16 / downscale;
  for (int y = margin; y < map.height - margin; ++y) {
    for (int x = margin; x < map.width - margin; ++x) {
      ++interior;
      const size_t i = map.index(x, y);
      if (map.depth[i] <= 0) continue;
      const double error = map.depth[i] / pinhole.TrueDepth(x, y) - 1;
      if (std::abs(error) > 0.005) continue;
      ++within;
      sum_sq += error * error;
      normals_within += map.normal[i].dot(true_normal) > std::cos(0.2);
    }
  }
  const double rms_percent = 100 * std::sqrt(sum_sq / std::max(within, 1));
  std::printf(
      "downscale %d: %d of %d interior pixels within 0.5 %% (RMS "
      "%.3f %%), %d normals within 11.5 deg\n",
      downscale,
      within,
      interior,
      rms_percent,
      normals_within);
  EXPECT_GT(within, 0.95 * interior);
  EXPECT_LT(rms_percent, max_rms_percent);
  EXPECT_GT(normals_within, 0.9 * within);
}

TEST(PatchMatch, RecoversThePlaneFromRandomStarts) {
  ExpectPlaneRecovered(1, 0.1);
}

TEST(PatchMatch, RecoversThePlaneAtHalfResolution) {
  ExpectPlaneRecovered(2, 0.2);
}

// The share of the master's interior pixels whose depth is within 0.5 %
// of the plane's.
double ShareRecovered(const PinholeScene& pinhole, const DepthMap& map) {
  int interior = 0, within = 0;
  for (int y = 16; y < map.height - 16; ++y) {
    for (int x = 16; x < map.width - 16; ++x) {
      ++interior;
      const float depth = map.depth[map.index(x, y)];
      within +=
          depth > 0 && std::abs(depth / pinhole.TrueDepth(x, y) - 1) <= 0.005;
    }
  }
  return static_cast<double>(within) / interior;
}

TEST(PatchMatch, CoarseToFineCoversThePlaneInFewerSweeps) {
  // One red-black iteration: from random starts alone, propagation carries
  // the few good planes a few pixels; started from the half-size level's
  // planes (one iteration there too), the whole plane is found.
  const PlaneScene scene(2.0);
  const PinholeScene pinhole(scene, 1);
  PatchMatchOptions options;
  options.num_iterations = 1;
  options.num_levels = 1;
  const double single = ShareRecovered(
      pinhole,
      EstimateDepthMap(
          pinhole.views[0], pinhole.sources, 3.0, 5.5, {}, options, 2));
  options.num_levels = 2;
  const double coarse_to_fine = ShareRecovered(
      pinhole,
      EstimateDepthMap(
          pinhole.views[0], pinhole.sources, 3.0, 5.5, {}, options, 2));
  std::printf(
      "one iteration: %.1f %% of the plane in one level, %.1f %% "
      "coarse to fine\n",
      100 * single,
      100 * coarse_to_fine);
  EXPECT_GT(coarse_to_fine, single + 0.05);
  EXPECT_GT(coarse_to_fine, 0.9);
}

TEST(PatchMatch, TheSameResultOnAnyNumberOfThreads) {
  const PlaneScene scene(2.0);
  const PinholeScene pinhole(scene, 2);
  const PatchMatchOptions options;
  const DepthMap one = EstimateDepthMap(
      pinhole.views[0], pinhole.sources, 3.0, 5.5, {}, options, 1);
  const DepthMap two = EstimateDepthMap(
      pinhole.views[0], pinhole.sources, 3.0, 5.5, {}, options, 2);
  EXPECT_EQ(one.depth, two.depth);
  EXPECT_EQ(one.cost, two.cost);
}

TEST(PatchMatch, RefusesBadInput) {
  const PlaneScene scene(2.0);
  const PinholeScene pinhole(scene, 2);
  const PatchMatchOptions options;
  EXPECT_THROW(EstimateDepthMap(pinhole.views[0], {}, 3.0, 5.5, {}, options, 1),
               InputError);
  EXPECT_THROW(EstimateDepthMap(
                   pinhole.views[0], pinhole.sources, 5.5, 3.0, {}, options, 1),
               InputError);
  PatchMatchOptions bad;
  bad.window_step = 9;
  EXPECT_THROW(bad.Check(), InputError);
}

}  // namespace
}  // namespace bayon
