// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/adjustment.h"

#include "ext/colmap/calibration_json.h"
#include "ext/core/alignment.h"
#include "ext/core/errors.h"
#include "ext/core/progress.h"
#include "ext/core/statistics.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace bayon {
namespace {

// Observations whose point lies behind the camera cannot be projected; they
// leave the block before the first solution.
int DeactivateObservationsBehindCameras(AdjustmentBlock* block) {
  int count = 0;
  for (BlockObservation& observation : block->observations) {
    if (!observation.active) continue;
    const BlockImage& image = block->images[observation.image_idx];
    const Eigen::Vector3d in_cam =
        image.CamFromWorld() * block->points[observation.point_idx].xyz;
    if (in_cam.z() <= 0) {
      observation.active = false;
      ++count;
    }
  }
  return count;
}

// The focal length among a camera's parameters: Brown/Beyer's correction
// dc, a COLMAP model's focal length(s).
std::vector<int> FocalLengthParameters(const Camera& camera) {
  if (camera.model_id == CameraModelId::kBrownBeyer) return {brown::kDc};
  return camera.ModelInfo().focal_idxs;
}

std::vector<std::vector<int>> ResolveCandidates(
    const AdjustmentOptions& options, const AdjustmentBlock& block) {
  std::vector<std::vector<int>> candidates(block.cameras.size());
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    const CameraModelId model = block.cameras[c].camera.model_id;
    if (options.self_calibration == SelfCalibration::kNone) continue;
    if (options.self_calibration != SelfCalibration::kList) {
      candidates[c] = CandidateParameters(model);
      continue;
    }
    const std::vector<std::string> names = ParameterNames(model);
    for (const std::string& wanted : options.parameter_list) {
      const auto it = std::find(names.begin(), names.end(), wanted);
      if (it == names.end()) {
        std::string known;
        for (int idx : CandidateParameters(model)) {
          known += (known.empty() ? "" : ", ") + names[idx];
        }
        ThrowInputError("self_calibration: '",
                        wanted,
                        "' is not a parameter of the ",
                        CameraModelInfoFor(model).name,
                        " camera (",
                        known,
                        ")");
      }
      const int idx = static_cast<int>(it - names.begin());
      if (model == CameraModelId::kBrownBeyer &&
          idx < brown::kFirstAdditional) {
        ThrowInputError("self_calibration: ",
                        wanted,
                        " is a nominal value; estimate its correction d",
                        wanted,
                        " instead");
      }
      candidates[c].push_back(idx);
    }
  }
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    const BlockCamera& camera = block.cameras[c];
    if (!camera.focal_unknown) continue;
    for (int idx : FocalLengthParameters(camera.camera)) {
      if (std::find(candidates[c].begin(), candidates[c].end(), idx) ==
          candidates[c].end()) {
        ThrowInputError(
            "camera ",
            camera.camera.camera_id,
            ": its focal length is unknown (COLMAP's guess of 1.2 x the long "
            "side: no EXIF, no calibration, and bayon relative could not "
            "estimate it from the photographs), and --self_calibration ",
            options.self_calibration == SelfCalibration::kNone ? "none"
                                                               : "without it",
            " would hold the guess; estimate it (--self_calibration "
            "significant, all, or a list with ",
            ParameterNames(camera.camera.model_id)[idx],
            ") or give the lens (bayon import --focal_length_mm)");
      }
    }
  }
  return candidates;
}

class Adjuster {
 public:
  Adjuster(const AdjustmentOptions& options, AdjustmentBlock* block)
      : options_(options), block_(block) {}

