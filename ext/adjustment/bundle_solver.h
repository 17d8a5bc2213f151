// SPDX-License-Identifier: BSD-3-Clause
//
// The non-linear least-squares solution of an AdjustmentBlock with Ceres:
// every residual term of the block, parameter blocks held or freed as the
// block says (fixed images, fixed control point coordinates, the camera
// parameters that self-calibration estimates), Levenberg-Marquardt on the
// Schur complement.
#pragma once

#include "ext/adjustment/adjustment_block.h"

#include <string>

namespace bayon {

enum class RobustLoss { kNone, kHuber, kCauchy };

struct BundleSolverOptions {
  int max_num_iterations = 100;
  // Relative decrease of the cost, and relative change of the parameters,
  // at which the iteration stops (Ceres's defaults: far below what the
  // statistics can resolve).
  double function_tolerance = 1e-6;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  // Robust loss on the image observations (not on control points and
  // distances), for a first solution with blunders in the data. Its scale
  // is `loss_scale` reference standard deviations (sigma0_px of the block).
  RobustLoss loss = RobustLoss::kNone;
  double loss_scale = 3.0;
  int num_threads = -1;  // -1: all cores
  // Log Ceres's per-iteration lines.
  bool verbose = false;
  void Check() const;
};

struct BundleSolverSummary {
  bool usable = false;  // converged or stopped at the iteration limit
  int num_iterations = 0;
  double initial_cost = 0;  // Ceres cost: 0.5 v^T P v
  double final_cost = 0;
  double time_s = 0;
  int num_residuals = 0;
  int num_parameters = 0;  // free parameters (tangent space)
  std::string message;     // Ceres's termination message
};

BundleSolverSummary SolveBundle(const BundleSolverOptions& options,
                                AdjustmentBlock* block);

}  // namespace bayon
