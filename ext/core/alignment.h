// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "ext/core/sim3.h"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace bayon {

// The least-squares similarity dst_from_src minimising
// sum_i w_i |dst_i - (s R src_i + t)|^2 (Umeyama 1991; Horn 1987 for the
// unweighted case). Returns nullopt for fewer than 3 points or a degenerate
// (collinear) configuration. `weights` may be empty (all ones).
std::optional<Sim3d> EstimateSim3d(const std::vector<Eigen::Vector3d>& src,
                                   const std::vector<Eigen::Vector3d>& dst,
                                   const std::vector<double>& weights = {});

struct RobustSim3dOptions {
  // Residuals above this (in dst units) mark a point as an outlier. 0 picks
  // the threshold from the data: 2.5 robust standard deviations (LMedS).
  double max_residual = 0.0;
  int num_samples = 500;
  unsigned int random_seed = 1;
};

struct RobustSim3dReport {
  bool success = false;
  Sim3d dst_from_src;
  std::vector<double> residuals;  // |dst_i - T src_i|, every point
  std::vector<char> inlier_mask;
  int num_inliers = 0;
  double threshold = 0.0;  // the outlier threshold that was used
};

// Least median of squares over minimal samples of 3 points, then a
// least-squares refit to the inliers; for control points with blunders.
RobustSim3dReport EstimateSim3dRobust(const std::vector<Eigen::Vector3d>& src,
                                      const std::vector<Eigen::Vector3d>& dst,
                                      const RobustSim3dOptions& options = {});

}  // namespace bayon
