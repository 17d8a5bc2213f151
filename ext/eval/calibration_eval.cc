// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/calibration_eval.h"

#include "ext/core/errors.h"

#include <cmath>
#include <cstdio>

namespace bayon {
namespace {

// Standard deviation of the sum of parameters `indices` of an entry, from
// its covariance where known, else from its standard deviations (taken as
// uncorrelated); 0 when neither is known.
double SigmaOfSum(const CalibrationEntry& entry,
                  const std::vector<int>& indices) {
  const size_t n = entry.camera.params.size();
  if (entry.covariance.size() == n * n) {
    double variance = 0;
    for (int i : indices) {
      for (int j : indices) variance += entry.covariance[i * n + j];
    }
    return std::sqrt(std::max(variance, 0.0));
  }
  if (entry.std_devs.size() == n) {
    double variance = 0;
    for (int i : indices) variance += entry.std_devs[i] * entry.std_devs[i];
    return std::sqrt(variance);
  }
  return 0;
}

double Sum(const Camera& camera, const std::vector<int>& indices) {
  double sum = 0;
  for (int i : indices) sum += camera.params[i];
  return sum;
}

ParameterError Compare(const std::string& name,
                       double estimate,
                       double truth,
                       double sigma,
                       const std::string& unit) {
  ParameterError p;
  p.name = name;
  p.estimate = estimate;
  p.truth = truth;
  p.error = estimate - truth;
  p.sigma = sigma;
  p.ratio = sigma > 0 ? p.error / sigma : 0;
  p.unit = unit;
  return p;
}

}  // namespace

CalibrationEvaluation EvaluateCalibration(const CalibrationEntry& estimate,
                                          const CalibrationEntry& truth) {
  const Camera& e = estimate.camera;
  const Camera& t = truth.camera;
  CalibrationEvaluation evaluation;
  evaluation.camera_id = static_cast<int>(e.camera_id);
  evaluation.model = e.ModelName();
  evaluation.truth_model = t.ModelName();
  auto add = [&](const std::string& name,
                 const std::vector<int>& indices,
                 const std::string& unit) {
    evaluation.parameters.push_back(Compare(name,
                                            Sum(e, indices),
                                            Sum(t, indices),
                                            SigmaOfSum(estimate, indices),
                                            unit));
  };
  if (e.model_id == CameraModelId::kBrownBeyer &&
      t.model_id == CameraModelId::kBrownBeyer) {
    add("c+dc", {brown::kC, brown::kDc}, "mm");
    add("x0+dx0", {brown::kX0, brown::kDx0}, "mm");
    add("y0+dy0", {brown::kY0, brown::kDy0}, "mm");
    const std::vector<std::string> names = ParameterNames(e.model_id);
    for (int i = brown::kK1; i < brown::kNumParams; ++i) add(names[i], {i}, "");
  } else if (e.model_id == t.model_id) {
    const std::vector<std::string> names = ParameterNames(e.model_id);
    for (size_t i = 0; i < names.size(); ++i) {
      add(names[i], {static_cast<int>(i)}, "");
    }
  } else {
    // Different models: what every model has, in pixels (no sigma: it would
    // need the model's Jacobian of these derived values).
    evaluation.parameters.push_back(Compare(
        "focal_px", e.MeanFocalLengthPx(), t.MeanFocalLengthPx(), 0, "px"));
    const Eigen::Vector2d pe = e.PrincipalPointPx(), pt = t.PrincipalPointPx();
    evaluation.parameters.push_back(Compare("cx_px", pe.x(), pt.x(), 0, "px"));
    evaluation.parameters.push_back(Compare("cy_px", pe.y(), pt.y(), 0, "px"));
  }
  for (const ParameterError& p : evaluation.parameters) {
    if (p.sigma > 0) {
      evaluation.max_abs_ratio =
          std::max(evaluation.max_abs_ratio, std::abs(p.ratio));
    }
  }
  return evaluation;
}

std::vector<CalibrationEvaluation> EvaluateCalibrations(
    const std::vector<CalibrationEntry>& estimates,
    const std::vector<CalibrationEntry>& truths) {
  std::vector<CalibrationEvaluation> evaluations;
  if (estimates.size() == 1 && truths.size() == 1) {
    evaluations.push_back(EvaluateCalibration(estimates[0], truths[0]));
    return evaluations;
  }
  for (const CalibrationEntry& estimate : estimates) {
    const CalibrationEntry* truth = nullptr;
    for (const CalibrationEntry& t : truths) {
      if (t.camera.camera_id == estimate.camera.camera_id) truth = &t;
    }
    if (truth == nullptr) {
      ThrowInputError("camera ",
                      estimate.camera.camera_id,
                      " of the calibration has no true camera of that id");
    }
    evaluations.push_back(EvaluateCalibration(estimate, *truth));
  }
  return evaluations;
}

std::string CalibrationTable(const CalibrationEvaluation& evaluation) {
  std::string table;
  char line[256];
  std::snprintf(line,
                sizeof(line),
                "camera %d: %s against true %s\n",
                evaluation.camera_id,
                evaluation.model.c_str(),
                evaluation.truth_model.c_str());
  table += line;
  std::snprintf(line,
                sizeof(line),
                "  %-10s %14s %14s %12s %12s %8s\n",
                "parameter",
                "estimate",
                "truth",
                "error",
                "sigma",
                "err/sig");
  table += line;
  for (const ParameterError& p : evaluation.parameters) {
    if (p.sigma > 0) {
      std::snprintf(line,
                    sizeof(line),
                    "  %-10s %14.6g %14.6g %12.4g %12.4g %8.2f %s\n",
                    p.name.c_str(),
                    p.estimate,
                    p.truth,
                    p.error,
                    p.sigma,
                    p.ratio,
                    p.unit.c_str());
    } else {
      std::snprintf(line,
                    sizeof(line),
                    "  %-10s %14.6g %14.6g %12.4g %12s %8s %s\n",
                    p.name.c_str(),
                    p.estimate,
                    p.truth,
                    p.error,
                    "-",
                    "-",
                    p.unit.c_str());
    }
    table += line;
  }
  return table;
}

nlohmann::ordered_json CalibrationEvaluationJson(
    const CalibrationEvaluation& e) {
  nlohmann::ordered_json json = {{"camera_id", e.camera_id},
                                 {"model", e.model},
                                 {"truth_model", e.truth_model},
                                 {"max_abs_error_over_sigma", e.max_abs_ratio}};
  json["parameters"] = nlohmann::ordered_json::array();
  for (const ParameterError& p : e.parameters) {
    nlohmann::ordered_json row = {{"name", p.name},
                                  {"estimate", p.estimate},
                                  {"truth", p.truth},
                                  {"error", p.error}};
    if (p.sigma > 0) {
      row["sigma"] = p.sigma;
      row["error_over_sigma"] = p.ratio;
    }
    json["parameters"].push_back(row);
  }
  return json;
}

}  // namespace bayon
