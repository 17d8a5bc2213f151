// SPDX-License-Identifier: BSD-3-Clause
//
// The second-order surface patch of Fua and Sander's local surface fitting
// (P. Fua, P. Sander, Segmenting Unstructured 3D Points into Surfaces,
// ECCV 1992), as the Bayon paper's editing step uses it (sec. 3.4): around a
// query point, a local frame from the principal axes of its neighbours
// (t1, t2 tangent, n normal), and the height over the tangent plane
//
//   w(u, v) = c0 + c1 u + c2 v + c3 u^2 + c4 u v + c5 v^2
//
// fitted to the neighbours by weighted least squares (weights 1 / sigma_n^2,
// sigma_n the neighbour's standard deviation along n from its per-axis
// sigmas sx, sy, sz; or 1 when no precision is known). The frame is
// centred on the query point, which is not part of the fit, so c0 is the
// height of the fitted surface at the query point and -c0 its deviation:
// a leave-one-out test that a blunder cannot pull towards itself.
// Object units (metres).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace bayon {

// Median of chi-square with one degree of freedom: a robust variance is the
// median of the squares divided by it, so that it estimates the variance,
// not the median.
inline constexpr double kChiSquare1Median = 0.454936;

struct QuadricPatch {
  bool valid = false;
  // 6 for the quadric; 3 when the neighbourhood could only carry a plane
  // (too few points or too narrow a spread for the second-order terms).
  int num_parameters = 0;
  int num_points = 0;    // neighbours in the final fit
  int num_rejected = 0;  // neighbours left out as outliers of the patch
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();  // columns t1, t2, n
  Eigen::Matrix<double, 6, 1> coefficients =
      Eigen::Matrix<double, 6, 1>::Zero();
  // Variance of c0 from the normal equations: in m^2 when the weights were
  // 1 / sigma^2, in units of the variance factor when they were 1.
  double c0_variance = 0;
  // Covariance of the coefficients (same units as c0_variance; rows and
  // columns of unused coefficients are zero).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  // The frame's origin: the query point.
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  // Robust a-posteriori variance factor: the median of the weighted squared
  // residuals over the median of chi-square(1) (0.4549), corrected for the
  // redundancy. About 1 when the weights match the scatter around the patch,
  // larger where the surface is rougher than a quadric at this scale.
  double variance_factor = 0;

  // Signed distance of the query point from the patch along n (positive on
  // the side n points to), first order in the slope at the query point.
  double QueryDeviation() const;

  // Signed distance of any point from the patch along n (first order), and
  // the variance of the patch's height there (in c0_variance's units):
  // for testing a point against a neighbour's patch.
  double Deviation(const Eigen::Vector3d& point) const;
  double HeightVariance(const Eigen::Vector3d& point) const;
};

struct QuadricFitOptions {
  // Rounds of refitting without the neighbours whose standardised residual
  // exceeds rejection_sigma robust standard deviations (the frame is
  // recomputed too). Without them, two blunders next to each other pull the
  // patch towards themselves and pass the test together.
  int robust_rounds = 2;
  double rejection_sigma = 4.0;
  void Check() const;
};

// Fits the patch around `query` to `neighbors`, with `sigmas` (per-axis
// standard deviations, one per neighbour, all > 0) or unit weights when
// `sigmas` is empty. The frame's normal is `normal` when it is not zero,
// else the neighbours' smallest principal axis. Returns valid = false when
// fewer than 5 neighbours are given or they do not span a surface (all on a
// line).
//
// Why a given normal: around a blunder 20 cm off a densely sampled surface,
// the nearest neighbours are a small disc of surface points (5 cm across)
// and, now and then, a second blunder next to the first; that one point can
// outweigh the disc in the principal axes and turn the frame on its side, so
// that the patch passes through both blunders. The average normal of the
// neighbours (each from its own neighbourhood) does not turn.
QuadricPatch FitQuadricPatch(
    const Eigen::Vector3d& query,
    const std::vector<Eigen::Vector3d>& neighbors,
    const std::vector<Eigen::Vector3d>& sigmas,
    const Eigen::Vector3d& normal = Eigen::Vector3d::Zero(),
    const QuadricFitOptions& options = {});

// The dominant direction of a set of unoriented unit normals (the largest
// eigenvector of sum n n^T), or zero when there are none.
Eigen::Vector3d MeanAxis(const std::vector<Eigen::Vector3d>& normals);

// Variance along the unit direction n of a point with independent per-axis
// standard deviations s: sum_k (n_k s_k)^2.
inline double VarianceAlong(const Eigen::Vector3d& n,
                            const Eigen::Vector3d& s) {
  return n.cwiseProduct(s).squaredNorm();
}

// The normal frame of a set of points from their principal axes (columns:
// largest, middle, smallest axis; the last is the normal) and the
// eigenvalues in decreasing order.
void PrincipalAxes(const std::vector<Eigen::Vector3d>& points,
                   Eigen::Matrix3d* axes,
                   Eigen::Vector3d* eigenvalues);

}  // namespace bayon
