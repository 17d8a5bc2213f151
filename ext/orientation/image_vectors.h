// SPDX-License-Identifier: BSD-3-Clause
//
// From pixels to the image vectors of the photogrammetric model and back:
// each image's interior orientation as the relative orientation and the
// disparity surfaces use it (relative_orientation.h states the frames).
//
// Where the interior orientation comes from, per image:
// - a bayon_calibration row for its camera (BROWN_BEYER: camera constant,
//   principal point and the ten additional parameters, in millimetres), with
//   the image's own frame from bayon_interior when there is one (scanned
//   film) or the camera's digital frame (pixel pitch, image centre):
//   image coordinates in millimetres, as in the paper;
// - otherwise COLMAP's camera row (any COLMAP model): there is no pixel
//   pitch, so normalized coordinates stand in for millimetres (the same
//   thing with a pitch of 1 / focal length).
// In both cases the vectors are scaled to pixels (u = (x, y, -c) / pitch),
// so that one set of thresholds serves every camera.
//
// "Calibrated" (the pair's two-view geometry is written as COLMAP's config
// CALIBRATED) means the focal length is known: a bayon_calibration row, or
// COLMAP's prior_focal_length flag (EXIF or a given lens). Otherwise the
// focal length is COLMAP's guess and the geometry is UNCALIBRATED.
//
// assume_zero_distortion: the paper's starting point ("since the lens
// distortion is not known at this point it is assumed to be zero"): the
// nominal camera constant and principal point only; all additional
// parameters (Brown/Beyer dc ... B2) or distortion coefficients (COLMAP
// models) are set to zero.
#pragma once

#include "ext/colmap/database.h"
#include "ext/core/camera.h"
#include "ext/core/image_frame.h"

#include <Eigen/Core>

#include <optional>
#include <string>

namespace bayon {

class ImageVectors {
 public:
  ImageVectors() = default;
  ImageVectors(const Camera& camera,
               const std::optional<ImageFrame>& frame,
               bool calibrated,
               bool assume_zero_distortion);

  // The interior orientation of an image of `database` (see above).
  static ImageVectors FromDatabase(Database* database,
                                   const DatabaseImage& image,
                                   bool assume_zero_distortion);

  // u = (x, y, -c) / pitch, pixels. False where the camera model cannot be
  // inverted (far outside the calibrated frame).
  bool FromPixel(const Eigen::Vector2d& pixel, Eigen::Vector3d* u) const;
  // The pixel a direction u (any length, pointing at the object) projects
  // to. False for directions behind the camera.
  bool ToPixel(const Eigen::Vector3d& u, Eigen::Vector2d* pixel) const;

  const Camera& camera() const { return camera_; }
  double camera_constant_px() const { return camera_constant_px_; }
  bool calibrated() const { return calibrated_; }
  int width() const { return static_cast<int>(camera_.width); }
  int height() const { return static_cast<int>(camera_.height); }
  // "BROWN_BEYER (bayon_calibration, frame from bayon_interior)" etc.
  const std::string& description() const { return description_; }

 private:
  Camera camera_;
  std::optional<ImageFrame> frame_;
  double camera_constant_px_ = 1;
  bool calibrated_ = false;
  std::string description_;
};

}  // namespace bayon
