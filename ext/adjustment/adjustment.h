// SPDX-License-Identifier: BSD-3-Clause
//
// The self-calibrating bundle adjustment as the Bayon paper ran it with SGAP
// (section 3.2.4), on an AdjustmentBlock whose datum is already set up
// (adjustment_input.h):
//
//  1. a first adjustment without additional parameters, "to guarantee
//     global convergence" (the camera as given);
//  1b. where a camera's focal length is unknown (BlockCamera::focal_unknown:
//     COLMAP's guess of 1.2 x the long side), that focal length alone
//     freed and estimated, as COLMAP's incremental bundle refines it from
//     the same guess; it is then kept through steps 2 and 4 whatever its
//     correlations and t-value, since holding it would mean holding the
//     guess. Freeing every parameter at once from a guess that is off by
//     half lets the affinity and the distortion take the focal length's
//     place (temple-ring: B1 drove fx to 3.2 times fy);
//  2. the additional parameters (the ten of Brown 1971 / Beyer 1992 for
//     BROWN_BEYER cameras) freed, the block adjusted again;
//  3. blunder detection: data snooping (Baarda 1968) with redundancy
//     numbers, optionally after a robust (Huber) adjustment whose
//     down-weighting brings blunders out first; the observation with the
//     largest normalised residual w above the critical value is rejected in
//     each point, and the block is adjusted again until none is left;
//  4. selection of the additional parameters: the t-test of each estimate
//     against its standard deviation, the least significant one removed
//     (reset to its value of step 1) and the block adjusted again, until all
//     remaining ones are significant; correlations above a limit flagged;
//  5. the final statistics (precision.h).
//
// For a free network (AdjustmentBlock::free_network) the block holds seven
// parameters during the solution;
// the result is transformed into the datum of inner constraints over the
// tie points whose rays fix them (InnerConstraintPoints: minimum trace of
// their covariance, centred on their input coordinates) before the
// statistics are taken.
#pragma once

#include "ext/adjustment/adjustment_block.h"
#include "ext/adjustment/bundle_solver.h"
#include "ext/adjustment/precision.h"
#include "ext/core/option_registry.h"

#include <string>
#include <vector>

