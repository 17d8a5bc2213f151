// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/views.h"

#include "ext/core/errors.h"

#include <Eigen/Geometry>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <set>

namespace bayon {
namespace {

constexpr double kDegree = M_PI / 180.0;

// Depths of the points in front of the camera: (nearest, median).
std::pair<double, double> DepthRange(
    const Rigid3d& cam_from_world, const std::vector<Eigen::Vector3d>& points) {
  // A few thousand points describe the depths well enough.
  const size_t step = std::max<size_t>(1, points.size() / 4096);
  std::vector<double> depths;
  for (size_t i = 0; i < points.size(); i += step) {
    const double z = (cam_from_world * points[i]).z();
    if (z > 0) depths.push_back(z);
  }
  if (depths.empty()) return {0.0, 0.0};
  const auto middle = depths.begin() + depths.size() / 2;
  std::nth_element(depths.begin(), middle, depths.end());
  return {*std::min_element(depths.begin(), depths.end()), *middle};
}

// Unit vectors spanning the horizontal plane: the first nearest to the
// world's x axis (y when up is x), the second up x first.
std::pair<Eigen::Vector3d, Eigen::Vector3d> HorizontalAxes(
    const Eigen::Vector3d& up) {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
  if (std::abs(up.dot(axis)) > 0.9) axis = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d first = (axis - up * up.dot(axis)).normalized();
  return {first, up.cross(first)};
}

std::string ViewNameOfImage(const std::string& image_name) {
  std::string name =
      std::filesystem::path(image_name).replace_extension().string();
  std::replace(name.begin(), name.end(), '/', '_');
  std::replace(name.begin(), name.end(), '\\', '_');
  return name;
}

// Focal length in pixels of the view as it will be rendered (a Brown/Beyer
// camera's pixels are its frame's, which ScaleView may have changed).
double FocalLengthPx(const RenderView& view) {
  const Camera& camera = view.camera;
  if (camera.model_id != CameraModelId::kBrownBeyer) {
    return camera.MeanFocalLengthPx();
  }
  const ImageFrame frame = view.frame ? *view.frame : camera.DefaultFrame();
  return (camera.params[brown::kC] + camera.params[brown::kDc]) /
         frame.MeanPitchMm();
}

}  // namespace

void OrbitOptions::Register(OptionRegistry* r) {
  r->Add("num_views", &num_views, "orbit: number of cameras");
  r->Add("elevation_deg",
         &elevation_deg,
         "orbit: angle of the cameras above the model's centre");
  r->Add("start_azimuth_deg",
         &start_azimuth_deg,
         "orbit: azimuth of the first camera (from x, counter-clockwise seen "
         "from above; -90 = looking along +y)");
  r->Add("width", &width, "orbit: image width in pixels");
  r->Add("height", &height, "orbit: image height in pixels");
  r->Add("fov_deg", &fov_deg, "orbit: horizontal field of view (degrees)");
  r->Add(
      "fill", &fill, "orbit: share of the frame the model fills (0.05 to 1)");
}

void OrbitOptions::Check() const {
  CheckOption(num_views >= 1, "num_views", ">= 1", num_views);
  CheckOption(std::abs(elevation_deg) <= 89,
              "elevation_deg",
              "between -89 and 89",
              elevation_deg);
  CheckOption(width >= 8 && width <= 16384, "width", "8 to 16384", width);
  CheckOption(height >= 8 && height <= 16384, "height", "8 to 16384", height);
  CheckOption(fov_deg > 1 && fov_deg < 170, "fov_deg", "1 to 170", fov_deg);
  CheckOption(fill > 0.05 && fill <= 1, "fill", "in (0.05, 1]", fill);
  CheckOption(up.allFinite() && up.norm() > 1e-9,
              "up",
              "a non-zero vector",
              up.transpose());
}

void StereoOptions::Check() const {
  CheckOption(base_m >= 0 && std::isfinite(base_m),
              "stereo_base",
              ">= 0 (0 = automatic)",
              base_m);
  CheckOption(base_ratio > 0 && base_ratio < 1,
              "StereoOptions.base_ratio",
              "in (0, 1)",
              base_ratio);
}

Rigid3d LookAt(const Eigen::Vector3d& center,
               const Eigen::Vector3d& target,
               const Eigen::Vector3d& up) {
  const Eigen::Vector3d forward = (target - center).normalized();
  const Eigen::Vector3d right = forward.cross(up);
  if (!forward.allFinite() || right.norm() < 1e-9 * up.norm()) {
    ThrowInputError("view direction (",
                    forward.transpose(),
                    ") is parallel to the up direction");
  }
  Eigen::Matrix3d rotation;
  // Rows: the camera's axes in world coordinates (x right, y down, z ahead).
  rotation.row(0) = right.normalized();
  rotation.row(2) = forward;
  rotation.row(1) = forward.cross(rotation.row(0).transpose()).transpose();
  const Eigen::Quaterniond q(rotation);
  return Rigid3d(q, -(rotation * center));
}

std::vector<Viewpoint> OrbitViewpoints(
    const std::vector<Eigen::Vector3d>& points, const OrbitOptions& options) {
  options.Check();
  if (points.empty()) ThrowInputError("orbit viewpoints: the model is empty");
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : points) box.extend(p);
  const Eigen::Vector3d target = box.center();
  const Eigen::Vector3d up = options.up.normalized();
  const auto [axis1, axis2] = HorizontalAxes(up);
  const double focal =
      0.5 * options.width / std::tan(0.5 * options.fov_deg * kDegree);
  // Tangents of the half angles the model may fill.
  const double tan_x = options.fill * 0.5 * options.width / focal;
  const double tan_y = options.fill * 0.5 * options.height / focal;
  const double elevation = options.elevation_deg * kDegree;
  std::vector<Viewpoint> viewpoints;
  for (int i = 0; i < options.num_views; ++i) {
    const double azimuth =
        options.start_azimuth_deg * kDegree + 2 * M_PI * i / options.num_views;
    const Eigen::Vector3d towards_camera =
        std::cos(elevation) *
            (std::cos(azimuth) * axis1 + std::sin(azimuth) * axis2) +
        std::sin(elevation) * up;
    // Orientation first (at unit distance), then the distance: a point p
    // (relative to the target, in camera axes) is inside the share `fill`
    // when |p.x| <= tan_x (d + p.z) and |p.y| <= tan_y (d + p.z).
    const Rigid3d unit = LookAt(target + towards_camera, target, up);
    const Eigen::Matrix3d rotation = unit.rotation.toRotationMatrix();
    double distance = 0;
    for (const Eigen::Vector3d& point : points) {
      const Eigen::Vector3d p = rotation * (point - target);
      distance = std::max({distance,
                           std::abs(p.x()) / tan_x - p.z(),
                           std::abs(p.y()) / tan_y - p.z()});
    }
    // Flat models seen edge-on: keep some distance.
    distance = std::max(distance, 1e-3 * (box.diagonal().norm() + 1e-9));
    Viewpoint viewpoint;
    char name[16];
    std::snprintf(name, sizeof(name), "%03d", i);
    viewpoint.name = name;
    viewpoint.view.camera = Camera::Create(
        CameraModelId::kPinhole, focal, options.width, options.height);
    viewpoint.view.cam_from_world =
        LookAt(target + distance * towards_camera, target, up);
    viewpoint.convergence_depth_m = distance;
    viewpoint.nearest_depth_m =
        DepthRange(viewpoint.view.cam_from_world, points).first;
    viewpoints.push_back(viewpoint);
  }
  return viewpoints;
}

