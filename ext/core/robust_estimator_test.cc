// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/robust_estimator.h"

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <random>
#include <set>

namespace bayon {
namespace {

// y = slope x + offset through two points; the model is (slope, offset).
class LineEstimator {
 public:
  using Model = Eigen::Vector2d;
  static constexpr int kMinNumSamples = 2;

  explicit LineEstimator(const std::vector<Eigen::Vector2d>& points)
      : points_(points) {}

  bool Estimate(const std::vector<int>& sample, Model* model) const {
    ++num_estimates;
    const Eigen::Vector2d& a = points_[sample[0]];
    const Eigen::Vector2d& b = points_[sample[1]];
    if (std::abs(b.x() - a.x()) < 1e-12) return false;
    const double slope = (b.y() - a.y()) / (b.x() - a.x());
    *model = Model(slope, a.y() - slope * a.x());
    return true;
  }

  void Residuals(const Model& model, std::vector<double>* residuals) const {
    residuals->resize(points_.size());
    for (size_t i = 0; i < points_.size(); ++i) {
      (*residuals)[i] = points_[i].y() - model[0] * points_[i].x() - model[1];
    }
  }

  mutable int num_estimates = 0;

 private:
  const std::vector<Eigen::Vector2d>& points_;
};

// A sampler that returns fixed samples in turn.
class ListSampler {
 public:
  explicit ListSampler(std::vector<std::vector<int>> samples)
      : samples_(std::move(samples)) {}
  void Sample(int size, std::vector<int>* sample) {
    EXPECT_EQ(size, 2);
    *sample = samples_[next_++ % samples_.size()];
  }

 private:
  std::vector<std::vector<int>> samples_;
  size_t next_ = 0;
};

// Points on y = 0.5 x + 2 with noise of 0.01, the first `num_outliers`
// moved off it by 5 to 50.
std::vector<Eigen::Vector2d> LineWithOutliers(int n, int num_outliers) {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 0.01);
  std::uniform_real_distribution<double> off(5, 50);
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < n; ++i) {
    const double x = 0.1 * i;
    double y = 0.5 * x + 2 + noise(rng);
    if (i < num_outliers) y += (i % 2 ? 1 : -1) * off(rng);
    points.emplace_back(x, y);
  }
  return points;
}

TEST(RobustEstimator, MedianOfSquaresIsTheUpperMiddleSquare) {
  std::vector<double> odd = {3, -1, 2};
  EXPECT_EQ(MedianOfSquares(&odd), 4);
  std::vector<double> even = {1, -4, 2, 3};
  EXPECT_EQ(MedianOfSquares(&even), 9);
  std::vector<double> none;
  EXPECT_EQ(MedianOfSquares(&none), 0);
}

TEST(RobustEstimator, LeastMedianOfSquaresRejectsNearlyHalfTheData) {
  const std::vector<Eigen::Vector2d> points = LineWithOutliers(100, 45);
  UniformSampler sampler(100, 1);
  const LmedsReport<Eigen::Vector2d> report =
      LeastMedianOfSquares(LineEstimator(points), 500, &sampler);
  ASSERT_TRUE(report.success());
  EXPECT_EQ(report.num_trials, 500);
  EXPECT_NEAR(report.best().model[0], 0.5, 0.01);
  EXPECT_NEAR(report.best().model[1], 2.0, 0.05);
  // The median residual is that of a good point: a few noise sigmas.
  EXPECT_LT(std::sqrt(report.best().median_of_squares), 0.03);
}

TEST(RobustEstimator, LeadersAreTheBestModelsSmallestFirst) {
  const std::vector<Eigen::Vector2d> points = LineWithOutliers(50, 10);
  UniformSampler sampler(50, 3);
  const LmedsReport<Eigen::Vector2d> report =
      LeastMedianOfSquares(LineEstimator(points), 200, &sampler, 5);
  ASSERT_EQ(report.leaders.size(), 5u);
  for (size_t i = 1; i < report.leaders.size(); ++i) {
    EXPECT_LE(report.leaders[i - 1].median_of_squares,
              report.leaders[i].median_of_squares);
  }
  // The first leader is the one a single-leader run keeps.
  UniformSampler same(50, 3);
  const LmedsReport<Eigen::Vector2d> single =
      LeastMedianOfSquares(LineEstimator(points), 200, &same);
  EXPECT_EQ(single.best().median_of_squares, report.best().median_of_squares);
  EXPECT_EQ(single.best().model, report.best().model);
}

