// SPDX-License-Identifier: BSD-3-Clause
//
// The exact viewing ray of every position in an image, for renderers and
// other per-pixel work (dense matching, visibility) that must agree with the
// camera model to far below a pixel, lens distortion included.
//
// Camera::CamFromImg inverts the distortion by Newton's method with a
// numerical Jacobian: exact, but about twenty evaluations of the model per
// pixel. PixelRays calls it only on a coarse grid of nodes (every
// `grid_step` pixels, the image border included), keeps each node's ray and
// the Jacobian d(pixel)/d(u, v) of the forward model there, and for any
// position interpolates both bilinearly and takes Newton steps on the
// camera's own forward model, Camera::ImgFromCam:
//
//   (u, v) <- (u, v) - J^-1 (ImgFromCam(u, v, 1) - pixel)
//
// until the residual is below `tolerance_px` (one step from the
// interpolated start lands at about 1e-7 px for the Brown/Beyer lenses of
// the synthetic scenes; the result is exact in the sense that re-projecting
// the ray through the camera model gives the position back). The same holds
// for every camera model with an inverse, and for film scans whose image
// frame (ImageFrame) is rotated and shifted in the scan.
#pragma once

#include "ext/core/camera.h"
#include "ext/core/image_frame.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <optional>
#include <vector>

namespace bayon {

struct PixelRaysOptions {
  // Spacing of the nodes where Camera::CamFromImg is called, in pixels.
  // Smaller costs more set-up time and saves nothing per position.
  int grid_step = 8;
  // Newton steps go on while the error before a step exceeds 0.01 px, up
  // to this many; from the interpolated start one step is the rule.
  int max_newton_steps = 4;
  // When the residual is asked for, a ray that re-projects further than
  // 1000 times this from its position is rejected.
  double tolerance_px = 1e-6;
  void Check() const;
};

class PixelRays {
 public:
  // Rays for positions in [0, width] x [0, height] of `camera` (COLMAP
  // pixels: the centre of the upper-left pixel is (0.5, 0.5)). `frame`
  // replaces the default image frame of a BROWN_BEYER camera (film scans).
  // Throws InputError if the camera is invalid or its inverse fails at most
  // of the nodes.
  PixelRays(const Camera& camera,
            const std::optional<ImageFrame>& frame = std::nullopt,
            const PixelRaysOptions& options = {});

  // Normalized coordinates (u, v) of the ray (u, v, 1) in the camera frame
  // (x right, y down, z forward) through `pixel`. Returns false where the
  // model has no inverse (far outside a calibrated frame). `residual_px`,
  // when given, receives the re-projection miss of the result;
  // `uv_from_pixel`, when given, the derivative d uv / d pixel there (the
  // interpolated inverse Jacobian, ~1e-4 relative), or NaNs where the slow
  // exact inverse had to be used.
  bool Ray(const Eigen::Vector2d& pixel,
           Eigen::Vector2d* uv,
           double* residual_px = nullptr,
           Eigen::Matrix2d* uv_from_pixel = nullptr) const;

  // The box of normalized coordinates that contains the rays of every
  // position of the image, and the largest magnification |d pixel / d uv|
  // (the largest singular value of the forward Jacobian) over the nodes:
  // a pinhole raster with focal length s * that value has pixels no larger
  // than 1/s image pixels anywhere.
  const Eigen::AlignedBox2d& bounds() const { return bounds_; }
  double max_magnification() const { return max_magnification_; }

  int width() const { return width_; }
  int height() const { return height_; }

 private:
  struct Node {
    Eigen::Vector2d uv;
    Eigen::Matrix2d uv_from_pixel;  // inverse of the forward Jacobian
    bool valid = false;
  };
  Eigen::Vector2d Project(const Eigen::Vector2d& uv) const;

  Camera camera_;
  std::optional<ImageFrame> frame_;
  PixelRaysOptions options_;
  int width_ = 0;
  int height_ = 0;
  int num_nodes_x_ = 0;
  int num_nodes_y_ = 0;
  std::vector<double> node_x_;  // pixel positions of the node columns
  std::vector<double> node_y_;
  std::vector<Node> nodes_;  // row-major, num_nodes_y_ x num_nodes_x_
  Eigen::AlignedBox2d bounds_;
  double max_magnification_ = 0;
};

}  // namespace bayon
