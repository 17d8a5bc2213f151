// SPDX-License-Identifier: BSD-3-Clause
//
// bayon::Scene, the one in-memory description of a reconstruction: cameras,
// images with their cam_from_world poses and 2D points, and 3D points with
// their tracks. It is what COLMAP's sparse model files hold, and ext/colmap
// reads and writes it. Dense clouds, meshes and textures are files in the
// workspace, not part of the scene.
//
// Conventions (stated once, here):
// - Poses are cam_from_world (X_cam = R X_world + t); the camera frame has
//   x right, y down, z forward (COLMAP).
// - Pixel coordinates follow COLMAP: the centre of the upper-left pixel is
//   (0.5, 0.5). Image coordinates in mm go through ImageFrame.
// - Object coordinates are metres in a right-handed frame.
// - Angles are degrees in options and reports, radians in the math.
#pragma once

#include "ext/core/camera.h"
#include "ext/core/ordered_map.h"
#include "ext/core/rigid3.h"
#include "ext/core/types.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace bayon {

struct Point2D {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // pixels
  point3D_t point3D_id = kInvalidPoint3DId;
  bool HasPoint3D() const { return point3D_id != kInvalidPoint3DId; }
};

struct Image {
  image_t image_id = kInvalidImageId;
  std::string name;  // relative to the image folder, '/' separators
  camera_t camera_id = kInvalidCameraId;
  Rigid3d cam_from_world;
  std::vector<Point2D> points2D;
  // The image's own interior orientation where it differs from the camera's
  // default (scanned film frames); applies to BROWN_BEYER cameras.
  std::optional<ImageFrame> frame;

  int NumPoints3D() const;
};

struct TrackElement {
  image_t image_id = kInvalidImageId;
  point2D_t point2D_idx = kInvalidPoint2DIdx;
};

struct Point3D {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Matrix<uint8_t, 3, 1> color = Eigen::Matrix<uint8_t, 3, 1>::Zero();
  double error = -1.0;  // mean reprojection error in pixels; -1 unknown
  std::vector<TrackElement> track;
};

struct SceneStats {
  int num_cameras = 0;
  int num_images = 0;
  int num_points3D = 0;
  int num_observations = 0;
  double mean_track_length = 0;
  double mean_observations_per_image = 0;
  double mean_reprojection_error_px = 0;  // mean of the points' `error`
};

class Scene {
 public:
  OrderedMap<camera_t, Camera> cameras;
  OrderedMap<image_t, Image> images;
  OrderedMap<point3D_t, Point3D> points3D;

  const Image* FindImageByName(const std::string& name) const;

  // Projects a world point into an image (pixels); false if behind it.
  bool Project(const Image& image,
               const Eigen::Vector3d& point_in_world,
               Eigen::Vector2d* pixel) const;

  // Adds a 3D point and links its track's 2D points to it. Returns its id
  // (one more than the largest id so far).
  point3D_t AddPoint3D(const Eigen::Vector3d& xyz,
                       const std::vector<TrackElement>& track);

  // Recomputes every point's mean reprojection error from the observations.
  void UpdateReprojectionErrors();

  // The figures `colmap model_analyzer` prints.
  SceneStats Stats() const;

  // Throws InputError on dangling references (an image's camera missing, a
  // track pointing at a missing image or 2D point). `what` names the source.
  void CheckConsistency(const std::string& what) const;
};

}  // namespace bayon
