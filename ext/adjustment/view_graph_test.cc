// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/view_graph.h"

#include "ext/core/errors.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace bayon {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Matrix3d RandomRotation(std::mt19937* rng, double max_angle_rad) {
  std::normal_distribution<double> normal(0, 1);
  std::uniform_real_distribution<double> unit(0, 1);
  const Eigen::Vector3d axis =
      Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng)).normalized();
  return Eigen::AngleAxisd(max_angle_rad * unit(*rng), axis).toRotationMatrix();
}

// A ring of `n` cameras (world from camera rotations at random), each
// paired with its next and second-next: every pair lies on triangles. Each
// relative rotation carries `noise_deg` of error; the pairs listed in
// `false_pairs` are turned by 40-100 deg instead, as chance matches
// between photographs that do not overlap give.
std::vector<ViewGraphPair> Ring(int n,
                                double noise_deg,
                                const std::vector<int>& false_pairs,
                                unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<Eigen::Matrix3d> cam_from_world;
  for (int i = 0; i < n; ++i) {
    cam_from_world.push_back(RandomRotation(&rng, M_PI));
  }
  std::vector<ViewGraphPair> pairs;
  for (int i = 0; i < n; ++i) {
    for (int step : {1, 2}) {
      const int j = (i + step) % n;
      ViewGraphPair pair;
      pair.image1 = i;
      pair.image2 = j;
      pair.rotation = RandomRotation(&rng, noise_deg * kDeg) *
                      cam_from_world[j] * cam_from_world[i].transpose();
      pairs.push_back(pair);
    }
  }
  std::uniform_real_distribution<double> wrong(40, 100);
  for (int p : false_pairs) {
    pairs[p].rotation =
        Eigen::AngleAxisd(wrong(rng) * kDeg, Eigen::Vector3d::UnitY()) *
        pairs[p].rotation;
  }
  return pairs;
}

std::vector<int> Dropped(const std::vector<DroppedPair>& dropped) {
  std::vector<int> idxs;
  for (const DroppedPair& pair : dropped) idxs.push_back(pair.pair_idx);
  std::sort(idxs.begin(), idxs.end());
  return idxs;
}

TEST(ViewGraph, CorrectPairsAreKept) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const std::vector<DroppedPair> dropped =
        FindInconsistentPairs(Ring(12, 0.5, {}, seed), ViewGraphOptions());
    EXPECT_TRUE(dropped.empty()) << seed;
  }
}

TEST(ViewGraph, FalsePairsAreDroppedAndTheirNeighboursKept) {
  // Pair 4 is images 2-3, on two triangles, which it spoils for its
  // neighbours 1-3 and 2-4 (their only triangles); pair 15 is images 7-9,
  // on one triangle.
  const std::vector<int> false_pairs = {4, 15};
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const std::vector<DroppedPair> dropped = FindInconsistentPairs(
        Ring(12, 0.5, false_pairs, seed), ViewGraphOptions());
    EXPECT_EQ(Dropped(dropped), false_pairs) << seed;
    for (const DroppedPair& pair : dropped) {
      EXPECT_GT(pair.median_loop_error_deg, 5) << seed;
      EXPECT_GT(2 * pair.num_failing, pair.num_triangles) << seed;
    }
  }
}

TEST(ViewGraph, AWeakPairIsNotTakenForAFalseOne) {
  // One triangle, one of its pairs 7 deg off: false if the pairs are known
  // to 0.3 deg, within three standard deviations if that pair is known to
  // 2.5 deg (a narrow pair of few points, as temple-ring has).
  std::vector<ViewGraphPair> pairs;
  for (const ViewGraphPair& pair : Ring(12, 0.0, {}, 2)) {
    if (pair.image1 <= 2 && pair.image2 <= 2) pairs.push_back(pair);
  }
  ASSERT_EQ(pairs.size(), 3u);
  pairs[0].rotation =
      Eigen::AngleAxisd(7 * kDeg, Eigen::Vector3d::UnitX()) * pairs[0].rotation;
  for (ViewGraphPair& pair : pairs) pair.sigma_deg = 0.3;
  EXPECT_EQ(FindInconsistentPairs(pairs, ViewGraphOptions()).size(), 1u);
  pairs[0].sigma_deg = 2.5;
  EXPECT_TRUE(FindInconsistentPairs(pairs, ViewGraphOptions()).empty());
}

TEST(ViewGraph, PairsOnNoTriangleCannotBeTested) {
  // Neighbours only: a ring without triangles keeps even a false pair.
  std::vector<ViewGraphPair> pairs;
  for (const ViewGraphPair& pair : Ring(8, 0.5, {2}, 3)) {
    if ((pair.image2 - pair.image1 + 8) % 8 == 1) pairs.push_back(pair);
  }
  ASSERT_EQ(pairs.size(), 8u);
  EXPECT_TRUE(FindInconsistentPairs(pairs, ViewGraphOptions()).empty());
  ViewGraphOptions bad;
  bad.max_loop_error_deg = 0;
  EXPECT_THROW(FindInconsistentPairs(pairs, bad), InputError);
}

TEST(ViewGraph, RotationAngle) {
  EXPECT_NEAR(RotationAngleDeg(Eigen::Matrix3d::Identity()), 0, 1e-6);
  EXPECT_NEAR(RotationAngleDeg(
                  Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).matrix()),
              0.3 / kDeg,
              1e-9);
}

}  // namespace
}  // namespace bayon
