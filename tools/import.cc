// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/database.h"
#include "ext/core/camera.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/progress.h"
#include "ext/image/image_io.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <glog/logging.h>

#include <filesystem>
#include <map>
#include <vector>

namespace fs = std::filesystem;

namespace bayon {
namespace {

struct ImportOptions {
  std::string image_path;
  std::string database_path;
  bool single_camera = false;
  std::string camera_model = "SIMPLE_RADIAL";
  // Both given: the focal length prior in pixels is f / pitch.
  double focal_length_mm = 0;
  double pixel_size_um = 0;
  // COLMAP's guess without any prior: f = factor * max(width, height).
  double default_focal_length_factor = 1.2;
  // A calibrated camera: every parameter of camera_model in COLMAP's order
  // (COLMAP's --ImageReader.camera_params); its focal length counts as
  // known.
  std::vector<double> camera_params;
  std::string log_path;

  void Check() const {
    CheckDirectoryExists(image_path, "--image_path");
    if (database_path.empty()) ThrowInputError("--database_path is required");
    const auto model = CameraModelIdFromName(camera_model);
    if (!model) {
      ThrowInputError("--camera_model '",
                      camera_model,
                      "' is unknown (known: ",
                      CameraModelNames(),
                      ")");
    }
    CheckOption(
        focal_length_mm >= 0, "--focal_length_mm", ">= 0", focal_length_mm);
    CheckOption(pixel_size_um >= 0, "--pixel_size_um", ">= 0", pixel_size_um);
    if ((focal_length_mm > 0) != (pixel_size_um > 0)) {
      ThrowInputError("--focal_length_mm and --pixel_size_um go together");
    }
    if (*model == CameraModelId::kBrownBeyer && pixel_size_um <= 0) {
      ThrowInputError(
          "--camera_model BROWN_BEYER needs --pixel_size_um (and "
          "--focal_length_mm): the camera works in millimetres");
    }
    if (!camera_params.empty()) {
      if (*model == CameraModelId::kBrownBeyer) {
        ThrowInputError(
            "--camera_params: BROWN_BEYER cameras are calibrated by bayon "
            "adjust (calibration.json), not given as COLMAP parameters");
      }
      if (focal_length_mm > 0) {
        ThrowInputError(
            "--camera_params and --focal_length_mm both give the focal "
            "length; give one");
      }
      CheckNumCameraParams(*model, camera_params.size(), "--camera_params");
    }
    CheckOption(default_focal_length_factor > 0,
                "--default_focal_length_factor",
                "> 0",
                default_focal_length_factor);
  }
};

struct ImageFacts {
  std::string name;
  int width = 0;
  int height = 0;
  double focal_px = 0;  // 0: no prior
  bool focal_from_exif = false;
};

// Reads every image fully before anything is written: a corrupt image stops
// the import with its name and leaves the database as it was.
std::vector<ImageFacts> InspectImages(const ImportOptions& options,
                                      const std::vector<std::string>& names) {
  std::vector<ImageFacts> facts;
  Progress progress("Reading images", names.size(), "images");
  for (const std::string& name : names) {
    const std::string path = (fs::path(options.image_path) / name).string();
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

int RunImport(int argc, char** argv) {
  ImportOptions options;
  CommandLine command("import",
                      "Create COLMAP camera and image rows for a folder of "
                      "images, with deterministic ids (sorted names) and focal "
                      "length priors from EXIF or the given camera.");
  CLI::App& app = command.app();
  app.add_option("--image_path", options.image_path, "Folder of images")
      ->required();
  app.add_option("--database_path",
                 options.database_path,
                 "COLMAP database; created if missing, else images are added")
      ->required();
  app.add_option("--single_camera",
                 options.single_camera,
                 "1: all images share one camera (they must have one size)");
  app.add_option("--camera_model",
                 options.camera_model,
                 "SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, "
                 "FULL_OPENCV, ... or BROWN_BEYER");
  app.add_option("--focal_length_mm",
                 options.focal_length_mm,
                 "Focal length of the lens (with --pixel_size_um)");
  app.add_option("--pixel_size_um",
                 options.pixel_size_um,
                 "Pixel pitch on the sensor or scan, micrometres");
  app.add_option("--camera_params",
                 options.camera_params,
                 "A calibrated camera: the model's parameters in COLMAP's "
                 "order, e.g. PINHOLE fx,fy,cx,cy (focal length known)")
      ->delimiter(',');
  app.add_option("--default_focal_length_factor",
                 options.default_focal_length_factor,
                 "Focal length guess without prior, times the long side");
  app.add_option("--log_path", options.log_path, "Append the log to this file");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  command.StartLog(options.log_path);

  const std::vector<std::string> names = ListImages(options.image_path);
  if (names.empty()) {
    ThrowInputError(options.image_path,
                    ": no images found (looked for jpg, "
                    "png, tif, bmp, pgm/ppm, webp, jp2, exr, hdr)");
  }
  // Images already in an existing database are left alone, unread.
  std::vector<std::string> new_names;
  if (fs::exists(options.database_path)) {
    Database existing(options.database_path, Database::Mode::kReadOnly);
    for (const std::string& name : names) {
      if (!existing.ReadImageWithName(name)) new_names.push_back(name);
    }
  } else {
    new_names = names;
  }
  const int num_skipped = static_cast<int>(names.size() - new_names.size());
  CheckCanWrite(options.database_path, "the database");
  const std::vector<ImageFacts> facts = InspectImages(options, new_names);
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
                        "(--single_camera 0)");
      }
    }
  }

  // A new database is built under a temporary name and renamed when done,
  // so an interrupted import never leaves a half-filled file behind.
  const bool created = !fs::exists(options.database_path);
  if (created) RemoveStaleTemporaries(options.database_path);
  const std::string target =
      created ? options.database_path + TempSuffix() : options.database_path;
  TempFileGuard temp_guard(created ? target : std::string());
  if (!created) temp_guard.Keep();
  int num_added = 0, num_cameras = 0, num_priors = 0;
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
        ++num_cameras;
        num_priors += camera.has_prior_focal_length;
        if (options.single_camera) shared_camera_id = camera_id;
      }
      DatabaseImage image;
      image.name = fact.name;
      image.camera_id = camera_id;
      database.WriteImage(image);
      ++num_added;
    }
    transaction.Commit();
  } catch (const InputError& error) {
    // Name the database the user gave, not its temporary (a full disk).
    std::string message = error.what();
    if (created && message.rfind(target, 0) == 0) {
      message.replace(0, target.size(), options.database_path);
    }
    throw InputError(message);
  }
  if (created) {
    fs::rename(target, options.database_path);
    temp_guard.Keep();
  }
  command.PrintSummary(StrCat(num_added,
                              " images added (",
                              num_skipped,
                              " already present), ",
                              num_cameras,
                              " cameras (",
                              options.camera_model,
                              ", ",
                              num_priors,
                              " with a focal length prior) -> ",
                              options.database_path));
  return num_added + num_skipped > 0 ? 0 : 1;
}

}  // namespace bayon
