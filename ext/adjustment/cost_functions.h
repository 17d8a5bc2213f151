// SPDX-License-Identifier: BSD-3-Clause
//
// Ceres residuals of the bundle adjustment, one functor per residual type in
// the shape of Snavely's reprojection error: the observation is a const
// member, the computation a templated operator(), and Create() hides the
// AutoDiffCostFunction block sizes.
//
// Parameter blocks (units):
//   rotation    4  cam_from_world rotation as a unit quaternion (w, x, y, z),
//                  with RotationManifold: the tangent is a rotation vector of
//                  the camera axes in radians (R <- Exp(delta) R), so that
//                  its standard deviations are angles about the camera's
//                  x (tilt), y (pan) and z (roll) axes;
//   center      3  projection centre X0, Y0, Z0 in object units (metres);
//                  X_cam = R (X - X0), the photogrammetric form of the
//                  collinearity equations;
//   point       3  object point X, Y, Z (metres);
//   intrinsics  n  the camera's parameters in the order of camera_models.h:
//                  13 for BROWN_BEYER (c, x0, y0 held fixed with a
//                  SubsetManifold, the ten additional parameters free or
//                  fixed as self-calibration decides), COLMAP's for the
//                  COLMAP models.
//
// Residuals are in pixels: a BROWN_BEYER projection in image millimetres goes
// through the image's interior orientation (ImageFrame) to COLMAP pixels,
// where the observation lives. Every residual is multiplied by its square
// root information matrix, sqrt(P) = sigma0 / sigma for uncorrelated
// observations, so that 2 * cost = v^T P v in units of the reference
// observation (sigma0 pixels) and sigma0 a posteriori = sqrt(v^T P v / r).
#pragma once

#include "ext/core/camera_models.h"
#include "ext/core/image_frame.h"

#include <Eigen/Core>
#include <ceres/autodiff_cost_function.h>
#include <ceres/autodiff_manifold.h>
#include <ceres/rotation.h>

namespace bayon {

// Number of parameters of a camera model, at compile time.
constexpr int CameraModelNumParams(CameraModelId model) {
  switch (model) {
    case CameraModelId::kSimplePinhole:
      return 3;
    case CameraModelId::kPinhole:
    case CameraModelId::kSimpleRadial:
    case CameraModelId::kSimpleRadialFisheye:
      return 4;
    case CameraModelId::kRadial:
    case CameraModelId::kFOV:
    case CameraModelId::kRadialFisheye:
      return 5;
    case CameraModelId::kOpenCV:
    case CameraModelId::kOpenCVFisheye:
      return 8;
    case CameraModelId::kFullOpenCV:
    case CameraModelId::kThinPrismFisheye:
      return 12;
    case CameraModelId::kBrownBeyer:
      return brown::kNumParams;
    default:
      return 0;
  }
}

// Projection of a camera-frame point to COLMAP pixels, one type per model, so
// that the reprojection functor is templated on the model (Ceres needs the
// intrinsics block size at compile time).
template <CameraModelId kModel>
struct ColmapProjection {
  static constexpr CameraModelId kModelId = kModel;
  static constexpr int kNumParams = CameraModelNumParams(kModel);
  template <typename T>
  static bool PixelFromCam(const T* params,
                           const T* point_in_cam,
                           const ImageFrame& /*frame*/,
                           T* pixel) {
    return ColmapImgFromCam(kModel, params, point_in_cam, pixel);
  }
};

// BROWN_BEYER: image millimetres (camera_models.h) mapped to pixels by the
// image's interior orientation.
struct BrownBeyerProjection {
  static constexpr CameraModelId kModelId = CameraModelId::kBrownBeyer;
  static constexpr int kNumParams = brown::kNumParams;
  template <typename T>
  static bool PixelFromCam(const T* params,
                           const T* point_in_cam,
                           const ImageFrame& frame,
                           T* pixel) {
    T xy_mm[2];
    if (!BrownBeyerFrameFromCam(params, point_in_cam, xy_mm)) return false;
    frame.PixelFromFrame(xy_mm, pixel);
    return true;
  }
};

// The rotation parameter block: a unit quaternion (w, x, y, z) updated by a
// rotation vector of the camera axes, q <- Exp(delta) * q. Unlike Ceres's
// QuaternionManifold (whose delta is half the rotation angle), delta is the
// full angle in radians, so covariances are angles directly.
struct RotationVectorPlus {
  template <typename T>
  bool Plus(const T* q, const T* delta, T* q_plus_delta) const {
    T delta_q[4];
    ceres::AngleAxisToQuaternion(delta, delta_q);
    ceres::QuaternionProduct(delta_q, q, q_plus_delta);
    return true;
  }
  template <typename T>
  bool Minus(const T* y, const T* x, T* y_minus_x) const {
    const T x_inverse[4] = {x[0], -x[1], -x[2], -x[3]};
    T relative[4];
    ceres::QuaternionProduct(y, x_inverse, relative);
    ceres::QuaternionToAngleAxis(relative, y_minus_x);
    return true;
  }
};
using RotationManifold = ceres::AutoDiffManifold<RotationVectorPlus, 4, 3>;

// Collinearity: the pixel where `point` appears in an image with pose
// (rotation, center) and camera `intrinsics`, minus the observed pixel,
// weighted by sqrt_information (2x2). Blocks: rotation 4, center 3, point 3,
// intrinsics Projection::kNumParams.
template <typename Projection>
struct ReprojectionCost {
  ReprojectionCost(const Eigen::Vector2d& observed,
                   const Eigen::Matrix2d& sqrt_information,
                   const ImageFrame& frame)
      : observed_(observed),
        sqrt_information_(sqrt_information),
        frame_(frame) {}