  AdjustmentResult Run() {
    Timer timer;
    for (const BlockCamera& camera : block_->cameras) {
      initial_params_.push_back(camera.camera.params);
    }
    for (const BlockPoint& point : block_->points) {
      initial_xyz_.push_back(point.xyz);
    }
    const int behind = DeactivateObservationsBehindCameras(block_);
    if (behind > 0) {
      LOG(WARNING) << behind
                   << " observations of points behind their camera left out";
    }
    result_.num_points_removed += block_->DeactivateWeakPoints();
    candidates_ = ResolveCandidates(options_, *block_);
    for (size_t c = 0; c < candidates_.size(); ++c) {
      const std::vector<std::string> names =
          ParameterNames(block_->cameras[c].camera.model_id);
      for (int idx : candidates_[c]) {
        result_.candidate_parameters.push_back(names[idx]);
      }
    }
    const bool robust = options_.blunder_detection == BlunderDetection::kRobust;
    const bool self_calibrate =
        options_.self_calibration != SelfCalibration::kNone;

    SetCameraParametersFree(false);
    if (options_.two_steps || !self_calibrate) {
      Solve("step 1: without self-calibration", robust);
    }
    if (self_calibrate && FreeUnknownFocalLengths()) {
      Solve("step 1b: the unknown focal lengths", robust);
      LogUnknownFocalLengths();
    }
    if (self_calibrate) {
      SetCameraParametersFree(true);
      if (options_.self_calibration == SelfCalibration::kSignificant) {
        RemoveUndeterminableParameters();
      }
      Solve("step 2: with self-calibration", robust);
    }
    if (options_.variance_components) EstimateVarianceComponents(robust);
    if (robust) RejectAfterRobustSolution();
    if (options_.blunder_detection != BlunderDetection::kNone) {
      Snoop();
    } else if (robust) {
      Solve("final solution", false);
    }
    if (options_.self_calibration == SelfCalibration::kSignificant) {
      SelectSignificantParameters();
    }
    if (block_->free_network) TransformToInnerConstraintDatum();
    PrecisionOptions precision_options;
    precision_options.inner_constraints = block_->free_network;
    Timer statistics_timer;
    result_.precision = ComputePrecision(block_, precision_options);
    CollectParameters();
    AdjustmentStep statistics;
    statistics.name = "statistics (inverse of the normal equations)";
    statistics.sigma0 = result_.precision.sigma0;
    statistics.time_s = statistics_timer.Seconds();
    result_.steps.push_back(statistics);
    LOG(INFO) << statistics.name << ": " << statistics.time_s << " s";
    result_.total_time_s = timer.Seconds();
    return std::move(result_);
  }

 private:
  void SetCameraParametersFree(bool free) {
    for (size_t c = 0; c < block_->cameras.size(); ++c) {
      BlockCamera& camera = block_->cameras[c];
      std::fill(camera.free.begin(), camera.free.end(), false);
      if (!free) continue;
      for (int idx : candidates_[c]) camera.free[idx] = true;
    }
  }

  // Frees only the focal lengths that are unknown; false where there are
  // none.
  bool FreeUnknownFocalLengths() {
    SetCameraParametersFree(false);
    bool any = false;
    for (BlockCamera& camera : block_->cameras) {
      if (!camera.focal_unknown) continue;
      for (int idx : FocalLengthParameters(camera.camera)) {
        camera.free[idx] = true;
        any = true;
      }
    }
    return any;
  }

  void LogUnknownFocalLengths() const {
    for (size_t c = 0; c < block_->cameras.size(); ++c) {
      const BlockCamera& camera = block_->cameras[c];
      if (!camera.focal_unknown) continue;
      Camera guess = camera.camera;
      guess.params = initial_params_[c];
      LOG(INFO) << "camera " << camera.camera.camera_id
                << ": focal length unknown, estimated alone first: "
                << guess.MeanFocalLengthPx() << " px (the guess) -> "
                << camera.camera.MeanFocalLengthPx() << " px";
    }
  }

  // The unknown focal lengths are never removed (step 1b above).
  bool KeptUnknownFocalLength(const ParameterEstimate& estimate) const {
    const BlockCamera& camera = block_->cameras[estimate.camera_idx];
    if (!camera.focal_unknown) return false;
    const std::vector<int> focal = FocalLengthParameters(camera.camera);
    return std::find(focal.begin(), focal.end(), estimate.param_idx) !=
           focal.end();
  }

