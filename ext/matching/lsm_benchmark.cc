// SPDX-License-Identifier: BSD-3-Clause
//
// Throughput of least-squares matching (scripts/bench.sh lsm): one 15 x 15
// template matched into 3 search images (affine + 2 radiometric parameters,
// bilinear), from approximations 0.5 to 1 pixel off, on synthetic textures
// with noise; and the same with refine_keypoints' checks and back-matching.
// Run with --benchmark_filter etc.; Threads(2) runs the loop on both cores
// at once (items per second summed over the threads, real time).
#include "ext/matching/keypoint_refinement.h"
#include "ext/matching/lsm.h"
#include "ext/synth/texture_patches.h"

#include <Eigen/Geometry>
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

namespace bayon {
namespace {

constexpr int kImageSize = 256;
constexpr int kNumSearches = 3;

// One template image, three transformed search images, and template points
// with approximations in every search image.
struct Scene {
  cv::Mat template_image;
  std::vector<cv::Mat> search_images;
  std::vector<TexturePairTruth> truths;
  std::vector<Eigen::Vector2d> points;
  // approximations[k][i]: point k in search image i, 0.5..1 px off.
  std::vector<std::vector<Eigen::Vector2d>> approximations;

  Eigen::Vector2d Conjugate(int i, const Eigen::Vector2d& p) const {
    return truths[i].search_xy + truths[i].shape * (p - truths[i].template_xy);
  }
};

const Scene& GetScene() {
  static const Scene scene = [] {
    Scene s;
    WaveTextureOptions texture_options;
    texture_options.seed = 5;
    const WaveTexture texture(texture_options);
    s.template_image = RenderTemplateImage(texture, kImageSize, kImageSize);
    AddGaussianNoise(2.0, 1, &s.template_image);
    for (int i = 0; i < kNumSearches; ++i) {
      TexturePairTruth truth;
      truth.template_xy = Eigen::Vector2d(128, 128);
      truth.search_xy = Eigen::Vector2d(128 + 1.3 * i, 128 - 0.7 * i);
      truth.shape = (1.0 + 0.05 * i) *
                    Eigen::Rotation2Dd(0.04 * (i - 1)).toRotationMatrix();
      truth.shape(0, 1) += 0.03;
      truth.r0 = 5.0 * i;
      truth.r1 = 1.0 - 0.05 * i;
      s.truths.push_back(truth);
      s.search_images.push_back(
          RenderSearchImage(texture, truth, kImageSize, kImageSize));
      AddGaussianNoise(2.0, 10 + i, &s.search_images.back());
    }
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> offset(0.5, 1.0);
    std::uniform_int_distribution<int> sign(0, 1);
    for (int y = 80; y <= 176; y += 8) {
      for (int x = 80; x <= 176; x += 8) {
        const Eigen::Vector2d p(x + 0.5, y + 0.5);
        s.points.push_back(p);
        std::vector<Eigen::Vector2d> approximations;
        for (int i = 0; i < kNumSearches; ++i) {
          // y first, then x; each its sign before its size (the order of
          // draws is fixed: see ext/core/random.h).
          Eigen::Vector2d error;
          for (int axis = 1; axis >= 0; --axis) {
            const double side = sign(rng) ? 1 : -1;
            error[axis] = offset(rng) * side;
          }
          approximations.push_back(s.Conjugate(i, p) + 0.7 * error);
        }
        s.approximations.push_back(approximations);
      }
    }
    return s;
  }();
  return scene;
}

// Template cut out and matched into the three search images, per point.
void BM_LsmThreeSearchImages(benchmark::State& state) {
  const Scene& scene = GetScene();
  LsmOptions options;  // patch_radius 7: 15 x 15
  size_t k = static_cast<size_t>(state.thread_index()) * 7;
  int64_t num_converged = 0, num_iterations = 0;
  for (auto _ : state) {
    k = (k + 1) % scene.points.size();
    LsmTemplate patch;
    ExtractLsmTemplate(scene.template_image,
                       scene.points[k],
                       options.patch_radius,
                       options.interpolation,
                       &patch);
    std::vector<LsmSearch> searches(kNumSearches);
    for (int i = 0; i < kNumSearches; ++i) {
      searches[i].image = &scene.search_images[i];
      searches[i].approximation = LsmParameters::At(scene.approximations[k][i]);
    }
    const std::vector<LsmMatch> matches =
        MatchLsmMulti(patch, searches, options);
    for (const LsmMatch& match : matches) {
      num_converged += match.ok();
      num_iterations += match.iterations;
    }
    benchmark::DoNotOptimize(matches.data());
  }
  state.SetItemsProcessed(state.iterations() * kNumSearches);
  state.counters["points"] = benchmark::Counter(
      static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["converged_pct"] = benchmark::Counter(
      100.0 * num_converged / std::max<int64_t>(1, state.iterations()) /
          kNumSearches,
      benchmark::Counter::kAvgThreads);
  state.counters["gn_iterations"] = benchmark::Counter(
      static_cast<double>(num_iterations) /
          std::max<int64_t>(1, state.iterations()) / kNumSearches,
      benchmark::Counter::kAvgThreads);
}
BENCHMARK(BM_LsmThreeSearchImages)->Threads(1)->Threads(2)->UseRealTime();

// What refine_keypoints does per observation: forward match, checks and
// back-matching, into the three search images.
void BM_RefineObservationThreeSearchImages(benchmark::State& state) {
  const Scene& scene = GetScene();
  KeypointRefinementOptions options;
  size_t k = static_cast<size_t>(state.thread_index()) * 7;
  int64_t num_refined = 0;
  for (auto _ : state) {
    k = (k + 1) % scene.points.size();
    for (int i = 0; i < kNumSearches; ++i) {
      const ObservationRefinement result =
          RefineObservation(scene.template_image,
                            scene.points[k],
                            scene.search_images[i],
                            scene.approximations[k][i],
                            Eigen::Matrix2d::Identity(),
                            options);
      num_refined += result.outcome == ObservationOutcome::kRefined;
      benchmark::DoNotOptimize(result.refined_xy);
    }
  }
  state.SetItemsProcessed(state.iterations() * kNumSearches);
  state.counters["points"] = benchmark::Counter(
      static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["refined_pct"] = benchmark::Counter(
      100.0 * num_refined / std::max<int64_t>(1, state.iterations()) /
          kNumSearches,
      benchmark::Counter::kAvgThreads);
}
BENCHMARK(BM_RefineObservationThreeSearchImages)
    ->Threads(1)
    ->Threads(2)
    ->UseRealTime();

}  // namespace
}  // namespace bayon

BENCHMARK_MAIN();
