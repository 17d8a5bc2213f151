// SPDX-License-Identifier: BSD-3-Clause
//
// Spatial resection: the exterior orientation of one image from object
// points it sees, for images that no relative orientation attaches to the
// strip (strip.h). The rays are the images' normalised camera directions
// (x/z, y/z of the camera model's inverse), so any camera model works.
//
// Approximations by the direct linear transformation from random 6-point
// samples (RANSAC, scored by the normalised image error), and, where the
// points are nearly coplanar and the DLT is degenerate, from a given guess
// (the neighbouring station); then the collinearity equations in
// normalised coordinates by Gauss-Newton (Ceres) with a robust loss, and
// the inliers of the final orientation.
#pragma once

#include "ext/core/rigid3.h"

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <vector>

namespace bayon {

struct ResectionOptions {
  // Largest error of an inlier, normalised image units (pixels / focal
  // length).
  double max_error = 0.003;
  int min_inliers = 8;
  int num_samples = 300;
  uint64_t seed = 1;
};

struct Resection {
  Rigid3d cam_from_world;
  std::vector<bool> inliers;
  int num_inliers = 0;
  double rms_error = 0;  // of the inliers, normalised units
};

// `image_xy`: normalised image coordinates (x/z, y/z) of the observations
// of `points` (world). `guess`: an approximate orientation tried besides the
// DLT (nullptr: none). Returns nullopt for fewer than min_inliers points or
// when no orientation has min_inliers inliers in front of the camera.
std::optional<Resection> ResectImage(
    const std::vector<Eigen::Vector2d>& image_xy,
    const std::vector<Eigen::Vector3d>& points,
    const Rigid3d* guess,
    const ResectionOptions& options);

}  // namespace bayon
