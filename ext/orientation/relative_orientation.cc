// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/relative_orientation.h"

#include "ext/core/errors.h"
#include "ext/core/robust_estimator.h"
#include "ext/core/statistics.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

namespace bayon {

void RelativeOrientationOptions::Register(OptionRegistry* r) {
  r->Add("num_samples", &num_samples, "LMedS random 8-point samples (m)");
  r->Add("blunder_threshold",
         &blunder_threshold,
         "Blunder threshold, robust sigmas");
  r->AddChoice("residual",
               &residual,
               {{"sampson", DrtResidual::kSampson},
                {"algebraic", DrtResidual::kAlgebraic}},
               "sampson or algebraic (eq. 2)");
  r->Add("min_num_inliers",
         &min_num_inliers,
         "Pairs with fewer inliers are not oriented");
  r->Add("max_sigma_px",
         &max_sigma_px,
         "Robust sigma above this: no epipolar geometry, pixels");
  r->Add("min_parallax_px",
         &min_parallax_px,
         "A rotation alone fitting this well: no base, pixels");
  r->Add("seed", &seed, "Random seed of the samples");
}

void RelativeOrientationOptions::Check() const {
  CheckOption(num_samples >= 1,
              "RelativeOrientationOptions.num_samples",
              ">= 1",
              num_samples);
  CheckOption(num_candidates >= 1,
              "RelativeOrientationOptions.num_candidates",
              ">= 1",
              num_candidates);
  CheckOption(blunder_threshold > 0,
              "RelativeOrientationOptions.blunder_threshold",
              "> 0",
              blunder_threshold);
  CheckOption(max_iterations >= 1,
              "RelativeOrientationOptions.max_iterations",
              ">= 1",
              max_iterations);
  CheckOption(max_rounds >= 1,
              "RelativeOrientationOptions.max_rounds",
              ">= 1",
              max_rounds);
  CheckOption(min_num_points >= 9,
              "RelativeOrientationOptions.min_num_points",
              ">= 9 (8 for the DRT and one to check it)",
              min_num_points);
  CheckOption(min_num_inliers >= 6,
              "RelativeOrientationOptions.min_num_inliers",
              ">= 6",
              min_num_inliers);
  CheckOption(max_sigma_px > 0,
              "RelativeOrientationOptions.max_sigma_px",
              "> 0",
              max_sigma_px);
  CheckOption(min_sigma_px >= 0 && min_sigma_px < max_sigma_px,
              "RelativeOrientationOptions.min_sigma_px",
              ">= 0 and < max_sigma_px",
              min_sigma_px);
  CheckOption(min_parallax_sigma0 >= 0,
              "RelativeOrientationOptions.min_parallax_sigma0",
              ">= 0",
              min_parallax_sigma0);
  CheckOption(min_parallax_px >= 0,
              "RelativeOrientationOptions.min_parallax_px",
              ">= 0",
              min_parallax_px);
}

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Matrix3d ExpRotation(const Eigen::Vector3d& theta) {
  const double angle = theta.norm();
  if (angle < 1e-300) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, theta / angle).toRotationMatrix();
}

// Two unit vectors perpendicular to b (and to each other).
void TangentBasis(const Eigen::Vector3d& b,
                  Eigen::Vector3d* e1,
                  Eigen::Vector3d* e2) {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ().cross(b);
  if (axis.norm() < 1e-6) axis = Eigen::Vector3d::UnitX().cross(b);
  *e1 = axis.normalized();
  *e2 = b.cross(*e1);
}

// The scale of eq. (4) from the squared residuals of a model with p
// parameters.
double RobustSigma(const std::vector<double>& residuals, int p) {
  std::vector<double> squared(residuals.size());
  for (size_t i = 0; i < residuals.size(); ++i) {
    squared[i] = residuals[i] * residuals[i];
  }
  const double n = static_cast<double>(residuals.size());
  return 1.48 * (1.0 + 5.0 / std::max(1.0, n - p)) *
         std::sqrt(Median(std::move(squared)));
}

// Scales of the two rays that meet best: lambda1 d1 - lambda2 d2 = b.
Eigen::Vector2d RayScales(const Eigen::Vector3d& d1,
                          const Eigen::Vector3d& d2,
                          const Eigen::Vector3d& b) {
  Eigen::Matrix2d normal;
  normal << d1.dot(d1), -d1.dot(d2), -d1.dot(d2), d2.dot(d2);
  const Eigen::Vector2d rhs(d1.dot(b), -d2.dot(b));
  if (std::abs(normal.determinant()) < 1e-15) {
    return Eigen::Vector2d(-1, -1);  // parallel rays: not in front
  }
  return normal.inverse() * rhs;
}

// s_i: point i's standard deviation relative to the typical point's.
double RelativeSigma(const ConjugatePoints& points, int i) {
  return points.sigma.empty() ? 1.0 : points.sigma[i];
}