  void Solve(const std::string& name, bool robust) {
    BundleSolverOptions solver = options_.solver;
    if (robust) {
      solver.loss = RobustLoss::kHuber;
      solver.loss_scale = options_.robust_loss_scale;
    }
    const BundleSolverSummary summary = SolveBundle(solver, block_);
    if (!summary.usable) {
      throw RunFailure(
          StrCat(name, ": the adjustment failed: ", summary.message));
    }
    AdjustmentStep step;
    step.name = name;
    step.num_iterations = summary.num_iterations;
    step.time_s = summary.time_s;
    step.message = summary.message;
    LOG(INFO) << name << ": " << summary.num_iterations << " iterations, "
              << summary.time_s << " s, cost " << summary.initial_cost << " -> "
              << summary.final_cost;
    result_.steps.push_back(step);
  }

  void RecordSigma0(double sigma0) {
    if (!result_.steps.empty()) result_.steps.back().sigma0 = sigma0;
  }

  // Baarda's data snooping, iterated: in each round the observation with the
  // largest normalised residual above the critical value is rejected in
  // every point that has one (rejecting only the worst of a point keeps a
  // blunder from taking its good neighbours in the same track along).
  void Snoop() {
    PrecisionOptions precision_options;
    precision_options.compute_residual_cofactors = true;
    for (int iteration = 1; iteration <= options_.max_snooping_iterations;
         ++iteration) {
      Solve(StrCat("data snooping ", iteration), false);
      const AdjustmentPrecision precision =
          ComputePrecision(block_, precision_options);
      RecordSigma0(precision.sigma0);
      result_.num_snooping_iterations = iteration;
      std::map<int, RejectedObservation> worst_per_point;
      for (size_t o = 0; o < block_->observations.size(); ++o) {
        const ObservationStatistics& stats = precision.observations[o];
        if (!stats.valid) continue;
        const double w = stats.normalized.cwiseAbs().maxCoeff();
        if (w <= options_.snooping_critical_value) continue;
        const int point = block_->observations[o].point_idx;
        auto it = worst_per_point.find(point);
        if (it != worst_per_point.end() && it->second.w >= w) continue;
        RejectedObservation rejected;
        rejected.observation_idx = static_cast<int>(o);
        rejected.residual_px = stats.residual_px;
        rejected.w = w;
        rejected.redundancy = stats.redundancy.minCoeff();
        rejected.iteration = iteration;
        worst_per_point[point] = rejected;
      }
      if (worst_per_point.empty()) return;
      for (const auto& [point, rejected] : worst_per_point) {
        block_->observations[rejected.observation_idx].active = false;
        result_.rejected.push_back(rejected);
      }
      result_.num_points_removed += block_->DeactivateWeakPoints();
      LOG(INFO) << "data snooping " << iteration << ": sigma0 "
                << precision.sigma0 << " px, " << worst_per_point.size()
                << " observations rejected";
    }
    Solve("data snooping: last solution", false);
    LOG(WARNING) << "data snooping stopped after "
                 << options_.max_snooping_iterations << " iterations";
  }

  // The group of an image observation (VarianceComponent).
  int GroupOf(const BlockObservation& observation) const {
    if (!observation.covariance.isZero()) return 1;
    if (observation.point2D_idx == kInvalidPoint2DIdx) return 2;
    return 0;
  }

