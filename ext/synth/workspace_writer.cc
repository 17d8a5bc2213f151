// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/workspace_writer.h"

#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/calibration_json.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/scene_database.h"
#include "ext/core/camera_conversion.h"
#include "ext/core/file_util.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {

namespace {

// The camera as a user knows it before calibration: nominal camera constant
// and principal point, additional parameters zero.
Scene WithNominalCameras(const Scene& scene) {
  Scene nominal = scene;
  for (auto& [camera_id, camera] : nominal.cameras) {
    if (camera.model_id != CameraModelId::kBrownBeyer) continue;
    for (int idx = brown::kFirstAdditional; idx < brown::kNumParams; ++idx) {
      camera.params[idx] = 0;
    }
  }
  return nominal;
}

}  // namespace

SyntheticWorkspaceSummary WriteSyntheticWorkspace(
    const SyntheticTruth& truth,
    const std::string& workspace,
    bool overwrite,
    const SyntheticWorkspaceExtras& extras) {
  OutputDirectory output(workspace, overwrite);
  SyntheticWorkspaceSummary summary;

  Scene colmap_truth = truth.scene;
  const std::vector<SceneCameraConversion> conversions =
      ConvertSceneCamerasToColmap(&colmap_truth);
  Scene colmap_noisy = extras.nominal_calibration
                           ? WithNominalCameras(truth.noisy_scene)
                           : truth.noisy_scene;
  const std::vector<SceneCameraConversion> database_conversions =
      ConvertSceneCamerasToColmap(&colmap_noisy);

  std::vector<CalibrationEntry> calibration;
  for (const SceneCameraConversion& conversion : conversions) {
    const CalibrationEntry entry = CalibrationEntryFromConversion(conversion);
    summary.colmap_fit_rms_px =
        std::max(summary.colmap_fit_rms_px, entry.colmap_fit_rms_px);
    summary.colmap_fit_max_px =
        std::max(summary.colmap_fit_max_px, entry.colmap_fit_max_px);
    calibration.push_back(entry);
  }

  // COLMAP's mapper insists on an image folder, even without images.
  fs::create_directories(output.File("images"));
  const std::string gt = output.File("gt");
  fs::create_directories(gt + "/sparse");
  WriteModel(colmap_truth, gt + "/sparse", ModelFormat::kText);
  WriteCalibrationJson(gt + "/calibration.json", calibration);
  WriteFileAtomically(gt + "/synth.json", truth.description);

  {
    Database database(output.File("database.db"), Database::Mode::kCreate);
    SceneImportOptions import_options;
    const SceneImportSummary imported =
        ImportSceneIntoDatabase(colmap_noisy, import_options, &database);
    summary.num_pairs = imported.num_pairs;
    auto transaction = database.BeginTransaction();
    for (const SceneCameraConversion& conversion : database_conversions) {
      CalibrationRecord record;
      record.camera = conversion.source;
      record.colmap_fit_rms_px = conversion.conversion.rms_residual_px;
      record.colmap_fit_max_px = conversion.conversion.max_residual_px;
      WriteCalibration(&database, record);
    }
    for (const auto& [image_id, image] : truth.scene.images) {
      InteriorRecord interior;
      interior.frame = truth.scene.cameras.at(image.camera_id).DefaultFrame();
      interior.method = kDigitalInteriorMethod;
      WriteInterior(&database, image_id, interior);
    }
    transaction.Commit();
  }

  if (!extras.control.empty()) {
    WriteSyntheticControl(extras.control, output.File("control"));
  }

  const SceneStats stats = truth.scene.Stats();
  summary.num_images = stats.num_images;
  summary.num_points3D = stats.num_points3D;
  summary.num_observations = stats.num_observations;
  output.Commit();
  return summary;
}

}  // namespace bayon
