// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon synth --scene tower`: renders the tower's photographs and writes a
// complete workspace with its truth.
//
//   images/image_NNN.png|jpg   the photographs (film scans: the whole scan)
//   database.db                cameras and images rows as `bayon import
//                              --single_camera 1` writes them (camera 1,
//                              image ids in name order), the true
//                              calibration in bayon_calibration and the true
//                              frames in bayon_interior (truth_in_database)
//   control/points.txt         control points as surveyed (noisy, with their
//   control/observations.txt   standard deviations; three marked `check`),
//   control/distances.txt      image measurements as measured (noisy) and
//                              the levelling bar (vertical)
//   gt/sparse/                 the true cameras (FULL_OPENCV fit), poses and
//                              the targets as 3D points, COLMAP text
//   gt/calibration.json        the true BROWN_BEYER camera, every parameter
//   gt/interior.json           each image's frame (pixel_from_frame) and,
//                              for film scans, its corners in pixels
//   gt/surface.ply             the true surface (tower, platform, bar),
//   gt/surface_texture.png     with texture coordinates into this atlas
//   gt/ground.ply              the ground (not part of the surface)
//   gt/control/                exact control points, image positions,
//                              distances (same formats as control/)
//   gt/heldout/                viewpoints not photographed, COLMAP text
//                              (for texture evaluation)
//   gt/synth.json              every option, each image's light, exposure and
//                              weather, the planned station pairs, the
//                              evaluation region and ground sampling distance
#pragma once

#include "ext/synth/tower_scene.h"

#include <string>

namespace bayon {

struct TowerWorkspaceSummary {
  int num_images = 0;
  int num_targets = 0;
  int num_observations = 0;  // visible target images
  size_t num_surface_faces = 0;
  double colmap_fit_rms_px = 0;
  double render_seconds = 0;  // rendering the photographs
  double total_seconds = 0;
  double gsd_m = 0;  // mean ground sampling distance on the tower
};

TowerWorkspaceSummary WriteTowerWorkspace(const TowerSceneOptions& options,
                                          const std::string& workspace,
                                          bool overwrite);

}  // namespace bayon