namespace bayon {

enum class SelfCalibration { kNone, kAll, kSignificant, kList };
enum class BlunderDetection { kNone, kSnooping, kRobust };
// "none", "snooping", "robust".
std::string BlunderDetectionName(BlunderDetection method);

struct AdjustmentOptions {
  // Which camera parameters the second step estimates: none, all candidate
  // ones (BROWN_BEYER: the ten additional parameters; COLMAP models: focal
  // length(s) and distortion, as COLMAP's bundle_adjuster), the significant
  // ones among those, or `parameter_list` (names as in calibration.json,
  // e.g. "dc,dx0,dy0,K1"; the principal point of a COLMAP model only here).
  SelfCalibration self_calibration = SelfCalibration::kSignificant;
  std::vector<std::string> parameter_list;
  // Run step 1 (without self-calibration) before step 2. Off: one step.
  bool two_steps = true;
  // t-test: a parameter is significant when |value| / std_dev exceeds this
  // (Student's t, two-sided, for the large redundancy of a block: 1.96 is
  // 5 %, 2.0 the customary round value, 2.58 is 1 %).
  double significance_t = 2.0;
  // Correlations above this between estimated camera parameters are
  // flagged in the report.
  double max_correlation = 0.9;
  // Determinability, with kSignificant, before the t-test: a parameter
  // correlated above max_exterior_correlation with an exterior orientation
  // element is removed; the interior orientation (dc, dx0, dy0; a COLMAP
  // model's focal length and principal point) only when it is also
  // imprecise, with a standard deviation above max_interior_sigma of the
  // image diagonal (adjustment.cc, RemoveUndeterminableParameters).
  double max_exterior_correlation = 0.99;
  double max_interior_sigma = 0.01;
  BlunderDetection blunder_detection = BlunderDetection::kRobust;
  // Baarda's critical value for the normalised residual w (alpha0 = 0.1 %,
  // beta0 = 80 %, the classic 3.29).
  double snooping_critical_value = 3.29;
  int max_snooping_iterations = 30;
  // Huber scale for the robust step, in reference standard deviations.
  double robust_loss_scale = 2.0;
  // Variance component estimation (Foerstner 1979) where the image
  // observations come in groups of different precision (keypoint tracks,
  // least-squares tie points, manual measurements): each group's a priori
  // variances are scaled by its variance factor v'Pv / r (from the
  // redundancy numbers), iterated, before data snooping. Groups with less
  // redundancy than min_component_redundancy keep their weights.
  bool variance_components = true;
  int max_component_iterations = 4;
  double min_component_redundancy = 30;
  BundleSolverOptions solver;
  // "none", "all", "significant", or the parameter list ("dc,dx0,dy0").
  std::string SelfCalibrationName() const;
  // Reads what SelfCalibrationName() writes.
  void SetSelfCalibration(const std::string& name);
  // The fields `bayon adjust` takes (the solver's iterations and threads
  // among them), under its flags' names.
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct AdjustmentStep {
  std::string name;
  int num_iterations = 0;
  double sigma0 = 0;  // reference pixels (0 where not computed)
  double time_s = 0;
  std::string message;
};

struct ParameterEstimate {
  int camera_idx = -1;
  int param_idx = -1;
  std::string name;
  double value = 0;
  double std_dev = 0;
  double t_value = 0;
  // Largest correlation with an exterior orientation parameter.
  double exterior_correlation = 0;
};

struct RemovedParameter {
  ParameterEstimate estimate;  // at the time of its removal
  std::string reason;
};

struct RejectedObservation {
  int observation_idx = -1;
  Eigen::Vector2d residual_px = Eigen::Vector2d::Zero();
  double w = 0;  // largest |normalised residual| of x and y
  double redundancy = 0;
  int iteration = 0;  // 0: after the robust solution, 1...: data snooping
};

// One group of image observations and its estimated precision.
struct VarianceComponent {
  std::string name;
  int num_observations = 0;  // image points
  double redundancy = 0;     // sum of the redundancy numbers
  // Scale applied to the group's a priori variances (product over the
  // iterations), and the resulting median standard deviation of a
  // coordinate, pixels.
  double variance_scale = 1;
  double median_sigma_px = 0;
};

struct CorrelationFlag {
  int camera_idx = -1;
  std::string name1;
  std::string name2;
  double correlation = 0;
};

struct AdjustmentResult {
  std::vector<AdjustmentStep> steps;
  // Self-calibration: candidates, the removal history and the final set.
  std::vector<std::string> candidate_parameters;
  std::vector<RemovedParameter> removed_parameters;
  std::vector<ParameterEstimate> final_parameters;
  std::vector<CorrelationFlag> correlation_flags;
  // Per camera: the correlation matrix of its estimated parameters, in the
  // order of `final_parameters` for that camera.
  std::vector<Eigen::MatrixXd> parameter_correlations;
  // Data snooping.
  std::vector<RejectedObservation> rejected;
  int num_snooping_iterations = 0;
  // Variance components (empty where there is one group).
  std::vector<VarianceComponent> variance_components;
  int num_points_removed = 0;  // tie points left with fewer than 2 rays
  // Final statistics.
  AdjustmentPrecision precision;
  double total_time_s = 0;
};

// Runs the steps above on `block` (changed in place). Throws RunFailure when
// the block cannot be solved.
AdjustmentResult RunAdjustment(const AdjustmentOptions& options,
                               AdjustmentBlock* block);

// Names of a camera model's parameters that self-calibration may estimate
// by default (see AdjustmentOptions::self_calibration).
std::vector<int> CandidateParameters(CameraModelId model);

}  // namespace bayon
