// SPDX-License-Identifier: BSD-3-Clause
//
// An estimated camera calibration (calibration.json beside an adjusted
// model) against the true one, parameter by parameter, each error also in
// units of the estimate's own standard deviation where the adjustment gave
// one: |error / sigma| well above 3 says the precision figures are not to
// be trusted, or a parameter is biased.
//
// Brown/Beyer against Brown/Beyer compares what the image formation sees:
// the camera constant c + dc and the principal point x0 + dx0, y0 + dy0 (a
// nominal value plus its correction can be split either way), then K1, K2,
// K3, P1, P2, B1, B2 directly (mm-based, the same for both). Two cameras of
// one COLMAP model compare every parameter by name; cameras of different
// models compare the focal length and the principal point in pixels.
#pragma once

#include "ext/colmap/calibration_json.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace bayon {

struct ParameterError {
  std::string name;
  double estimate = 0;
  double truth = 0;
  double error = 0;  // estimate - truth
  double sigma = 0;  // standard deviation of the estimate; 0 unknown
  double ratio = 0;  // error / sigma; 0 when sigma is unknown
  std::string unit;  // "mm", "px" or "" (dimensionless or mm^-k)
};

struct CalibrationEvaluation {
  int camera_id = 0;
  std::string model;        // the estimate's model
  std::string truth_model;  // the truth's model
  std::vector<ParameterError> parameters;
  double max_abs_ratio = 0;  // over the parameters with a sigma
};

CalibrationEvaluation EvaluateCalibration(const CalibrationEntry& estimate,
                                          const CalibrationEntry& truth);

// Pairs cameras by id, or the only camera of each side when both have one;
// throws InputError when a camera has no counterpart.
std::vector<CalibrationEvaluation> EvaluateCalibrations(
    const std::vector<CalibrationEntry>& estimates,
    const std::vector<CalibrationEntry>& truths);

// A table: one line per parameter.
std::string CalibrationTable(const CalibrationEvaluation& evaluation);

// One camera's evaluation as `bayon evaluate` reports it.
nlohmann::ordered_json CalibrationEvaluationJson(
    const CalibrationEvaluation& e);

}  // namespace bayon
