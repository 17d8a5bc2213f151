// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/resection.h"

#include "ext/core/robust_estimator.h"

#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

namespace bayon {
namespace {

// Collinearity in normalised coordinates: x_cam = R X + t, observed
// (x/z, y/z). Blocks: quaternion (w, x, y, z) 4, translation 3.
struct NormalisedCollinearity {
  NormalisedCollinearity(const Eigen::Vector2d& xy, const Eigen::Vector3d& X)
      : xy_(xy), X_(X) {}
  template <typename T>
  bool operator()(const T* q, const T* t, T* residual) const {
    const T X[3] = {T(X_.x()), T(X_.y()), T(X_.z())};
    T p[3];
    ceres::UnitQuaternionRotatePoint(q, X, p);
    p[0] += t[0];
    p[1] += t[1];
    p[2] += t[2];
    if (p[2] <= T(0)) return false;
    residual[0] = p[0] / p[2] - T(xy_.x());
    residual[1] = p[1] / p[2] - T(xy_.y());
    return true;
  }
  Eigen::Vector2d xy_;
  Eigen::Vector3d X_;
};

double Error(const Rigid3d& cam_from_world,
             const Eigen::Vector2d& xy,
             const Eigen::Vector3d& X) {
  const Eigen::Vector3d p = cam_from_world * X;
  if (p.z() <= 0) return std::numeric_limits<double>::infinity();
  return (p.head<2>() / p.z() - xy).norm();
}

// The DLT of the points `idx` (6 or more), the 3D points centred and scaled
// for conditioning; the rotation is the nearest one to the left 3 x 3 block.
std::optional<Rigid3d> Dlt(const std::vector<Eigen::Vector2d>& xy,
                           const std::vector<Eigen::Vector3d>& X,
                           const std::vector<int>& idx) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int i : idx) centre += X[i];
  centre /= static_cast<double>(idx.size());
  double spread = 0;
  for (int i : idx) spread += (X[i] - centre).norm();
  spread /= static_cast<double>(idx.size());
  if (!(spread > 0)) return std::nullopt;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * idx.size(), 12);
  for (size_t k = 0; k < idx.size(); ++k) {
    const Eigen::Vector4d Xh = ((X[idx[k]] - centre) / spread).homogeneous();
    const double u = xy[idx[k]].x(), v = xy[idx[k]].y();
    A.block<1, 4>(2 * k, 0) = Xh.transpose();
    A.block<1, 4>(2 * k, 8) = -u * Xh.transpose();
    A.block<1, 4>(2 * k + 1, 4) = Xh.transpose();
    A.block<1, 4>(2 * k + 1, 8) = -v * Xh.transpose();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd p = svd.matrixV().col(11);
  Eigen::Matrix<double, 3, 4> P;
  P << p.segment<4>(0).transpose(), p.segment<4>(4).transpose(),
      p.segment<4>(8).transpose();
  Eigen::Matrix3d M = P.leftCols<3>();
  if (M.determinant() < 0) {
    P = -P;
    M = -M;
  }
  // (A dynamic-size SVD: GCC 12 warns falsely on the fixed-size one.)
  const Eigen::JacobiSVD<Eigen::MatrixXd> m_svd(
      Eigen::MatrixXd(M), Eigen::ComputeFullU | Eigen::ComputeFullV);
  const double lambda = m_svd.singularValues().mean();
  if (!(lambda > 0)) return std::nullopt;
  const Eigen::Matrix3d R = m_svd.matrixU() * m_svd.matrixV().transpose();
  if (R.determinant() < 0) return std::nullopt;
  // x ~ R (X - centre) / spread + t  =>  t_world = spread t - R centre.
  const Eigen::Vector3d t = P.col(3) / lambda;
  return Rigid3d(Eigen::Quaterniond(R).normalized(), spread * t - R * centre);
}

