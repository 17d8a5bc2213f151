// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// One robust estimator for every model fitted to data with blunders: least
// median of squares (Rousseeuw 1984; the paper's eq. 2) and RANSAC
// (Fischler and Bolles 1981), both over a fixed number of random minimal
// samples, in COLMAP's shape (estimator, sampler, report).
//
// An Estimator fits one model to a minimal sample and measures every datum
// against a model:
//
//   struct LineEstimator {
//     using Model = Eigen::Vector2d;
//     static constexpr int kMinNumSamples = 2;
//     // false: the sample is degenerate (no model, or not a unique one).
//     bool Estimate(const std::vector<int>& sample, Model* model) const;
//     // One residual per datum, in the data's order; its sign is not used.
//     void Residuals(const Model& model, std::vector<double>* residuals) const;
//   };
//
// A Sampler draws the indices of one sample: `void Sample(int size,
// std::vector<int>* sample)`. UniformSampler draws them independently, so a
// sample may hold an index twice: such a sample is not estimated but counts
// as a trial. The number of trials is fixed rather than adapted to the
// inlier ratio found so far, so that a seed gives the same result however
// the data are ordered in time.

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace bayon {

// Indices drawn uniformly and independently from [0, num_data).
class UniformSampler {
 public:
  UniformSampler(int num_data, unsigned int seed)
      : rng_(seed), pick_(0, std::max(num_data, 1) - 1) {}

  void Sample(int size, std::vector<int>* sample) {
    sample->resize(size);
    for (int& index : *sample) index = pick_(rng_);
  }

 private:
  std::mt19937 rng_;
  std::uniform_int_distribution<int> pick_;
};

template <typename Model>
struct LmedsReport {
  struct Leader {
    double median_of_squares = 0;  // of the residuals
    Model model;
  };
  // The best models, the smallest median first; at most num_leaders.
  std::vector<Leader> leaders;
  int num_trials = 0;
  int num_degenerate = 0;  // samples with a repeated index or no model

  bool success() const { return !leaders.empty(); }
  const Leader& best() const { return leaders.front(); }
};

template <typename Model>
struct RansacReport {
  bool success = false;
  Model model{};
  std::vector<int> inliers;  // residual <= max_residual, in the data's order
  int num_trials = 0;
  int num_degenerate = 0;
};

namespace internal {

inline bool HasRepeatedIndex(const std::vector<int>& sample) {
  for (size_t i = 1; i < sample.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      if (sample[i] == sample[j]) return true;
    }
  }
  return false;
}

// Draws one sample and estimates its model; false for a degenerate one.
template <typename Estimator, typename Sampler>
bool EstimateFromSample(const Estimator& estimator,
                        Sampler* sampler,
                        std::vector<int>* sample,
                        typename Estimator::Model* model) {
  sampler->Sample(Estimator::kMinNumSamples, sample);
  return !HasRepeatedIndex(*sample) && estimator.Estimate(*sample, model);
}

}  // namespace internal

// The median of the squared residuals, the upper one for an even number.
inline double MedianOfSquares(std::vector<double>* residuals) {
  if (residuals->empty()) return 0;
  for (double& r : *residuals) r *= r;
  const auto mid = residuals->begin() + residuals->size() / 2;
  std::nth_element(residuals->begin(), mid, residuals->end());
  return *mid;
}

// The models of num_trials samples with the smallest medians of squared
// residuals, the best num_leaders of them kept for a caller that refines
// more than one (relative orientation polishes several, since a loose
// minimal solution can beat every sample of good points).
template <typename Estimator, typename Sampler>
LmedsReport<typename Estimator::Model> LeastMedianOfSquares(
    const Estimator& estimator,
    int num_trials,
    Sampler* sampler,
    int num_leaders = 1) {
  using Report = LmedsReport<typename Estimator::Model>;
  Report report;
  std::vector<int> sample;
  std::vector<double> residuals;
  typename Estimator::Model model;
  const size_t max_leaders = static_cast<size_t>(std::max(num_leaders, 1));
  for (; report.num_trials < num_trials; ++report.num_trials) {
    if (!internal::EstimateFromSample(estimator, sampler, &sample, &model)) {
      ++report.num_degenerate;
      continue;
    }
    estimator.Residuals(model, &residuals);
    const double median = MedianOfSquares(&residuals);
    if (!std::isfinite(median)) continue;
    auto& leaders = report.leaders;
    if (leaders.size() < max_leaders ||
        median < leaders.back().median_of_squares) {
      if (leaders.size() == max_leaders) leaders.pop_back();
      leaders.push_back({median, model});
      std::sort(
          leaders.begin(), leaders.end(), [](const auto& a, const auto& b) {
            return a.median_of_squares < b.median_of_squares;
          });
    }
  }
  return report;
}

// The model of num_trials samples with the most inliers (the first of
// equals).
template <typename Estimator, typename Sampler>
RansacReport<typename Estimator::Model> Ransac(const Estimator& estimator,
                                               int num_trials,
                                               double max_residual,
                                               Sampler* sampler) {
  RansacReport<typename Estimator::Model> report;
  std::vector<int> sample;
  std::vector<int> inliers;
  std::vector<double> residuals;
  typename Estimator::Model model;
  for (; report.num_trials < num_trials; ++report.num_trials) {
    if (!internal::EstimateFromSample(estimator, sampler, &sample, &model)) {
      ++report.num_degenerate;
      continue;
    }
    estimator.Residuals(model, &residuals);
    inliers.clear();
    for (size_t i = 0; i < residuals.size(); ++i) {
      if (std::abs(residuals[i]) <= max_residual) {
        inliers.push_back(static_cast<int>(i));
      }
    }
    if (!report.success || inliers.size() > report.inliers.size()) {
      report.success = true;
      report.model = model;
      report.inliers = inliers;
    }
  }
  return report;
}

}  // namespace bayon
