// SPDX-License-Identifier: BSD-3-Clause
#include "ext/report/report_workspace.h"

#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <exception>

namespace bayon {
namespace report {

namespace fs = std::filesystem;

const Json& Child(const Json& json, const char* key) {
  static const Json kNull;
  if (!json.is_object()) return kNull;
  const auto it = json.find(key);
  return it == json.end() ? kNull : *it;
}

double Number(const Json& json, const char* key) {
  const Json& value = Child(json, key);
  return value.is_number() ? value.get<double>() : kNaN;
}

double Number(const Json& json) {
  return json.is_number() ? json.get<double>() : kNaN;
}

double NumberAt(const Json& json, size_t index) {
  return json.is_array() && index < json.size() ? Number(json[index]) : kNaN;
}

int64_t Integer(const Json& json, const char* key) {
  const Json& value = Child(json, key);
  return value.is_number() ? static_cast<int64_t>(value.get<double>()) : -1;
}

std::string String(const Json& json, const char* key) {
  return String(Child(json, key));
}

std::string String(const Json& json) {
  return json.is_string() ? json.get<std::string>() : "";
}

namespace {

JsonFile LoadJson(const fs::path& root, const std::string& relative) {
  JsonFile file;
  file.relative_path = relative;
  const fs::path path = root / relative;
  std::error_code ec;
  file.exists = fs::is_regular_file(path, ec);
  if (!file.exists) return file;
  try {
    file.json = Json::parse(ReadFileToString(path.string()));
  } catch (const std::exception& error) {
    file.error = error.what();
  }
  return file;
}

void ReadDatabaseFacts(Workspace* ws) {
  const fs::path path = ws->root / "database.db";
  if (!fs::is_regular_file(path)) return;
  try {
    Database database(path.string(), Database::Mode::kReadOnly);
    ws->num_database_images = database.NumImages();
    for (const auto& [image_id, image] : ws->model.images) {
      if (database.ExistsKeypoints(image_id)) {
        ws->num_keypoints[image_id] =
            static_cast<int>(database.ReadKeypoints(image_id).rows());
      }
    }
    SetInteriorFrames(&database, &ws->model);
  } catch (const std::exception& error) {
    ws->database_error = error.what();
    ws->num_keypoints.clear();
  }
}

void ComputeObservations(Workspace* ws) {
  for (const auto& [image_id, image] : ws->model.images) {
    const auto keypoints = ws->num_keypoints.find(image_id);
    if (keypoints != ws->num_keypoints.end() &&
        static_cast<int>(image.points2D.size()) > keypoints->second) {
      ws->has_tie_observations = true;
    }
  }
  for (const auto& [image_id, image] : ws->model.images) {
    const auto keypoints = ws->num_keypoints.find(image_id);
    for (size_t idx = 0; idx < image.points2D.size(); ++idx) {
      const Point2D& point2D = image.points2D[idx];
      if (!point2D.HasPoint3D() ||
          !ws->model.points3D.contains(point2D.point3D_id)) {
        continue;
      }
      Observation o;
      o.image_id = image_id;
      o.xy = point2D.xy;
      Eigen::Vector2d projected;
      o.residual =
          ws->model.Project(
              image, ws->model.points3D.at(point2D.point3D_id).xyz, &projected)
              ? Eigen::Vector2d(projected - point2D.xy)
              : Eigen::Vector2d::Constant(kNaN);
      o.tie = ws->has_tie_observations &&
              keypoints != ws->num_keypoints.end() &&
              static_cast<int>(idx) >= keypoints->second;
      ws->observations.push_back(o);
    }
  }
}

}  // namespace

Workspace LoadWorkspace(const std::string& workspace_path) {
  Workspace ws;
  ws.root = fs::path(workspace_path);
  if (!fs::is_directory(ws.root)) {
    ThrowInputError(workspace_path, ": no such workspace folder");
  }
  const fs::path adjusted = ws.root / "sparse" / "adjusted";
  if (!fs::is_directory(adjusted)) {
    ThrowInputError(adjusted.string(),
                    ": no adjusted model (run bayon pipeline or bayon adjust "
                    "first)");
  }
  ws.model = ReadModel(adjusted.string());
  if (fs::is_regular_file(adjusted / "calibration.json")) {
    try {
      ws.calibration =
          ReadCalibrationJson((adjusted / "calibration.json").string());
      for (const CalibrationEntry& entry : ws.calibration) {
        if (ws.model.cameras.contains(entry.camera.camera_id)) {
          ws.model.cameras.at(entry.camera.camera_id) = entry.camera;
        }
      }
    } catch (const InputError& error) {
      ws.calibration_error = error.what();
    }
  }
  ReadDatabaseFacts(&ws);
  ComputeObservations(&ws);
  ws.pipeline = LoadJson(ws.root, "pipeline.json");
  ws.adjustment = LoadJson(ws.root, "sparse/adjusted/adjustment.json");
  ws.strip = LoadJson(ws.root, "sparse/initial/strip.json");
  ws.tiepoints = LoadJson(ws.root, "pipeline/tiepoints.json");
  ws.dense = LoadJson(ws.root, "dense/points.json");
  ws.edit = LoadJson(ws.root, "dense/edit.json");
  ws.mesh = LoadJson(ws.root, "mesh/mesh.json");
  ws.texture = LoadJson(ws.root, "model/texture.json");
  ws.comparison = LoadJson(ws.root, "colmap/comparison.json");
  ws.evaluation = LoadJson(ws.root, "evaluation.json");
  return ws;
}

bool IsDatumMetric(const Workspace& ws) {
  const std::string type = String(Child(ws.adjustment.json, "datum"), "type");
  return type == "control" || type == "minimum";
}

bool IsDatumUpright(const Workspace& ws) {
  return IsDatumMetric(ws) ||
         !String(Child(ws.adjustment.json, "datum"), "vertical").empty();
}

Units DatumUnits(const Workspace& ws) {
  if (IsDatumMetric(ws)) return {"m", "mm"};
  return {"model units", "10<sup>&minus;3</sup>&nbsp;units"};
}

}  // namespace report
}  // namespace bayon
