// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/calibration_json.h"

#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <sstream>

namespace bayon {

CalibrationEntry CalibrationEntryFromConversion(
    const SceneCameraConversion& conversion) {
  CalibrationEntry entry;
  entry.camera = conversion.source;
  entry.colmap_camera = conversion.conversion.camera;
  entry.colmap_fit_rms_px = conversion.conversion.rms_residual_px;
  entry.colmap_fit_max_px = conversion.conversion.max_residual_px;
  return entry;
}

std::vector<std::string> ParameterNames(CameraModelId model_id) {
  std::vector<std::string> names;
  std::istringstream stream(CameraModelInfoFor(model_id).params_info);
  std::string name;
  while (std::getline(stream, name, ',')) {
    const size_t start = name.find_first_not_of(' ');
    names.push_back(name.substr(start));
  }
  return names;
}

std::string CalibrationToJson(const std::vector<CalibrationEntry>& entries) {
  nlohmann::ordered_json root;
  root["format"] = "bayon-calibration";
  root["version"] = 1;
  root["cameras"] = nlohmann::ordered_json::array();
  for (const CalibrationEntry& entry : entries) {
    const Camera& camera = entry.camera;
    nlohmann::ordered_json item;
    item["camera_id"] = camera.camera_id;
    item["model"] = camera.ModelName();
    item["width"] = camera.width;
    item["height"] = camera.height;
    if (camera.pixel_pitch_mm > 0)
      item["pixel_pitch_mm"] = camera.pixel_pitch_mm;
    const std::vector<std::string> names = ParameterNames(camera.model_id);
    nlohmann::ordered_json params;
    for (size_t i = 0; i < names.size(); ++i)
      params[names[i]] = camera.params[i];
    item["params"] = params;
    if (!entry.std_devs.empty()) {
      nlohmann::ordered_json std_devs;
      for (size_t i = 0; i < names.size() && i < entry.std_devs.size(); ++i) {
        std_devs[names[i]] = entry.std_devs[i];
      }
      item["std_devs"] = std_devs;
    }
    if (!entry.covariance.empty()) {
      const size_t n = names.size();
      nlohmann::ordered_json rows = nlohmann::ordered_json::array();
      for (size_t r = 0; r < n; ++r) {
        std::vector<double> row(entry.covariance.begin() + r * n,
                                entry.covariance.begin() + (r + 1) * n);
        rows.push_back(row);
      }
      item["covariance"] = rows;
    }
    if (entry.colmap_camera) {
      nlohmann::ordered_json colmap;
      colmap["model"] = entry.colmap_camera->ModelName();
      colmap["params"] = entry.colmap_camera->params;
      colmap["fit_rms_px"] = entry.colmap_fit_rms_px;
      colmap["fit_max_px"] = entry.colmap_fit_max_px;
      item["colmap"] = colmap;
    }
    root["cameras"].push_back(item);
  }
  return root.dump(2) + "\n";
}

void WriteCalibrationJson(const std::string& path,
                          const std::vector<CalibrationEntry>& entries) {
  WriteFileAtomically(path, CalibrationToJson(entries));
}

std::vector<CalibrationEntry> ReadCalibrationJson(const std::string& path) {
  const std::string text = ReadFileToString(path);
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& error) {
    ThrowInputError(path, ": not valid JSON: ", error.what());
  }
  if (!root.is_object() || !root.contains("cameras") ||
      !root["cameras"].is_array()) {
    ThrowInputError(path, ": expected an object with a \"cameras\" array");
  }
  std::vector<CalibrationEntry> entries;
  int index = 0;
  for (const auto& item : root["cameras"]) {
    const std::string where = StrCat(path, ": cameras[", index++, "]");
    try {
      CalibrationEntry entry;
      Camera& camera = entry.camera;
      camera.camera_id = item.at("camera_id").get<camera_t>();
      const std::string model = item.at("model").get<std::string>();
      const auto model_id = CameraModelIdFromName(model);
      if (!model_id) ThrowInputError(where, ": unknown model '", model, "'");
      camera.model_id = *model_id;
      camera.width = item.at("width").get<uint64_t>();
      camera.height = item.at("height").get<uint64_t>();
      camera.pixel_pitch_mm = item.value("pixel_pitch_mm", 0.0);
      const std::vector<std::string> names = ParameterNames(camera.model_id);
      const auto& params = item.at("params");
      for (const std::string& name : names) {
        if (!params.contains(name)) {
          ThrowInputError(where, ": params lacks \"", name, "\"");
        }
        camera.params.push_back(params.at(name).get<double>());
      }
      if (item.contains("std_devs")) {
        for (const std::string& name : names) {
          entry.std_devs.push_back(item["std_devs"].value(name, 0.0));
        }
      }
      if (item.contains("covariance")) {
        for (const auto& row : item["covariance"]) {
          for (const auto& value : row)
            entry.covariance.push_back(value.get<double>());
        }
        if (entry.covariance.size() != names.size() * names.size()) {
          ThrowInputError(where,
                          ": covariance must be ",
                          names.size(),
                          " x ",
                          names.size());
        }
      }
      if (item.contains("colmap")) {
        const auto& colmap = item["colmap"];
        const auto colmap_model =
            CameraModelIdFromName(colmap.at("model").get<std::string>());
        if (!colmap_model || !IsColmapCameraModel(*colmap_model)) {
          ThrowInputError(where, ": colmap.model is not a COLMAP model");
        }
        Camera colmap_camera;
        colmap_camera.camera_id = camera.camera_id;
        colmap_camera.model_id = *colmap_model;
        colmap_camera.width = camera.width;
        colmap_camera.height = camera.height;
        colmap_camera.params = colmap.at("params").get<std::vector<double>>();
        colmap_camera.Check();
        entry.colmap_camera = colmap_camera;
        entry.colmap_fit_rms_px = colmap.value("fit_rms_px", 0.0);
        entry.colmap_fit_max_px = colmap.value("fit_max_px", 0.0);
      }
      camera.Check();
      entries.push_back(std::move(entry));
    } catch (const nlohmann::json::exception& error) {
      ThrowInputError(where, ": ", error.what());
    } catch (const InputError& error) {
      const std::string message = error.what();
      if (message.rfind(path, 0) == 0) throw;
      ThrowInputError(where, ": ", message);
    }
  }
  return entries;
}