TEST(RobustEstimator, OneSeedGivesOneResult) {
  const std::vector<Eigen::Vector2d> points = LineWithOutliers(40, 15);
  UniformSampler a(40, 7), b(40, 7), c(40, 8);
  const auto first = LeastMedianOfSquares(LineEstimator(points), 30, &a);
  const auto second = LeastMedianOfSquares(LineEstimator(points), 30, &b);
  const auto other = LeastMedianOfSquares(LineEstimator(points), 30, &c);
  EXPECT_EQ(first.best().model, second.best().model);
  EXPECT_EQ(first.num_degenerate, second.num_degenerate);
  // Thirty samples from another seed pick other pairs.
  EXPECT_NE(first.best().model, other.best().model);
}

TEST(RobustEstimator, RepeatedIndicesAndDegenerateSamplesCountAsTrials) {
  // Points 0 and 1 share x: no line through them.
  const std::vector<Eigen::Vector2d> points = {{1, 1}, {1, 2}, {2, 3}, {3, 4}};
  LineEstimator estimator(points);
  ListSampler sampler({{0, 0}, {0, 1}, {2, 3}});
  const LmedsReport<Eigen::Vector2d> report =
      LeastMedianOfSquares(estimator, 6, &sampler);
  EXPECT_EQ(report.num_trials, 6);
  EXPECT_EQ(report.num_degenerate, 4);
  // A repeated index is never handed to the estimator.
  EXPECT_EQ(estimator.num_estimates, 4);
  ASSERT_TRUE(report.success());
  EXPECT_NEAR(report.best().model[0], 1.0, 1e-12);
}

TEST(RobustEstimator, NothingEstimatedIsNoSuccess) {
  const std::vector<Eigen::Vector2d> points = {{1, 1}, {1, 2}, {1, 3}};
  UniformSampler sampler(3, 1);
  EXPECT_FALSE(
      LeastMedianOfSquares(LineEstimator(points), 50, &sampler).success());
  UniformSampler again(3, 1);
  const RansacReport<Eigen::Vector2d> ransac =
      Ransac(LineEstimator(points), 50, 1.0, &again);
  EXPECT_FALSE(ransac.success);
  EXPECT_TRUE(ransac.inliers.empty());
  EXPECT_EQ(ransac.num_degenerate, 50);
}

TEST(RobustEstimator, RansacFindsTheInliersOfTheBestModel) {
  const std::vector<Eigen::Vector2d> points = LineWithOutliers(100, 60);
  UniformSampler sampler(100, 5);
  const RansacReport<Eigen::Vector2d> report =
      Ransac(LineEstimator(points), 300, 0.05, &sampler);
  ASSERT_TRUE(report.success);
  EXPECT_NEAR(report.model[0], 0.5, 0.01);
  // The 40 points on the line, no outlier (they are 5 or more off).
  std::set<int> inliers(report.inliers.begin(), report.inliers.end());
  EXPECT_EQ(inliers.size(), report.inliers.size());
  EXPECT_EQ(report.inliers.size(), 40u);
  EXPECT_EQ(*inliers.begin(), 60);
}

TEST(RobustEstimator, RansacKeepsTheFirstOfEqualModels) {
  // Two lines of two points each: y = x through 0 and 1, y = -x + 10
  // through 2 and 3; each has two inliers.
  const std::vector<Eigen::Vector2d> points = {{0, 0}, {1, 1}, {2, 8}, {3, 7}};
  ListSampler sampler({{2, 3}, {0, 1}});
  const RansacReport<Eigen::Vector2d> report =
      Ransac(LineEstimator(points), 2, 1e-9, &sampler);
  ASSERT_TRUE(report.success);
  EXPECT_EQ(report.inliers, std::vector<int>({2, 3}));
  EXPECT_NEAR(report.model[0], -1.0, 1e-12);
}

}  // namespace
}  // namespace bayon