Eigen::Vector3d MeanImageUp(const Scene& scene) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& [image_id, image] : scene.images) {
    sum += image.cam_from_world.rotation.inverse() * Eigen::Vector3d(0, -1, 0);
  }
  return sum.norm() > 1e-6 ? Eigen::Vector3d(sum.normalized())
                           : Eigen::Vector3d::Zero();
}

std::vector<Viewpoint> StationViewpoints(
    const Scene& scene,
    const std::vector<Eigen::Vector3d>& points,
    int max_image_size) {
  CheckOption(max_image_size >= 0, "max_image_size", ">= 0", max_image_size);
  std::vector<Viewpoint> viewpoints;
  std::set<std::string> names;
  for (const auto& [image_id, image] : scene.images) {
    const Camera* found = scene.cameras.Find(image.camera_id);
    if (found == nullptr) {
      ThrowInputError("image ",
                      image.name,
                      ": its camera ",
                      image.camera_id,
                      " is not in the model");
    }
    const Camera& camera = *found;
    RenderView view;
    view.camera = camera;
    view.cam_from_world = image.cam_from_world;
    view.frame = image.frame;
    const auto [nearest, median] = DepthRange(view.cam_from_world, points);
    if (median <= 0) continue;
    const double longer = double(std::max(camera.width, camera.height));
    if (max_image_size > 0 && longer > max_image_size) {
      view = ScaleView(view, max_image_size / longer);
    }
    Viewpoint viewpoint;
    viewpoint.name = ViewNameOfImage(image.name);
    // `a/b.jpg` and `a_b.jpg`, or `x.jpg` and `x.tif`, would share a name
    // and one picture overwrite the other: the later one gets the image id.
    if (!names.insert(viewpoint.name).second) {
      viewpoint.name += "_" + std::to_string(image.image_id);
      names.insert(viewpoint.name);
    }
    viewpoint.view = view;
    viewpoint.convergence_depth_m = median;
    viewpoint.nearest_depth_m = nearest;
    viewpoints.push_back(viewpoint);
  }
  return viewpoints;
}

