// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon targets`: the coded targets (coded_targets.h) in every photograph
// of a COLMAP database, as image measurements of named points in the format
// of a workspace's control/observations.txt (control_io.h), so that
// `bayon tiepoints --manual_path` takes them as named tie points and a name
// with coordinates in control/points.txt makes a target a control or check
// point.
//
// A measurement's SIGMA is the larger axis of the target centre's
// covariance: the file keeps one standard deviation per measurement.
#pragma once

#include "ext/colmap/control_io.h"
#include "ext/targets/coded_targets.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace bayon {

struct CodedTargetImageReport {
  std::string image_name;
  CodedTargetReport detection;
};

struct CodedTargetSummary {
  std::vector<ImageMeasurement> measurements;  // image, then code order
  std::vector<CodedTargetImageReport> images;  // the database's order
  int num_targets = 0;                         // distinct names
  int num_refused = 0;                         // decoded, but not measured
  double median_sigma_px = 0;
  double seconds = 0;
  // "N coded targets measured M times in P of Q photographs ...".
  std::string Summary() const;
};

// Reads the database's image list and every photograph under image_path;
// InputError before any work for a missing database or photograph, and
// during it for a photograph that is not an image or shows a code twice
// (naming it).
CodedTargetSummary FindCodedTargets(const std::string& database_path,
                                    const std::string& image_path,
                                    const CodedTargetOptions& options,
                                    int num_threads);

// The report as `bayon targets --report_path` writes it: the totals and,
// per photograph, what was decoded, measured and refused (with why).
nlohmann::ordered_json CodedTargetReportJson(const CodedTargetSummary& summary,
                                             const CodedTargetOptions& options);

}  // namespace bayon
