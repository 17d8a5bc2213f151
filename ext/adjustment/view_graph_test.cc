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

// The neighbours of a ring of `n` (no triangles), each rotation up to
// `noise_deg` off, and chords across it from `chords` (image pairs, the
// rotations through the neighbours between them).
std::vector<ViewGraphPair> RingOfNeighbours(
    int n,
    unsigned seed,
    const std::vector<std::pair<int, int>>& chords = {},
    double noise_deg = 0.5) {
  std::vector<ViewGraphPair> ring;
  const std::vector<ViewGraphPair> all = Ring(n, noise_deg, {}, seed);
  for (const ViewGraphPair& pair : all) {
    if ((pair.image2 - pair.image1 + n) % n == 1) ring.push_back(pair);
  }
  // A chord's rotation from the ring's own: j from i through the
  // neighbours between them.
  for (const auto& [i, j] : chords) {
    ViewGraphPair chord;
    chord.image1 = i;
    chord.image2 = j;
    for (int k = i; k != j; k = (k + 1) % n) {
      chord.rotation = ring[k].rotation * chord.rotation;
    }
    ring.push_back(chord);
  }
  return ring;
}

void TurnPair(ViewGraphPair* pair, double angle_deg) {
  pair->rotation =
      Eigen::AngleAxisd(angle_deg * kDeg, Eigen::Vector3d::UnitZ()) *
      pair->rotation;
}

TEST(ViewGraph, AFalsePairOnLongerLoopsOnlyIsDropped) {
  // A ring of 16 neighbours with two chords that cross it (0-5, 8-13),
  // every pair on loops of 5 to 12 pairs and none on a triangle. Chord
  // 3-11, turned by 90 deg, is the doppelganger of a symmetric object:
  // it lies on no triangle, but on loops of 9 pairs either way.
  for (unsigned seed = 1; seed <= 5; ++seed) {
    std::vector<ViewGraphPair> pairs =
        RingOfNeighbours(16, seed, {{0, 5}, {8, 13}, {3, 11}});
    for (ViewGraphPair& pair : pairs) pair.weight = 100;
    const int false_pair = static_cast<int>(pairs.size()) - 1;
    EXPECT_TRUE(FindInconsistentPairs(pairs, ViewGraphOptions()).empty())
        << seed;
    TurnPair(&pairs[false_pair], 90);
    pairs[false_pair].weight = 40;
    const std::vector<DroppedPair> dropped =
        FindInconsistentPairs(pairs, ViewGraphOptions());
    ASSERT_EQ(Dropped(dropped), std::vector<int>{false_pair}) << seed;
    EXPECT_EQ(dropped[0].num_triangles, 0);
    EXPECT_GE(dropped[0].loop_length, 5);
    EXPECT_NEAR(dropped[0].loop_error_deg, 90, 5);
    EXPECT_LT(dropped[0].loop_limit_deg, 10);
  }
}

TEST(ViewGraph, ALoopThatCannotTellWhichPairIsFalseKeepsThemAll) {
  // One loop of 8 equal neighbours, one of them 60 deg off: the loop
  // fails, but nothing tells which pair is false, so none is dropped. With
  // fewer conjugate points than the others, the false one gives way.
  for (unsigned seed = 1; seed <= 3; ++seed) {
    std::vector<ViewGraphPair> pairs = RingOfNeighbours(8, seed);
    ASSERT_EQ(pairs.size(), 8u);
    TurnPair(&pairs[2], 60);
    EXPECT_TRUE(FindInconsistentPairs(pairs, ViewGraphOptions()).empty())
        << seed;
    for (ViewGraphPair& pair : pairs) pair.weight = 100;
    pairs[2].weight = 30;
    EXPECT_EQ(Dropped(FindInconsistentPairs(pairs, ViewGraphOptions())),
              std::vector<int>{2})
        << seed;
  }
}

TEST(ViewGraph, LongLoopsAllowForTheirErrorsAndBridgesAreKept) {
  // A ring of 30 neighbours, each up to 2 deg off: the ring's loop error
  // grows with its length (beyond a triangle's 5 deg for these seeds) and
  // passes, so even its lightest pair is kept. A false pair that is the
  // only link of an image to the rest cannot be tested.
  for (unsigned seed = 1; seed <= 3; ++seed) {
    std::vector<ViewGraphPair> pairs = RingOfNeighbours(30, seed, {}, 2.0);
    for (ViewGraphPair& pair : pairs) pair.weight = 100;
    pairs[0].weight = 50;
    ViewGraphPair bridge;
    bridge.image1 = 4;
    bridge.image2 = 99;
    TurnPair(&bridge, 120);
    bridge.weight = 10;
    pairs.push_back(bridge);
    EXPECT_TRUE(FindInconsistentPairs(pairs, ViewGraphOptions()).empty())
        << seed;
  }
}

TEST(ViewGraph, PairsOnNoLoopCannotBeTested) {
  // A chain of neighbours without its closing pair keeps even a false one.
  std::vector<ViewGraphPair> pairs = RingOfNeighbours(8, 3);
  pairs.pop_back();
  TurnPair(&pairs[2], 70);
  EXPECT_TRUE(FindInconsistentPairs(pairs, ViewGraphOptions()).empty());
  ViewGraphOptions bad;
  bad.max_loop_error_deg = 0;
  EXPECT_THROW(FindInconsistentPairs(pairs, bad), InputError);
  bad = ViewGraphOptions();
  bad.num_spanning_trees = 0;
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
