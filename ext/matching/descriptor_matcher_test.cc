// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/descriptor_matcher.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <numeric>
#include <random>

namespace bayon {
namespace {

// A unit vector in COLMAP's byte form (non-negative, norm 512).
Eigen::VectorXd RandomDescriptor(std::mt19937* rng) {
  std::uniform_real_distribution<double> uniform(0, 1);
  Eigen::VectorXd v(128);
  for (int k = 0; k < 128; ++k) v(k) = uniform(*rng);
  return v.normalized();
}

void SetRow(FeatureDescriptors* d, int row, const Eigen::VectorXd& unit) {
  for (int k = 0; k < 128; ++k) {
    (*d)(row, k) = static_cast<uint8_t>(
        std::min(255.0, std::round(512 * std::max(0.0, unit(k)))));
  }
}

Eigen::VectorXd Perturbed(const Eigen::VectorXd& v,
                          double sigma,
                          std::mt19937* rng) {
  std::normal_distribution<double> normal(0, sigma);
  Eigen::VectorXd w = v;
  for (int k = 0; k < 128; ++k) w(k) = std::max(0.0, w(k) + normal(*rng));
  return w.normalized();
}

TEST(DescriptorMatcher, FindsConjugatesAmongDistractors) {
  std::mt19937 rng(4);
  const int n = 300;
  FeatureDescriptors d1(n, 128), d2(n + 200, 128);
  // Image 2 holds noisy copies in reverse order, then 200 others.
  for (int i = 0; i < n; ++i) {
    const Eigen::VectorXd v = RandomDescriptor(&rng);
    SetRow(&d1, i, v);
    SetRow(&d2, n - 1 - i, Perturbed(v, 0.02, &rng));
  }
  for (int j = n; j < n + 200; ++j) SetRow(&d2, j, RandomDescriptor(&rng));
  const std::vector<DescriptorMatch> matches =
      MatchDescriptors(ToUnitDescriptors(d1),
                       ToUnitDescriptors(d2),
                       DescriptorMatchingOptions());
  ASSERT_GT(matches.size(), 0.95 * n);
  for (const DescriptorMatch& match : matches) {
    EXPECT_EQ(match.idx2, n - 1 - match.idx1);
    EXPECT_LT(match.distance, 0.7);
  }
  // Only the rows asked for, and their indices.
  std::vector<int> rows2(n + 200);
  std::iota(rows2.begin(), rows2.end(), 0);
  const std::vector<DescriptorMatch> some =
      MatchDescriptors(d1, {5, 6, 7}, d2, rows2, DescriptorMatchingOptions());
  ASSERT_EQ(some.size(), 3u);
  EXPECT_EQ(some[0].idx1, 5);
  EXPECT_EQ(some[0].idx2, n - 6);
}

TEST(DescriptorMatcher, RatioTestMutualBestAndDistance) {
  std::mt19937 rng(8);
  const Eigen::VectorXd a = RandomDescriptor(&rng);
  const Eigen::VectorXd b = RandomDescriptor(&rng);
  FeatureDescriptors d1(2, 128), d2(3, 128);
  SetRow(&d1, 0, a);
  SetRow(&d1, 1, Perturbed(a, 0.01, &rng));  // also nearest to a's copy
  SetRow(&d2, 0, Perturbed(a, 0.005, &rng));
  SetRow(&d2, 1, b);
  SetRow(&d2, 2, Perturbed(b, 0.001, &rng));
  const DescriptorMatchingOptions options;
  // Row 0 and row 1 of image 1 both have image-2 row 0 nearest: the mutual
  // best keeps one of them.
  std::vector<DescriptorMatch> matches =
      MatchDescriptors(d1, {0, 1}, d2, {0, 1, 2}, options);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].idx2, 0);
  DescriptorMatchingOptions one_way = options;
  one_way.cross_check = false;
  EXPECT_EQ(MatchDescriptors(d1, {0, 1}, d2, {0, 1, 2}, one_way).size(), 2u);
  // b has two near-identical candidates: not distinctive.
  FeatureDescriptors db(1, 128);
  SetRow(&db, 0, Perturbed(b, 0.01, &rng));
  EXPECT_TRUE(MatchDescriptors(db, {0}, d2, {0, 1, 2}, one_way).empty());
  // Distinctive but far: beyond max_distance.
  DescriptorMatchingOptions near = one_way;
  near.max_distance = 1e-3;
  EXPECT_TRUE(MatchDescriptors(d1, {0}, d2, {0, 1}, near).empty());
  EXPECT_TRUE(MatchDescriptors(d1, {}, d2, {0, 1}, options).empty());
}

TEST(DescriptorMatcher, RefusesBadOptions) {
  DescriptorMatchingOptions options;
  options.max_ratio = 1.5;
  EXPECT_THROW(options.Check(), InputError);
  options = DescriptorMatchingOptions();
  options.max_distance = 0;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace bayon
