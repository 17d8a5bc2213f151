// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/focal_length.h"

#include "ext/core/errors.h"
#include "ext/core/random.h"
#include "ext/synth/synthetic_camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace bayon {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kWidth = 1800, kHeight = 1200;

// A ring of `num_stations` stations around an object (radius 10 m), each
// looking at a point near the object's centre, as a photographer on foot
// aims: heights and aims scattered by `scatter_m`, so that the optical axes
// nearly meet, the case the closed forms fail on. With scatter_m = 0 they
// meet: a turntable, where two views do not fix the focal length.
// Neighbouring stations form the pairs; their conjugate points are given as
// the image vectors of a camera guessed at `guess_px` (only x and y count),
// with Gaussian noise and a share of blunders.
std::vector<ConjugatePoints> RingPairs(double focal_px,
                                       double guess_px,
                                       int num_stations,
                                       double step_deg,
                                       double noise_px,
                                       double blunder_share,
                                       unsigned seed,
                                       double scatter_m = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, noise_px);
  std::uniform_real_distribution<double> unit(0, 1);
  const Eigen::Vector3d centre(0, 0, 2);
  std::vector<Rigid3d> poses;
  for (int k = 0; k < num_stations; ++k) {
    const double azimuth = k * step_deg * kDeg;
    const Eigen::Vector3d station(10 * std::cos(azimuth),
                                  10 * std::sin(azimuth),
                                  4 + scatter_m * 2 * (unit(rng) - 0.5));
    const Eigen::Vector3d aim =
        centre + scatter_m * (RandomVector<3>(unit, rng) -
                              Eigen::Vector3d::Constant(0.5));
    poses.push_back(LookAt(station, aim));
  }
  const auto project = [&](const Rigid3d& pose,
                           const Eigen::Vector3d& X,
                           Eigen::Vector2d* pixel) {
    const Eigen::Vector3d p = pose * X;
    *pixel = Eigen::Vector2d(focal_px * p.x() / p.z() + kWidth / 2,
                             focal_px * p.y() / p.z() + kHeight / 2);
    return p.z() > 0 && pixel->x() > 0 && pixel->y() > 0 &&
           pixel->x() < kWidth && pixel->y() < kHeight;
  };
  const auto vector = [&](const Eigen::Vector2d& pixel) {
    return Eigen::Vector3d(
        pixel.x() - kWidth / 2, -(pixel.y() - kHeight / 2), -guess_px);
  };
  std::vector<ConjugatePoints> pairs;
  for (int k = 0; k + 1 < num_stations; ++k) {
    ConjugatePoints points;
    while (points.size() < 200) {
      // The object: points in a cylinder of 3 m radius and 4 m height.
      const double angle = 2 * M_PI * unit(rng), r = 3 * std::sqrt(unit(rng));
      const Eigen::Vector3d X(
          r * std::cos(angle), r * std::sin(angle), 4 * unit(rng));
      Eigen::Vector2d x1, x2;
      if (!project(poses[k], X, &x1) || !project(poses[k + 1], X, &x2)) {
        continue;
      }
      x1 += RandomVector<2>(noise, rng);
      x2 += RandomVector<2>(noise, rng);
      if (unit(rng) < blunder_share) {
        x2 = Eigen::Vector2d(kWidth * unit(rng), kHeight * unit(rng));
      }
      points.u1.push_back(vector(x1));
      points.u2.push_back(vector(x2));
    }
    pairs.push_back(points);
  }
  return pairs;
}

// The synthetic pairs have few blunders: a quarter of the samples and a few
// candidates per orientation find them (the search itself is the same), so
// that the tests stay quick under the sanitizers.
FocalLengthOptions Options() {
  FocalLengthOptions options;
  options.estimation.num_samples = 256;
  options.estimation.num_candidates = 4;
  return options;
}

TEST(FocalLength, FoundFromARingWhoseAxesNearlyMeet) {
  const double truth = 1750;
  // COLMAP's guess, 1.2 x the long side.
  const std::vector<ConjugatePoints> pairs =
      RingPairs(truth, 1.2 * kWidth, 8, 25, 0.3, 0.1, 7);
  const FocalLengthEstimate estimate =
      EstimateFocalLength(pairs, kWidth, Options());
  ASSERT_TRUE(estimate.success) << estimate.reason;
  EXPECT_EQ(estimate.num_pairs, 7);
  const double error = estimate.focal_length_px / truth - 1;
  std::printf("focal %.1f px (truth %.0f): error %.3f %%, sigma %.3f %%\n",
              estimate.focal_length_px,
              truth,
              100 * error,
              100 * estimate.relative_sigma);
  // Pairs fix short focal lengths well and long ones weakly (the score
  // rises steeply below the truth and slowly above it): about 1 %, which
  // the bundle then refines with all the rays at once.
  EXPECT_LT(std::abs(error), 0.02);
  // The stated precision is plausible: the error is one draw from it.
  EXPECT_LT(std::abs(error), 3 * estimate.relative_sigma);
  EXPECT_LT(estimate.relative_sigma, 0.03);
  // The grid spans the range asked for.
  ASSERT_FALSE(estimate.grid.empty());
  EXPECT_NEAR(estimate.grid.front().first, 0.3 * kWidth, 1e-6);
}

TEST(FocalLength, AWideAngleAndATelephotoLensAlike) {
  for (double truth : {800.0, 6000.0}) {
    const std::vector<ConjugatePoints> pairs =
        RingPairs(truth, 1.2 * kWidth, 6, 20, 0.3, 0.05, 11);
    const FocalLengthEstimate estimate =
        EstimateFocalLength(pairs, kWidth, Options());
    ASSERT_TRUE(estimate.success) << truth << ": " << estimate.reason;
    const double error = estimate.focal_length_px / truth - 1;
    EXPECT_LT(std::abs(error), 3 * estimate.relative_sigma) << truth;
    EXPECT_LT(std::abs(error), 0.03) << truth;
  }
}

TEST(FocalLength, ATurntableDoesNotFixIt) {
  const FocalLengthEstimate estimate = EstimateFocalLength(
      RingPairs(1750, 2160, 8, 25, 0.3, 0.05, 5, 0), kWidth, Options());
  EXPECT_FALSE(estimate.success);
  EXPECT_NE(estimate.reason.find("do not fix the focal length"),
            std::string::npos)
      << estimate.reason;
}

TEST(FocalLength, SaysWhatIsMissing) {
  const FocalLengthEstimate none = EstimateFocalLength({}, kWidth, Options());
  EXPECT_FALSE(none.success);
  EXPECT_NE(none.reason.find("no image pair"), std::string::npos);
  // A lens shorter than the range searched.
  FocalLengthOptions narrow = Options();
  narrow.min_focal_ratio = 1.2;
  const FocalLengthEstimate outside = EstimateFocalLength(
      RingPairs(1750, 2160, 6, 20, 0.3, 0, 3), kWidth, narrow);
  EXPECT_FALSE(outside.success);
  EXPECT_NE(outside.reason.find("range searched"), std::string::npos)
      << outside.reason;
  FocalLengthOptions bad;
  bad.grid_step = 1;
  EXPECT_THROW(EstimateFocalLength({}, kWidth, bad), InputError);
}

}  // namespace
}  // namespace bayon