struct Adjustment {
  bool converged = false;
  int iterations = 0;
  double sigma0 = 0;
  Eigen::Matrix<double, 5, 5> covariance = Eigen::Matrix<double, 5, 5>::Zero();
};

// Gauss-Helmert adjustment of (R, b) with the coplanarity condition
// F = b . (u1 x R u2) = 0 in the observations x1, y1, x2, y2 of the points
// with mask 1 (pixels; each point's four coordinates with the cofactor
// s_i^2 of its relative standard deviation, 1 where none is given).
Adjustment RefineElements(const ConjugatePoints& points,
                          const std::vector<uint8_t>& mask,
                          int max_iterations,
                          Eigen::Matrix3d* R,
                          Eigen::Vector3d* b) {
  Adjustment result;
  const std::vector<Eigen::Vector3d>& u1 = points.u1;
  const std::vector<Eigen::Vector3d>& u2 = points.u2;
  std::vector<int> used;
  for (size_t i = 0; i < u1.size(); ++i) {
    if (mask[i]) used.push_back(static_cast<int>(i));
  }
  const int n = static_cast<int>(used.size());
  if (n <= 5) return result;
  // Corrections of the observations (x1, y1, x2, y2) per point.
  std::vector<Eigen::Vector4d> v(n, Eigen::Vector4d::Zero());
  Eigen::Matrix<double, 5, 5> N;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    Eigen::Vector3d e1, e2;
    TangentBasis(*b, &e1, &e2);
    N.setZero();
    Eigen::Matrix<double, 5, 1> rhs = Eigen::Matrix<double, 5, 1>::Zero();
    std::vector<Eigen::Matrix<double, 1, 5>> A(n);
    std::vector<Eigen::Vector4d> B(n);
    std::vector<double> w(n), q(n), cofactor(n);
    for (int k = 0; k < n; ++k) {
      const int i = used[k];
      cofactor[k] = RelativeSigma(points, i) * RelativeSigma(points, i);
      const Eigen::Vector3d a1 = u1[i] + Eigen::Vector3d(v[k](0), v[k](1), 0);
      const Eigen::Vector3d a2 = u2[i] + Eigen::Vector3d(v[k](2), v[k](3), 0);
      const Eigen::Vector3d r2 = *R * a2;
      const Eigen::Vector3d b_x_a1 = b->cross(a1);
      const double F = r2.dot(b_x_a1);
      const Eigen::Vector3d dF_da1 = r2.cross(*b);
      const Eigen::Vector3d dF_da2 = R->transpose() * b_x_a1;
      B[k] << dF_da1.x(), dF_da1.y(), dF_da2.x(), dF_da2.y();
      // R(dtheta) = R Exp(dtheta): dF/dtheta = (a2 x q)^T, q = R^T (b x a1).
      A[k].head<3>() = a2.cross(dF_da2).transpose();
      const Eigen::Vector3d a1_x_r2 = a1.cross(r2);
      A[k](3) = e1.dot(a1_x_r2);
      A[k](4) = e2.dot(a1_x_r2);
      // Misclosure against the original observations.
      w[k] = F - B[k].dot(v[k]);
      // The condition's cofactor: s_i^2 B B^T.
      q[k] = cofactor[k] * B[k].squaredNorm();
      if (q[k] <= 0) return result;
      N += A[k].transpose() * A[k] / q[k];
      rhs += A[k].transpose() * w[k] / q[k];
    }
    const Eigen::LDLT<Eigen::Matrix<double, 5, 5>> ldlt(N);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return result;
    const Eigen::Matrix<double, 5, 1> dx = -ldlt.solve(rhs);
    if (!dx.allFinite()) return result;
    double vtpv = 0;
    for (int k = 0; k < n; ++k) {
      const double kk = -(A[k].dot(dx) + w[k]) / q[k];
      v[k] = cofactor[k] * B[k] * kk;
      vtpv += v[k].squaredNorm() / cofactor[k];
    }
    *R = *R * ExpRotation(dx.head<3>());
    *b = (*b + dx(3) * e1 + dx(4) * e2).normalized();
    result.iterations = iteration + 1;
    result.sigma0 = std::sqrt(vtpv / (n - 5));
    // Steps of 1e-10 rad move an image point by 1e-7 px.
    if (dx.norm() < 1e-10) {
      result.converged = true;
      break;
    }
  }
  result.covariance = result.sigma0 * result.sigma0 * N.inverse();
  return result;
}

