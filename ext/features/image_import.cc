// SPDX-License-Identifier: BSD-3-Clause
#include "ext/features/image_import.h"

#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/database.h"
#include "ext/core/camera.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/progress.h"
#include "ext/image/image_io.h"

#include <algorithm>
#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {

void ImportOptions::Register(OptionRegistry* r) {
  r->Add("single_camera",
         &single_camera,
         "1: all images share one camera (they must have one size)");
  r->Add("camera_model",
         &camera_model,
         "SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, "
         "FULL_OPENCV, ... or BROWN_BEYER");
  r->Add("focal_length_mm",
         &focal_length_mm,
         "Focal length of the lens (with pixel_size_um)");
  r->Add("pixel_size_um",
         &pixel_size_um,
         "Pixel pitch on the sensor or scan, micrometres");
  r->Add("camera_params",
         &camera_params,
         "A calibrated camera: the model's parameters in COLMAP's order, "
         "e.g. PINHOLE fx,fy,cx,cy (focal length known)");
  r->Add("default_focal_length_factor",
         &default_focal_length_factor,
         "Focal length guess without prior, times the long side");
}

void ImportOptions::Check() const {
  const auto model = CameraModelIdFromName(camera_model);
  if (!model) {
    ThrowInputError("camera_model '",
                    camera_model,
                    "' is unknown (known: ",
                    CameraModelNames(),
                    ")");
  }
  CheckOption(focal_length_mm >= 0, "focal_length_mm", ">= 0", focal_length_mm);
  CheckOption(pixel_size_um >= 0, "pixel_size_um", ">= 0", pixel_size_um);
  if ((focal_length_mm > 0) != (pixel_size_um > 0)) {
    ThrowInputError("focal_length_mm and pixel_size_um go together");
  }
  if (*model == CameraModelId::kBrownBeyer && pixel_size_um <= 0) {
    ThrowInputError(
        "camera_model BROWN_BEYER needs pixel_size_um (and "
        "focal_length_mm): the camera works in millimetres");
  }
  if (!camera_params.empty()) {
    if (*model == CameraModelId::kBrownBeyer) {
      ThrowInputError(
          "camera_params: BROWN_BEYER cameras are calibrated by bayon "
          "adjust (calibration.json), not given as COLMAP parameters");
    }
    if (focal_length_mm > 0) {
      ThrowInputError(
          "camera_params and focal_length_mm both give the focal "
          "length; give one");
    }
    CheckNumCameraParams(*model, camera_params.size(), "camera_params");
  }
  CheckOption(default_focal_length_factor > 0,
              "default_focal_length_factor",
              "> 0",
              default_focal_length_factor);
}

namespace {

struct ImageFacts {
  std::string name;
  int width = 0;
  int height = 0;
  double focal_px = 0;  // 0: no prior
  bool focal_from_exif = false;
};

// Reads every image fully before anything is written: a corrupt image stops
// the import with its name and leaves the database as it was.
std::vector<ImageFacts> InspectImages(const std::string& image_path,
                                      const ImportOptions& options,
                                      const std::vector<std::string>& names) {
  std::vector<ImageFacts> facts;
  Progress progress("Reading images", names.size(), "images");
  for (const std::string& name : names) {
    const std::string path = (fs::path(image_path) / name).string();
    const cv::Mat image = ReadImage(path);
    ImageFacts fact;
    fact.name = name;
    fact.width = image.cols;
    fact.height = image.rows;
    if (options.focal_length_mm > 0) {
      fact.focal_px =
          options.focal_length_mm / (options.pixel_size_um / 1000.0);
    } else if (const auto exif = ReadExifFocal(path)) {
      fact.focal_px = FocalLengthPxFromExif(*exif, fact.width, fact.height);
      fact.focal_from_exif = fact.focal_px > 0;
    }
    facts.push_back(fact);
    progress.Add();
  }
  progress.Finish();
  return facts;
}

Camera MakeCamera(const ImportOptions& options, const ImageFacts& fact) {
  const CameraModelId model = *CameraModelIdFromName(options.camera_model);
  const bool prior = fact.focal_px > 0;
  const double focal = prior ? fact.focal_px
                             : options.default_focal_length_factor *
                                   std::max(fact.width, fact.height);
  Camera camera = Camera::Create(
      model, focal, fact.width, fact.height, options.pixel_size_um / 1000.0);
  camera.has_prior_focal_length = prior;
  if (!options.camera_params.empty()) {
    camera.params = options.camera_params;
    camera.has_prior_focal_length = true;
  }
  return camera;
}

}  // namespace

