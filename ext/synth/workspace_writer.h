// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "ext/synth/control_scene.h"
#include "ext/synth/points_scene.h"

#include <string>

namespace bayon {

struct SyntheticWorkspaceSummary {
  int num_images = 0;
  int num_points3D = 0;
  int64_t num_observations = 0;
  int num_pairs = 0;
  double colmap_fit_rms_px = 0;  // how well FULL_OPENCV holds the true camera
  double colmap_fit_max_px = 0;
};

// Writes a synthetic scene as a workspace:
//   database.db        cameras (the COLMAP model fitted to the true camera),
//                      images, keypoints = noisy observations, matches and
//                      two-view geometries from the true tracks, and the true
//                      calibration in bayon_calibration / bayon_interior;
//   gt/sparse/         the true model as COLMAP text (exact projections);
//   gt/calibration.json the true BROWN_BEYER camera and its COLMAP fit;
//   gt/synth.json      the options used.
// The workspace is assembled in a temporary folder and moved into place.
//
// Extras: `control` (when not empty) goes to control/ as the measured
// control (ext/synth/control_scene.h); with `nominal_calibration` the
// database gets the nominal camera (c and the pixel pitch, additional
// parameters zero, as a user would import it) instead of the true one, so
// that self-calibration has to find the additional parameters (gt/ keeps
// the truth either way).
struct SyntheticWorkspaceExtras {
  SyntheticControl control;
  bool nominal_calibration = false;
};
SyntheticWorkspaceSummary WriteSyntheticWorkspace(
    const SyntheticTruth& truth,
    const std::string& workspace,
    bool overwrite,
    const SyntheticWorkspaceExtras& extras = {});

}  // namespace bayon
