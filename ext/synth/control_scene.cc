// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/control_scene.h"

#include "ext/core/errors.h"
#include "ext/core/random.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

namespace bayon {
namespace {

struct Placed {
  std::string name;
  Eigen::Vector3d xyz;
  Eigen::Vector3d normal;
};

std::string Numbered(const char* prefix, int number) {
  char name[32];
  std::snprintf(name, sizeof(name), "%s%02d", prefix, number);
  return name;
}

Placed OnSurface(const std::string& name,
                 const PointsSceneOptions& scene,
                 double azimuth,
                 double height) {
  const Eigen::Vector3d normal(std::cos(azimuth), std::sin(azimuth), 0);
  return {name,
          Eigen::Vector3d(scene.object_radius_m * normal.x(),
                          scene.object_radius_m * normal.y(),
                          height),
          normal};
}

}  // namespace

void SyntheticControlOptions::Check() const {
  CheckOption(num_control_points >= 0,
              "num_control_points",
              ">= 0",
              num_control_points);
  CheckOption(
      num_check_points >= 0, "num_check_points", ">= 0", num_check_points);
  CheckOption(bar_length_m > 0, "bar_length_m", "> 0", bar_length_m);
  CheckOption(bar_sigma_m >= 0, "bar_sigma_m", ">= 0", bar_sigma_m);
  CheckOption(control_sigma_m >= 0, "control_sigma_m", ">= 0", control_sigma_m);
}

SyntheticControl SynthesizeControl(const SyntheticTruth& truth,
                                   const PointsSceneOptions& scene_options,
                                   const SyntheticControlOptions& options) {
  options.Check();
  std::mt19937 rng(scene_options.seed + 7919);
  std::uniform_real_distribution<double> uniform(0, 1);
  const double height = scene_options.object_height_m;
  std::vector<Placed> placed;
  std::vector<ControlPointType> types;
  for (int i = 0; i < options.num_control_points; ++i) {
    const double azimuth = 2 * M_PI * (i + 0.5) / options.num_control_points;
    const double z = height * (i % 2 == 0 ? 0.2 : 0.8);
    placed.push_back(
        OnSurface(Numbered("C", i + 1), scene_options, azimuth, z));
    types.push_back(ControlPointType::kControl);
  }
  for (int i = 0; i < options.num_check_points; ++i) {
    const double azimuth = 2 * M_PI * uniform(rng);
    const double z = height * (0.1 + 0.8 * uniform(rng));
    placed.push_back(
        OnSurface(Numbered("K", i + 1), scene_options, azimuth, z));
    types.push_back(ControlPointType::kCheck);
  }
  SyntheticControl control;
  if (options.levelling_bar) {
    // Standing on the object at azimuth 0 (towards the first station),
    // centred at mid height. Its ends are control points too.
    const double bottom = 0.5 * (height - options.bar_length_m);
    placed.push_back(OnSurface("BAR_A", scene_options, 0.0, bottom));
    placed.push_back(
        OnSurface("BAR_B", scene_options, 0.0, bottom + options.bar_length_m));
    types.push_back(ControlPointType::kControl);
    types.push_back(ControlPointType::kControl);
    DistanceObservation bar;
    bar.name1 = "BAR_A";
    bar.name2 = "BAR_B";
    bar.distance_m = options.bar_length_m;
    bar.sigma_m = options.bar_sigma_m;
    bar.vertical = true;
    control.distances.push_back(bar);
  }

  const double noise_px = options.measurement_noise_px >= 0
                              ? options.measurement_noise_px
                              : scene_options.keypoint_noise_px;
  std::normal_distribution<double> noise(0, noise_px);
  const double cos_max =
      std::cos(scene_options.max_view_angle_deg * M_PI / 180.0);
  const Scene& scene = truth.scene;
  for (size_t p = 0; p < placed.size(); ++p) {
    ControlPoint point;
    point.name = placed[p].name;
    point.xyz = placed[p].xyz;
    point.sigma.setConstant(options.control_sigma_m);
    point.type = types[p];
    control.points.push_back(point);
    for (const auto& [image_id, image] : scene.images) {
      const Eigen::Vector3d to_camera =
          (image.cam_from_world.Center() - point.xyz).normalized();
      if (to_camera.dot(placed[p].normal) < cos_max) continue;
      Eigen::Vector2d pixel;
      if (!scene.Project(image, point.xyz, &pixel)) continue;
      const Camera& camera = scene.cameras.at(image.camera_id);
      if (pixel.x() < 0 || pixel.y() < 0 || pixel.x() > camera.width ||
          pixel.y() > camera.height) {
        continue;
      }
      ImageMeasurement measurement;
      measurement.point_name = point.name;
      measurement.image_name = image.name;
      measurement.xy = pixel + RandomVector<2>(noise, rng);
      measurement.sigma_px = noise_px > 0 ? noise_px : 0;
      control.measurements.push_back(measurement);
    }
  }
  return control;
}

void WriteSyntheticControl(const SyntheticControl& control,
                           const std::string& folder) {
  std::filesystem::create_directories(folder);
  WriteControlPoints(folder + "/points.txt", control.points);
  WriteImageMeasurements(folder + "/observations.txt", control.measurements);
  if (!control.distances.empty()) {
    WriteDistances(folder + "/distances.txt", control.distances);
  }
}

}  // namespace bayon
