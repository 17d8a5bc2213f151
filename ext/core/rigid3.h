// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace bayon {

// A rigid transform b_from_a: x_in_b = rotation * x_in_a + translation.
// Poses are stored as COLMAP does: cam_from_world, so the camera centre is
// -R^T t. Quaternions are Hamilton, constructed as Quaterniond(w, x, y, z).
struct Rigid3d {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Rigid3d() = default;
  Rigid3d(const Eigen::Quaterniond& rotation,
          const Eigen::Vector3d& translation)
      : rotation(rotation), translation(translation) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& x_in_a) const {
    return rotation * x_in_a + translation;
  }

  Rigid3d Inverse() const {
    const Eigen::Quaterniond inverse_rotation = rotation.inverse();
    return Rigid3d(inverse_rotation, -(inverse_rotation * translation));
  }

  // Returns the 3x4 matrix [R | t].
  Eigen::Matrix<double, 3, 4> ToMatrix() const {
    Eigen::Matrix<double, 3, 4> matrix;
    matrix.leftCols<3>() = rotation.toRotationMatrix();
    matrix.col(3) = translation;
    return matrix;
  }

  // For a cam_from_world pose: the projection centre in world coordinates.
  Eigen::Vector3d Center() const { return rotation.inverse() * -translation; }
};

// c_from_a = c_from_b * b_from_a.
inline Rigid3d operator*(const Rigid3d& c_from_b, const Rigid3d& b_from_a) {
  return Rigid3d(
      c_from_b.rotation * b_from_a.rotation,
      c_from_b.rotation * b_from_a.translation + c_from_b.translation);
}

// Angle of the relative rotation between two rotations, in radians.
inline double RotationAngleBetween(const Eigen::Quaterniond& a,
                                   const Eigen::Quaterniond& b) {
  return a.normalized().angularDistance(b.normalized());
}

}  // namespace bayon
