// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "ext/core/camera_models.h"
#include "ext/core/image_frame.h"
#include "ext/core/types.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace bayon {

// One physical camera: a model (ext/core/camera_models.h), its parameters and
// the image size. Images refer to cameras by id; several images share one.
struct Camera {
  camera_t camera_id = kInvalidCameraId;
  CameraModelId model_id = CameraModelId::kInvalid;
  uint64_t width = 0;
  uint64_t height = 0;
  std::vector<double> params;
  // COLMAP's prior_focal_length flag: the focal length came from EXIF or the
  // user, not from the default guess 1.2 * max(width, height).
  bool has_prior_focal_length = false;
  // Brown/Beyer only: the nominal pixel pitch in mm, which defines the
  // default image frame of a digital image (DefaultFrame()).
  double pixel_pitch_mm = 0.0;

  // A camera with the given focal length in pixels, the principal point at
  // the image centre and zero distortion, as COLMAP initialises cameras. For
  // kBrownBeyer `pixel_pitch_mm` must be positive; c = focal * pitch.
  static Camera Create(CameraModelId model_id,
                       double focal_length_px,
                       uint64_t width,
                       uint64_t height,
                       double pixel_pitch_mm = 0.0);

  const CameraModelInfo& ModelInfo() const {
    return CameraModelInfoFor(model_id);
  }
  std::string ModelName() const { return ModelInfo().name; }

  // Throws InputError if the parameter count or image size is wrong.
  void Check() const;

  // The digital image frame: pixel pitch and image centre.
  ImageFrame DefaultFrame() const;

  // Focal length in pixels (mean of fx and fy; c' / pitch for Brown/Beyer).
  double MeanFocalLengthPx() const;
  // Principal point in pixels.
  Eigen::Vector2d PrincipalPointPx() const;

  // Projects a point in the camera frame to a pixel. `frame` replaces the
  // default image frame for Brown/Beyer cameras (scanned film). Returns false
  // for points behind the camera.
  bool ImgFromCam(const Eigen::Vector3d& point_in_cam,
                  Eigen::Vector2d* pixel,
                  const ImageFrame* frame = nullptr) const;
  // Convenience: NaN for points behind the camera.
  Eigen::Vector2d ImgFromCam(const Eigen::Vector3d& point_in_cam,
                             const ImageFrame* frame = nullptr) const;

  // The ray through a pixel as normalized coordinates (u, v, 1), by
  // iterative inversion of the distortion (Newton). Returns false where the
  // iteration does not converge (far outside the calibrated frame).
  bool CamFromImg(const Eigen::Vector2d& pixel,
                  Eigen::Vector3d* ray,
                  const ImageFrame* frame = nullptr) const;
  Eigen::Vector3d CamFromImg(const Eigen::Vector2d& pixel,
                             const ImageFrame* frame = nullptr) const;

  // Brown/Beyer only: image coordinates (mm) of a camera-frame point, and
  // the inverse, the ray (u, v, 1) through image coordinates.
  bool FrameFromCam(const Eigen::Vector3d& point_in_cam,
                    Eigen::Vector2d* xy_mm) const;
  bool CamFromFrame(const Eigen::Vector2d& xy_mm, Eigen::Vector3d* ray) const;

  // "f, cx, cy, k" style listing with values, for logs and reports.
  std::string ParamsToString() const;
};

// Throws InputError, naming `flag`, unless `num_values` parameters fit
// `model` (COLMAP's order, as --ImageReader.camera_params takes them).
void CheckNumCameraParams(CameraModelId model,
                          size_t num_values,
                          const std::string& flag);

}  // namespace bayon
