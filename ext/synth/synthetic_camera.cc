// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/synthetic_camera.h"

#include "ext/core/errors.h"

#include <Eigen/Geometry>

namespace bayon {

void SyntheticCameraOptions::Check() const {
  CheckOption(focal_length_mm > 0, "focal_length_mm", "> 0", focal_length_mm);
  CheckOption(pixel_pitch_mm > 0, "pixel_pitch_mm", "> 0", pixel_pitch_mm);
  CheckOption(width >= 16, "width", ">= 16", width);
  CheckOption(height >= 16, "height", ">= 16", height);
}

Camera SyntheticCamera(const SyntheticCameraOptions& options) {
  options.Check();
  Camera camera =
      Camera::Create(CameraModelId::kBrownBeyer,
                     options.focal_length_mm / options.pixel_pitch_mm,
                     options.width,
                     options.height,
                     options.pixel_pitch_mm);
  camera.camera_id = 1;
  camera.has_prior_focal_length = true;
  if (!options.distortion) return camera;
  // Magnitudes of a consumer 35 mm lens on film, scaled to the frame: about
  // 20 px of radial distortion in the corners of a 1800 x 1200 image, a
  // principal point 0.1 mm off centre, decentring and affinity of a few
  // tenths of a pixel.
  const double half_diagonal =
      0.5 * options.pixel_pitch_mm * std::hypot(options.width, options.height);
  const double r2 = half_diagonal * half_diagonal;
  auto& p = camera.params;
  p[brown::kDc] = 0.12 * options.focal_length_mm / 35.0;
  p[brown::kDx0] = 0.004 * half_diagonal;
  p[brown::kDy0] = -0.003 * half_diagonal;
  p[brown::kK1] = -0.017 / r2;
  p[brown::kK2] = 0.004 / (r2 * r2);
  p[brown::kK3] = 0.0;
  p[brown::kP1] = 2.0e-5 * 21.6 / half_diagonal;
  p[brown::kP2] = -1.5e-5 * 21.6 / half_diagonal;
  p[brown::kB1] = 1.5e-4;
  p[brown::kB2] = -1.0e-4;
  return camera;
}

Rigid3d LookAt(const Eigen::Vector3d& center,
               const Eigen::Vector3d& target,
               const Eigen::Vector3d& up,
               double roll_rad) {
  const Eigen::Vector3d forward = (target - center).normalized();
  Eigen::Vector3d right = forward.cross(up);
  if (right.norm() < 1e-9) right = forward.unitOrthogonal();
  right.normalize();
  const Eigen::Vector3d down = forward.cross(right);
  Eigen::Matrix3d cam_from_world_rotation;
  cam_from_world_rotation.row(0) = right;
  cam_from_world_rotation.row(1) = down;
  cam_from_world_rotation.row(2) = forward;
  const Eigen::Matrix3d roll =
      Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d rotation = roll * cam_from_world_rotation;
  Rigid3d pose;
  pose.rotation = Eigen::Quaterniond(rotation).normalized();
  pose.translation = -(rotation * center);
  return pose;
}

}  // namespace bayon
