// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/adjustment_input.h"

#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/calibration_json.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/core/camera_conversion.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <glog/logging.h>

#include <cmath>
#include <filesystem>
#include <map>

namespace fs = std::filesystem;

namespace bayon {
namespace {

// Replaces each image's 2D points by the database's keypoints (same rows:
// a COLMAP model's 2D points are its database's keypoints in order).
void TakeKeypointsFromDatabase(const std::string& input_path,
                               Database* database,
                               Scene* scene) {
  for (auto& [image_id, image] : scene->images) {
    const std::optional<DatabaseImage> row =
        database->ReadImageWithName(image.name);
    if (!row) {
      ThrowInputError(input_path,
                      ": image '",
                      image.name,
                      "' is not in the database ",
                      database->path(),
                      " (the model must come from this database)");
    }
    const FeatureKeypoints keypoints = database->ReadKeypoints(row->image_id);
    if (static_cast<size_t>(keypoints.rows()) != image.points2D.size()) {
      ThrowInputError(input_path,
                      ": image '",
                      image.name,
                      "' has ",
                      image.points2D.size(),
                      " 2D points, but the database has ",
                      keypoints.rows(),
                      " keypoints for it (the model must come from this "
                      "database)");
    }
    for (size_t k = 0; k < image.points2D.size(); ++k) {
      image.points2D[k].xy = KeypointXY(keypoints, static_cast<int>(k));
    }
  }
}

std::map<camera_t, Camera> CalibrationsBesideModel(const std::string& path) {
  std::map<camera_t, Camera> cameras;
  const std::string json = path + "/calibration.json";
  if (!fs::exists(json)) return cameras;
  for (const CalibrationEntry& entry : ReadCalibrationJson(json)) {
    cameras[entry.camera.camera_id] = entry.camera;
  }
  return cameras;
}

}  // namespace

void AdjustmentInputOptions::Check() const {
  CheckOption(image_sigma_px > 0,
              "AdjustmentInputOptions.image_sigma_px",
              "> 0",
              image_sigma_px);
  datum.Check();
}

void CheckCameraCalibration(const Camera& camera, const std::string& what) {
  try {
    camera.Check();
  } catch (const InputError& error) {
    ThrowInputError(what, ": ", error.what());
  }
  const double focal = camera.MeanFocalLengthPx();
  if (!(focal > 0) || !std::isfinite(focal)) {
    ThrowInputError(what,
                    ": camera ",
                    camera.camera_id,
                    " (",
                    camera.ModelName(),
                    ") has no calibration: focal length ",
                    focal,
                    " px");
  }
}

AdjustmentInput LoadAdjustmentInput(const std::string& database_path,
                                    const std::string& input_path,
                                    const std::string& control_path,
                                    const AdjustmentInputOptions& options) {
  options.Check();
  CheckFileExists(database_path, "--database_path");
  CheckDirectoryExists(input_path, "--input_path");
  AdjustmentInput input;
  input.scene = ReadModel(input_path);
  Scene& scene = input.scene;
  if (scene.images.size() < 2) {
    ThrowInputError(input_path,
                    ": a model with ",
                    scene.images.size(),
                    " images cannot be adjusted (two or more needed)");
  }
  if (scene.points3D.empty()) {
    ThrowInputError(input_path, ": the model has no 3D points (tie points)");
  }
  for (const auto& [camera_id, camera] : scene.cameras) {
    CheckCameraCalibration(camera, input_path);
  }
  // Read everything needed first; the control is read before any work.
  const ControlData control = ReadControlFolder(control_path);

  Database database(database_path, Database::Mode::kReadOnly);
  TakeKeypointsFromDatabase(input_path, &database, &scene);
  const std::map<camera_t, Camera> beside = CalibrationsBesideModel(input_path);
  std::map<camera_t, CalibrationRecord> calibrations;
  std::map<image_t, InteriorRecord> interiors;
  if (BayonTableExists(&database, kCalibrationTable.name)) {
    calibrations = ReadAllCalibrations(&database);
  }
  if (BayonTableExists(&database, kInteriorTable.name)) {
    interiors = ReadAllInteriors(&database);
  }

  // The cameras the block adjusts.
  Scene block_scene = scene;
  for (auto& [camera_id, camera] : block_scene.cameras) {
    CameraSource source;
    source.camera_id = camera_id;
    source.input_model = camera.ModelName();
    if (options.camera_model == CameraModelChoice::kColmap) {
      source.source = "the input model";
    } else if (auto it = beside.find(camera_id);
               it != beside.end() &&
               it->second.model_id == CameraModelId::kBrownBeyer) {
      camera = it->second;
      source.source = input_path + "/calibration.json";
    } else if (auto record = calibrations.find(camera_id);
               record != calibrations.end() &&
               record->second.camera.model_id == CameraModelId::kBrownBeyer) {
      camera = record->second.camera;
      camera.camera_id = camera_id;
      source.source = "the database (bayon_calibration)";
    } else {
      const CameraConversion conversion =
          ConvertCamera(camera, CameraModelId::kBrownBeyer);
      source.source = StrCat(source.input_model,
                             " of the input model, converted to BROWN_BEYER");
      source.conversion_rms_px = conversion.rms_residual_px;
      camera = conversion.camera;
    }
    if (camera.width != scene.cameras.at(camera_id).width ||
        camera.height != scene.cameras.at(camera_id).height) {
      ThrowInputError(source.source,
                      ": camera ",
                      camera_id,
                      " is ",
                      camera.width,
                      "x",
                      camera.height,
                      " but the model's camera is ",
                      scene.cameras.at(camera_id).width,
                      "x",
                      scene.cameras.at(camera_id).height);
    }
    CheckCameraCalibration(camera, source.source);
    input.cameras.push_back(source);
  }
  // Interior orientations of scanned film frames (digital images use the
  // camera's default frame).
  for (auto& [image_id, image] : block_scene.images) {
    const std::optional<DatabaseImage> row =
        database.ReadImageWithName(image.name);
    auto interior = interiors.find(row->image_id);
    if (interior != interiors.end()) image.frame = interior->second.frame;
  }

  input.block = BlockFromScene(block_scene, options.image_sigma_px);
  for (size_t c = 0; c < input.block.cameras.size(); ++c) {
    input.block.cameras[c].source_model =
        scene.cameras.at(input.block.cameras[c].camera.camera_id).model_id;
  }
  if (input.block.points.empty()) {
    ThrowInputError(input_path, ": no 3D point is seen in two or more images");
  }
  input.datum = SetUpDatum(control, options.datum, &input.block);
  for (const std::string& note : input.datum.notes) {
    LOG(WARNING) << note;
    input.notes.push_back(note);
  }
  return input;
}

}  // namespace bayon
