// SPDX-License-Identifier: BSD-3-Clause
//
// Control for a synthetic block: signalised control points and check points
// on the object's surface, a vertical levelling bar (the Bayon paper's
// minimum datum, section 3.2), and their image measurements with noise, in
// the formats of ext/colmap/control_io.h (written to <workspace>/control/).
#pragma once

#include "ext/colmap/control_io.h"
#include "ext/core/scene.h"
#include "ext/synth/points_scene.h"

#include <vector>

namespace bayon {

struct SyntheticControlOptions {
  // Control points (used in the datum) spread evenly in azimuth around the
  // object at alternating heights, and check points at random places.
  int num_control_points = 0;
  int num_check_points = 0;
  // A vertical levelling bar of this length on the object's surface (two
  // points BAR_A below BAR_B, listed in distances.txt as `vertical`).
  bool levelling_bar = false;
  double bar_length_m = 1.0;
  double bar_sigma_m = 0.0005;
  // Standard deviation written for the control coordinates (0: fixed) and
  // the noise added to their image measurements (< 0: the scene's keypoint
  // noise).
  double control_sigma_m = 0.0;
  double measurement_noise_px = -1.0;
  void Check() const;
};

struct SyntheticControl {
  std::vector<ControlPoint> points;  // true coordinates
  std::vector<ImageMeasurement> measurements;
  std::vector<DistanceObservation> distances;
  bool empty() const { return points.empty() && distances.empty(); }
};

// Places the points on the object of a points scene (`options` as used to
// make `truth`) and measures them in every image that sees them (the same
// visibility rule as the tie points). Deterministic for a given seed.
SyntheticControl SynthesizeControl(const SyntheticTruth& truth,
                                   const PointsSceneOptions& scene_options,
                                   const SyntheticControlOptions& options);

// Writes control/points.txt, observations.txt and distances.txt (the latter
// only with a levelling bar) into `folder` (created).
void WriteSyntheticControl(const SyntheticControl& control,
                           const std::string& folder);

}  // namespace bayon
