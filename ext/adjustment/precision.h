// SPDX-License-Identifier: BSD-3-Clause
//
// The statistics of an adjusted block from the inverse of its normal
// equations, computed here rather than by ceres::Covariance so that the
// datum, the redundancy numbers and the per-point precision come out of one
// pass over the Jacobians:
//
//   N = J^T J (J whitened: every residual times its sqrt information),
//   object points eliminated by the Schur complement (each point's 3x3 block
//   is inverted on its own, the reduced system of the exterior and interior
//   orientations is inverted densely), Q = N^-1 recovered per point as
//   Q_jj = N_jj^-1 + M_j^T Q_kk M_j with M_j = N_kj N_jj^-1.
//
// Statistics (Foerstner/Wrobel, Photogrammetric Computer Vision, ch. 4;
// Baarda 1968 for data snooping):
//   sigma0^2 = v^T P v / r, r = n - u + d (d = datum defect);
//   covariance of the unknowns C_xx = sigma0^2 Q;
//   cofactor of the residuals Q_vv = P^-1 - J Q J^T (whitened: I - J Q J^T),
//   redundancy numbers r_i = (Q_vv P)_ii, sum r_i = r;
//   normalised residuals w_i = v_i / (sigma0 sqrt(q_vv,i)).
//
// Datum: with control points or the minimum datum the normal matrix is
// regular. A free network is solved with seven parameters held (a minimal
// datum), and its precision is transformed into the datum of inner
// constraints over the tie points (Meissl; the S-transformation of Baarda
// 1973): Q_E = S Q S^T, S = I - G (G^T W G)^-1 G^T W, where the columns of
// G span the seven similarity motions and W selects the tie points. The
// residuals and their cofactors do not depend on the datum. W selects the
// tie points that the rays fix (InnerConstraintPoints, adjustment_block.h):
// the covariances are relative to the centroid of those points, and they
// are the precision that an alignment to any reference over those points
// leaves.
#pragma once

#include "ext/adjustment/adjustment_block.h"

#include <Eigen/Core>

#include <vector>

namespace bayon {

struct PrecisionOptions {
  // Residual cofactors, redundancy numbers and normalised residuals for
  // every observation (needed for data snooping).
  bool compute_residual_cofactors = true;
  // Free network: transform the covariances into the inner-constraint datum
  // of the active tie points (the block must hold seven parameters fixed).
  bool inner_constraints = false;
};

// An image coordinate with less redundancy than this is not controlled by
// the others: a blunder shows in its residual at less than a hundredth of
// its size, and its normalised residual would be the solver's last
// thousandth of a pixel over a vanishing root (a point seen twice has all
// its redundancy across the epipolar line). It is not tested: its w is 0.
constexpr double kMinTestableRedundancy = 0.01;

struct ObservationStatistics {
  bool valid = false;
  Eigen::Vector2d residual_px =
      Eigen::Vector2d::Zero();                           // projected - observed
  Eigen::Vector2d redundancy = Eigen::Vector2d::Zero();  // r_i
  Eigen::Vector2d normalized =
      Eigen::Vector2d::Zero();  // w_i (0 where not testable)
  // Whether coordinate k has the redundancy to be tested.
  bool Testable(int k) const { return redundancy(k) >= kMinTestableRedundancy; }
};

struct AdjustmentPrecision {
  int num_observations = 0;  // n: image coordinates, control coordinates,
                             // distances
  int num_image_coordinates = 0;
  int num_unknowns = 0;  // u
  int datum_defect = 0;  // d
  // Free network: the tie points of the inner constraints (W above).
  int num_datum_points = 0;
  int redundancy = 0;  // r = n - u + d
  double vtpv = 0;     // in reference pixels squared
  double sigma0 = 0;   // a posteriori, in reference pixels
  // Covariances (sigma0^2 Q) per block entry; zero for inactive entries and
  // fixed parameters. Points in metres^2; images as (rotation about the
  // camera axes [rad], centre [m]); cameras over all model parameters.
  std::vector<Eigen::Matrix3d> point_covariance;
  std::vector<Eigen::Matrix<double, 6, 6>> image_covariance;
  std::vector<Eigen::MatrixXd> camera_covariance;
  // Per camera and parameter: the largest correlation with a rotation or
  // centre coordinate of one of its images (0 for fixed parameters).
  std::vector<Eigen::VectorXd> camera_exterior_correlation;
  // Per block observation (valid only for active ones).
  std::vector<ObservationStatistics> observations;
  // Weighted control points: residuals (adjusted - given, metres) and their
  // redundancy numbers, per block point.
  std::vector<Eigen::Vector3d> control_residual;
  std::vector<Eigen::Vector3d> control_redundancy;
  // Distances: residual (metres) and redundancy, per block distance.
  std::vector<double> distance_residual;
  std::vector<double> distance_redundancy;
};

// Throws RunFailure when the normal matrix is singular (the datum is not
// defined, or a parameter cannot be determined).
AdjustmentPrecision ComputePrecision(AdjustmentBlock* block,
                                     const PrecisionOptions& options);

// The correlation matrix of a covariance matrix (zero where a variance is
// zero).
Eigen::MatrixXd CorrelationFromCovariance(const Eigen::MatrixXd& covariance);

}  // namespace bayon