  // Each group's variance factor: with the robust solution (blunders still
  // in, down-weighted) from the median of its normalised residuals, else
  // v'Pv / r from the redundancy numbers; iterated until no group's variance
  // changes by more than 5 %.
  void EstimateVarianceComponents(bool robust) {
    static const char* kNames[3] = {
        "keypoint tracks", "least-squares tie points", "manual measurements"};
    std::vector<VarianceComponent> groups(3);
    for (int g = 0; g < 3; ++g) groups[g].name = kNames[g];
    PrecisionOptions precision_options;
    precision_options.compute_residual_cofactors = true;
    for (int iteration = 1; iteration <= options_.max_component_iterations;
         ++iteration) {
      if (iteration > 1) {
        Solve(StrCat("variance components ", iteration), robust);
      }
      AdjustmentPrecision precision;
      try {
        precision = ComputePrecision(block_, precision_options);
      } catch (const RunFailure& failure) {
        LOG(WARNING) << "variance components: " << failure.what();
        return;
      }
      std::vector<std::vector<double>> abs_w(3);
      std::vector<double> vpv(3, 0.0), r(3, 0.0);
      std::vector<int> count(3, 0);
      for (size_t o = 0; o < block_->observations.size(); ++o) {
        const ObservationStatistics& stats = precision.observations[o];
        if (!stats.valid) continue;
        const int g = GroupOf(block_->observations[o]);
        ++count[g];
        for (int k = 0; k < 2; ++k) {
          // normalized = whitened / (sigma0 sqrt(r)); a coordinate that is
          // not testable has next to no residual and redundancy.
          if (!stats.Testable(k)) continue;
          const double whitened = stats.normalized(k) * precision.sigma0 *
                                  std::sqrt(stats.redundancy(k));
          vpv[g] += whitened * whitened;
          r[g] += stats.redundancy(k);
          abs_w[g].push_back(std::abs(stats.normalized(k)));
        }
      }
      std::vector<int> estimable;
      for (int g = 0; g < 3; ++g) {
        groups[g].num_observations = count[g];
        groups[g].redundancy = r[g];
        if (r[g] >= options_.min_component_redundancy) estimable.push_back(g);
      }
      if (estimable.size() < 2) return;  // one group: sigma0 says it all
      // Variance factors relative to the reference sigma0 a priori.
      const double reference = block_->sigma0_px * block_->sigma0_px;
      double largest_change = 0;
      std::vector<double> factor(3, 1.0);
      for (int g : estimable) {
        if (robust) {
          const double scale = 1.4826 * Median(abs_w[g]) * precision.sigma0;
          factor[g] = scale * scale / reference;
        } else {
          factor[g] = vpv[g] / r[g] / reference;
        }
        if (!(factor[g] > 0) || !std::isfinite(factor[g])) return;
        largest_change =
            std::max(largest_change, std::abs(std::log(factor[g])));
      }
      LOG(INFO) << "variance components " << iteration << ": "
                << kNames[estimable[0]] << " x" << factor[estimable[0]] << ", "
                << kNames[estimable[1]] << " x" << factor[estimable[1]];
      for (BlockObservation& observation : block_->observations) {
        observation.ScaleVariance(factor[GroupOf(observation)]);
      }
      result_.variance_components.clear();
      for (int g : estimable) {
        groups[g].variance_scale *= factor[g];
        std::vector<double> sigmas;
        for (const BlockObservation& observation : block_->observations) {
          if (observation.active && GroupOf(observation) == g) {
            sigmas.push_back(observation.sigma_px);
          }
        }
        groups[g].median_sigma_px = Median(std::move(sigmas));
        result_.variance_components.push_back(groups[g]);
      }
      if (largest_change < std::log(1.05)) break;
    }
    Solve("variance components: solution", robust);
  }

  // The robust solution has down-weighted the blunders, so that the good
  // observations of a track keep small residuals: every observation whose
  // normalised residual, against a robust sigma0 (1.4826 x the median of the
  // standardised residuals), exceeds twice the critical value is a gross
  // error and rejected at once. Data snooping then decides the rest with
  // least squares, one observation per point and iteration.
  void RejectAfterRobustSolution() {
    PrecisionOptions precision_options;
    const AdjustmentPrecision precision =
        ComputePrecision(block_, precision_options);
    std::vector<double> standardised;
    for (const ObservationStatistics& stats : precision.observations) {
      if (!stats.valid) continue;
      for (int k = 0; k < 2; ++k) {
        if (!stats.Testable(k)) continue;
        standardised.push_back(std::abs(stats.normalized(k)));
      }
    }
    if (standardised.empty()) return;
    // normalized = z / sigma0: the median of |normalized| in units of the
    // least-squares sigma0 of the robust solution.
    const double robust_scale = 1.4826 * Median(std::move(standardised));
    if (!(robust_scale > 0)) return;
    int count = 0;
    for (size_t o = 0; o < block_->observations.size(); ++o) {
      const ObservationStatistics& stats = precision.observations[o];
      if (!stats.valid) continue;
      const double w = stats.normalized.cwiseAbs().maxCoeff() / robust_scale;
      if (w <= 2 * options_.snooping_critical_value) continue;
      block_->observations[o].active = false;
      RejectedObservation rejected;
      rejected.observation_idx = static_cast<int>(o);
      rejected.residual_px = stats.residual_px;
      rejected.w = w;
      rejected.redundancy = stats.redundancy.minCoeff();
      rejected.iteration = 0;
      result_.rejected.push_back(rejected);
      ++count;
    }
    result_.num_points_removed += block_->DeactivateWeakPoints();
    LOG(INFO) << "robust solution: sigma0 " << precision.sigma0
              << " px, robust sigma0 " << robust_scale * precision.sigma0
              << " px, " << count << " observations rejected";
  }

