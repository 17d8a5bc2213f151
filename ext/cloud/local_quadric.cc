// SPDX-License-Identifier: BSD-3-Clause
#include "ext/cloud/local_quadric.h"

#include "ext/core/errors.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace bayon {
namespace {

// Smallest eigenvalue over largest of the normal matrix (in the scaled
// coordinates) below which its solution is not trusted.
constexpr double kMinConditioning = 1e-9;

// Weighted least squares for the first P coefficients (P = 6 quadric, 3
// plane) in coordinates scaled by `scale`, over the neighbours with
// `use[j]`; fills the patch (and `residuals`) and returns true unless the
// normal matrix is too poorly conditioned.
template <int P>
bool SolvePatch(const std::vector<Eigen::Vector3d>& local,
                const std::vector<Eigen::Matrix<double, 6, 1>>& rows,
                const std::vector<double>& weights,
                const std::vector<bool>& use,
                double scale,
                QuadricPatch* patch,
                std::vector<double>* residuals) {
  using Vector = Eigen::Matrix<double, P, 1>;
  using Matrix = Eigen::Matrix<double, P, P>;
  const int m = static_cast<int>(local.size());
  Matrix normal = Matrix::Zero();
  Vector rhs = Vector::Zero();
  for (int j = 0; j < m; ++j) {
    if (!use[j]) continue;
    const Vector a = rows[j].template head<P>();
    normal.noalias() += weights[j] * a * a.transpose();
    rhs += weights[j] * local[j].z() * a;
  }
  const Eigen::LDLT<Matrix> ldlt(normal);
  if (ldlt.info() != Eigen::Success) return false;
  // The pivots bound the conditioning: a neighbourhood too narrow for the
  // second-order terms (or a plane's slope) leaves a pivot near zero.
  const auto pivots = ldlt.vectorD();
  if (!(pivots.minCoeff() > kMinConditioning * pivots.maxCoeff())) {
    return false;
  }
  const Vector c = ldlt.solve(rhs);
  const Matrix inverse = ldlt.solve(Matrix::Identity());

  std::vector<double> weighted_squares;
  weighted_squares.reserve(m);
  residuals->resize(m);
  for (int j = 0; j < m; ++j) {
    (*residuals)[j] = local[j].z() - rows[j].template head<P>().dot(c);
    if (use[j]) {
      weighted_squares.push_back(weights[j] * (*residuals)[j] *
                                 (*residuals)[j]);
    }
  }
  const size_t used = weighted_squares.size();
  std::nth_element(weighted_squares.begin(),
                   weighted_squares.begin() + used / 2,
                   weighted_squares.end());
  patch->variance_factor = weighted_squares[used / 2] / kChiSquare1Median /
                           (1.0 - static_cast<double>(P) / used);
  patch->c0_variance = inverse(0, 0);
  // Back from the scaled coordinates: c = D c_scaled.
  Vector unscale;
  const double unscale_all[6] = {1,
                                 1 / scale,
                                 1 / scale,
                                 1 / (scale * scale),
                                 1 / (scale * scale),
                                 1 / (scale * scale)};
  for (int k = 0; k < P; ++k) unscale(k) = unscale_all[k];
  patch->covariance.setZero();
  patch->covariance.template topLeftCorner<P, P>() =
      unscale.asDiagonal() * inverse * unscale.asDiagonal();
  patch->coefficients.setZero();
  patch->coefficients.template head<P>() = c;
  // Back from the scaled coordinates.
  patch->coefficients(1) /= scale;
  patch->coefficients(2) /= scale;
  patch->coefficients.template tail<3>() /= scale * scale;
  patch->num_parameters = P;
  patch->valid = true;
  return true;
}

// Principal axes of the points with use[j] (see PrincipalAxes).
void SelectedPrincipalAxes(const std::vector<Eigen::Vector3d>& points,
                           const std::vector<bool>& use,
                           Eigen::Matrix3d* axes,
                           Eigen::Vector3d* eigenvalues) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  int count = 0;
  for (size_t j = 0; j < points.size(); ++j) {
    if (use[j]) {
      mean += points[j];
      ++count;
    }
  }
  mean /= std::max(count, 1);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (size_t j = 0; j < points.size(); ++j) {
    if (!use[j]) continue;
    const Eigen::Vector3d d = points[j] - mean;
    covariance += d * d.transpose();
  }
  covariance /= std::max(count, 1);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  // Eigen sorts increasing; the frame wants largest first, normal last.
  for (int k = 0; k < 3; ++k) {
    axes->col(k) = solver.eigenvectors().col(2 - k);
    (*eigenvalues)(k) = std::max(0.0, solver.eigenvalues()(2 - k));
  }
  axes->col(2) = axes->col(0).cross(axes->col(1));  // right-handed
}

// A right-handed frame whose third axis is n.
Eigen::Matrix3d FrameAround(const Eigen::Vector3d& n) {
  int axis = 0;
  n.cwiseAbs().minCoeff(&axis);
  const Eigen::Vector3d t1 = n.cross(Eigen::Vector3d::Unit(axis)).normalized();
  Eigen::Matrix3d frame;
  frame << t1, n.cross(t1), n;
  return frame;
}

