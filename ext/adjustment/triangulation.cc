// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/triangulation.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace bayon {

std::optional<Ray> RayThroughPixel(const Camera& camera,
                                   const Rigid3d& cam_from_world,
                                   const Eigen::Vector2d& pixel,
                                   const ImageFrame* frame) {
  Eigen::Vector3d ray_in_cam;
  if (!camera.CamFromImg(pixel, &ray_in_cam, frame)) return std::nullopt;
  Ray ray;
  ray.origin = cam_from_world.Center();
  ray.direction = (cam_from_world.rotation.inverse() * ray_in_cam).normalized();
  return ray;
}

std::optional<Eigen::Vector3d> IntersectRays(const std::vector<Ray>& rays,
                                             double min_angle_deg) {
  if (rays.size() < 2) return std::nullopt;
  double max_angle = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    for (size_t j = i + 1; j < rays.size(); ++j) {
      const double cosine =
          std::clamp(rays[i].direction.dot(rays[j].direction), -1.0, 1.0);
      max_angle = std::max(max_angle, std::acos(cosine));
    }
  }
  if (max_angle < min_angle_deg * M_PI / 180.0) return std::nullopt;
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const Ray& ray : rays) {
    const Eigen::Matrix3d P =
        Eigen::Matrix3d::Identity() - ray.direction * ray.direction.transpose();
    A += P;
    b += P * ray.origin;
  }
  const Eigen::Vector3d point = A.ldlt().solve(b);
  if (!point.allFinite()) return std::nullopt;
  for (const Ray& ray : rays) {
    if ((point - ray.origin).dot(ray.direction) <= 0) return std::nullopt;
  }
  return point;
}

}  // namespace bayon