  // Before the parameters are estimated: at the stable block of step 1 the
  // normal equations with every candidate free show which ones the
  // exterior orientations could imitate (correlation above
  // max_exterior_correlation); those are removed one at a time, the most
  // correlated first, so that step 2 does not wander off with them. The
  // interior orientation (camera constant and principal point) is removed
  // only when it is also imprecise, with a standard deviation above
  // max_interior_sigma of the image diagonal: a principal point 16 px off
  // the centre of a narrow-angle camera correlates 0.99 with the rotations,
  // yet with a standard deviation of 1 px it is well determined, and holding
  // it at the centre turns the rotations by the 0.3 deg it is off
  // (fountain-P11). The t-test then decides.
  void RemoveUndeterminableParameters() {
    PrecisionOptions precision_options;
    precision_options.compute_residual_cofactors = false;
    while (true) {
      AdjustmentPrecision precision;
      try {
        precision = ComputePrecision(block_, precision_options);
      } catch (const RunFailure&) {
        return;  // step 2 and the statistics will say which one
      }
      ParameterEstimate imitated;
      std::string reason;
      for (const ParameterEstimate& estimate : FreeEstimates(precision)) {
        std::string why;
        if (estimate.exterior_correlation > imitated.exterior_correlation &&
            !KeptUnknownFocalLength(estimate) &&
            Undeterminable(estimate, &why)) {
          imitated = estimate;
          reason = why;
        }
      }
      if (imitated.camera_idx < 0) return;
      RemoveParameter(imitated, "not determinable: " + reason);
    }
  }

  // Whether `estimate` is to be removed before step 2 (above), and why.
  bool Undeterminable(const ParameterEstimate& estimate,
                      std::string* reason) const {
    const BlockCamera& camera = block_->cameras[estimate.camera_idx];
    const std::vector<int> interior = InteriorParameters(camera.camera);
    const bool is_interior =
        std::find(interior.begin(), interior.end(), estimate.param_idx) !=
        interior.end();
    if (estimate.exterior_correlation > options_.max_exterior_correlation) {
      const double sigma_px = estimate.std_dev * PixelsPerUnit(camera.camera);
      const double diagonal =
          std::hypot(static_cast<double>(camera.camera.width),
                     static_cast<double>(camera.camera.height));
      if (!is_interior || sigma_px > options_.max_interior_sigma * diagonal) {
        *reason = StrCat("correlation ",
                         estimate.exterior_correlation,
                         " with an exterior orientation > ",
                         options_.max_exterior_correlation,
                         is_interior
                             ? StrCat(", standard deviation ", sigma_px, " px")
                             : std::string());
        return true;
      }
    }
    return false;
  }

  // The interior orientation among a camera's parameters: Brown/Beyer's
  // corrections dc, dx0, dy0; a COLMAP model's focal length(s) and
  // principal point.
  static std::vector<int> InteriorParameters(const Camera& camera) {
    if (camera.model_id == CameraModelId::kBrownBeyer) {
      return {brown::kDc, brown::kDx0, brown::kDy0};
    }
    const CameraModelInfo& info = camera.ModelInfo();
    std::vector<int> idxs = info.focal_idxs;
    idxs.insert(idxs.end(),
                info.principal_point_idxs.begin(),
                info.principal_point_idxs.end());
    return idxs;
  }