RenderView ScaleView(const RenderView& view, double scale) {
  CHECK_GT(scale, 0);
  RenderView scaled = view;
  Camera& camera = scaled.camera;
  camera.width = std::max<uint64_t>(1, std::llround(camera.width * scale));
  camera.height = std::max<uint64_t>(1, std::llround(camera.height * scale));
  if (camera.model_id == CameraModelId::kBrownBeyer) {
    // Image coordinates (mm) stay; the frame maps them to scaled pixels.
    ImageFrame frame = view.frame ? *view.frame : view.camera.DefaultFrame();
    frame.pixel_from_frame *= scale;
    scaled.frame = frame;
  } else {
    const CameraModelInfo& info = camera.ModelInfo();
    for (int i : info.focal_idxs) camera.params[i] *= scale;
    for (int i : info.principal_point_idxs) camera.params[i] *= scale;
  }
  return scaled;
}

RenderView ShiftView(const RenderView& view, double dx_px) {
  RenderView shifted = view;
  if (view.camera.model_id == CameraModelId::kBrownBeyer) {
    ImageFrame frame = view.frame ? *view.frame : view.camera.DefaultFrame();
    frame.pixel_from_frame(0, 2) += dx_px;
    shifted.frame = frame;
  } else {
    shifted.camera.params[view.camera.ModelInfo().principal_point_idxs[0]] +=
        dx_px;
  }
  return shifted;
}

StereoPair MakeStereoPair(const Viewpoint& viewpoint,
                          const StereoOptions& options) {
  options.Check();
  StereoPair pair;
  pair.base_m = options.base_m > 0
                    ? options.base_m
                    : options.base_ratio * viewpoint.nearest_depth_m;
  const double half = 0.5 * pair.base_m;
  // The left camera sits at -half along the camera's x axis, so a world
  // point appears at camera x + half in it: t_left = t + (half, 0, 0).
  RenderView left = viewpoint.view, right = viewpoint.view;
  left.cam_from_world.translation.x() += half;
  right.cam_from_world.translation.x() -= half;
  // A point at the convergence depth on the axis lands f * half / depth to
  // the right of the principal point in the left image: move it back.
  const double depth = std::max(viewpoint.convergence_depth_m, 1e-9);
  const double shift = FocalLengthPx(viewpoint.view) * half / depth;
  pair.left = ShiftView(left, -shift);
  pair.right = ShiftView(right, shift);
  return pair;
}

}  // namespace bayon
