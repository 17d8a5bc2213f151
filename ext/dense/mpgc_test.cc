// SPDX-License-Identifier: BSD-3-Clause
#include "ext/dense/mpgc.h"

#include "ext/core/errors.h"
#include "ext/core/random.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "tests/plane_scene_testing.h"

namespace bayon {
namespace {

using testing::PlaneScene;

TEST(Mpgc, ObjectPointsAgreeWithTheirCovariance) {
  const PlaneScene scene(2.0);
  const std::vector<MpgcView> search = scene.SearchViews();
  std::mt19937 rng(7);
  // About a pixel: what the search along the master ray leaves.
  std::normal_distribution<double> offset(0, 0.002);
  // The orientation is exact here: the collinearity conditions as good as
  // hard, so that the covariance reflects the matching alone.
  MpgcOptions options;
  options.geometric_sigma_px = 0.005;
  int num_points = 0, num_ok = 0, within = 0, coordinates = 0, num_views = 0;
  double sum_sq = 0, sum_normalised_sq = 0;
  std::vector<double> sigma0s;
  for (int y = 60; y <= 180; y += 15) {
    for (int x = 70; x <= 250; x += 15) {
      const Eigen::Vector2d master_xy(x + 0.5, y + 0.5);
      const Eigen::Vector3d truth = *scene.OnPlane(scene.poses[0], master_xy);
      const Eigen::Vector3d start = truth + RandomVector<3>(offset, rng);
      ++num_points;
      const MpgcResult result =
          MatchMpgc(scene.View(0), master_xy, search, start, options);
      if (!result.ok()) {
        std::printf("failed: %s after %d iterations, %zu dropped\n",
                    MpgcStatusName(result.status),
                    result.iterations,
                    result.dropped.size());
        continue;
      }
      ++num_ok;
      num_views += static_cast<int>(result.views.size());
      const Eigen::Vector3d error = result.xyz - truth;
      const Eigen::Vector3d sigma = result.StdDev();
      for (int k = 0; k < 3; ++k) {
        ++coordinates;
        within += std::abs(error(k)) <= 3 * sigma(k);
        sum_normalised_sq += std::pow(error(k) / sigma(k), 2);
      }
      sum_sq += error.squaredNorm();
      sigma0s.push_back(result.sigma0);
    }
  }
  ASSERT_GT(num_ok, 0);
  std::sort(sigma0s.begin(), sigma0s.end());
  const double rms_mm = 1000 * std::sqrt(sum_sq / num_ok);
  std::printf(
      "MPGC on a textured plane, 5 images, noise 2 grey values: %d/%d "
      "converged (%.2f search images each), RMS error %.3f mm, %d/%d "
      "coordinates within 3 sigma, RMS error / sigma %.2f, median sigma0 "
      "%.2f\n",
      num_ok,
      num_points,
      static_cast<double>(num_views) / num_ok,
      rms_mm,
      within,
      coordinates,
      std::sqrt(sum_normalised_sq / coordinates),
      sigma0s[sigma0s.size() / 2]);
  EXPECT_GE(num_ok, 0.95 * num_points);
  EXPECT_LT(rms_mm, 0.5);  // a fifth of a pixel's footprint
  EXPECT_GE(within, 0.95 * coordinates);
  // The covariance describes the errors (measured 0.78: sigma0 also holds
  // the rendering's interpolation error, which the errors do not show).
  const double normalised_rms = std::sqrt(sum_normalised_sq / coordinates);
  EXPECT_GT(normalised_rms, 0.5);
  EXPECT_LT(normalised_rms, 1.3);
  // sigma0 is that of a grey-value difference template - search: noise of
  // 2 in each, 2.83 together, plus about 1.3 of interpolation error of the
  // point-sampled renders (1.27 measured without noise).
  EXPECT_GT(sigma0s[sigma0s.size() / 2], 2.6);
  EXPECT_LT(sigma0s[sigma0s.size() / 2], 4.0);
}

TEST(Mpgc, AnOccludedSearchImageIsDropped) {
  PlaneScene scene(2.0);
  const Eigen::Vector2d master_xy(160.5, 120.5);
  const Eigen::Vector3d truth = *scene.OnPlane(scene.poses[0], master_xy);
  // Something else in front of the point in search image 2 (view 3).
  Eigen::Vector2d xy;
  ASSERT_TRUE(scene.camera.ImgFromCam(scene.poses[3] * truth, &xy));
  WaveTextureOptions other;
  other.seed = 11;
  const cv::Mat occluder = RenderTemplateImage(WaveTexture(other), 40, 40);
  occluder.copyTo(scene.images[3](cv::Rect(
      static_cast<int>(xy.x()) - 20, static_cast<int>(xy.y()) - 20, 40, 40)));
  const MpgcResult result =
      MatchMpgc(scene.View(0),
                master_xy,
                scene.SearchViews(),
                truth + Eigen::Vector3d(0.0015, -0.001, 0.002),
                MpgcOptions());
  ASSERT_TRUE(result.ok()) << MpgcStatusName(result.status);
  EXPECT_EQ(result.dropped, std::vector<int>{2});
  EXPECT_EQ(result.views.size(), 3u);
  const Eigen::Vector3d error = result.xyz - truth;
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(std::abs(error(k)), 3 * result.StdDev()(k)) << k;
  }
}

// Approximations from the master ray alone (half a metre either side of
// the plane, about 60 px of epipolar line in the widest search image),
// then MPGC from them.
TEST(Mpgc, ApproximationsAlongTheMasterRay) {
  const PlaneScene scene(2.0);
  const std::vector<MpgcView> search = scene.SearchViews();
  int num_points = 0, num_close = 0, num_matched = 0;
  for (int y = 60; y <= 180; y += 30) {
    for (int x = 70; x <= 250; x += 30) {
      const Eigen::Vector2d master_xy(x + 0.5, y + 0.5);
      const Eigen::Vector3d truth = *scene.OnPlane(scene.poses[0], master_xy);
      const double distance = (truth - scene.poses[0].Center()).norm();
      const EpipolarSearchResult approximation =
          SearchMasterRay(scene.View(0),
                          master_xy,
                          search,
                          distance - 0.5,
                          distance + 0.5,
                          EpipolarSearchOptions());
      ++num_points;
      if (!approximation.found) continue;
      EXPECT_EQ(approximation.num_views, 4);
      // Within a pixel in every search image.
      bool close = true;
      for (const MpgcView& view : search) {
        Eigen::Vector2d a, b;
        ASSERT_TRUE(scene.camera.ImgFromCam(
            view.cam_from_world * approximation.xyz, &a));
        ASSERT_TRUE(scene.camera.ImgFromCam(view.cam_from_world * truth, &b));
        close &= (a - b).norm() < 1.0;
      }
      num_close += close;
      const MpgcResult result = MatchMpgc(
          scene.View(0), master_xy, search, approximation.xyz, MpgcOptions());
      num_matched += result.ok() && (result.xyz - truth).norm() < 0.001;
    }
  }
  std::printf(
      "master-ray search: %d/%d points within a pixel, %d matched by MPGC "
      "within 1 mm\n",
      num_close,
      num_points,
      num_matched);
  EXPECT_GE(num_close, 0.95 * num_points);
  EXPECT_GE(num_matched, 0.95 * num_points);
}

// Coarse to fine along the ray (every second sample, then around the best
// peaks) over a range ten times as deep as the one above: the same
// approximation as scoring every sample, for about 60 % of the work.
TEST(Mpgc, CoarseToFineSearchFindsTheSamePeaks) {
  const PlaneScene scene(2.0);
  const std::vector<MpgcView> search = scene.SearchViews();
  EpipolarSearchOptions every, coarse;
  coarse.stride = 2;
  int num_points = 0, num_same = 0, num_found = 0;
  long scored_every = 0, scored_coarse = 0;
  for (int y = 60; y <= 180; y += 20) {
    for (int x = 70; x <= 250; x += 20) {
      const Eigen::Vector2d master_xy(x + 0.5, y + 0.5);
      const Eigen::Vector3d truth = *scene.OnPlane(scene.poses[0], master_xy);
      const double distance = (truth - scene.poses[0].Center()).norm();
      const auto run = [&](const EpipolarSearchOptions& options) {
        return SearchMasterRay(scene.View(0),
                               master_xy,
                               search,
                               0.5 * distance,
                               2 * distance,
                               options);
      };
      const EpipolarSearchResult a = run(every), b = run(coarse);
      ++num_points;
      ASSERT_EQ(a.num_samples, b.num_samples);
      EXPECT_EQ(a.num_scored, a.num_samples);
      scored_every += a.num_scored;
      scored_coarse += b.num_scored;
      num_found += a.found;
      num_same += a.found == b.found &&
                  std::abs(a.distance - b.distance) < 1e-9 * a.distance &&
                  a.ncc == b.ncc;
    }
  }
  std::printf(
      "coarse to fine: %d/%d approximations the same as every sample's (%d "
      "found), %ld of %ld samples scored\n",
      num_same,
      num_points,
      num_found,
      scored_coarse,
      scored_every);
  EXPECT_GE(num_found, 0.9 * num_points);
  EXPECT_GE(num_same, 0.95 * num_points);
  EXPECT_LT(scored_coarse, 0.65 * scored_every);
}

TEST(Mpgc, FailuresSayWhy) {
  const PlaneScene scene(2.0);
  PlaneScene flat(0.0);
  flat.images[0].setTo(100);
  const Eigen::Vector2d centre(160.5, 120.5);
  const auto match = [](const PlaneScene& s,
                        const Eigen::Vector2d& xy,
                        const Eigen::Vector3d& approximation,
                        const MpgcOptions& options = MpgcOptions()) {
    return MatchMpgc(s.View(0), xy, s.SearchViews(), approximation, options)
        .status;
  };
  // The template leaves the master image.
  EXPECT_EQ(match(scene, Eigen::Vector2d(2.5, 2.5), Eigen::Vector3d::Zero()),
            MpgcStatus::kOutsideImage);
  // An approximation behind the master.
  EXPECT_EQ(match(scene, centre, Eigen::Vector3d(0, 0, 8)),
            MpgcStatus::kBehindCamera);
  // A flat master patch.
  EXPECT_EQ(match(flat, centre, Eigen::Vector3d::Zero()),
            MpgcStatus::kFlatPatch);
  EpipolarSearchOptions bad_search;
  bad_search.step_px = 0;
  EXPECT_THROW(
      SearchMasterRay(
          scene.View(0), centre, scene.SearchViews(), 3.5, 4.5, bad_search),
      InputError);
  MpgcOptions bad;
  bad.geometric_sigma_px = 0;
  EXPECT_THROW(match(scene, centre, Eigen::Vector3d::Zero(), bad), InputError);
}

}  // namespace
}  // namespace bayon
