// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/image_vectors.h"

#include "ext/colmap/bayon_tables.h"
#include "ext/core/errors.h"

namespace bayon {

namespace {

// The camera with every distortion parameter zero.
Camera WithoutDistortion(Camera camera) {
  if (camera.model_id == CameraModelId::kBrownBeyer) {
    for (int k = brown::kFirstAdditional;
         k < brown::kFirstAdditional + brown::kNumAdditional;
         ++k) {
      camera.params[k] = 0;
    }
    return camera;
  }
  const CameraModelInfo& info = camera.ModelInfo();
  const size_t first_extra =
      info.focal_idxs.size() + info.principal_point_idxs.size();
  for (size_t k = first_extra; k < camera.params.size(); ++k) {
    camera.params[k] = 0;
  }
  return camera;
}

}  // namespace

ImageVectors::ImageVectors(const Camera& camera,
                           const std::optional<ImageFrame>& frame,
                           bool calibrated,
                           bool assume_zero_distortion)
    : camera_(assume_zero_distortion ? WithoutDistortion(camera) : camera),
      frame_(frame),
      calibrated_(calibrated) {
  camera_.Check();
  if (camera_.model_id == CameraModelId::kBrownBeyer) {
    const ImageFrame image_frame = frame_ ? *frame_ : camera_.DefaultFrame();
    camera_constant_px_ =
        (camera_.params[brown::kC] + camera_.params[brown::kDc]) /
        image_frame.MeanPitchMm();
  } else {
    camera_constant_px_ = camera_.MeanFocalLengthPx();
  }
  description_ =
      StrCat(camera_.ModelName(),
             frame_ ? " with its own image frame" : "",
             calibrated_ ? ", calibrated" : ", focal length guessed",
             assume_zero_distortion ? ", distortion assumed zero" : "");
}

ImageVectors ImageVectors::FromDatabase(Database* database,
                                        const DatabaseImage& image,
                                        bool assume_zero_distortion) {
  const std::optional<CalibrationRecord> calibration =
      ReadCalibration(database, image.camera_id);
  if (calibration) {
    std::optional<ImageFrame> frame;
    if (const auto interior = ReadInterior(database, image.image_id)) {
      frame = interior->frame;
    }
    return ImageVectors(
        calibration->camera, frame, true, assume_zero_distortion);
  }
  const Camera camera = database->ReadCamera(image.camera_id);
  return ImageVectors(camera,
                      std::nullopt,
                      camera.has_prior_focal_length,
                      assume_zero_distortion);
}

bool ImageVectors::FromPixel(const Eigen::Vector2d& pixel,
                             Eigen::Vector3d* u) const {
  Eigen::Vector3d ray;
  if (!camera_.CamFromImg(pixel, &ray, frame_ ? &*frame_ : nullptr)) {
    return false;
  }
  // COLMAP's camera frame (y down, z forward) to the image frame (y up,
  // z towards the viewer), scaled to z = -c.
  *u = camera_constant_px_ * Eigen::Vector3d(ray.x(), -ray.y(), -1.0);
  return true;
}

bool ImageVectors::ToPixel(const Eigen::Vector3d& u,
                           Eigen::Vector2d* pixel) const {
  if (u.z() >= 0) return false;
  return camera_.ImgFromCam(Eigen::Vector3d(u.x(), -u.y(), -u.z()),
                            pixel,
                            frame_ ? &*frame_ : nullptr);
}

}  // namespace bayon
