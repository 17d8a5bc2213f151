// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "ext/core/camera.h"

namespace bayon {

struct CameraConversionOptions {
  // Samples per image side; the fit uses grid_size^2 pixels spread over the
  // whole frame, corners included.
  int grid_size = 41;
  // Target BROWN_BEYER only: pixel pitch in mm. 0 keeps the source's pitch,
  // or, for a COLMAP source, assumes a 36 mm wide frame.
  double pixel_pitch_mm = 0.0;
  // Target FULL_OPENCV only: also fit the rational terms k4..k6. Off by
  // default, so that the result is Brown's polynomial (colmap-interop 1.5).
  bool fit_rational_terms = false;
  void Check() const;
};

struct CameraConversion {
  Camera camera;  // the fitted camera, same id and size as the source
  // Differences between the two cameras' projections of the same rays, in
  // pixels, over the sample grid. What the target model cannot express
  // (shear in a COLMAP model, say) shows up here.
  double rms_residual_px = 0.0;
  double max_residual_px = 0.0;
  int num_samples = 0;
};

// Converts a camera to another model by a least-squares fit over the whole
// frame: rays through a grid of pixels of `source` are projected by the target
// model, whose parameters minimise the pixel differences. Works in both
// directions between BROWN_BEYER and every COLMAP model with an inverse.
CameraConversion ConvertCamera(const Camera& source,
                               CameraModelId target_model,
                               const CameraConversionOptions& options = {});

// The COLMAP model chosen for writing a BROWN_BEYER camera to COLMAP's
// `cameras` table: FULL_OPENCV, which holds K1..K3, P1, P2 and fx != fy.
constexpr CameraModelId kColmapModelForBrownBeyer = CameraModelId::kFullOpenCV;

}  // namespace bayon

namespace bayon {

class Scene;

// Replaces every BROWN_BEYER camera of a scene by its closest COLMAP model
// (kColmapModelForBrownBeyer) so that the scene can be written for COLMAP.
// Returns the conversions (with the original cameras in `source`) by id.
struct SceneCameraConversion {
  Camera source;
  CameraConversion conversion;
};
std::vector<SceneCameraConversion> ConvertSceneCamerasToColmap(
    Scene* scene, const CameraConversionOptions& options = {});

}  // namespace bayon
