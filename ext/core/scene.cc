// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/scene.h"

#include "ext/core/errors.h"

#include <algorithm>

namespace bayon {

int Image::NumPoints3D() const {
  int count = 0;
  for (const Point2D& point : points2D) count += point.HasPoint3D();
  return count;
}

const Image* Scene::FindImageByName(const std::string& name) const {
  for (const auto& [image_id, image] : images) {
    if (image.name == name) return &image;
  }
  return nullptr;
}

bool Scene::Project(const Image& image,
                    const Eigen::Vector3d& point_in_world,
                    Eigen::Vector2d* pixel) const {
  const Camera& camera = cameras.at(image.camera_id);
  const ImageFrame* frame = image.frame ? &*image.frame : nullptr;
  return camera.ImgFromCam(image.cam_from_world * point_in_world, pixel, frame);
}

point3D_t Scene::AddPoint3D(const Eigen::Vector3d& xyz,
                            const std::vector<TrackElement>& track) {
  point3D_t point3D_id = 1;
  for (const auto& entry : points3D) {
    point3D_id = std::max(point3D_id, entry.first + 1);
  }
  Point3D point;
  point.xyz = xyz;
  point.track = track;
  for (const TrackElement& element : track) {
    images.at(element.image_id).points2D.at(element.point2D_idx).point3D_id =
        point3D_id;
  }
  points3D.Set(point3D_id, std::move(point));
  return point3D_id;
}

void Scene::UpdateReprojectionErrors() {
  for (auto& [point3D_id, point] : points3D) {
    double sum = 0;
    int count = 0;
    for (const TrackElement& element : point.track) {
      const Image& image = images.at(element.image_id);
      Eigen::Vector2d pixel;
      if (!Project(image, point.xyz, &pixel)) continue;
      sum += (pixel - image.points2D.at(element.point2D_idx).xy).norm();
      ++count;
    }
    point.error = count > 0 ? sum / count : -1.0;
  }
}

SceneStats Scene::Stats() const {
  SceneStats stats;
  stats.num_cameras = static_cast<int>(cameras.size());
  stats.num_images = static_cast<int>(images.size());
  stats.num_points3D = static_cast<int>(points3D.size());
  double error_sum = 0;
  for (const auto& [point3D_id, point] : points3D) {
    stats.num_observations += static_cast<int>(point.track.size());
    error_sum += point.error;
  }
  if (stats.num_points3D > 0) {
    stats.mean_track_length =
        static_cast<double>(stats.num_observations) / stats.num_points3D;
    stats.mean_reprojection_error_px = error_sum / stats.num_points3D;
  }
  if (stats.num_images > 0) {
    stats.mean_observations_per_image =
        static_cast<double>(stats.num_observations) / stats.num_images;
  }
  return stats;
}

void Scene::CheckConsistency(const std::string& what) const {
  for (const auto& [image_id, image] : images) {
    if (!cameras.contains(image.camera_id)) {
      ThrowInputError(what,
                      ": image ",
                      image_id,
                      " (",
                      image.name,
                      ") refers to camera ",
                      image.camera_id,
                      ", which is not in the model");
    }
    for (const Point2D& point : image.points2D) {
      if (point.HasPoint3D() && !points3D.contains(point.point3D_id)) {
        ThrowInputError(what,
                        ": image ",
                        image_id,
                        " refers to 3D point ",
                        point.point3D_id,
                        ", which is not in the model");
      }
    }
  }
  for (const auto& [point3D_id, point] : points3D) {
    for (const TrackElement& element : point.track) {
      const Image* image = images.Find(element.image_id);
      if (image == nullptr) {
        ThrowInputError(what,
                        ": 3D point ",
                        point3D_id,
                        " is seen in image ",
                        element.image_id,
                        ", which is not in the model");
      }
      if (element.point2D_idx >= image->points2D.size()) {
        ThrowInputError(what,
                        ": 3D point ",
                        point3D_id,
                        " refers to 2D point ",
                        element.point2D_idx,
                        " of image ",
                        element.image_id,
                        ", which has only ",
                        image->points2D.size());
      }
    }
  }
}

}  // namespace bayon
