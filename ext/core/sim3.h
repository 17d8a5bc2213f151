// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "ext/core/rigid3.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace bayon {

// A similarity b_from_a: x_in_b = scale * rotation * x_in_a + translation.
// The 7-parameter transformation of photogrammetry (Helmert).
struct Sim3d {
  double scale = 1.0;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Sim3d() = default;
  Sim3d(double scale,
        const Eigen::Quaterniond& rotation,
        const Eigen::Vector3d& translation)
      : scale(scale), rotation(rotation), translation(translation) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& x_in_a) const {
    return scale * (rotation * x_in_a) + translation;
  }

  Sim3d Inverse() const {
    const Eigen::Quaterniond inverse_rotation = rotation.inverse();
    return Sim3d(1.0 / scale,
                 inverse_rotation,
                 -(inverse_rotation * translation) / scale);
  }

  Eigen::Matrix<double, 3, 4> ToMatrix() const {
    Eigen::Matrix<double, 3, 4> matrix;
    matrix.leftCols<3>() = scale * rotation.toRotationMatrix();
    matrix.col(3) = translation;
    return matrix;
  }

  // Maps a pose cam_from_a into cam_from_b, where b_from_a is this similarity:
  // the camera centre moves with the similarity, the rotation turns with it,
  // and the translation scales so that projections are unchanged.
  Rigid3d TransformPose(const Rigid3d& cam_from_a) const {
    const Eigen::Quaterniond cam_from_b_rotation =
        cam_from_a.rotation * rotation.inverse();
    const Eigen::Vector3d center_in_b = (*this) * cam_from_a.Center();
    return Rigid3d(cam_from_b_rotation, -(cam_from_b_rotation * center_in_b));
  }
};

}  // namespace bayon
