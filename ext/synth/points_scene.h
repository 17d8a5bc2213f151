// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "ext/core/scene.h"
#include "ext/synth/synthetic_camera.h"

#include <string>

namespace bayon {

struct PointsSceneOptions {
  int num_views = 16;
  int num_points = 1500;
  // Cameras on a horizontal circle around the object, looking at its middle.
  double ring_radius_m = 10.0;
  double camera_height_m = 2.0;
  // Every other station turned by this angle about its viewing direction
  // (portrait and landscape shots), which self-calibration needs to separate
  // the principal point and affinity from the exterior orientation.
  double alternate_roll_deg = 0.0;
  // Points fill a vertical cylinder of this radius and height (z up).
  double object_radius_m = 2.0;
  double object_height_m = 4.0;
  // A point is seen by cameras within this angle of its outward normal, so
  // tracks are a few images long as on a real object.
  double max_view_angle_deg = 60.0;
  // Points far behind the object, each seen by two neighbouring stations
  // only (as the background, or data snooping, leaves them in a real block):
  // their rays meet at a fraction of a degree. Added after the others.
  int num_distant_points = 0;
  double distant_points_m = 300.0;
  // Gaussian noise added to the observations that go into the database.
  double keypoint_noise_px = 0.3;
  unsigned int seed = 1;
  SyntheticCameraOptions camera;
  void Check() const;
};

struct SyntheticTruth {
  // True cameras (BROWN_BEYER), poses, points and tracks; points2D hold the
  // exact projections.
  Scene scene;
  // The same with the observation noise applied (what a matcher would give).
  Scene noisy_scene;
  std::string description;  // options used, as JSON
};

// A ring of cameras around random 3D points, for tests of the sparse chain.
SyntheticTruth SynthesizePointsScene(const PointsSceneOptions& options);

}  // namespace bayon
