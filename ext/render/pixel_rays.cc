// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/pixel_rays.h"

#include "ext/core/errors.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace bayon {

void PixelRaysOptions::Check() const {
  CheckOption(grid_step >= 1, "PixelRaysOptions.grid_step", ">= 1", grid_step);
  CheckOption(
      tolerance_px > 0, "PixelRaysOptions.tolerance_px", "> 0", tolerance_px);
  CheckOption(max_newton_steps >= 1,
              "PixelRaysOptions.max_newton_steps",
              ">= 1",
              max_newton_steps);
}

namespace {

std::vector<double> NodePositions(int size, int step) {
  std::vector<double> positions;
  for (int x = 0; x < size; x += step) positions.push_back(x);
  positions.push_back(size);
  return positions;
}

}  // namespace

Eigen::Vector2d PixelRays::Project(const Eigen::Vector2d& uv) const {
  Eigen::Vector2d pixel;
  const ImageFrame* frame = frame_ ? &*frame_ : nullptr;
  if (!camera_.ImgFromCam(
          Eigen::Vector3d(uv.x(), uv.y(), 1.0), &pixel, frame)) {
    pixel.setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  return pixel;
}

PixelRays::PixelRays(const Camera& camera,
                     const std::optional<ImageFrame>& frame,
                     const PixelRaysOptions& options)
    : camera_(camera), frame_(frame), options_(options) {
  options.Check();
  camera.Check();
  if (camera.model_id != CameraModelId::kBrownBeyer) frame_.reset();
  width_ = static_cast<int>(camera.width);
  height_ = static_cast<int>(camera.height);
  node_x_ = NodePositions(width_, options.grid_step);
  node_y_ = NodePositions(height_, options.grid_step);
  num_nodes_x_ = static_cast<int>(node_x_.size());
  num_nodes_y_ = static_cast<int>(node_y_.size());
  nodes_.resize(node_x_.size() * node_y_.size());
  const ImageFrame* frame_ptr = frame_ ? &*frame_ : nullptr;
  int num_valid = 0;
  bounds_.setEmpty();
  for (int iy = 0; iy < num_nodes_y_; ++iy) {
    for (int ix = 0; ix < num_nodes_x_; ++ix) {
      Node& node = nodes_[iy * num_nodes_x_ + ix];
      Eigen::Vector3d ray;
      const Eigen::Vector2d pixel(node_x_[ix], node_y_[iy]);
      if (!camera_.CamFromImg(pixel, &ray, frame_ptr)) continue;
      node.uv = ray.head<2>();
      // Forward Jacobian by central differences; the step is small against
      // the curvature of any lens and large against rounding.
      const double h = 1e-6;
      Eigen::Matrix2d jacobian;
      for (int j = 0; j < 2; ++j) {
        Eigen::Vector2d plus = node.uv, minus = node.uv;
        plus(j) += h;
        minus(j) -= h;
        jacobian.col(j) = (Project(plus) - Project(minus)) / (2 * h);
      }
      if (!jacobian.allFinite() || std::abs(jacobian.determinant()) < 1e-12) {
        continue;
      }
      node.uv_from_pixel = jacobian.inverse();
      node.valid = true;
      ++num_valid;
      bounds_.extend(node.uv);
      const Eigen::JacobiSVD<Eigen::Matrix2d> svd(jacobian);
      max_magnification_ =
          std::max(max_magnification_, svd.singularValues()(0));
    }
  }
  if (num_valid < static_cast<int>(nodes_.size()) / 2) {
    ThrowInputError("camera ",
                    camera.camera_id,
                    " (",
                    camera.ModelName(),
                    "): the inverse of the camera model fails over most of "
                    "the image (",
                    num_valid,
                    " of ",
                    nodes_.size(),
                    " grid nodes)");
  }
  // Between nodes the rays bulge by at most the interpolation error; a
  // margin of a few pixels keeps every position inside the box.
  const Eigen::Vector2d margin =
      Eigen::Vector2d::Constant(4.0 * options.grid_step / max_magnification_);
  bounds_.min() -= margin;
  bounds_.max() += margin;
}

bool PixelRays::Ray(const Eigen::Vector2d& pixel,
                    Eigen::Vector2d* uv,
                    double* residual_px,
                    Eigen::Matrix2d* uv_from_pixel) const {
  const double step = options_.grid_step;
  const int ix = std::clamp(
      static_cast<int>(std::floor(pixel.x() / step)), 0, num_nodes_x_ - 2);
  const int iy = std::clamp(
      static_cast<int>(std::floor(pixel.y() / step)), 0, num_nodes_y_ - 2);
  const double fx = (pixel.x() - node_x_[ix]) / (node_x_[ix + 1] - node_x_[ix]);
  const double fy = (pixel.y() - node_y_[iy]) / (node_y_[iy + 1] - node_y_[iy]);
  const Node& n00 = nodes_[iy * num_nodes_x_ + ix];
  const Node& n10 = nodes_[iy * num_nodes_x_ + ix + 1];
  const Node& n01 = nodes_[(iy + 1) * num_nodes_x_ + ix];
  const Node& n11 = nodes_[(iy + 1) * num_nodes_x_ + ix + 1];
  Eigen::Vector2d x;
  Eigen::Matrix2d inverse_jacobian;
  if (n00.valid && n10.valid && n01.valid && n11.valid) {
    const double w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy),
                 w01 = (1 - fx) * fy, w11 = fx * fy;
    x = w00 * n00.uv + w10 * n10.uv + w01 * n01.uv + w11 * n11.uv;
    inverse_jacobian = w00 * n00.uv_from_pixel + w10 * n10.uv_from_pixel +
                       w01 * n01.uv_from_pixel + w11 * n11.uv_from_pixel;
  } else {
    // Near the edge of the model's domain: the slow exact inverse.
    Eigen::Vector3d ray;
    if (!camera_.CamFromImg(pixel, &ray, frame_ ? &*frame_ : nullptr)) {
      return false;
    }
    *uv = ray.head<2>();
    if (residual_px) *residual_px = (Project(*uv) - pixel).norm();
    if (uv_from_pixel) {
      uv_from_pixel->setConstant(std::numeric_limits<double>::quiet_NaN());
    }
    return true;
  }
  if (uv_from_pixel) *uv_from_pixel = inverse_jacobian;
  // Newton steps on the forward model. From the interpolated start one
  // step suffices (the start is within ~1e-3 px, the interpolated Jacobian
  // within ~1e-4 relative, so the step lands within ~1e-7 px); further steps
  // are taken only where the start was poor, which the step size shows.
  for (int i = 0; i < options_.max_newton_steps; ++i) {
    const Eigen::Vector2d error = Project(x) - pixel;
    if (!error.allFinite() || !(error.norm() < 1e6)) return false;
    const Eigen::Vector2d step = inverse_jacobian * error;
    x -= step;
    // |error| < 0.01 px: the quadratic term leaves well under 1e-6 px.
    if (error.norm() < 1e-2) break;
  }
  *uv = x;
  if (residual_px) {
    *residual_px = (Project(x) - pixel).norm();
    if (!(*residual_px < 1e3 * options_.tolerance_px)) return false;
  }
  return true;
}

}  // namespace bayon
