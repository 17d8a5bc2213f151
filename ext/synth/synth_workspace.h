// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon synth`: a workspace with known truth, of the points scene
// (points_scene.h, with control_scene.h's control) or the rendered tower
// (tower_workspace.h), from one set of options.
#pragma once

#include "ext/core/option_registry.h"
#include "ext/synth/control_scene.h"
#include "ext/synth/points_scene.h"
#include "ext/synth/tower_scene.h"

#include <limits>
#include <string>

namespace bayon {

struct SynthOptions {
  std::string scene = "points";  // points or tower
  // Shared by both scenes: num_views, seed and distortion (the points
  // scene's fields, copied into the tower's).
  PointsSceneOptions points;
  SyntheticControlOptions control;
  TowerSceneOptions tower;
  // The database gets the nominal camera (additional parameters zero); the
  // truth stays in gt/.
  bool nominal_calibration = false;
  // Tower: pixels across the 36 x 24 mm frame.
  int image_width = TowerSceneOptions().camera.width;
  // Standard deviation of the control coordinates; NaN: each scene's own
  // default (points: 0, fixed; tower: 0.002).
  double control_sigma_m = std::numeric_limits<double>::quiet_NaN();
  void Register(OptionRegistry* registry);
  void Check() const;
};

// Writes the workspace and returns its summary line.
std::string WriteSynthWorkspace(const SynthOptions& options,
                                const std::string& output_path,
                                bool overwrite);

}  // namespace bayon
