// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/points_scene.h"

#include "ext/core/errors.h"
#include "ext/core/random.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <random>
#include <vector>

namespace bayon {

void PointsSceneOptions::Check() const {
  CheckOption(num_views >= 2, "num_views", ">= 2", num_views);
  CheckOption(num_points >= 1, "num_points", ">= 1", num_points);
  CheckOption(ring_radius_m > object_radius_m,
              "ring_radius_m",
              "> object_radius_m",
              ring_radius_m);
  CheckOption(object_radius_m > 0, "object_radius_m", "> 0", object_radius_m);
  CheckOption(
      keypoint_noise_px >= 0, "keypoint_noise_px", ">= 0", keypoint_noise_px);
  CheckOption(num_distant_points >= 0,
              "num_distant_points",
              ">= 0",
              num_distant_points);
  CheckOption(distant_points_m > ring_radius_m,
              "distant_points_m",
              "> ring_radius_m",
              distant_points_m);
  CheckOption(max_view_angle_deg > 0 && max_view_angle_deg <= 90,
              "max_view_angle_deg",
              "in (0, 90]",
              max_view_angle_deg);
  camera.Check();
}

namespace {

// Each point on the bisector of two neighbouring stations' axes, at
// distant_points_m from their midpoint.
void AddDistantPoints(const PointsSceneOptions& options, Scene* scene) {
  std::vector<image_t> ids;
  for (const auto& [image_id, image] : scene->images) ids.push_back(image_id);
  for (int k = 0; k < options.num_distant_points; ++k) {
    const image_t id1 = ids[k % ids.size()];
    const image_t id2 = ids[(k + 1) % ids.size()];
    const Rigid3d& pose1 = scene->images.at(id1).cam_from_world;
    const Rigid3d& pose2 = scene->images.at(id2).cam_from_world;
    const Eigen::Vector3d axis =
        (pose1.rotation.inverse() * Eigen::Vector3d::UnitZ() +
         pose2.rotation.inverse() * Eigen::Vector3d::UnitZ())
            .normalized();
    const Eigen::Vector3d xyz = 0.5 * (pose1.Center() + pose2.Center()) +
                                options.distant_points_m * axis;
    std::vector<TrackElement> track;
    for (image_t id : {id1, id2}) {
      Image& image = scene->images.at(id);
      Point2D point;
      if (!scene->Project(image, xyz, &point.xy)) continue;
      image.points2D.push_back(point);
      track.push_back({id, static_cast<point2D_t>(image.points2D.size() - 1)});
    }
    if (track.size() == 2) {
      scene->AddPoint3D(xyz, track);
    } else {
      for (const TrackElement& element : track) {
        scene->images.at(element.image_id).points2D.pop_back();
      }
    }
  }
}

}  // namespace

SyntheticTruth SynthesizePointsScene(const PointsSceneOptions& options) {
  options.Check();
  SyntheticTruth truth;
  Scene& scene = truth.scene;
  std::mt19937 rng(options.seed);
  const Camera camera = SyntheticCamera(options.camera);
  scene.cameras.Set(camera.camera_id, camera);

  const Eigen::Vector3d target(0, 0, 0.5 * options.object_height_m);
  for (int i = 0; i < options.num_views; ++i) {
    const double azimuth = 2 * M_PI * i / options.num_views;
    const Eigen::Vector3d center(options.ring_radius_m * std::cos(azimuth),
                                 options.ring_radius_m * std::sin(azimuth),
                                 options.camera_height_m);
    Image image;
    image.image_id = static_cast<image_t>(i + 1);
    char name[32];
    std::snprintf(name, sizeof(name), "view_%03d.png", i + 1);
    image.name = name;
    image.camera_id = camera.camera_id;
    const double roll_rad =
        (i % 2 == 1) ? options.alternate_roll_deg * M_PI / 180.0 : 0.0;
    image.cam_from_world =
        LookAt(center, target, Eigen::Vector3d::UnitZ(), roll_rad);
    scene.images.Set(image.image_id, image);
  }

  std::uniform_real_distribution<double> uniform(0, 1);
  const double cos_max = std::cos(options.max_view_angle_deg * M_PI / 180.0);
  for (int p = 0; p < options.num_points; ++p) {
    const double azimuth = 2 * M_PI * uniform(rng);
    const double radius = options.object_radius_m * std::sqrt(uniform(rng));
    const Eigen::Vector3d xyz(radius * std::cos(azimuth),
                              radius * std::sin(azimuth),
                              options.object_height_m * uniform(rng));
    const Eigen::Vector3d normal(std::cos(azimuth), std::sin(azimuth), 0);
    std::vector<TrackElement> track;
    for (auto& [image_id, image] : scene.images) {
      const Eigen::Vector3d to_camera =
          (image.cam_from_world.Center() - xyz).normalized();
      if (to_camera.dot(normal) < cos_max) continue;
      Eigen::Vector2d pixel;
      if (!scene.Project(image, xyz, &pixel)) continue;
      if (pixel.x() < 0 || pixel.y() < 0 || pixel.x() > camera.width ||
          pixel.y() > camera.height) {
        continue;
      }
      Point2D point;
      point.xy = pixel;
      image.points2D.push_back(point);
      track.push_back(
          {image_id, static_cast<point2D_t>(image.points2D.size() - 1)});
    }
    if (track.size() < 2) {
      for (const TrackElement& element : track) {
        scene.images.at(element.image_id).points2D.pop_back();
      }
      continue;
    }
    const point3D_t point3D_id = scene.AddPoint3D(xyz, track);
    Point3D& point = scene.points3D.at(point3D_id);
    point.color = Eigen::Matrix<uint8_t, 3, 1>(200, 180, 150);
  }
  AddDistantPoints(options, &scene);
  scene.UpdateReprojectionErrors();

  truth.noisy_scene = scene;
  std::normal_distribution<double> noise(0, options.keypoint_noise_px);
  for (auto& [image_id, image] : truth.noisy_scene.images) {
    for (Point2D& point : image.points2D) {
      point.xy += RandomVector<2>(noise, rng);
    }
  }
  truth.noisy_scene.UpdateReprojectionErrors();

  nlohmann::ordered_json description;
  description["scene"] = "points";
  description["num_views"] = options.num_views;
  description["num_points"] = options.num_points;
  description["ring_radius_m"] = options.ring_radius_m;
  description["camera_height_m"] = options.camera_height_m;
  description["alternate_roll_deg"] = options.alternate_roll_deg;
  description["object_radius_m"] = options.object_radius_m;
  description["object_height_m"] = options.object_height_m;
  description["max_view_angle_deg"] = options.max_view_angle_deg;
  if (options.num_distant_points > 0) {
    description["num_distant_points"] = options.num_distant_points;
    description["distant_points_m"] = options.distant_points_m;
  }
  description["keypoint_noise_px"] = options.keypoint_noise_px;
  description["seed"] = options.seed;
  description["focal_length_mm"] = options.camera.focal_length_mm;
  description["pixel_pitch_mm"] = options.camera.pixel_pitch_mm;
  description["width"] = options.camera.width;
  description["height"] = options.camera.height;
  description["distortion"] = options.camera.distortion;
  truth.description = description.dump(2) + "\n";
  return truth;
}

}  // namespace bayon
