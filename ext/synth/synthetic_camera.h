// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "ext/core/camera.h"
#include "ext/core/rigid3.h"

#include <Eigen/Core>

namespace bayon {

struct SyntheticCameraOptions {
  double focal_length_mm = 35.0;  // camera constant c
  double pixel_pitch_mm = 0.02;   // 20 um: 1800 x 1200 on a 36 x 24 mm frame
  int width = 1800;
  int height = 1200;
  // Non-zero additional parameters (all ten except K3, which a 35 mm lens
  // does not need: self-calibration should drop it) so that self-calibration
  // has something to find; false gives an ideal camera.
  bool distortion = true;
  void Check() const;
};

// A camera like the Bayon paper's Minolta: c = 35 mm, 36 x 24 mm frame, with
// the additional parameters of a real lens and film transport (decentring,
// a small affinity and shear). BROWN_BEYER model, camera_id 1.
Camera SyntheticCamera(const SyntheticCameraOptions& options);

// cam_from_world for a camera at `center` looking at `target`, with world
// `up` (z up in bayon's synthetic scenes) pointing up in the image, rolled by
// `roll_rad` about the viewing direction.
Rigid3d LookAt(const Eigen::Vector3d& center,
               const Eigen::Vector3d& target,
               const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ(),
               double roll_rad = 0.0);

}  // namespace bayon
