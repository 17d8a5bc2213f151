// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/conjugate_refinement.h"

#include "ext/core/random.h"
#include "ext/synth/texture_patches.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace bayon {
namespace {

// A textured image and its affine copy (sheared and scaled, as a slanted
// surface between two views), keypoints on a grid in image 1 and, in image
// 2, each one's true conjugate moved by up to a pixel (an interest operator
// marks the same feature only to about a pixel).
struct Scene {
  cv::Mat gray1, gray2;
  TexturePairTruth truth;
  std::vector<Eigen::Vector2d> keypoints1, keypoints2;
  std::vector<Eigen::Vector2d> conjugates;  // true, of keypoints1's centres

  Eigen::Vector2d Map(const Eigen::Vector2d& p) const {
    return truth.search_xy + truth.shape * (p - truth.template_xy);
  }
};

Scene MakeScene() {
  Scene scene;
  WaveTextureOptions texture_options;
  texture_options.seed = 4;
  const WaveTexture texture(texture_options);
  constexpr int kWidth = 420, kHeight = 320;
  scene.truth.template_xy = Eigen::Vector2d(210, 160);
  scene.truth.search_xy = Eigen::Vector2d(203.3, 164.6);
  scene.truth.shape << 0.82, 0.12, -0.05, 1.08;
  scene.truth.r0 = 12;
  scene.truth.r1 = 0.9;
  scene.gray1 = RenderTemplateImage(texture, kWidth, kHeight);
  scene.gray2 = RenderSearchImage(texture, scene.truth, kWidth, kHeight);
  AddGaussianNoise(1.0, 7, &scene.gray1);
  AddGaussianNoise(1.0, 8, &scene.gray2);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  for (int y = 40; y < kHeight - 40; y += 14) {
    for (int x = 40; x < kWidth - 40; x += 14) {
      const Eigen::Vector2d keypoint(x + 0.5, y + 0.5);
      scene.keypoints1.push_back(keypoint);
      scene.conjugates.push_back(scene.Map(keypoint));
      scene.keypoints2.push_back(scene.conjugates.back() +
                                 RandomVector<2>(jitter, rng));
    }
  }
  return scene;
}

// Matches keypoint i to keypoint i for `count` keypoints spread over the
// image, at the true conjugate off by up to `error_px` (a correlation
// peak's bias).
PairMatches StartingMatches(const Scene& scene, int count, double error_px) {
  PairMatches matches;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> error(-error_px, error_px);
  matches.matches.resize(count, 2);
  const int step = static_cast<int>(scene.keypoints1.size()) / count;
  for (int k = 0; k < count; ++k) {
    const int i = k * step;
    matches.matches(k, 0) = matches.matches(k, 1) = static_cast<uint32_t>(i);
    matches.reference_xy1.push_back(scene.keypoints1[i]);
    matches.refined_xy2.push_back(scene.conjugates[i] +
                                  RandomVector<2>(error, rng));
    matches.ncc.push_back(0.9f);
    matches.sigma_px.push_back(0.3f);
  }
  return matches;
}

ConjugateRefinementReport Refine(const Scene& scene,
                                 const ConjugateRefinementOptions& options,
                                 PairMatches* matches) {
  return RefineConjugatePoints(scene.gray1,
                               scene.gray2,
                               scene.keypoints1,
                               scene.keypoints2,
                               options,
                               matches);
}

double RmsError(const Scene& scene, const PairMatches& matches) {
  double sum = 0;
  for (size_t k = 0; k < matches.refined_xy2.size(); ++k) {
    sum += (matches.refined_xy2[k] -
            scene.conjugates[matches.matches(static_cast<int>(k), 0)])
               .squaredNorm();
  }
  return std::sqrt(sum / matches.refined_xy2.size());
}

TEST(LocalAffinities, RecoverTheAffinityDespiteBlunders) {
  const Scene scene = MakeScene();
  std::vector<Eigen::Vector2d> xy1, xy2;
  for (size_t i = 0; i < 60; ++i) {
    xy1.push_back(scene.keypoints1[i]);
    xy2.push_back(scene.Map(scene.keypoints1[i]));
  }
  // Two blunders among the nearest neighbours of the query.
  xy2[10] += Eigen::Vector2d(9, -6);
  xy2[12] += Eigen::Vector2d(-7, 8);
  const std::vector<Eigen::Vector2d> queries = {xy1[11],
                                                Eigen::Vector2d(2000, 2000)};
  const auto local = LocalAffinities(
      xy1, xy2, queries, Eigen::Matrix2d::Identity(), 100.0, 12);
  ASSERT_TRUE(local[0].has_value());
  EXPECT_LT((local[0]->leftCols<2>() - scene.truth.shape).norm(), 1e-9);
  const Eigen::Vector2d predicted =
      local[0]->leftCols<2>() * queries[0] + local[0]->col(2);
  EXPECT_LT((predicted - scene.Map(queries[0])).norm(), 1e-9);
  // No match within reach: no affinity.
  EXPECT_FALSE(local[1].has_value());
}

TEST(ConjugateRefinement, RemovesTheBiasOfTheCorrelationPeaks) {
  const Scene scene = MakeScene();
  PairMatches matches = StartingMatches(scene, 60, 0.6);
  const double before = RmsError(scene, matches);
  ConjugateRefinementOptions options;
  options.propagation_rounds = 0;
  const ConjugateRefinementReport report = Refine(scene, options, &matches);
  EXPECT_GE(report.num_refined, 54);
  EXPECT_EQ(report.num_refined + report.NumRejected(), 60);
  EXPECT_EQ(matches.matches.rows(), report.num_refined);
  const double after = RmsError(scene, matches);
  EXPECT_GT(before, 0.3);
  EXPECT_LT(after, 0.05) << "before " << before;
}

TEST(ConjugateRefinement, DropsWrongConjugates) {
  const Scene scene = MakeScene();
  PairMatches matches = StartingMatches(scene, 60, 0.3);
  // Three conjugates on the wrong feature, several pixels away.
  for (int k : {5, 20, 41}) matches.refined_xy2[k] += Eigen::Vector2d(6, -5);
  ConjugateRefinementOptions options;
  options.propagation_rounds = 0;
  Refine(scene, options, &matches);
  for (int k = 0; k < matches.matches.rows(); ++k) {
    EXPECT_LT((matches.refined_xy2[k] - scene.conjugates[matches.matches(k, 0)])
                  .norm(),
              0.2)
        << "keypoint " << matches.matches(k, 0);
  }
}

TEST(ConjugateRefinement, KeepsTheUnrefinedPeaksOnRequest) {
  const Scene scene = MakeScene();
  PairMatches matches = StartingMatches(scene, 60, 0.3);
  const Eigen::Vector2d wrong =
      matches.refined_xy2[20] + Eigen::Vector2d(6, -5);
  matches.refined_xy2[20] = wrong;
  ConjugateRefinementOptions options;
  options.propagation_rounds = 0;
  options.keep_unrefined = true;
  const ConjugateRefinementReport report = Refine(scene, options, &matches);
  EXPECT_GE(report.NumRejected(), 1);
  ASSERT_EQ(matches.matches.rows(), 60);
  // Left where correlation put it, for the relative orientation to judge
  // with the peaks' standard deviation; the refined ones carry theirs.
  EXPECT_EQ(matches.refined_xy2[20], wrong);
  EXPECT_FLOAT_EQ(matches.sigma_px[20], 0.3f);
  const float refined_sigma = static_cast<float>(options.refined_sigma_px);
  EXPECT_EQ(
      std::count(
          matches.sigma_px.begin(), matches.sigma_px.end(), refined_sigma),
      report.num_refined);
}

TEST(ConjugateRefinement, PropagationMatchesTheOtherKeypoints) {
  const Scene scene = MakeScene();
  PairMatches matches = StartingMatches(scene, 30, 0.5);
  ConjugateRefinementOptions options;
  const ConjugateRefinementReport report = Refine(scene, options, &matches);
  const int num_keypoints = static_cast<int>(scene.keypoints1.size());
  EXPECT_GE(report.num_propagated, (num_keypoints - 30) * 2 / 3)
      << "of " << num_keypoints - 30;
  EXPECT_EQ(matches.matches.rows(), report.num_refined + report.num_propagated);
  for (int k = 0; k < matches.matches.rows(); ++k) {
    EXPECT_EQ(matches.matches(k, 0), matches.matches(k, 1));
  }
  EXPECT_LT(RmsError(scene, matches), 0.05);
}

}  // namespace
}  // namespace bayon
