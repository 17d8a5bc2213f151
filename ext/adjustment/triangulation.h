// SPDX-License-Identifier: BSD-3-Clause
//
// Forward intersection of image rays: the point closest to all rays in the
// least-squares sense (the multi-ray "midpoint" solution,
// X = (sum P_i)^-1 sum P_i C_i with P_i = I - d_i d_i^T), used for
// approximations of tie, control and check points before an adjustment.
#pragma once

#include "ext/core/camera.h"
#include "ext/core/image_frame.h"
#include "ext/core/rigid3.h"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace bayon {

struct Ray {
  Eigen::Vector3d origin;     // projection centre (world)
  Eigen::Vector3d direction;  // unit vector (world)
};

// The ray through a pixel of an image. `frame` is the image's interior
// orientation for BROWN_BEYER cameras (nullptr: the camera's default).
// Returns nullopt where the camera model cannot be inverted.
std::optional<Ray> RayThroughPixel(const Camera& camera,
                                   const Rigid3d& cam_from_world,
                                   const Eigen::Vector2d& pixel,
                                   const ImageFrame* frame = nullptr);

// The intersection of two or more rays. Returns nullopt for fewer than two
// rays, when the largest angle between any two rays is below
// `min_angle_deg` (a glancing intersection), or when the point lies behind
// one of the rays' origins.
std::optional<Eigen::Vector3d> IntersectRays(const std::vector<Ray>& rays,
                                             double min_angle_deg = 1.0);

}  // namespace bayon
