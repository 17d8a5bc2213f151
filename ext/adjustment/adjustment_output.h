// SPDX-License-Identifier: BSD-3-Clause
//
// The outputs of `bayon adjust`, written into one model folder:
//
//   cameras.bin images.bin points3D.bin   the adjusted COLMAP model; each
//       BROWN_BEYER camera as its closest COLMAP model (FULL_OPENCV, fitted
//       over the whole frame; the fit residual is in calibration.json and
//       the report);
//   calibration.json   the full calibration with standard deviations and
//       the covariance of the parameters (ext/colmap/calibration_json.h);
//   adjustment.json    every statistic: observations n, unknowns u, datum
//       defect d, redundancy r, r/n, sigma0 (pixels and micrometres in the
//       image), the additional parameters with their t-values and
//       correlations, rejected observations, the theoretical precision of
//       every object point and exterior orientation (from the inverse of the
//       normal equations), check-point differences;
//   adjustment.txt     the same as a readable printout in the style of a
//       classic bundle adjustment program.
//
// Units in the reports: object coordinates in metres, their precision in
// millimetres, rotations' precision in millidegrees about the camera axes,
// image residuals in pixels.
#pragma once

#include "ext/adjustment/adjustment.h"
#include "ext/adjustment/adjustment_input.h"
#include "ext/colmap/calibration_json.h"
#include "ext/core/scene.h"

#include <string>
#include <vector>

namespace bayon {

struct AdjustmentRunInfo {
  std::string database_path;
  std::string input_path;
  std::string control_path;
  // The control's crs.json (bayon import_control), or empty.
  std::string georeference_json;
  std::string self_calibration;   // the mode, as given
  std::string blunder_detection;  // the method, as given
};

struct AdjustmentOutputs {
  Scene model;  // COLMAP cameras
  std::vector<CalibrationEntry> calibration;
  std::string json;  // adjustment.json
  std::string text;  // adjustment.txt
  // The control's crs.json (bayon import_control), written beside the
  // model so that it says where it lies in the world; empty: none.
  std::string crs_json;
  // Key figures for the command's summary.
  double sigma0_px = 0;
  double check_rms_m = 0;  // 3D RMS over the check points; 0 without any
  double max_colmap_fit_rms_px = 0;
};

// `input.block` must be the block RunAdjustment adjusted.
AdjustmentOutputs MakeAdjustmentOutputs(const AdjustmentInput& input,
                                        const AdjustmentResult& result,
                                        const AdjustmentOptions& options,
                                        const AdjustmentRunInfo& info);

// Writes the folder atomically (assembled under a temporary name, then
// renamed); refuses an existing folder unless `overwrite`.
void WriteAdjustmentOutputs(const AdjustmentOutputs& outputs,
                            const std::string& output_path,
                            bool overwrite);

}  // namespace bayon
