// SPDX-License-Identifier: BSD-3-Clause
//
// Where `bayon render` looks from: orbit viewpoints around a model, the
// photographs' own stations, and stereo pairs made from either.
//
// Frames as everywhere in bayon: cam_from_world with the camera's x right,
// y down, z forward; world coordinates in metres; the world's vertical is
// given (`up`), z in bayon's datums.
#pragma once

#include "ext/core/option_registry.h"
#include "ext/core/scene.h"
#include "ext/render/mesh_renderer.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace bayon {

// One image to render and what stereo needs to know about it.
struct Viewpoint {
  std::string name;  // in file names: "000", "001", ... or the photograph's
  RenderView view;
  // Depth (camera z, metres) of the point that should appear in the screen
  // plane of a stereo pair (zero parallax): the model's centre.
  double convergence_depth_m = 0;
  // Depth of the model's nearest point in front of the camera (metres).
  double nearest_depth_m = 0;
};

struct OrbitOptions {
  // Cameras evenly spaced on a circle about the vertical through the centre
  // of the model's bounding box.
  int num_views = 8;
  // Height of the circle, as the angle above the horizontal at which the
  // cameras look down on the centre (degrees, -89 to 89).
  double elevation_deg = 20;
  // Azimuth of the first camera, counter-clockwise seen from above from the
  // horizontal axis nearest to the world's x axis (degrees).
  double start_azimuth_deg = -60;
  int width = 1024;  // pixels
  int height = 768;
  // Horizontal field of view (degrees); the focal length follows.
  double fov_deg = 40;
  // Share of the frame the model fills in its tighter direction: the
  // distance is the smallest at which every vertex lies inside that share.
  double fill = 0.8;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  // Every field but `up`, which the caller shares with the lighting.
  void Register(OptionRegistry* registry);
  void Check() const;
};

// PINHOLE cameras looking at the centre of the points' bounding box.
// Throws InputError if there are no points.
std::vector<Viewpoint> OrbitViewpoints(
    const std::vector<Eigen::Vector3d>& points, const OrbitOptions& options);

// The photographs of a model as viewpoints, named after their images
// ('/' and the extension replaced), with their cameras scaled so that the
// longer side has at most `max_image_size` pixels (0: full size). Images
// that see none of the points are left out.
// The photographer's vertical: the mean of the cameras' image up (-y) in
// the world; what lights a model from above whose datum, from relative
// orientation, has no known vertical. Zero for a model without images.
Eigen::Vector3d MeanImageUp(const Scene& scene);

std::vector<Viewpoint> StationViewpoints(
    const Scene& scene,
    const std::vector<Eigen::Vector3d>& points,
    int max_image_size);

// cam_from_world for a camera at `center` looking at `target`, the image's
// up towards the world's `up`. Throws InputError if they are parallel.
Rigid3d LookAt(const Eigen::Vector3d& center,
               const Eigen::Vector3d& target,
               const Eigen::Vector3d& up);

// The same view with the image scaled by `scale` (pixel coordinates times
// scale, the image size rounded); exact for integer scales.
RenderView ScaleView(const RenderView& view, double scale);

// The same view with the image content moved right by `dx_px` pixels (the
// principal point, or the frame origin of Brown/Beyer cameras, shifted).
RenderView ShiftView(const RenderView& view, double dx_px);

struct StereoOptions {
  // Stereo base in metres; 0: base_ratio times the nearest model depth.
  double base_m = 0;
  // The "1/30 rule" of stereo photography: a base of 1/30 of the distance
  // to the nearest object keeps the largest parallax (at the near point,
  // with the screen plane at the model's centre) within what the eyes fuse
  // without strain on a screen seen at arm's length.
  double base_ratio = 1.0 / 30.0;
  void Check() const;
};

struct StereoPair {
  RenderView left;
  RenderView right;
  double base_m = 0;
};

// Left and right views: the camera moved by half the base to each side along
// its x axis (parallel axes, no keystone), the images shifted so that points
// at the convergence depth have no parallax (off-axis stereo).
StereoPair MakeStereoPair(const Viewpoint& viewpoint,
                          const StereoOptions& options);

}  // namespace bayon