// The rotation that best maps the rays of image 2 onto those of image 1
// (Kabsch), and its median residual in pixels of image 1.
double RotationOnlyResidual(const std::vector<Eigen::Vector3d>& u1,
                            const std::vector<Eigen::Vector3d>& u2,
                            const std::vector<uint8_t>& mask) {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < u1.size(); ++i) {
    if (mask[i]) H += u2[i].normalized() * u1[i].normalized().transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(
      H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d fix = Eigen::Matrix3d::Identity();
  fix(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant();
  const Eigen::Matrix3d R = svd.matrixV() * fix * svd.matrixU().transpose();
  std::vector<double> residuals;
  for (size_t i = 0; i < u1.size(); ++i) {
    if (!mask[i]) continue;
    const Eigen::Vector3d a = u1[i].normalized();
    const Eigen::Vector3d c = R * u2[i].normalized();
    const double angle = std::atan2(a.cross(c).norm(), a.dot(c));
    residuals.push_back(angle * std::abs(u1[i].z()));
  }
  return Median(residuals);
}

}  // namespace

bool SolveDrtLinear(const std::vector<Eigen::Vector3d>& u1,
                    const std::vector<Eigen::Vector3d>& u2,
                    const std::vector<double>& weights,
                    bool calibrated,
                    Eigen::Matrix3d* M) {
  Eigen::Matrix<double, 9, 9> normal = Eigen::Matrix<double, 9, 9>::Zero();
  int count = 0;
  for (size_t i = 0; i < u1.size(); ++i) {
    if (weights[i] <= 0) continue;
    ++count;
    // Conditioning: the rays scaled to z = -1 (coordinates of order 1).
    const Eigen::Vector3d a1 = u1[i] / std::abs(u1[i].z());
    const Eigen::Vector3d a2 = u2[i] / std::abs(u2[i].z());
    Eigen::Matrix<double, 9, 1> row;
    for (int r = 0; r < 3; ++r) {
      for (int s = 0; s < 3; ++s) row(3 * r + s) = a1(r) * a2(s);
    }
    normal += weights[i] * row * row.transpose();
  }
  if (count < 8) return false;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> eigen(
      normal);
  if (eigen.info() != Eigen::Success) return false;
  const Eigen::Matrix<double, 9, 1> values = eigen.eigenvalues();
  // A second (near-)null direction: the points do not determine M.
  if (values(1) <= 1e-12 * values(8)) return false;
  const Eigen::Matrix<double, 9, 1> m = eigen.eigenvectors().col(0);
  Eigen::Matrix3d raw;
  raw << m(0), m(1), m(2), m(3), m(4), m(5), m(6), m(7), m(8);
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(
      raw, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d s = svd.singularValues();
  if (calibrated) {
    s = Eigen::Vector3d(1, 1, 0);
  } else {
    s(2) = 0;
  }
  *M = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
  const double norm = M->norm();
  if (!(norm > 0)) return false;
  *M /= norm;
  return true;
}

std::vector<double> DrtResiduals(const Eigen::Matrix3d& M,
                                 const std::vector<Eigen::Vector3d>& u1,
                                 const std::vector<Eigen::Vector3d>& u2,
                                 DrtResidual type) {
  std::vector<double> residuals(u1.size());
  Eigen::Matrix3d paper = M;
  if (type == DrtResidual::kAlgebraic && std::abs(M(2, 1)) > 1e-12) {
    paper = M / -M(2, 1);
  }
  for (size_t i = 0; i < u1.size(); ++i) {
    if (type == DrtResidual::kAlgebraic) {
      residuals[i] = u1[i].dot(paper * u2[i]);
      continue;
    }
    const Eigen::Vector3d g1 = M * u2[i];
    const Eigen::Vector3d g2 = M.transpose() * u1[i];
    const double gradient =
        std::sqrt(g1.head<2>().squaredNorm() + g2.head<2>().squaredNorm());
    residuals[i] = gradient > 0 ? u1[i].dot(g1) / gradient : 0;
  }
  return residuals;
}

std::optional<Eigen::Matrix<double, 8, 1>> PaperParameters(
    const Eigen::Matrix3d& M) {
  if (std::abs(M(2, 1)) < 1e-3 * M.norm()) return std::nullopt;
  const Eigen::Matrix3d P = M / -M(2, 1);
  Eigen::Matrix<double, 8, 1> L;
  L << P(1, 0), P(1, 1), P(1, 2), -P(2, 0), -P(2, 2), P(0, 0), P(0, 1), P(0, 2);
  return L;
}

int DecomposeDrt(const Eigen::Matrix3d& M,
                 const std::vector<Eigen::Vector3d>& u1,
                 const std::vector<Eigen::Vector3d>& u2,
                 const std::vector<uint8_t>& mask,
                 Eigen::Matrix3d* R,
                 Eigen::Vector3d* b) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(
      M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
  if (U.determinant() < 0) U.col(2) *= -1;
  if (V.determinant() < 0) V.col(2) *= -1;
  Eigen::Matrix3d W;
  W << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::Matrix3d rotations[2] = {U * W * V.transpose(),
                                        U * W.transpose() * V.transpose()};
  const Eigen::Vector3d t = U.col(2);
  int best = -1;
  for (const Eigen::Matrix3d& rotation : rotations) {
    for (double sign : {1.0, -1.0}) {
      const Eigen::Vector3d base = sign * t;
      int in_front = 0;
      for (size_t i = 0; i < u1.size(); ++i) {
        if (!mask[i]) continue;
        const Eigen::Vector2d scales =
            RayScales(u1[i].normalized(), rotation * u2[i].normalized(), base);
        in_front += scales(0) > 0 && scales(1) > 0;
      }
      if (in_front > best) {
        best = in_front;
        *R = rotation;
        *b = base.normalized();
      }
    }
  }
  return best;
}

Eigen::Matrix3d RotationFromOmegaPhiKappa(const Eigen::Vector3d& opk) {
  return (Eigen::AngleAxisd(opk(0), Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(opk(1), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(opk(2), Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

Eigen::Vector3d OmegaPhiKappaFromRotation(const Eigen::Matrix3d& R) {
  const double phi = std::asin(std::clamp(R(0, 2), -1.0, 1.0));
  const double omega = std::atan2(-R(1, 2), R(2, 2));
  const double kappa = std::atan2(-R(0, 1), R(0, 0));
  return Eigen::Vector3d(omega, phi, kappa);
}

void ElementsFromCam2FromCam1(const Rigid3d& cam2_from_cam1,
                              Eigen::Matrix3d* R,
                              Eigen::Vector3d* b) {
  const Eigen::Matrix3d D = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Matrix3d Rc = cam2_from_cam1.rotation.toRotationMatrix();
  *R = D * Rc.transpose() * D;
  const Eigen::Vector3d center2 =
      -(Rc.transpose() * cam2_from_cam1.translation);
  *b = (D * center2).normalized();
}

Rigid3d Cam2FromCam1FromElements(const Eigen::Matrix3d& R,
                                 const Eigen::Vector3d& b) {
  const Eigen::Matrix3d D = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Matrix3d Rc = D * R.transpose() * D;
  const Eigen::Vector3d center2 = D * b.normalized();
  return Rigid3d(Eigen::Quaterniond(Rc).normalized(), -(Rc * center2));
}

Rigid3d RelativeOrientation::Cam2FromCam1() const {
  return Cam2FromCam1FromElements(rotation, base);
}

namespace {

// The points grouped by where they lie in image 1, on a grid x grid
// partition of their bounding box; empty buckets are dropped.
std::vector<std::vector<int>> Buckets(const ConjugatePoints& points, int grid) {
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const Eigen::Vector3d& u : points.u1) {
    lo = lo.cwiseMin(u.head<2>());
    hi = hi.cwiseMax(u.head<2>());
  }
  const Eigen::Vector2d size = (hi - lo).cwiseMax(1e-9);
  std::vector<std::vector<int>> cells(grid * grid);
  for (int i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d f = (points.u1[i].head<2>() - lo).cwiseQuotient(size);
    const int cx = std::min(grid - 1, static_cast<int>(f.x() * grid));
    const int cy = std::min(grid - 1, static_cast<int>(f.y() * grid));
    cells[cy * grid + cx].push_back(i);
  }
  std::vector<std::vector<int>> buckets;
  for (auto& cell : cells) {
    if (!cell.empty()) buckets.push_back(std::move(cell));
  }
  return buckets;
}

// Samples from different buckets (a bucket chosen with a probability
// proportional to its number of points), as Zhang et al. (1995) draw their
// LMedS samples: spread samples give well-conditioned 8-point solutions,
// which matters most for narrow-angle images. With fewer buckets than
// points in a sample, points are drawn uniformly.
class SpreadSampler {
 public:
  SpreadSampler(std::vector<std::vector<int>> buckets, unsigned int seed)
      : buckets_(std::move(buckets)), rng_(seed) {
    for (const auto& bucket : buckets_) num_points_ += bucket.size();
  }

  void Sample(int size, std::vector<int>* sample) {
    sample->clear();
    std::uniform_int_distribution<size_t> pick(0, num_points_ - 1);
    const bool spread = buckets_.size() >= static_cast<size_t>(size);
    std::vector<size_t> used_buckets;
    while (static_cast<int>(sample->size()) < size) {
      // The bucket that contains the k-th point.
      size_t k = pick(rng_), b = 0;
      while (k >= buckets_[b].size()) {
        k -= buckets_[b].size();
        ++b;
      }
      if (spread && std::find(used_buckets.begin(), used_buckets.end(), b) !=
                        used_buckets.end()) {
        continue;
      }
      const int i = buckets_[b][k];
      if (std::find(sample->begin(), sample->end(), i) != sample->end()) {
        continue;
      }
      used_buckets.push_back(b);
      sample->push_back(i);
    }
  }

 private:
  std::vector<std::vector<int>> buckets_;
  size_t num_points_ = 0;
  std::mt19937 rng_;
};

// r_i / s_i: the residuals of points of different precision on one scale,
// that of the typical point (pixels).
std::vector<double> StandardizedResiduals(const Eigen::Matrix3d& M,
                                          const ConjugatePoints& points,
                                          DrtResidual type) {
  std::vector<double> residuals = DrtResiduals(M, points.u1, points.u2, type);
  for (size_t i = 0; i < residuals.size(); ++i) {
    residuals[i] /= RelativeSigma(points, static_cast<int>(i));
  }
  return residuals;
}

// The median of the squared residuals of M over all points (eq. 2).
double DrtMedianOfSquares(const Eigen::Matrix3d& M,
                          const ConjugatePoints& points,
                          DrtResidual type) {
  std::vector<double> residuals = StandardizedResiduals(M, points, type);
  return MedianOfSquares(&residuals);
}

// The DRT's M of eight points (eq. 1, linear), and every point's
// standardized residual.
class DrtEstimator {
 public:
  using Model = Eigen::Matrix3d;
  static constexpr int kMinNumSamples = 8;

  DrtEstimator(const ConjugatePoints& points,
               const RelativeOrientationOptions& options)
      : points_(points), options_(options), weights_(points.size(), 0.0) {}

  bool Estimate(const std::vector<int>& sample, Model* M) const {
    for (int i : sample) weights_[i] = 1.0;
    const bool solved = SolveDrtLinear(
        points_.u1, points_.u2, weights_, options_.calibrated, M);
    for (int i : sample) weights_[i] = 0.0;
    return solved;
  }

  void Residuals(const Model& M, std::vector<double>* residuals) const {
    *residuals = StandardizedResiduals(M, points_, options_.residual);
  }

 private:
  const ConjugatePoints& points_;
  const RelativeOrientationOptions& options_;
  mutable std::vector<double> weights_;  // 1 for the sample's points
};

Eigen::Matrix3d WeightedDrt(const ConjugatePoints& points,
                            const std::vector<uint8_t>& mask,
                            const RelativeOrientationOptions& options,
                            const Eigen::Matrix3d& lmeds_M);

// LMedS over random 8-point samples (eqs. 2 and 4): the best M and its
// minimal median of squared residuals. An 8-point solution from noisy
// points of a narrow-angle pair is so loose that a wrong model can have a
// smaller median than any sample of good points; so the most promising
// samples are each improved once by the weighted solution from the points
// they accept (the "local optimisation" of Chum, Matas and Kittler 2003,
// LO-RANSAC) before the minimum is taken.
struct LmedsCandidate {
  double median = 0;  // of the squared residuals
  Eigen::Matrix3d M;
};

std::vector<LmedsCandidate> DrtLeastMedianOfSquares(
    const ConjugatePoints& points, const RelativeOrientationOptions& options) {
  const int n = points.size();
  SpreadSampler sampler(Buckets(points, 8), options.seed);
  const LmedsReport<Eigen::Matrix3d> lmeds =
      LeastMedianOfSquares(DrtEstimator(points, options),
                           options.num_samples,
                           &sampler,
                           options.num_candidates);
  std::vector<LmedsCandidate> candidates;
  for (const auto& [median, M] : lmeds.leaders) {
    const double sigma = 1.48 * (1.0 + 5.0 / (n - 8)) * std::sqrt(median);
    const std::vector<double> residuals =
        StandardizedResiduals(M, points, options.residual);
    std::vector<uint8_t> mask(n);
    for (int i = 0; i < n; ++i) {
      mask[i] =
          std::abs(residuals[i]) <=
          options.blunder_threshold * std::max(sigma, options.min_sigma_px);
    }
    LmedsCandidate candidate{median, M};
    const Eigen::Matrix3d polished = WeightedDrt(points, mask, options, M);
    const double polished_median =
        DrtMedianOfSquares(polished, points, options.residual);
    if (polished_median < median) candidate = {polished_median, polished};
    candidates.push_back(candidate);
  }
  std::sort(candidates.begin(),
            candidates.end(),
            [](const LmedsCandidate& a, const LmedsCandidate& b) {
              return a.median < b.median;
            });
  return candidates;
}

std::vector<uint8_t> Classify(const std::vector<double>& residuals,
                              double sigma,
                              double threshold) {
  std::vector<uint8_t> mask(residuals.size());
  const double limit = threshold * sigma;
  for (size_t i = 0; i < residuals.size(); ++i) {
    mask[i] = std::abs(residuals[i]) <= limit;
  }
  return mask;
}

// Eq. (5): the weighted least-squares DRT from the points with weight 1.
// The misclosures of eq. (1) are divided by their standard deviations
// (computed from the previous M, starting with LMedS's), so that every
// point counts by its geometric fit, not by where it lies in the image; a
// few iterations settle these weights. Without that normalisation the
// linear solution of a narrow-angle pair is pulled far off by the points
// near the 2.5-sigma limit. The LMedS model is kept if the weighted one
// fits the points worse.
Eigen::Matrix3d WeightedDrt(const ConjugatePoints& points,
                            const std::vector<uint8_t>& mask,
                            const RelativeOrientationOptions& options,
                            const Eigen::Matrix3d& lmeds_M) {
  const auto cost = [&](const Eigen::Matrix3d& M) {
    const std::vector<double> residuals =
        StandardizedResiduals(M, points, DrtResidual::kSampson);
    double sum = 0;
    for (size_t i = 0; i < residuals.size(); ++i) {
      if (mask[i]) sum += residuals[i] * residuals[i];
    }
    return sum;
  };
  Eigen::Matrix3d best = lmeds_M;
  double best_cost = cost(lmeds_M);
  Eigen::Matrix3d M = lmeds_M;
  std::vector<double> weights(points.u1.size());
  for (int iteration = 0; iteration < 4; ++iteration) {
    for (size_t i = 0; i < weights.size(); ++i) {
      if (!mask[i]) {
        weights[i] = 0;
        continue;
      }
      // The conditioned rays SolveDrtLinear uses (z = -1).
      const Eigen::Vector3d a1 = points.u1[i] / std::abs(points.u1[i].z());
      const Eigen::Vector3d a2 = points.u2[i] / std::abs(points.u2[i].z());
      const Eigen::Vector3d g1 = M * a2, g2 = M.transpose() * a1;
      const double s_i = RelativeSigma(points, static_cast<int>(i));
      const double variance =
          s_i * s_i * (g1.head<2>().squaredNorm() + g2.head<2>().squaredNorm());
      weights[i] = variance > 0 ? 1.0 / variance : 0.0;
    }
    if (!SolveDrtLinear(
            points.u1, points.u2, weights, options.calibrated, &M)) {
      break;
    }
    const double c = cost(M);
    if (c < best_cost) {
      best_cost = c;
      best = M;
    }
  }
  return best;
}

// True (with the reason set) when a rotation alone explains the points of
// the mask to within `min_parallax_px`: no base to orient.
bool NoBase(const ConjugatePoints& points,
            const std::vector<uint8_t>& mask,
            double min_parallax_px,
            RelativeOrientation* result) {
  result->rotation_only_residual_px =
      RotationOnlyResidual(points.u1, points.u2, mask);
  if (result->rotation_only_residual_px >= min_parallax_px) return false;
  std::vector<double> shifts;
  for (size_t i = 0; i < points.pixel1.size(); ++i) {
    if (mask[i]) shifts.push_back((points.pixel2[i] - points.pixel1[i]).norm());
  }
  if (!shifts.empty() && Median(shifts) < 0.5) {
    result->reason = StrCat(
        "identical images (median shift ", Median(shifts), " px): no base");
  } else {
    result->reason =
        StrCat("no base: a rotation alone explains the points to ",
               result->rotation_only_residual_px,
               " px (pure rotation, or a base too short to measure)");
  }
  return true;
}

int CountInFront(const ConjugatePoints& points,
                 const std::vector<uint8_t>& mask,
                 const Eigen::Matrix3d& R,
                 const Eigen::Vector3d& b) {
  int in_front = 0;
  for (int i = 0; i < points.size(); ++i) {
    if (!mask[i]) continue;
    const Eigen::Vector2d scales = RayScales(
        points.u1[i].normalized(), (R * points.u2[i]).normalized(), b);
    in_front += scales(0) > 0 && scales(1) > 0;
  }
  return in_front;
}

// The coplanarity condition cannot tell (R, b) from (R, -b) and from the
// "twisted pair" (R turned by 180 degrees about the base): all four give the
// same residuals, and an adjustment can end in any of them. The one that
// puts the most points in front of both cameras is the real one.
void ResolveChirality(const ConjugatePoints& points,
                      const std::vector<uint8_t>& mask,
                      Eigen::Matrix3d* R,
                      Eigen::Vector3d* b) {
  const Eigen::Matrix3d twist =
      2.0 * *b * b->transpose() - Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d rotations[2] = {*R, twist * *R};
  int best = -1;
  Eigen::Matrix3d best_R = *R;
  Eigen::Vector3d best_b = *b;
  for (const Eigen::Matrix3d& rotation : rotations) {
    for (double sign : {1.0, -1.0}) {
      const int in_front = CountInFront(points, mask, rotation, sign * *b);
      if (in_front > best) {
        best = in_front;
        best_R = rotation;
        best_b = sign * *b;
      }
    }
  }
  *R = best_R;
  *b = best_b;
}

double LmedsSigma(double median, int n, const RelativeOrientationOptions& o) {
  return std::max(o.min_sigma_px,
                  1.48 * (1.0 + 5.0 / (n - 8)) * std::sqrt(median));
}

struct Solution {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d b = Eigen::Vector3d::UnitX();
  std::vector<uint8_t> mask;
  double sigma = 0;  // robust sigma of the final blunder test
  int num_rounds = 0;
  Adjustment adjustment;
};

// Eq. (3) with the candidate's sigma, eq. (5), the decomposition, and the
// rigorous adjustment with the blunder test repeated on the refined model
// until the blunders stay the same.
Solution SolveFromCandidate(const ConjugatePoints& points,
                            const RelativeOrientationOptions& options,
                            const LmedsCandidate& candidate) {
  Solution solution;
  solution.sigma = LmedsSigma(candidate.median, points.size(), options);
  solution.mask =
      Classify(StandardizedResiduals(candidate.M, points, options.residual),
               solution.sigma,
               options.blunder_threshold);
  const Eigen::Matrix3d M =
      WeightedDrt(points, solution.mask, options, candidate.M);
  DecomposeDrt(
      M, points.u1, points.u2, solution.mask, &solution.R, &solution.b);
  for (int round = 0; round < options.max_rounds; ++round) {
    solution.num_rounds = round + 1;
    solution.adjustment = RefineElements(points,
                                         solution.mask,
                                         options.max_iterations,
                                         &solution.R,
                                         &solution.b);
    if (!solution.adjustment.converged) break;
    const Eigen::Matrix3d refined =
        (Skew(solution.b) * solution.R).normalized();
    const std::vector<double> residuals =
        StandardizedResiduals(refined, points, options.residual);
    solution.sigma = std::max(options.min_sigma_px, RobustSigma(residuals, 5));
    std::vector<uint8_t> next =
        Classify(residuals, solution.sigma, options.blunder_threshold);
    if (next == solution.mask) break;
    solution.mask = std::move(next);
  }
  if (!solution.adjustment.converged) return solution;
  const Eigen::Matrix3d R = solution.R;
  ResolveChirality(points, solution.mask, &solution.R, &solution.b);
  if (!solution.R.isApprox(R)) {
    // The covariance belongs to the parameterisation at the new solution.
    solution.adjustment = RefineElements(points,
                                         solution.mask,
                                         options.max_iterations,
                                         &solution.R,
                                         &solution.b);
  }
  return solution;
}

// The result of one solution, with every check (success or the reason).
RelativeOrientation Finish(const ConjugatePoints& points,
                           const RelativeOrientationOptions& options,
                           const Solution& solution) {
  RelativeOrientation result;
  const int n = points.size();
  result.lmeds_sigma_px = solution.sigma;
  result.num_rounds = solution.num_rounds;
  if (!solution.adjustment.converged) {
    result.reason = StrCat("the coplanarity adjustment did not converge in ",
                           options.max_iterations,
                           " iterations");
    return result;
  }
  const std::vector<uint8_t>& mask = solution.mask;
  const Eigen::Matrix3d& R = solution.R;
  const Eigen::Vector3d& b = solution.b;
  const Adjustment& adjustment = solution.adjustment;
  const double sigma = solution.sigma;
  result.inliers = mask;
  result.num_inliers =
      static_cast<int>(std::count(mask.begin(), mask.end(), 1));
  result.num_blunders = n - result.num_inliers;
  result.num_iterations = adjustment.iterations;
  result.sigma0_px = adjustment.sigma0;
  result.rotation = R;
  result.base = b;
  result.M = (Skew(b) * R).normalized();
  result.L = PaperParameters(result.M);
  result.covariance = adjustment.covariance;
  if ((options.residual == DrtResidual::kSampson &&
       sigma > options.max_sigma_px) ||
      result.sigma0_px > options.max_sigma_px) {
    result.reason = StrCat("no consistent epipolar geometry (robust sigma ",
                           sigma,
                           " px, sigma0 ",
                           result.sigma0_px,
                           " px; at most ",
                           options.max_sigma_px,
                           " px)");
    return result;
  }
  if (result.num_inliers < options.min_num_inliers) {
    result.reason = StrCat("too few points fit one epipolar geometry (",
                           result.num_inliers,
                           " < ",
                           options.min_num_inliers,
                           ")");
    return result;
  }

  // The photogrammetric elements and their precision.
  result.omega_phi_kappa_deg = OmegaPhiKappaFromRotation(R) * kRadToDeg;
  Eigen::Matrix3d J;
  const double step = 1e-7;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(k) = step;
    J.col(k) = (OmegaPhiKappaFromRotation(R * ExpRotation(d)) -
                OmegaPhiKappaFromRotation(R * ExpRotation(-d))) /
               (2 * step);
  }
  const Eigen::Matrix3d opk_covariance =
      J * adjustment.covariance.topLeftCorner<3, 3>() * J.transpose();
  result.std_omega_phi_kappa_deg =
      opk_covariance.diagonal().cwiseSqrt() * kRadToDeg;
  result.std_base_deg =
      adjustment.covariance.bottomRightCorner<2, 2>().diagonal().cwiseSqrt() *
      kRadToDeg;

  // Geometry of the pair.
  result.convergence_angle_deg =
      std::acos(std::clamp(R(2, 2), -1.0, 1.0)) * kRadToDeg;
  std::vector<double> angles;
  for (int i = 0; i < n; ++i) {
    if (!mask[i]) continue;
    const Eigen::Vector3d d1 = points.u1[i].normalized();
    const Eigen::Vector3d d2 = (R * points.u2[i]).normalized();
    angles.push_back(std::atan2(d1.cross(d2).norm(), d1.dot(d2)) * kRadToDeg);
  }
  result.median_intersection_angle_deg = Median(angles);
  if (NoBase(points,
             mask,
             std::max(options.min_parallax_px,
                      options.min_parallax_sigma0 * result.sigma0_px),
             &result)) {
    return result;
  }
  const int in_front = CountInFront(points, mask, R, b);
  if (in_front < result.num_inliers / 2) {
    result.reason = StrCat("only ",
                           in_front,
                           " of ",
                           result.num_inliers,
                           " points lie in front of both cameras");
    return result;
  }
  result.success = true;
  return result;
}

// The points with their standard deviations divided by the median one
// (each at least min_sigma_px first), so that residuals, sigma0 and every
// threshold in pixels refer to the typical point; none where any point
// lacks one.
ConjugatePoints WithRelativeSigma(const ConjugatePoints& input,
                                  double min_sigma_px) {
  ConjugatePoints points = input;
  const bool known = points.sigma.size() == points.u1.size() &&
                     std::all_of(points.sigma.begin(),
                                 points.sigma.end(),
                                 [](double s) { return s > 0; });
  if (!known) {
    points.sigma.clear();
    return points;
  }
  for (double& s : points.sigma) s = std::max(s, min_sigma_px);
  const double median = Median(points.sigma);
  for (double& s : points.sigma) s /= median;
  return points;
}

}  // namespace

RelativeOrientation EstimateRelativeOrientation(
    const ConjugatePoints& input, const RelativeOrientationOptions& options) {
  options.Check();
  const ConjugatePoints points = WithRelativeSigma(input, options.min_sigma_px);
  RelativeOrientation result;
  const int n = points.size();
  if (n < options.min_num_points) {
    result.reason = StrCat(
        "too few conjugate points (", n, " < ", options.min_num_points, ")");
    return result;
  }

  // (d) LMedS, eqs. (2) and (4).
  const std::vector<LmedsCandidate> candidates =
      DrtLeastMedianOfSquares(points, options);
  if (candidates.empty()) {
    // Identical images and pure rotations leave the DRT undetermined.
    if (!NoBase(points,
                std::vector<uint8_t>(n, 1),
                options.min_parallax_px,
                &result)) {
      result.reason =
          "degenerate point configuration (no 8-point sample "
          "determines the DRT)";
    }
    return result;
  }
  // Without a base the coplanarity condition holds for any base direction:
  // the adjustment would wander. Tested before it, on the best candidate.
  {
    const double sigma = LmedsSigma(candidates.front().median, n, options);
    const std::vector<uint8_t> mask = Classify(
        StandardizedResiduals(candidates.front().M, points, options.residual),
        sigma,
        options.blunder_threshold);
    if (NoBase(points, mask, options.min_parallax_px, &result)) return result;
  }
  // Each candidate is taken through eqs. (3) and (5) and the rigorous
  // adjustment; of the solutions that pass every check, the one whose final
  // blunder test has the smallest robust sigma wins. (Narrow-angle pairs
  // have false minima with a tiny convergence angle whose 8-point median
  // can beat the true solution's; after refinement the true one fits
  // clearly better.) Without any, the best failure is reported.
  RelativeOrientation best;
  bool have_any = false;
  double best_sigma = 0;
  for (const LmedsCandidate& candidate : candidates) {
    const Solution solution = SolveFromCandidate(points, options, candidate);
    RelativeOrientation attempt = Finish(points, options, solution);
    const bool better =
        !have_any || (attempt.success && !best.success) ||
        (attempt.success == best.success && solution.sigma < best_sigma);
    if (better) {
      best = std::move(attempt);
      best_sigma = solution.sigma;
      have_any = true;
    }
  }
  return best;
}

}  // namespace bayon
