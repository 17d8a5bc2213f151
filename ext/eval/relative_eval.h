// SPDX-License-Identifier: BSD-3-Clause
//
// The pair orientations of a database (`bayon relative`'s records) against
// the truth: for each pair, the error of the relative rotation and the angle
// between the estimated and the true base direction (the base's length is
// not determined by a pair), also in units of the standard deviations the
// pair's adjustment stated. Images are matched by name, never by id.
#pragma once

#include "ext/colmap/database.h"
#include "ext/core/scene.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace bayon {

struct RelativeEvaluationOptions {
  // Only the pairs of neighbouring images in the database's order, the last
  // with the first: the stations of a ring photographed in order. Otherwise
  // every pair that has matches.
  bool adjacent_only = false;
};

struct PairEvaluation {
  std::string name1, name2;  // in image id order
  bool oriented = false;
  std::string reason;  // why not oriented
  int num_matches = 0;
  int num_inliers = 0;
  double sigma0_px = 0;
  double rotation_error_deg = 0;
  double base_error_deg = 0;
  // The norms of the stated standard deviations of omega, phi, kappa and of
  // the base direction's two angles.
  double std_rotation_deg = 0;
  double std_base_deg = 0;
};

struct RelativeEvaluation {
  std::vector<PairEvaluation> pairs;
  int num_pairs = 0;
  int num_oriented = 0;
  double median_rotation_error_deg = 0;  // of the oriented pairs
  double max_rotation_error_deg = 0;
  double max_base_error_deg = 0;
  // The largest errors in units of the pair's own standard deviations.
  double max_rotation_ratio = 0;
  double max_base_ratio = 0;
};

// Throws InputError if an image of a judged pair is not in the truth.
RelativeEvaluation EvaluateRelativeOrientations(
    Database* database,
    const Scene& truth,
    const RelativeEvaluationOptions& options = {});

// One line per pair and a summary line, for the terminal.
std::string RelativeEvaluationTable(const std::string& label,
                                    const RelativeEvaluation& evaluation);

// The evaluation as `bayon evaluate` reports it ("relative").
nlohmann::ordered_json RelativeEvaluationJson(const RelativeEvaluation& e);

}  // namespace bayon
