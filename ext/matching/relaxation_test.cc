// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/relaxation.h"

#include "ext/core/errors.h"
#include "ext/core/random.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace bayon {
namespace {

// 400 true correspondences under a mapping that turns and scales, each with
// three distractor candidates anywhere within 60 px, with correlations drawn
// from the same range as the true ones (so correlation alone cannot tell).
TEST(Relaxation, ContinuityAndUniquenessKeepTheTrueMatches) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(0, 600), y(0, 400), offset(-60, 60),
      ncc(0.75, 0.95);
  Eigen::Matrix2d L;
  L << 0, -1.1, 1.1, 0;  // a quarter turn and a 10 % scale change
  const Eigen::Vector2d shift(500, 30);
  std::vector<Eigen::Vector2d> xy1, xy2;
  std::vector<MatchCandidate> candidates;
  for (int i = 0; i < 400; ++i) {
    const double row = y(rng);  // y first: a fixed order of draws
    xy1.emplace_back(x(rng), row);
    xy2.push_back(L * xy1.back() + shift);
  }
  for (int i = 0; i < 400; ++i) {
    candidates.push_back({i, i, static_cast<float>(ncc(rng))});
    for (int k = 0; k < 3; ++k) {
      xy2.push_back(xy2[i] + RandomVector<2>(offset, rng));
      candidates.push_back(
          {i, static_cast<int>(xy2.size()) - 1, static_cast<float>(ncc(rng))});
    }
  }
  // Some distractors share an image-2 point with a true match.
  for (int i = 0; i < 100; ++i) {
    candidates.push_back({i, i + 1, static_cast<float>(ncc(rng))});
  }
  std::shuffle(candidates.begin(), candidates.end(), rng);
  const RelaxationResult result =
      RelaxMatches(xy1, xy2, candidates, L, 600, RelaxationOptions());
  int correct = 0;
  std::set<int> used1, used2;
  for (const MatchCandidate& m : result.matches) {
    correct += m.idx1 == m.idx2;
    EXPECT_TRUE(used1.insert(m.idx1).second);
    EXPECT_TRUE(used2.insert(m.idx2).second);
  }
  EXPECT_GE(correct, 390);
  EXPECT_LE(static_cast<int>(result.matches.size()) - correct, 4);
  EXPECT_GT(result.num_iterations, 1);
}

TEST(Relaxation, IsolatedCandidatesTakeNothing) {
  // Three far-apart points: nobody supports anybody.
  const std::vector<Eigen::Vector2d> xy1 = {{10, 10}, {500, 10}, {10, 500}};
  const std::vector<MatchCandidate> candidates = {
      {0, 0, 0.9f}, {1, 1, 0.9f}, {2, 2, 0.9f}};
  const RelaxationResult result =
      RelaxMatches(xy1, xy1, candidates, Eigen::Matrix2d::Identity(), 600, {});
  EXPECT_TRUE(result.matches.empty());
  RelaxationOptions options;
  options.min_support = 0;
  EXPECT_EQ(RelaxMatches(
                xy1, xy1, candidates, Eigen::Matrix2d::Identity(), 600, options)
                .matches.size(),
            3u);
  options.max_angle_deg = 0;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace bayon
