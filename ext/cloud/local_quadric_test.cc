// SPDX-License-Identifier: BSD-3-Clause
#include "ext/cloud/local_quadric.h"

#include "ext/core/random.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace bayon {
namespace {

// Points on w = 0.2 + 0.3 u - 0.1 v + 0.5 u^2 + 0.2 uv - 0.4 v^2 in a frame
// rotated away from the axes, around the origin of that frame.
struct TiltedQuadric {
  Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())
          .toRotationMatrix();
  Eigen::Vector3d origin{10, -4, 2};
  double Height(double u, double v) const {
    return 0.02 + 0.3 * u - 0.1 * v + 0.5 * u * u + 0.2 * u * v - 0.4 * v * v;
  }
  Eigen::Vector3d Point(double u, double v, double w) const {
    return origin + rotation * Eigen::Vector3d(u, v, w);
  }
};

TEST(LocalQuadric, RecoversAnExactQuadric) {
  const TiltedQuadric q;
  std::vector<Eigen::Vector3d> neighbors;
  for (int i = -3; i <= 3; ++i) {
    for (int j = -3; j <= 3; ++j) {
      if (i == 0 && j == 0) continue;
      const double u = 0.05 * i + 0.003 * j, v = 0.05 * j;
      neighbors.push_back(q.Point(u, v, q.Height(u, v)));
    }
  }
  // The query sits 0.02 below the surface at (0, 0), measured along w.
  const QuadricPatch patch = FitQuadricPatch(q.origin, neighbors, {});
  ASSERT_TRUE(patch.valid);
  EXPECT_EQ(patch.num_parameters, 6);
  EXPECT_EQ(patch.num_points, 48);
  // The fit runs in the neighbours' principal frame, slightly tilted from
  // the quadric's own: there the surface is a quadric only up to small
  // third-order terms.
  EXPECT_LT(patch.variance_factor, 1e-6);
  // The deviation is the orthogonal distance to the surface, to first order:
  // 0.02 / sqrt(1 + 0.3^2 + 0.1^2), with the sign of the fitted normal.
  const double sign =
      patch.frame.col(2).dot(q.rotation.col(2)) > 0 ? -1.0 : 1.0;
  EXPECT_NEAR(patch.QueryDeviation(), sign * 0.02 / std::sqrt(1.1), 5e-4);
  EXPECT_NEAR(patch.frame.determinant(), 1.0, 1e-12);
}

TEST(LocalQuadric, VarianceFactorAndHeightVarianceMatchTheNoise) {
  const TiltedQuadric q;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(-0.1, 0.1);
  std::normal_distribution<double> noise(0.0, 1.0);
  const Eigen::Vector3d sigma(0.002, 0.001, 0.003);
  double sum_factor = 0, sum_z2 = 0;
  const int trials = 400;
  for (int t = 0; t < trials; ++t) {
    std::vector<Eigen::Vector3d> neighbors, sigmas;
    for (int j = 0; j < 30; ++j) {
      const double u = uniform(rng), v = uniform(rng);
      const Eigen::Vector3d e = sigma.cwiseProduct(RandomVector<3>(noise, rng));
      neighbors.push_back(q.Point(u, v, q.Height(u, v)) + e);
      sigmas.push_back(sigma);
    }
    const Eigen::Vector3d e = sigma.cwiseProduct(RandomVector<3>(noise, rng));
    const Eigen::Vector3d query = q.Point(0, 0, q.Height(0, 0)) + e;
    const QuadricPatch patch = FitQuadricPatch(query, neighbors, sigmas);
    ASSERT_TRUE(patch.valid);
    sum_factor += patch.variance_factor;
    const double variance =
        VarianceAlong(patch.frame.col(2), sigma) + patch.c0_variance;
    sum_z2 += patch.QueryDeviation() * patch.QueryDeviation() / variance;
  }
  // Both average to one when the model is right (the robust factor is
  // noisier: 30 residuals).
  EXPECT_NEAR(sum_factor / trials, 1.0, 0.15);
  EXPECT_NEAR(sum_z2 / trials, 1.0, 0.2);
}

// The regression behind the given normal: a blunder 20 cm above a densely
// sampled plane, its nearest neighbours a 5 cm disc of surface points and a
// second blunder 2.5 cm away. The principal axes turn the frame on its side
// and the patch passes through both blunders; the surface's own normal
// keeps the deviation at 20 cm.
TEST(LocalQuadric, ASecondBlunderDoesNotCarryThePatch) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> uniform(-0.05, 0.05);
  std::vector<Eigen::Vector3d> neighbors;
  while (neighbors.size() < 23) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    p.head<2>() = RandomVector<2>(uniform, rng);
    if (p.norm() < 0.05) neighbors.push_back(p);
  }
  neighbors.emplace_back(0.02, 0.0, 0.185);
  const Eigen::Vector3d query(0.005, 0.01, 0.2);
  const QuadricPatch principal = FitQuadricPatch(query, neighbors, {});
  ASSERT_TRUE(principal.valid);
  EXPECT_LT(std::abs(principal.QueryDeviation()), 0.1);
  const QuadricPatch given =
      FitQuadricPatch(query, neighbors, {}, Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(given.valid);
  EXPECT_NEAR(std::abs(given.QueryDeviation()), 0.2, 0.005);
  EXPECT_EQ(given.num_rejected, 1);
  EXPECT_EQ(MeanAxis({Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ()})
                .cwiseAbs(),
            Eigen::Vector3d::UnitZ());
}

TEST(LocalQuadric, DegenerateNeighbourhoods) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 1; i <= 20; ++i) line.emplace_back(0.1 * i, 0.2 * i, 0.3 * i);
  EXPECT_FALSE(FitQuadricPatch(Eigen::Vector3d::Zero(), line, {}).valid);
  std::vector<Eigen::Vector3d> few = {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}};
  EXPECT_FALSE(FitQuadricPatch(Eigen::Vector3d::Zero(), few, {}).valid);
  // Seven points carry a plane, not a quadric.
  std::vector<Eigen::Vector3d> seven = {{1, 0, 0},
                                        {0, 1, 0},
                                        {-1, 0, 0},
                                        {0, -1, 0},
                                        {1, 1, 0},
                                        {-1, 1, 0},
                                        {1, -1, 0.1}};
  const QuadricPatch plane =
      FitQuadricPatch(Eigen::Vector3d(0, 0, 0.5), seven, {});
  ASSERT_TRUE(plane.valid);
  EXPECT_EQ(plane.num_parameters, 3);
}

}  // namespace
}  // namespace bayon
