// SPDX-License-Identifier: BSD-3-Clause
//
// The first stage: a folder of photographs into COLMAP's cameras and images
// tables, with deterministic ids (sorted names) and a focal length prior
// from EXIF, from the lens and pixel pitch given, or a calibrated camera.
// Without any, the focal length is COLMAP's guess (1.2 x the long side), not
// a prior.
#pragma once

#include "ext/core/option_registry.h"

#include <string>
#include <vector>

namespace bayon {

struct ImportOptions {
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
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct ImportSummary {
  int num_added = 0;
  int num_skipped = 0;  // already in the database, left alone
  int num_cameras = 0;
  int num_priors = 0;  // cameras with a focal length prior
};

// Adds the photographs of `image_path` that `database_path` does not hold
// yet (creating it where it is missing). Every new photograph is read
// before anything is written: a corrupt one stops the import with its name
// and leaves the database as it was. A new database is built under a
// temporary name and renamed when done.
ImportSummary ImportImages(const std::string& database_path,
                           const std::string& image_path,
                           const ImportOptions& options);

}  // namespace bayon