  // Pixels per unit of the interior orientation: Brown/Beyer's are
  // millimetres of the image frame, COLMAP's pixels.
  static double PixelsPerUnit(const Camera& camera) {
    if (camera.model_id == CameraModelId::kBrownBeyer) {
      return 1 / camera.DefaultFrame().MeanPitchMm();
    }
    return 1;
  }

  // The estimates of every free candidate parameter.
  std::vector<ParameterEstimate> FreeEstimates(
      const AdjustmentPrecision& precision) const {
    std::vector<ParameterEstimate> estimates;
    for (size_t c = 0; c < block_->cameras.size(); ++c) {
      const BlockCamera& camera = block_->cameras[c];
      const std::vector<std::string> names =
          ParameterNames(camera.camera.model_id);
      for (int idx : candidates_[c]) {
        if (camera.free[idx]) {
          estimates.push_back(
              Estimate(precision, static_cast<int>(c), idx, names[idx]));
        }
      }
    }
    return estimates;
  }

  // Holds a parameter at its initial value from now on, with the reason.
  void RemoveParameter(const ParameterEstimate& estimate,
                       const std::string& reason) {
    BlockCamera& camera = block_->cameras[estimate.camera_idx];
    camera.free[estimate.param_idx] = false;
    camera.camera.params[estimate.param_idx] =
        initial_params_[estimate.camera_idx][estimate.param_idx];
    RemovedParameter removed;
    removed.estimate = estimate;
    removed.reason = reason;
    result_.removed_parameters.push_back(removed);
    LOG(INFO) << "self-calibration: " << estimate.name << " " << reason
              << ", removed";
  }

  void SelectSignificantParameters() {
    PrecisionOptions precision_options;
    precision_options.compute_residual_cofactors = false;
    while (true) {
      const AdjustmentPrecision precision =
          ComputePrecision(block_, precision_options);
      RecordSigma0(precision.sigma0);
      // Significance, the weakest parameter at a time (determinability was
      // tested before step 2).
      ParameterEstimate weakest;
      weakest.t_value = std::numeric_limits<double>::infinity();
      for (const ParameterEstimate& estimate : FreeEstimates(precision)) {
        if (HigherRadialTermFree(block_->cameras[estimate.camera_idx],
                                 estimate.param_idx) ||
            KeptUnknownFocalLength(estimate)) {
          continue;
        }
        if (estimate.t_value < weakest.t_value) weakest = estimate;
      }
      if (weakest.camera_idx < 0 ||
          weakest.t_value >= options_.significance_t) {
        return;
      }
      RemoveParameter(weakest,
                      StrCat("not significant: t = ",
                             weakest.t_value,
                             " < ",
                             options_.significance_t));
      Solve(StrCat("without ", weakest.name), false);
    }
  }

  // Radial distortion is a polynomial: a term is tested (and can be
  // removed) only when no higher-order term is still estimated, so that the
  // strongly correlated K1, K2, K3 do not take each other's place.
  static bool HigherRadialTermFree(const BlockCamera& camera, int idx) {
    if (camera.camera.model_id != CameraModelId::kBrownBeyer) return false;
    if (idx < brown::kK1 || idx > brown::kK3) return false;
    for (int higher = idx + 1; higher <= brown::kK3; ++higher) {
      if (camera.free[higher]) return true;
    }
    return false;
  }

  ParameterEstimate Estimate(const AdjustmentPrecision& precision,
                             int camera_idx,
                             int param_idx,
                             const std::string& name) const {
    ParameterEstimate estimate;
    estimate.camera_idx = camera_idx;
    estimate.param_idx = param_idx;
    estimate.name = name;
    estimate.value = block_->cameras[camera_idx].camera.params[param_idx];
    const double variance =
        precision.camera_covariance[camera_idx](param_idx, param_idx);
    estimate.std_dev = std::sqrt(std::max(variance, 0.0));
    if (camera_idx <
        static_cast<int>(precision.camera_exterior_correlation.size())) {
      estimate.exterior_correlation =
          precision.camera_exterior_correlation[camera_idx](param_idx);
    }
    estimate.t_value = estimate.std_dev > 0
                           ? std::abs(estimate.value) / estimate.std_dev
                           : std::numeric_limits<double>::infinity();
    return estimate;
  }