ImportSummary ImportImages(const std::string& database_path,
                           const std::string& image_path,
                           const ImportOptions& options) {
  options.Check();
  CheckDirectoryExists(image_path, "image_path");
  const std::vector<std::string> names = ListImages(image_path);
  if (names.empty()) {
    ThrowInputError(image_path,
                    ": no images found (looked for jpg, "
                    "png, tif, bmp, pgm/ppm, webp, jp2, exr, hdr)");
  }
  // Images already in an existing database are left alone, unread.
  std::vector<std::string> new_names;
  if (fs::exists(database_path)) {
    Database existing(database_path, Database::Mode::kReadOnly);
    for (const std::string& name : names) {
      if (!existing.ReadImageWithName(name)) new_names.push_back(name);
    }
  } else {
    new_names = names;
  }
  ImportSummary summary;
  summary.num_skipped = static_cast<int>(names.size() - new_names.size());
  CheckCanWrite(database_path, "the database");
  const std::vector<ImageFacts> facts =
      InspectImages(image_path, options, new_names);
  if (options.single_camera && !facts.empty()) {
    for (const ImageFacts& fact : facts) {
      if (fact.width != facts[0].width || fact.height != facts[0].height) {
        ThrowInputError(fact.name,
                        ": ",
                        fact.width,
                        "x",
                        fact.height,
                        " differs from ",
                        facts[0].name,
                        " (",
                        facts[0].width,
                        "x",
                        facts[0].height,
                        "); images of different sizes cannot share one camera "
                        "(single_camera 0)");
      }
    }
  }

  // A new database is built under a temporary name and renamed when done,
  // so an interrupted import never leaves a half-filled file behind.
  const bool created = !fs::exists(database_path);
  if (created) RemoveStaleTemporaries(database_path);
  const std::string target =
      created ? database_path + TempSuffix() : database_path;
  TempFileGuard temp_guard(created ? target : std::string());
  if (!created) temp_guard.Keep();
  try {
    Database database(
        target, created ? Database::Mode::kCreate : Database::Mode::kReadWrite);
    CheckBayonSchema(&database);
    auto transaction = database.BeginTransaction();
    camera_t shared_camera_id = kInvalidCameraId;
    for (const ImageFacts& fact : facts) {
      if (database.ReadImageWithName(fact.name)) continue;  // added meanwhile
      camera_t camera_id = shared_camera_id;
      if (camera_id == kInvalidCameraId) {
        const Camera camera = MakeCamera(options, fact);
        camera_id = WriteCameraWithCalibration(&database, camera);
        ++summary.num_cameras;
        summary.num_priors += camera.has_prior_focal_length;
        if (options.single_camera) shared_camera_id = camera_id;
      }
      DatabaseImage image;
      image.name = fact.name;
      image.camera_id = camera_id;
      database.WriteImage(image);
      ++summary.num_added;
    }
    transaction.Commit();
  } catch (const InputError& error) {
    // Name the database the user gave, not its temporary (a full disk).
    std::string message = error.what();
    if (created && message.rfind(target, 0) == 0) {
      message.replace(0, target.size(), database_path);
    }
    throw InputError(message);
  }
  if (created) {
    fs::rename(target, database_path);
    temp_guard.Keep();
  }
  return summary;
}

}  // namespace bayon
