// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>

#include <functional>

namespace bayon {

struct LevenbergMarquardtOptions {
  int max_iterations = 100;
  // Stop when the relative decrease of the cost falls below this.
  double function_tolerance = 1e-14;
  // Finite-difference step of parameter i is step_scale * scales(i), so that
  // parameters of very different magnitude (mm and mm^-6) get fitting steps.
  double step_scale = 1e-6;
};

struct LevenbergMarquardtSummary {
  int num_iterations = 0;
  double initial_cost = 0;  // 0.5 * sum of squared residuals
  double final_cost = 0;
  bool converged = false;
};

// Minimises 0.5 |residuals(x)|^2 over x by Levenberg-Marquardt with Marquardt's
// diagonal scaling and a central-difference Jacobian. For small dense
// problems (model fits with tens of parameters); the adjustments use Ceres.
// `scales` gives the typical magnitude of each parameter (see the options).
LevenbergMarquardtSummary SolveLevenbergMarquardt(
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& residuals,
    const Eigen::VectorXd& scales,
    const LevenbergMarquardtOptions& options,
    Eigen::VectorXd* x);

}  // namespace bayon
