// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/alignment.h"

#include "ext/core/robust_estimator.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace bayon {

std::optional<Sim3d> EstimateSim3d(const std::vector<Eigen::Vector3d>& src,
                                   const std::vector<Eigen::Vector3d>& dst,
                                   const std::vector<double>& weights) {
  const size_t n = src.size();
  if (n < 3 || dst.size() != n || (!weights.empty() && weights.size() != n)) {
    return std::nullopt;
  }
  double weight_sum = 0;
  Eigen::Vector3d src_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d dst_mean = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    weight_sum += w;
    src_mean += w * src[i];
    dst_mean += w * dst[i];
  }
  if (!(weight_sum > 0)) return std::nullopt;
  src_mean /= weight_sum;
  dst_mean /= weight_sum;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double src_variance = 0;
  for (size_t i = 0; i < n; ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    const Eigen::Vector3d a = src[i] - src_mean;
    const Eigen::Vector3d b = dst[i] - dst_mean;
    covariance += w * b * a.transpose();
    src_variance += w * a.squaredNorm();
  }
  covariance /= weight_sum;
  src_variance /= weight_sum;
  if (!(src_variance > 0)) return std::nullopt;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(
      covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d singular = svd.singularValues();
  // Collinear points leave the rotation about their line undetermined.
  if (singular(1) <= 1e-12 * std::max(singular(0), 1e-300)) return std::nullopt;
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) {
    s(2, 2) = -1;
  }
  const Eigen::Matrix3d rotation =
      svd.matrixU() * s * svd.matrixV().transpose();
  const double scale = (singular.asDiagonal() * s).trace() / src_variance;
  Sim3d result;
  result.scale = scale;
  result.rotation = Eigen::Quaterniond(rotation).normalized();
  result.translation = dst_mean - scale * (rotation * src_mean);
  return result;
}

namespace {

// The similarity of three point pairs, and every pair's distance under it.
class Sim3dEstimator {
 public:
  using Model = Sim3d;
  static constexpr int kMinNumSamples = 3;

  Sim3dEstimator(const std::vector<Eigen::Vector3d>& src,
                 const std::vector<Eigen::Vector3d>& dst)
      : src_(src), dst_(dst) {}

  bool Estimate(const std::vector<int>& sample, Sim3d* model) const {
    const std::optional<Sim3d> estimate =
        EstimateSim3d({src_[sample[0]], src_[sample[1]], src_[sample[2]]},
                      {dst_[sample[0]], dst_[sample[1]], dst_[sample[2]]});
    if (estimate) *model = *estimate;
    return estimate.has_value();
  }

  void Residuals(const Sim3d& model, std::vector<double>* residuals) const {
    residuals->resize(src_.size());
    for (size_t i = 0; i < src_.size(); ++i) {
      (*residuals)[i] = (dst_[i] - model * src_[i]).norm();
    }
  }

 private:
  const std::vector<Eigen::Vector3d>& src_;
  const std::vector<Eigen::Vector3d>& dst_;
};

}  // namespace

RobustSim3dReport EstimateSim3dRobust(const std::vector<Eigen::Vector3d>& src,
                                      const std::vector<Eigen::Vector3d>& dst,
                                      const RobustSim3dOptions& options) {
  RobustSim3dReport report;
  const size_t n = src.size();
  if (n < 3 || dst.size() != n) return report;
  const Sim3dEstimator estimator(src, dst);
  auto residuals_of = [&](const Sim3d& t) {
    std::vector<double> r;
    estimator.Residuals(t, &r);
    return r;
  };

  std::optional<Sim3d> best;
  double best_median = std::numeric_limits<double>::infinity();
  if (n <= 4) {
    // Too few points for a sample to leave any out.
    best = EstimateSim3d(src, dst);
    if (best) {
      std::vector<double> r = residuals_of(*best);
      best_median = MedianOfSquares(&r);
    }
  } else {
    UniformSampler sampler(static_cast<int>(n), options.random_seed);
    const LmedsReport<Sim3d> lmeds =
        LeastMedianOfSquares(estimator, options.num_samples, &sampler);
    if (lmeds.success()) {
      best = lmeds.best().model;
      best_median = lmeds.best().median_of_squares;
    }
  }
  if (!best) return report;

  // Rousseeuw's robust standard deviation with the small-sample correction,
  // the same rule as the paper's equation (4) with p = 3.
  double threshold = options.max_residual;
  if (threshold <= 0) {
    const double sigma = 1.4826 * (1.0 + 5.0 / std::max<double>(1.0, n - 3.0)) *
                         std::sqrt(best_median);
    threshold = std::max(2.5 * sigma, 1e-12);
  }
  std::vector<double> r = residuals_of(*best);
  std::vector<Eigen::Vector3d> src_in, dst_in;
  for (size_t i = 0; i < n; ++i) {
    if (r[i] <= threshold) {
      src_in.push_back(src[i]);
      dst_in.push_back(dst[i]);
    }
  }
  if (src_in.size() >= 3) {
    if (auto refined = EstimateSim3d(src_in, dst_in)) best = refined;
  }
  report.dst_from_src = *best;
  report.residuals = residuals_of(*best);
  report.threshold = threshold;
  report.inlier_mask.resize(n);
  for (size_t i = 0; i < n; ++i) {
    report.inlier_mask[i] = report.residuals[i] <= threshold;
    report.num_inliers += report.inlier_mask[i];
  }
  report.success = report.num_inliers >= 3;
  return report;
}

}  // namespace bayon
