// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "ext/colmap/database.h"
#include "ext/core/scene.h"

#include <map>

namespace bayon {

struct SceneImportOptions {
  // Write matches and two-view geometries for every image pair that shares at
  // least this many 3D points (from the tracks).
  int min_num_shared_points = 15;
  // Write cameras and images with the scene's ids (else SQLite assigns).
  bool keep_ids = true;
};

struct SceneImportSummary {
  int num_cameras = 0;
  int num_images = 0;
  int64_t num_keypoints = 0;
  int num_pairs = 0;
  int64_t num_matches = 0;
};

// Writes a scene into a COLMAP database so that stock COLMAP can take over:
// cameras (COLMAP models only; convert BROWN_BEYER first), images,
// keypoints = each image's points2D in order, and for image pairs that share
// tracks, matches and calibrated two-view geometries (inlier matches, E, F
// and the relative pose from the scene's poses). One transaction.
SceneImportSummary ImportSceneIntoDatabase(const Scene& scene,
                                           const SceneImportOptions& options,
                                           Database* database);

// The two-view geometry of two posed images: cam2_from_cam1 with |t| = 1,
// E = [t]x R and F = K2^-T E K1^-1 from the cameras' focal lengths and
// principal points (distortion ignored; COLMAP's SfM never reads F or E).
TwoViewGeometry TwoViewGeometryFromPoses(const Camera& camera1,
                                         const Rigid3d& cam1_from_world,
                                         const Camera& camera2,
                                         const Rigid3d& cam2_from_world);

}  // namespace bayon
