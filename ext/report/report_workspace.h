// SPDX-License-Identifier: BSD-3-Clause
//
// Inside `bayon report` (workspace_report.h): what a workspace holds, read
// once for all sections. The adjusted model with its full calibration and
// every observation's residual; the JSON reports of the stages, each
// optional. JSON is read without throwing: a missing key or a value of
// another type reads as NaN, -1 or "".
#pragma once

#include "ext/colmap/calibration_json.h"
#include "ext/core/scene.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace bayon {
namespace report {

using Json = nlohmann::ordered_json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// json[key], or null.
const Json& Child(const Json& json, const char* key);
// A number, or NaN.
double Number(const Json& json, const char* key);
double Number(const Json& json);
// json[index] of an array as a number, or NaN.
double NumberAt(const Json& json, size_t index);
// A number as an integer, or -1.
int64_t Integer(const Json& json, const char* key);
// A string, or "".
std::string String(const Json& json, const char* key);
std::string String(const Json& json);

// A stage's JSON report.
struct JsonFile {
  std::string relative_path;  // in the workspace, as the page shows it
  bool exists = false;
  std::string error;  // why it could not be read
  Json json;
  bool ok() const { return exists && error.empty(); }
};

// One image observation of the adjusted model with its residual.
struct Observation {
  image_t image_id = kInvalidImageId;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  // Projected minus observed (the correction v of the observation), pixels;
  // NaN where the point projects behind the camera.
  Eigen::Vector2d residual = Eigen::Vector2d::Zero();
  bool tie = false;  // an LSM tie observation (else a keypoint track's)
};

struct Workspace {
  std::filesystem::path root;
  Scene model;  // sparse/adjusted with the full calibration
  std::vector<CalibrationEntry> calibration;
  std::string calibration_error;
  // Keypoints per image (the database's), where the database is readable.
  std::map<image_t, int> num_keypoints;
  int num_database_images = -1;
  std::string database_error;
  // True where the model's 2D points continue past the keypoints with tie
  // observations (bayon strip's layout: keypoints, then the image's tie
  // observations).
  bool has_tie_observations = false;
  std::vector<Observation> observations;
  JsonFile pipeline, adjustment, strip, tiepoints, dense, edit, mesh, texture,
      comparison, evaluation;
};

// Throws InputError for a missing workspace or adjusted model, or a model
// that cannot be read; everything else is optional.
Workspace LoadWorkspace(const std::string& workspace_path);

// Whether the adjustment's datum is metric and z-up (control or minimum);
// a free network keeps the strip's model units.
bool IsDatumMetric(const Workspace& ws);
// Whether z is up: a metric datum, or a free network turned upright by the
// photographs' up direction (adjustment.json's datum.vertical).
bool IsDatumUpright(const Workspace& ws);

// Units of object coordinates and of their precision, as HTML.
struct Units {
  std::string length;     // "m" or "model units"
  std::string precision;  // "mm" or thousandths of a model unit
};
Units DatumUnits(const Workspace& ws);

}  // namespace report
}  // namespace bayon