  template <typename T>
  bool operator()(const T* rotation,
                  const T* center,
                  const T* point,
                  const T* intrinsics,
                  T* residuals) const {
    const T relative[3] = {
        point[0] - center[0], point[1] - center[1], point[2] - center[2]};
    T point_in_cam[3];
    ceres::UnitQuaternionRotatePoint(rotation, relative, point_in_cam);
    T pixel[2];
    if (!Projection::PixelFromCam(intrinsics, point_in_cam, frame_, pixel)) {
      return false;
    }
    const T dx = pixel[0] - T(observed_.x());
    const T dy = pixel[1] - T(observed_.y());
    residuals[0] =
        T(sqrt_information_(0, 0)) * dx + T(sqrt_information_(0, 1)) * dy;
    residuals[1] =
        T(sqrt_information_(1, 0)) * dx + T(sqrt_information_(1, 1)) * dy;
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector2d& observed,
                                     const Eigen::Matrix2d& sqrt_information,
                                     const ImageFrame& frame = ImageFrame()) {
    return new ceres::AutoDiffCostFunction<ReprojectionCost,
                                           2,
                                           4,
                                           3,
                                           3,
                                           Projection::kNumParams>(
        new ReprojectionCost(observed, sqrt_information, frame));
  }

 private:
  const Eigen::Vector2d observed_;
  const Eigen::Matrix2d sqrt_information_;
  const ImageFrame frame_;
};

// A weighted control point: the adjusted coordinates minus the given ones,
// weighted by sqrt_information (3x3, sigma0 / sigma for uncorrelated
// coordinates). Block: point 3.
struct PointPriorCost {
  PointPriorCost(const Eigen::Vector3d& prior,
                 const Eigen::Matrix3d& sqrt_information)
      : prior_(prior), sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* point, T* residuals) const {
    T difference[3];
    for (int k = 0; k < 3; ++k) difference[k] = point[k] - T(prior_(k));
    for (int i = 0; i < 3; ++i) {
      residuals[i] = T(0);
      for (int k = 0; k < 3; ++k) {
        residuals[i] += T(sqrt_information_(i, k)) * difference[k];
      }
    }
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector3d& prior,
                                     const Eigen::Matrix3d& sqrt_information) {
    return new ceres::AutoDiffCostFunction<PointPriorCost, 3, 3>(
        new PointPriorCost(prior, sqrt_information));
  }

 private:
  const Eigen::Vector3d prior_;
  const Eigen::Matrix3d sqrt_information_;
};

// A measured distance between two object points: |B - A| - distance,
// times sqrt_information (sigma0 / sigma). Blocks: point A 3, point B 3.
struct DistanceCost {
  DistanceCost(double distance, double sqrt_information)
      : distance_(distance), sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* a, const T* b, T* residuals) const {
    using std::sqrt;
    const T dx = b[0] - a[0];
    const T dy = b[1] - a[1];
    const T dz = b[2] - a[2];
    residuals[0] = T(sqrt_information_) *
                   (sqrt(dx * dx + dy * dy + dz * dz) - T(distance_));
    return true;
  }

  static ceres::CostFunction* Create(double distance, double sqrt_information) {
    return new ceres::AutoDiffCostFunction<DistanceCost, 1, 3, 3>(
        new DistanceCost(distance, sqrt_information));
  }

 private:
  const double distance_;
  const double sqrt_information_;
};

}  // namespace bayon
