// SPDX-License-Identifier: BSD-3-Clause
//
// A sparse model against the truth: which images were registered, and how far
// their projection centres and rotations are from the true ones, after a
// 7-parameter similarity fitted to the centres (or directly when both share
// a datum). Images are matched by name, never by id.
#pragma once

#include "ext/core/scene.h"
#include "ext/core/sim3.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace bayon {

struct SparseEvaluationOptions {
  // Fit a similarity truth_from_model to the camera centres first. Off when
  // the model was oriented in the truth's datum (control points).
  bool align = true;
};

struct ImageEvaluation {
  std::string name;
  bool registered = false;
  double center_error = 0;  // object units
  double rotation_error_deg = 0;
};

struct SparseEvaluation {
  int num_truth_images = 0;
  int num_registered = 0;  // truth images present in the model
  int num_model_points = 0;
  Sim3d truth_from_model;
  // Mean distance from the true camera centres to their centroid: the scale
  // against which the centre errors are given as fractions.
  double mean_camera_distance = 0;
  double center_rms = 0;
  double center_max = 0;
  double center_rms_relative = 0;  // center_rms / mean_camera_distance
  double center_max_relative = 0;
  double rotation_rms_deg = 0;
  double rotation_max_deg = 0;
  std::vector<ImageEvaluation> images;  // in truth order
};

// Throws InputError if fewer than 3 images (2 without alignment) are shared.
SparseEvaluation EvaluateSparse(const Scene& model,
                                const Scene& truth,
                                const SparseEvaluationOptions& options = {});

// The evaluation as `bayon evaluate` reports it ("sparse").
nlohmann::ordered_json SparseEvaluationJson(const SparseEvaluation& e);

// Its one-line table: registered images, centre and rotation errors.
std::string SparseEvaluationTable(const std::string& label,
                                  const SparseEvaluation& e);

}  // namespace bayon
