// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/least_squares.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace bayon {

LevenbergMarquardtSummary SolveLevenbergMarquardt(
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& residuals,
    const Eigen::VectorXd& scales,
    const LevenbergMarquardtOptions& options,
    Eigen::VectorXd* x) {
  LevenbergMarquardtSummary summary;
  const int n = static_cast<int>(x->size());
  Eigen::VectorXd r = residuals(*x);
  double cost = 0.5 * r.squaredNorm();
  summary.initial_cost = cost;
  double lambda = 1e-3;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    summary.num_iterations = iteration + 1;
    Eigen::MatrixXd jacobian(r.size(), n);
    for (int j = 0; j < n; ++j) {
      const double h = options.step_scale * scales(j);
      Eigen::VectorXd xp = *x, xm = *x;
      xp(j) += h;
      xm(j) -= h;
      jacobian.col(j) = (residuals(xp) - residuals(xm)) / (2 * h);
    }
    const Eigen::MatrixXd normal = jacobian.transpose() * jacobian;
    const Eigen::VectorXd gradient = jacobian.transpose() * r;
    bool improved = false;
    for (int attempt = 0; attempt < 20 && !improved; ++attempt) {
      Eigen::MatrixXd damped = normal;
      for (int j = 0; j < n; ++j) {
        damped(j, j) += lambda * std::max(normal(j, j), 1e-300);
      }
      const Eigen::VectorXd step = damped.ldlt().solve(-gradient);
      const Eigen::VectorXd candidate = *x + step;
      const Eigen::VectorXd candidate_r = residuals(candidate);
      const double candidate_cost = 0.5 * candidate_r.squaredNorm();
      if (std::isfinite(candidate_cost) && candidate_cost <= cost) {
        const double decrease = cost - candidate_cost;
        *x = candidate;
        r = candidate_r;
        improved = true;
        lambda = std::max(lambda / 10, 1e-12);
        if (decrease <= options.function_tolerance * std::max(cost, 1e-300)) {
          cost = candidate_cost;
          summary.converged = true;
          summary.final_cost = cost;
          return summary;
        }
        cost = candidate_cost;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) {
      summary.converged = true;  // no step decreases the cost: a minimum
      break;
    }
  }
  summary.final_cost = cost;
  return summary;
}

}  // namespace bayon