  // The solution moved into the datum of inner constraints over the tie
  // points that fix it (InnerConstraintPoints): the similarity that brings
  // them closest to their input coordinates (the linearised condition
  // G^T dx = 0).
  void TransformToInnerConstraintDatum() {
    const std::vector<bool> datum_points = InnerConstraintPoints(*block_);
    std::vector<Eigen::Vector3d> adjusted, reference;
    for (size_t p = 0; p < block_->points.size(); ++p) {
      if (!datum_points[p]) continue;
      adjusted.push_back(block_->points[p].xyz);
      reference.push_back(initial_xyz_[p]);
    }
    const std::optional<Sim3d> transform = EstimateSim3d(adjusted, reference);
    if (!transform) throw RunFailure("free network: too few tie points left");
    for (BlockPoint& point : block_->points) point.xyz = *transform * point.xyz;
    for (BlockImage& image : block_->images) {
      image.SetCamFromWorld(transform->TransformPose(image.CamFromWorld()));
    }
  }

  void CollectParameters() {
    const AdjustmentPrecision& precision = result_.precision;
    result_.parameter_correlations.resize(block_->cameras.size());
    for (size_t c = 0; c < block_->cameras.size(); ++c) {
      const BlockCamera& camera = block_->cameras[c];
      const std::vector<std::string> names =
          ParameterNames(camera.camera.model_id);
      std::vector<int> free_idxs;
      for (size_t idx = 0; idx < camera.free.size(); ++idx) {
        if (!camera.free[idx]) continue;
        free_idxs.push_back(static_cast<int>(idx));
        result_.final_parameters.push_back(
            Estimate(precision, static_cast<int>(c), idx, names[idx]));
      }
      const Eigen::MatrixXd correlation =
          CorrelationFromCovariance(precision.camera_covariance[c]);
      Eigen::MatrixXd selected(free_idxs.size(), free_idxs.size());
      for (size_t a = 0; a < free_idxs.size(); ++a) {
        for (size_t b = 0; b < free_idxs.size(); ++b) {
          selected(a, b) = correlation(free_idxs[a], free_idxs[b]);
          if (b > a && std::abs(selected(a, b)) > options_.max_correlation) {
            result_.correlation_flags.push_back({static_cast<int>(c),
                                                 names[free_idxs[a]],
                                                 names[free_idxs[b]],
                                                 selected(a, b)});
          }
        }
      }
      result_.parameter_correlations[c] = selected;
      // Determinability: a parameter that moves with an exterior orientation
      // is not separated from it by this network.
      for (int idx : free_idxs) {
        const double r = precision.camera_exterior_correlation[c](idx);
        if (r > options_.max_correlation) {
          result_.correlation_flags.push_back(
              {static_cast<int>(c), names[idx], "exterior orientation", r});
        }
      }
    }
    RecordSigma0(precision.sigma0);
  }

  const AdjustmentOptions& options_;
  AdjustmentBlock* block_;
  AdjustmentResult result_;
  std::vector<std::vector<double>> initial_params_;
  std::vector<Eigen::Vector3d> initial_xyz_;
  std::vector<std::vector<int>> candidates_;
};

}  // namespace

std::string BlunderDetectionName(BlunderDetection method) {
  switch (method) {
    case BlunderDetection::kNone:
      return "none";
    case BlunderDetection::kSnooping:
      return "snooping";
    case BlunderDetection::kRobust:
      break;
  }
  return "robust";
}

std::string AdjustmentOptions::SelfCalibrationName() const {
  switch (self_calibration) {
    case SelfCalibration::kNone:
      return "none";
    case SelfCalibration::kAll:
      return "all";
    case SelfCalibration::kSignificant:
      return "significant";
    case SelfCalibration::kList:
      break;
  }
  std::string list;
  for (const std::string& name : parameter_list) {
    list += (list.empty() ? "" : ",") + name;
  }
  return list;
}

void AdjustmentOptions::SetSelfCalibration(const std::string& name) {
  parameter_list.clear();
  if (name == "none") {
    self_calibration = SelfCalibration::kNone;
  } else if (name == "all") {
    self_calibration = SelfCalibration::kAll;
  } else if (name == "significant") {
    self_calibration = SelfCalibration::kSignificant;
  } else {
    self_calibration = SelfCalibration::kList;
    parameter_list = SplitList(name);
  }
}

