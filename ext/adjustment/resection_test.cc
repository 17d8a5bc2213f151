// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/resection.h"

#include "ext/core/random.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace bayon {
namespace {

constexpr double kFocalPx = 1000;

struct Observations {
  Rigid3d truth;
  std::vector<Eigen::Vector2d> xy;
  std::vector<Eigen::Vector3d> points;
  std::vector<bool> outlier;
};

// A camera 10 m from points spread over a 4 m box (flat: in a plane), 0.5
// px noise, every fifth observation an outlier of 20-100 px.
Observations Make(bool flat, unsigned seed) {
  Observations o;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-2, 2);
  std::normal_distribution<double> noise(0, 0.5 / kFocalPx);
  o.truth.rotation = Eigen::Quaterniond(
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 1, 0.1).normalized()));
  const Eigen::Vector3d center =
      -10 * (o.truth.rotation.inverse() * Eigen::Vector3d::UnitZ());
  o.truth.translation = -(o.truth.rotation * center);
  for (int i = 0; i < 80; ++i) {
    Eigen::Vector3d X = RandomVector<3>(uniform, rng);
    if (flat) X.z() = 0;
    Eigen::Vector2d xy = (o.truth * X).hnormalized();
    xy += RandomVector<2>(noise, rng);
    const bool outlier = i % 5 == 0;
    if (outlier)
      xy += (20 + 80 * (uniform(rng) + 2) / 4) / kFocalPx *
            Eigen::Vector2d(1, 0.5).normalized();
    o.xy.push_back(xy);
    o.points.push_back(X);
    o.outlier.push_back(outlier);
  }
  return o;
}

// RMS of the inliers' errors under the true pose: a least-squares
// resection fits them at least as well.
double TrueRms(const Observations& o) {
  double sum = 0;
  int n = 0;
  for (size_t i = 0; i < o.xy.size(); ++i) {
    if (o.outlier[i]) continue;
    sum += ((o.truth * o.points[i]).hnormalized() - o.xy[i]).squaredNorm();
    ++n;
  }
  return std::sqrt(sum / n);
}

double RotationErrorDeg(const Rigid3d& a, const Rigid3d& b) {
  return a.rotation.angularDistance(b.rotation) * 180 / M_PI;
}

TEST(Resection, DltWithOutliersFindsThePose) {
  const Observations o = Make(false, 1);
  ResectionOptions options;
  options.max_error = 2 / kFocalPx;
  const std::optional<Resection> result =
      ResectImage(o.xy, o.points, nullptr, options);
  ASSERT_TRUE(result);
  // 0.5 px over a 23 degree field: rotation and position correlate, and
  // their errors are a few milliradians and centimetres.
  EXPECT_LT(RotationErrorDeg(result->cam_from_world, o.truth), 0.3);
  EXPECT_LT((result->cam_from_world.Center() - o.truth.Center()).norm(), 0.1);
  EXPECT_LE(result->rms_error, TrueRms(o) * (1 + 1e-6));
  for (size_t i = 0; i < o.xy.size(); ++i) {
    EXPECT_EQ(result->inliers[i], !o.outlier[i]) << i;
  }
  EXPECT_LT(result->rms_error * kFocalPx, 1.0);
}

// Coplanar points make the DLT degenerate; the neighbouring station's
// orientation, 15 degrees and a metre off, is enough of a start.
TEST(Resection, CoplanarPointsFromAGuess) {
  const Observations o = Make(true, 2);
  Rigid3d guess = o.truth;
  guess.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(
                       15 * M_PI / 180, Eigen::Vector3d::UnitY())) *
                   guess.rotation;
  guess.translation += Eigen::Vector3d(1, 0, 0);
  ResectionOptions options;
  options.max_error = 2 / kFocalPx;
  const std::optional<Resection> result =
      ResectImage(o.xy, o.points, &guess, options);
  ASSERT_TRUE(result);
  EXPECT_LT(RotationErrorDeg(result->cam_from_world, o.truth), 0.3);
  EXPECT_EQ(result->num_inliers, 64);
  EXPECT_LE(result->rms_error, TrueRms(o) * (1 + 1e-6));
}

TEST(Resection, TooFewPointsGiveNothing) {
  Observations o = Make(false, 3);
  o.xy.resize(5);
  o.points.resize(5);
  EXPECT_FALSE(ResectImage(o.xy, o.points, nullptr, ResectionOptions()));
}

}  // namespace
}  // namespace bayon
