// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/alignment.h"

#include "ext/core/random.h"

#include <gtest/gtest.h>

#include <random>

namespace bayon {
namespace {

Sim3d TrueTransform() {
  return Sim3d(2.5,
               Eigen::Quaterniond(Eigen::AngleAxisd(
                   0.7, Eigen::Vector3d(1, 2, 3).normalized())),
               Eigen::Vector3d(10, -4, 3));
}

std::vector<Eigen::Vector3d> RandomPoints(int n, std::mt19937* rng) {
  std::normal_distribution<double> normal(0, 1);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < n; ++i) {
    points.emplace_back(normal(*rng), normal(*rng), normal(*rng));
  }
  return points;
}

TEST(Alignment, RecoversSimilarityExactly) {
  std::mt19937 rng(3);
  const auto src = RandomPoints(10, &rng);
  std::vector<Eigen::Vector3d> dst;
  for (const auto& p : src) dst.push_back(TrueTransform() * p);
  const auto estimate = EstimateSim3d(src, dst);
  ASSERT_TRUE(estimate);
  EXPECT_NEAR(estimate->scale, 2.5, 1e-12);
  EXPECT_LT(estimate->rotation.angularDistance(TrueTransform().rotation),
            1e-12);
  EXPECT_LT((estimate->translation - TrueTransform().translation).norm(),
            1e-10);
}

TEST(Alignment, RefusesCollinearAndTooFewPoints) {
  std::vector<Eigen::Vector3d> line = {
      {0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}};
  EXPECT_FALSE(EstimateSim3d(line, line));
  EXPECT_FALSE(EstimateSim3d({{0, 0, 0}, {1, 0, 0}}, {{0, 0, 0}, {1, 0, 0}}));
}

TEST(Alignment, RobustFitFlagsBlunders) {
  std::mt19937 rng(5);
  const auto src = RandomPoints(30, &rng);
  std::vector<Eigen::Vector3d> dst;
  std::normal_distribution<double> noise(0, 0.001);
  for (const auto& p : src) {
    dst.push_back(TrueTransform() * p + RandomVector<3>(noise, rng));
  }
  for (int i : {3, 11, 17, 25}) dst[i] += Eigen::Vector3d(0.5, -0.3, 0.2);
  const RobustSim3dReport report = EstimateSim3dRobust(src, dst);
  ASSERT_TRUE(report.success);
  EXPECT_EQ(report.num_inliers, 26);
  for (int i : {3, 11, 17, 25}) EXPECT_FALSE(report.inlier_mask[i]);
  EXPECT_NEAR(report.dst_from_src.scale, 2.5, 1e-3);
}

TEST(Sim3d, TransformPoseKeepsProjections) {
  const Rigid3d cam_from_a(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())),
      Eigen::Vector3d(0.1, 0.2, 3));
  const Sim3d b_from_a = TrueTransform();
  const Rigid3d cam_from_b = b_from_a.TransformPose(cam_from_a);
  const Eigen::Vector3d x_in_a(0.3, -0.2, 0.5);
  const Eigen::Vector3d in_cam_a = cam_from_a * x_in_a;
  const Eigen::Vector3d in_cam_b = cam_from_b * (b_from_a * x_in_a);
  EXPECT_LT((in_cam_a.hnormalized() - in_cam_b.hnormalized()).norm(), 1e-12);
  EXPECT_LT((cam_from_b.Center() - b_from_a * cam_from_a.Center()).norm(),
            1e-12);
}

}  // namespace
}  // namespace bayon