void AdjustmentOptions::Register(OptionRegistry* r) {
  r->AddParsed(
      "self_calibration",
      [this] { return SelfCalibrationName(); },
      [this](const std::string& name) { SetSelfCalibration(name); },
      "none, all, significant (t-test, stepwise), or a list of parameters, "
      "e.g. dc,dx0,dy0,K1");
  r->Add("variance_components",
         &variance_components,
         "1: estimate the precision of each observation group (keypoint "
         "tracks, tie points, manual measurements) by variance component "
         "estimation before data snooping");
  r->AddChoice("blunder_detection",
               &blunder_detection,
               ChoicesOf<BlunderDetection>(BlunderDetectionName,
                                           {BlunderDetection::kRobust,
                                            BlunderDetection::kSnooping,
                                            BlunderDetection::kNone}),
               "robust (Huber, then data snooping), snooping, or none");
  r->Add("critical_value",
         &snooping_critical_value,
         "Data snooping: critical normalised residual (Baarda)");
  r->Add("significance_t",
         &significance_t,
         "Self-calibration: t-value below which a parameter is removed");
  r->Add("max_correlation",
         &max_correlation,
         "Correlations above this are flagged");
  r->Add("max_exterior_correlation",
         &max_exterior_correlation,
         "Self-calibration (significant): a parameter correlated above this "
         "with an exterior orientation is not determinable and removed (the "
         "interior orientation only when also imprecise, max_interior_sigma)");
  r->Add("max_interior_sigma",
         &max_interior_sigma,
         "Self-calibration (significant): the interior orientation is removed "
         "for such a correlation only with a standard deviation above this "
         "share of the image diagonal");
  r->Add("two_steps",
         &two_steps,
         "1: adjust without self-calibration first (the paper's first step)");
  r->Add("max_num_iterations",
         &solver.max_num_iterations,
         "Iterations per solution");
  r->Add("num_threads", &solver.num_threads, "-1: all cores");
}

void AdjustmentOptions::Check() const {
  CheckOption(significance_t > 0, "significance_t", "> 0", significance_t);
  CheckOption(max_correlation > 0 && max_correlation <= 1,
              "max_correlation",
              "in (0, 1]",
              max_correlation);
  CheckOption(max_exterior_correlation > 0 && max_exterior_correlation <= 1,
              "max_exterior_correlation",
              "in (0, 1]",
              max_exterior_correlation);
  CheckOption(
      max_interior_sigma > 0, "max_interior_sigma", "> 0", max_interior_sigma);
  CheckOption(snooping_critical_value > 0,
              "critical_value",
              "> 0",
              snooping_critical_value);
  CheckOption(max_snooping_iterations >= 1,
              "max_snooping_iterations",
              ">= 1",
              max_snooping_iterations);
  CheckOption(
      robust_loss_scale > 0, "robust_loss_scale", "> 0", robust_loss_scale);
  if (self_calibration == SelfCalibration::kList && parameter_list.empty()) {
    ThrowInputError("self_calibration: the list names no parameter");
  }
  solver.Check();
}

std::vector<int> CandidateParameters(CameraModelId model) {
  std::vector<int> idxs;
  if (model == CameraModelId::kBrownBeyer) {
    for (int idx = brown::kFirstAdditional; idx < brown::kNumParams; ++idx) {
      idxs.push_back(idx);
    }
    return idxs;
  }
  const CameraModelInfo& info = CameraModelInfoFor(model);
  for (int idx : info.focal_idxs) idxs.push_back(idx);
  const int first_extra = static_cast<int>(info.focal_idxs.size()) + 2;
  for (int idx = first_extra; idx < info.num_params; ++idx) idxs.push_back(idx);
  return idxs;
}

AdjustmentResult RunAdjustment(const AdjustmentOptions& options,
                               AdjustmentBlock* block) {
  options.Check();
  return Adjuster(options, block).Run();
}

}  // namespace bayon