// Gauss-Newton from `pose` on the points within `loss_scale` (Cauchy loss).
Rigid3d Refine(const std::vector<Eigen::Vector2d>& xy,
               const std::vector<Eigen::Vector3d>& X,
               const Rigid3d& pose,
               double loss_scale) {
  const Eigen::Quaterniond q0 = pose.rotation.normalized();
  double q[4] = {q0.w(), q0.x(), q0.y(), q0.z()};
  double t[3] = {
      pose.translation.x(), pose.translation.y(), pose.translation.z()};
  ceres::Problem problem;
  for (size_t i = 0; i < xy.size(); ++i) {
    if ((pose * X[i]).z() <= 0) continue;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<NormalisedCollinearity, 2, 4, 3>(
            new NormalisedCollinearity(xy[i], X[i])),
        new ceres::CauchyLoss(loss_scale),
        q,
        t);
  }
  if (problem.NumResidualBlocks() == 0) return pose;
  problem.SetManifold(q, new ceres::QuaternionManifold);
  ceres::Solver::Options options;
  options.max_num_iterations = 50;
  options.linear_solver_type = ceres::DENSE_QR;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return Rigid3d(Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized(),
                 Eigen::Vector3d(t[0], t[1], t[2]));
}

// The DLT's pose of six points, and every point's reprojection error
// (infinite behind the camera).
class DltEstimator {
 public:
  using Model = Rigid3d;
  static constexpr int kMinNumSamples = 6;

  DltEstimator(const std::vector<Eigen::Vector2d>& xy,
               const std::vector<Eigen::Vector3d>& X)
      : xy_(xy), X_(X) {}

  bool Estimate(const std::vector<int>& sample, Rigid3d* pose) const {
    const std::optional<Rigid3d> estimate = Dlt(xy_, X_, sample);
    if (estimate) *pose = *estimate;
    return estimate.has_value();
  }

  void Residuals(const Rigid3d& pose, std::vector<double>* errors) const {
    errors->resize(xy_.size());
    for (size_t i = 0; i < xy_.size(); ++i) {
      (*errors)[i] = Error(pose, xy_[i], X_[i]);
    }
  }

 private:
  const std::vector<Eigen::Vector2d>& xy_;
  const std::vector<Eigen::Vector3d>& X_;
};

// Samples without repetition: the first `size` of a permutation by a partial
// Fisher-Yates shuffle, the permutation kept from one sample to the next.
class ShuffleSampler {
 public:
  ShuffleSampler(int num_data, uint64_t seed) : rng_(seed), order_(num_data) {
    std::iota(order_.begin(), order_.end(), 0);
  }

  void Sample(int size, std::vector<int>* sample) {
    const int n = static_cast<int>(order_.size());
    for (int k = 0; k < size; ++k) {
      std::swap(order_[k], order_[k + rng_() % (n - k)]);
    }
    sample->assign(order_.begin(), order_.begin() + size);
  }

 private:
  std::mt19937_64 rng_;
  std::vector<int> order_;
};

}  // namespace

std::optional<Resection> ResectImage(
    const std::vector<Eigen::Vector2d>& image_xy,
    const std::vector<Eigen::Vector3d>& points,
    const Rigid3d* guess,
    const ResectionOptions& options) {
  const int n = static_cast<int>(image_xy.size());
  if (n < std::max(options.min_inliers, 6)) return std::nullopt;
  std::vector<Rigid3d> candidates;
  if (guess != nullptr) candidates.push_back(*guess);
  ShuffleSampler sampler(n, options.seed);
  const RansacReport<Rigid3d> dlt = Ransac(DltEstimator(image_xy, points),
                                           options.num_samples,
                                           options.max_error,
                                           &sampler);
  if (dlt.success && dlt.inliers.size() >= 6) candidates.push_back(dlt.model);

  std::optional<Resection> best;
  for (const Rigid3d& start : candidates) {
    // Two rounds: robust from the approximation, then again from there
    // with the loss at the inlier limit.
    Rigid3d pose = Refine(image_xy, points, start, 10 * options.max_error);
    pose = Refine(image_xy, points, pose, options.max_error);
    Resection result;
    result.cam_from_world = pose;
    result.inliers.assign(n, false);
    double sum = 0;
    for (int i = 0; i < n; ++i) {
      const double error = Error(pose, image_xy[i], points[i]);
      if (error <= options.max_error) {
        result.inliers[i] = true;
        ++result.num_inliers;
        sum += error * error;
      }
    }
    if (result.num_inliers < options.min_inliers) continue;
    result.rms_error = std::sqrt(sum / result.num_inliers);
    if (!best || result.num_inliers > best->num_inliers) best = result;
  }
  return best;
}

}  // namespace bayon