// One least-squares patch over the neighbours with use[j]: frame, local
// coordinates, weights, then the quadric or, failing that, the plane.
bool FitOnce(const Eigen::Vector3d& query,
             const std::vector<Eigen::Vector3d>& neighbors,
             const std::vector<Eigen::Vector3d>& sigmas,
             const Eigen::Vector3d& normal,
             const std::vector<bool>& use,
             QuadricPatch* patch,
             std::vector<double>* prior_weights,
             std::vector<double>* residuals) {
  const int m = static_cast<int>(neighbors.size());
  const int used = static_cast<int>(std::count(use.begin(), use.end(), true));
  patch->valid = false;
  patch->num_points = used;
  if (used < 5) return false;
  if (normal.squaredNorm() > 0) {
    patch->frame = FrameAround(normal.normalized());
  } else {
    Eigen::Vector3d eigenvalues;
    SelectedPrincipalAxes(neighbors, use, &patch->frame, &eigenvalues);
    if (!(eigenvalues(1) > 1e-12 * eigenvalues(0))) return false;  // a line
  }
  const Eigen::Vector3d n = patch->frame.col(2);

  // Local coordinates, u and v scaled to about [-1, 1] so that the normal
  // matrix stays well conditioned whatever the point spacing.
  std::vector<Eigen::Vector3d> local(m);
  double scale = 0;
  for (int j = 0; j < m; ++j) {
    local[j] = patch->frame.transpose() * (neighbors[j] - query);
    if (use[j]) {
      scale = std::max({scale, std::abs(local[j].x()), std::abs(local[j].y())});
    }
  }
  if (!(scale > 0)) return false;
  prior_weights->assign(m, 1.0);
  if (!sigmas.empty()) {
    for (int j = 0; j < m; ++j) {
      (*prior_weights)[j] = 1.0 / VarianceAlong(n, sigmas[j]);
    }
  }
  std::vector<Eigen::Matrix<double, 6, 1>> rows(m);
  for (int j = 0; j < m; ++j) {
    const double u = local[j].x() / scale, v = local[j].y() / scale;
    rows[j] << 1, u, v, u * u, u * v, v * v;
  }
  if (used >= 9 &&
      SolvePatch<6>(
          local, rows, *prior_weights, use, scale, patch, residuals)) {
    return true;
  }
  return used >= 6 &&
         SolvePatch<3>(
             local, rows, *prior_weights, use, scale, patch, residuals);
}

}  // namespace

void PrincipalAxes(const std::vector<Eigen::Vector3d>& points,
                   Eigen::Matrix3d* axes,
                   Eigen::Vector3d* eigenvalues) {
  SelectedPrincipalAxes(
      points, std::vector<bool>(points.size(), true), axes, eigenvalues);
}

Eigen::Vector3d MeanAxis(const std::vector<Eigen::Vector3d>& normals) {
  if (normals.empty()) return Eigen::Vector3d::Zero();
  Eigen::Matrix3d tensor = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& n : normals) tensor += n * n.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(tensor);
  return solver.eigenvectors().col(2);
}

namespace {

Eigen::Matrix<double, 6, 1> Monomials(double u, double v) {
  Eigen::Matrix<double, 6, 1> a;
  a << 1, u, v, u * u, u * v, v * v;
  return a;
}

}  // namespace

double QuadricPatch::Deviation(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d local = frame.transpose() * (point - origin);
  const double u = local.x(), v = local.y();
  const Eigen::Matrix<double, 6, 1>& c = coefficients;
  const double height = Monomials(u, v).dot(c);
  const double du = c(1) + 2 * c(3) * u + c(4) * v;
  const double dv = c(2) + c(4) * u + 2 * c(5) * v;
  return (local.z() - height) / std::sqrt(1 + du * du + dv * dv);
}

double QuadricPatch::HeightVariance(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d local = frame.transpose() * (point - origin);
  const Eigen::Matrix<double, 6, 1> a = Monomials(local.x(), local.y());
  return a.dot(covariance * a);
}

double QuadricPatch::QueryDeviation() const {
  const double slope2 =
      coefficients(1) * coefficients(1) + coefficients(2) * coefficients(2);
  return -coefficients(0) / std::sqrt(1.0 + slope2);
}

void QuadricFitOptions::Check() const {
  CheckOption(robust_rounds >= 0 && robust_rounds <= 10,
              "QuadricFitOptions.robust_rounds",
              "in [0, 10]",
              robust_rounds);
  CheckOption(rejection_sigma > 0,
              "QuadricFitOptions.rejection_sigma",
              "> 0",
              rejection_sigma);
}

QuadricPatch FitQuadricPatch(const Eigen::Vector3d& query,
                             const std::vector<Eigen::Vector3d>& neighbors,
                             const std::vector<Eigen::Vector3d>& sigmas,
                             const Eigen::Vector3d& normal,
                             const QuadricFitOptions& options) {
  QuadricPatch patch;
  const int m = static_cast<int>(neighbors.size());
  std::vector<bool> use(m, true);
  std::vector<double> prior_weights, residuals;
  if (!FitOnce(query,
               neighbors,
               sigmas,
               normal,
               use,
               &patch,
               &prior_weights,
               &residuals)) {
    return QuadricPatch{};
  }
  for (int round = 0; round < options.robust_rounds; ++round) {
    // The scale of the standardised residuals: the robust variance factor,
    // never below the stated precision when there is one.
    double variance = patch.variance_factor;
    if (!sigmas.empty()) variance = std::max(variance, 1.0);
    const double limit2 =
        options.rejection_sigma * options.rejection_sigma * variance;
    std::vector<bool> next(m);
    for (int j = 0; j < m; ++j) {
      next[j] = prior_weights[j] * residuals[j] * residuals[j] <= limit2;
    }
    if (next == use) break;
    QuadricPatch refit;
    std::vector<double> refit_weights, refit_residuals;
    if (!FitOnce(query,
                 neighbors,
                 sigmas,
                 normal,
                 next,
                 &refit,
                 &refit_weights,
                 &refit_residuals)) {
      break;  // too few left: keep the last good fit
    }
    use = std::move(next);
    patch = refit;
    prior_weights = std::move(refit_weights);
    residuals = std::move(refit_residuals);
  }
  patch.num_rejected = m - patch.num_points;
  patch.origin = query;
  return patch;
}

}  // namespace bayon
