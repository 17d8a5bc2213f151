// SPDX-License-Identifier: BSD-3-Clause
//
// calibration.json: the full calibration of each camera, written beside a
// model (sparse/<name>/calibration.json) and as ground truth (gt/). Layout:
//
// {
//   "format": "bayon-calibration", "version": 1,
//   "cameras": [{
//     "camera_id": 1, "model": "BROWN_BEYER", "width": 1800, "height": 1200,
//     "pixel_pitch_mm": 0.02,
//     "params": {"c": 35.0, "x0": 0.0, ..., "B2": 0.0},   // names of the model
//     "std_devs": {"dc": 0.001, ...},                      // optional
//     "covariance": [[...]],                               // optional, n x n
//     "colmap": {"model": "FULL_OPENCV", "params": [...],
//                "fit_rms_px": 0.01, "fit_max_px": 0.05}   // optional
//   }]
// }
#pragma once

#include "ext/core/camera.h"
#include "ext/core/camera_conversion.h"
#include "ext/core/scene.h"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace bayon {

struct CalibrationEntry {
  Camera camera;
  std::vector<double> std_devs;    // per parameter; empty if unknown
  std::vector<double> covariance;  // n x n row-major; empty if unknown
  std::optional<Camera> colmap_camera;
  double colmap_fit_rms_px = 0;
  double colmap_fit_max_px = 0;
};

// The entry of a camera converted for COLMAP (ConvertSceneCamerasToColmap):
// the original camera with its COLMAP fit and the fit residual.
CalibrationEntry CalibrationEntryFromConversion(
    const SceneCameraConversion& conversion);

// Parameter names of a model, in order ("c", "x0", ... or "f", "cx", ...).
std::vector<std::string> ParameterNames(CameraModelId model_id);

std::string CalibrationToJson(const std::vector<CalibrationEntry>& entries);
void WriteCalibrationJson(const std::string& path,
                          const std::vector<CalibrationEntry>& entries);
// Throws InputError naming the file and the entry that is wrong.
std::vector<CalibrationEntry> ReadCalibrationJson(const std::string& path);

// The full calibrations in `<model_path>/calibration.json`, by camera id;
// empty where the model has no such file (a stock COLMAP model, whose
// cameras rows are the whole calibration).
std::map<camera_t, Camera> ReadCalibrationsBesideModel(
    const std::string& model_path);

// A sparse model as the dense and texture stages need it: the cameras with
// their full calibration (calibration.json beside the model) and, where a
// database is given, the scanned frames' interior orientations from its
// bayon_interior table. Throws InputError for an unreadable model or
// database.
Scene ReadOrientedModel(const std::string& model_path,
                        const std::string& database_path);

}  // namespace bayon
