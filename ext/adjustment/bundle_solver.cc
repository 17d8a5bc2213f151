// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/bundle_solver.h"

#include "ext/adjustment/cost_functions.h"
#include "ext/core/errors.h"

#include <ceres/ceres.h>

#include <set>
#include <thread>

namespace bayon {
namespace {

// A manifold that holds the coordinates in `fixed`; nullptr when none are.
ceres::Manifold* SubsetManifoldFor(int size, const std::vector<int>& fixed) {
  if (fixed.empty()) return nullptr;
  return new ceres::SubsetManifold(size, fixed);
}

std::vector<int> FixedIndices(const std::vector<bool>& free) {
  std::vector<int> fixed;
  for (size_t i = 0; i < free.size(); ++i) {
    if (!free[i]) fixed.push_back(static_cast<int>(i));
  }
  return fixed;
}

std::vector<int> FixedIndices(const std::array<bool, 3>& fixed_mask) {
  std::vector<int> fixed;
  for (int i = 0; i < 3; ++i) {
    if (fixed_mask[i]) fixed.push_back(i);
  }
  return fixed;
}

// Sets manifolds and constant blocks for every parameter block in use.
void ConfigureParameters(AdjustmentBlock* block, ceres::Problem* problem) {
  for (BlockImage& image : block->images) {
    if (!problem->HasParameterBlock(image.rotation.data())) continue;
    if (image.rotation_fixed) {
      problem->SetParameterBlockConstant(image.rotation.data());
    } else {
      problem->SetManifold(image.rotation.data(), new RotationManifold);
    }
    const std::vector<int> fixed = FixedIndices(image.center_fixed);
    if (fixed.size() == 3) {
      problem->SetParameterBlockConstant(image.center.data());
    } else if (!fixed.empty()) {
      problem->SetManifold(image.center.data(), SubsetManifoldFor(3, fixed));
    }
  }
  for (BlockPoint& point : block->points) {
    if (!problem->HasParameterBlock(point.xyz.data())) continue;
    const std::vector<int> fixed = FixedIndices(point.fixed);
    if (fixed.size() == 3) {
      problem->SetParameterBlockConstant(point.xyz.data());
    } else if (!fixed.empty()) {
      problem->SetManifold(point.xyz.data(), SubsetManifoldFor(3, fixed));
    }
  }
  for (BlockCamera& camera : block->cameras) {
    double* params = camera.camera.params.data();
    if (!problem->HasParameterBlock(params)) continue;
    const std::vector<int> fixed = FixedIndices(camera.free);
    if (fixed.size() == camera.free.size()) {
      problem->SetParameterBlockConstant(params);
    } else if (!fixed.empty()) {
      problem->SetManifold(
          params,
          SubsetManifoldFor(static_cast<int>(camera.free.size()), fixed));
    }
  }
}

}  // namespace

void BundleSolverOptions::Check() const {
  CheckOption(max_num_iterations >= 1,
              "BundleSolverOptions.max_num_iterations",
              ">= 1",
              max_num_iterations);
  CheckOption(
      loss_scale > 0, "BundleSolverOptions.loss_scale", "> 0", loss_scale);
  CheckOption(num_threads == -1 || num_threads >= 1,
              "BundleSolverOptions.num_threads",
              "-1 or >= 1",
              num_threads);
}

BundleSolverSummary SolveBundle(const BundleSolverOptions& options,
                                AdjustmentBlock* block) {
  options.Check();
  const std::vector<ResidualTerm> terms = BuildResidualTerms(block);
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);

  std::unique_ptr<ceres::LossFunction> loss;
  const double scale = options.loss_scale * block->sigma0_px;
  if (options.loss == RobustLoss::kHuber) {
    loss = std::make_unique<ceres::HuberLoss>(scale);
  } else if (options.loss == RobustLoss::kCauchy) {
    loss = std::make_unique<ceres::CauchyLoss>(scale);
  }
  for (const ResidualTerm& term : terms) {
    ceres::LossFunction* term_loss =
        term.type == TermType::kReprojection ? loss.get() : nullptr;
    problem.AddResidualBlock(term.cost.get(), term_loss, term.parameters);
  }
  ConfigureParameters(block, &problem);

  // Points are eliminated first (Schur complement on the cameras), as in
  // every photogrammetric bundle program since Brown's.
  auto* ordering = new ceres::ParameterBlockOrdering;
  std::set<double*> point_blocks;
  for (BlockPoint& point : block->points) {
    if (problem.HasParameterBlock(point.xyz.data())) {
      point_blocks.insert(point.xyz.data());
    }
  }
  // A point in a distance observation shares a residual with another point,
  // so it cannot be eliminated independently: it joins the camera group.
  for (const ResidualTerm& term : terms) {
    if (term.type == TermType::kDistance) {
      for (double* parameter : term.parameters) point_blocks.erase(parameter);
    }
  }
  std::vector<double*> all_blocks;
  problem.GetParameterBlocks(&all_blocks);
  for (double* parameter : all_blocks) {
    ordering->AddElementToGroup(parameter,
                                point_blocks.count(parameter) ? 0 : 1);
  }

  ceres::Solver::Options solver_options;
  // The reduced camera system is dense for small blocks (every image sees
  // most others); a sparse factorisation pays off only for larger ones.
  constexpr size_t kMaxImagesForDenseSchur = 50;
  solver_options.linear_solver_type = ceres::SPARSE_SCHUR;
  if (block->images.size() <= kMaxImagesForDenseSchur ||
      (!ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) &&
       !ceres::IsSparseLinearAlgebraLibraryTypeAvailable(
           ceres::EIGEN_SPARSE))) {
    solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  }
  if (point_blocks.empty() || point_blocks.size() == all_blocks.size()) {
    delete ordering;
    solver_options.linear_solver_type = ceres::DENSE_QR;
  } else {
    solver_options.linear_solver_ordering.reset(ordering);
  }
  solver_options.max_num_iterations = options.max_num_iterations;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.gradient_tolerance = options.gradient_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  solver_options.num_threads =
      options.num_threads > 0
          ? options.num_threads
          : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  solver_options.minimizer_progress_to_stdout = false;
  solver_options.logging_type =
      options.verbose ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;

  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);

  // Keep the quaternions at unit length for the output and the statistics.
  for (BlockImage& image : block->images) image.rotation.normalize();

  BundleSolverSummary result;
  result.usable = summary.IsSolutionUsable();
  result.num_iterations = static_cast<int>(summary.iterations.size());
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.time_s = summary.total_time_in_seconds;
  result.num_residuals = summary.num_residuals_reduced;
  result.num_parameters = summary.num_effective_parameters_reduced;
  result.message = summary.message;
  return result;
}

}  // namespace bayon
