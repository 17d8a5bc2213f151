// SPDX-License-Identifier: BSD-3-Clause
//
// How well a sparse model fits its own observations, computed the same way
// for any COLMAP model (bayon's or the mapper's) so that two can be set side
// by side: counts, track lengths, and the reprojection errors of every
// observation through the model's own camera (COLMAP camera models, or
// Brown/Beyer with the image's frame).
//
// For an observation x of point X in image i the residual is
//   r = x - P_i(X)  (pixels),
// and over the n observations that project (X in front of the camera):
//   mean error  = sum |r| / n            (what `colmap model_analyzer` calls
//                                          the mean reprojection error, but
//                                          per observation, not per point)
//   RMS error   = sqrt(sum |r|^2 / n)
//   sigma0      = sqrt(sum |r|^2 / (2n - u)),
//   u = 6 per image + 3 per point + every parameter of the model's cameras,
// the standard deviation of unit weight of a bundle adjustment with all
// image coordinates weighted alike (no datum defect subtracted: u is the
// count of the model's parameters, not of the determinable ones).
#pragma once

#include "ext/core/scene.h"

namespace bayon {

struct ModelStatistics {
  int num_cameras = 0;
  int num_images = 0;  // images in the model (COLMAP: the registered ones)
  int num_points3D = 0;
  int num_observations = 0;  // track elements of all points
  // Observations whose point lies behind the camera: counted above, left
  // out of the errors and of n below.
  int num_unprojected = 0;
  double mean_track_length = 0;  // observations / points
  double mean_reprojection_error_px = 0;
  double median_reprojection_error_px = 0;
  double rms_reprojection_error_px = 0;
  double max_reprojection_error_px = 0;
  int num_camera_params = 0;
  int num_unknowns = 0;  // u
  int redundancy = 0;    // 2 n - u
  double sigma0_px = 0;  // 0 where the redundancy is not positive
};

// Precondition: `model` is consistent (Scene::CheckConsistency; ReadModel
// checks it).
ModelStatistics ComputeModelStatistics(const Scene& model);

}  // namespace bayon