std::map<camera_t, Camera> ReadCalibrationsBesideModel(
    const std::string& model_path) {
  std::map<camera_t, Camera> cameras;
  const std::string json = model_path + "/calibration.json";
  if (!std::filesystem::exists(json)) return cameras;
  for (const CalibrationEntry& entry : ReadCalibrationJson(json)) {
    cameras[entry.camera.camera_id] = entry.camera;
  }
  return cameras;
}

Scene ReadOrientedModel(const std::string& model_path,
                        const std::string& database_path) {
  Scene scene = ReadModel(model_path);
  for (const auto& [camera_id, camera] :
       ReadCalibrationsBesideModel(model_path)) {
    if (scene.cameras.contains(camera_id)) scene.cameras.at(camera_id) = camera;
  }
  // Dense matching, texturing and rendering project through the cameras: a
  // camera without a focal length (a model that was never calibrated, or
  // whose parameters were lost) would give nothing, silently.
  for (const auto& [image_id, image] : scene.images) {
    const Camera& camera = scene.cameras.at(image.camera_id);
    const double focal = camera.MeanFocalLengthPx();
    bool finite = std::isfinite(focal);
    for (double p : camera.params) finite = finite && std::isfinite(p);
    if (!finite || !(focal > 0)) {
      ThrowInputError(model_path,
                      ": camera ",
                      image.camera_id,
                      " (",
                      camera.ModelName(),
                      ", of image ",
                      image.name,
                      ") has no calibration: focal length ",
                      focal,
                      " px; orient and calibrate the images first (bayon "
                      "adjust) or give a calibrated model");
    }
  }
  if (!database_path.empty()) {
    Database database(database_path, Database::Mode::kReadOnly);
    SetInteriorFrames(&database, &scene);
  }
  return scene;
}

}  // namespace bayon
