// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/views.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bayon {
namespace {

Eigen::Vector2d Project(const RenderView& view, const Eigen::Vector3d& point) {
  const ImageFrame* frame = view.frame ? &*view.frame : nullptr;
  return view.camera.ImgFromCam(view.cam_from_world * point, frame);
}

// The corners of a box 4 m wide, 2 m deep and 10 m tall (a tower).
std::vector<Eigen::Vector3d> TowerCorners() {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 8; ++i) {
    points.emplace_back(
        100 + 4.0 * (i & 1), 50 + 2.0 * ((i >> 1) & 1), 3 + 10.0 * (i >> 2));
  }
  return points;
}

TEST(Views, LookAtCentresTheTargetWithUpUp) {
  const Camera camera = Camera::Create(CameraModelId::kPinhole, 500, 640, 480);
  RenderView view;
  view.camera = camera;
  view.cam_from_world = LookAt(Eigen::Vector3d(5, -10, 2),
                               Eigen::Vector3d(5, 0, 2),
                               Eigen::Vector3d::UnitZ());
  const Eigen::Vector2d center = Project(view, Eigen::Vector3d(5, 0, 2));
  EXPECT_NEAR(center.x(), 320, 1e-9);
  EXPECT_NEAR(center.y(), 240, 1e-9);
  // Higher in the world is higher in the image (smaller row), +x is right.
  EXPECT_LT(Project(view, Eigen::Vector3d(5, 0, 3)).y(), 239);
  EXPECT_GT(Project(view, Eigen::Vector3d(6, 0, 2)).x(), 321);
  EXPECT_THROW(LookAt(Eigen::Vector3d(0, 0, 5),
                      Eigen::Vector3d::Zero(),
                      Eigen::Vector3d::UnitZ()),
               InputError);
}

TEST(Views, OrbitFramesTheModelAtTheRequestedShare) {
  const std::vector<Eigen::Vector3d> points = TowerCorners();
  OrbitOptions options;
  options.num_views = 6;
  options.elevation_deg = 25;
  const std::vector<Viewpoint> viewpoints = OrbitViewpoints(points, options);
  ASSERT_EQ(viewpoints.size(), 6u);
  const Eigen::Vector3d target(102, 51, 8);
  for (const Viewpoint& viewpoint : viewpoints) {
    SCOPED_TRACE(viewpoint.name);
    const RenderView& view = viewpoint.view;
    EXPECT_EQ(view.camera.width, 1024u);
    // Elevation of the camera above the centre, and the distance recorded.
    const Eigen::Vector3d offset = view.cam_from_world.Center() - target;
    EXPECT_NEAR(std::asin(offset.z() / offset.norm()) * 180 / M_PI, 25, 1e-9);
    EXPECT_NEAR(viewpoint.convergence_depth_m, offset.norm(), 1e-9);
    EXPECT_GT(viewpoint.nearest_depth_m, 0);
    EXPECT_LT(viewpoint.nearest_depth_m, viewpoint.convergence_depth_m);
    // Every corner inside 80 % of the frame, one of them on its edge.
    double largest = 0;
    for (const Eigen::Vector3d& point : points) {
      const Eigen::Vector2d pixel = Project(view, point);
      largest = std::max({largest,
                          std::abs(pixel.x() - 512) / 512,
                          std::abs(pixel.y() - 384) / 384});
    }
    EXPECT_NEAR(largest, 0.8, 1e-9);
  }
  // Evenly around: neighbouring cameras 60 degrees apart about the vertical.
  const Eigen::Vector3d a = viewpoints[0].view.cam_from_world.Center() - target;
  const Eigen::Vector3d b = viewpoints[1].view.cam_from_world.Center() - target;
  EXPECT_NEAR(
      std::atan2(a.x() * b.y() - a.y() * b.x(), a.x() * b.x() + a.y() * b.y()) *
          180 / M_PI,
      60,
      1e-9);
  EXPECT_EQ(viewpoints[5].name, "005");
  options.fill = 0;
  EXPECT_THROW(OrbitViewpoints(points, options), InputError);
  EXPECT_THROW(OrbitViewpoints({}, OrbitOptions()), InputError);
}

TEST(Views, OrbitFollowsAnotherUpAxis) {
  OrbitOptions options;
  options.up = Eigen::Vector3d(0, 1, 0);
  options.elevation_deg = 30;
  const std::vector<Viewpoint> viewpoints =
      OrbitViewpoints(TowerCorners(), options);
  const Eigen::Vector3d offset =
      viewpoints[0].view.cam_from_world.Center() - Eigen::Vector3d(102, 51, 8);
  EXPECT_NEAR(std::asin(offset.y() / offset.norm()) * 180 / M_PI, 30, 1e-9);
}

TEST(Views, ScaleAndShiftMoveEveryPixel) {
  const Eigen::Vector3d point(0.3, -0.2, 4.0);
  RenderView pinhole;
  pinhole.camera = Camera::Create(CameraModelId::kSimpleRadial, 800, 600, 400);
  pinhole.camera.params[3] = -0.05;
  RenderView brown;
  brown.camera =
      Camera::Create(CameraModelId::kBrownBeyer, 800, 600, 400, 0.006);
  brown.camera.params[brown::kK1] = 1e-4;
  for (const RenderView& view : {pinhole, brown}) {
    SCOPED_TRACE(view.camera.ModelName());
    const Eigen::Vector2d pixel = Project(view, point);
    const RenderView half = ScaleView(view, 0.5);
    EXPECT_EQ(half.camera.width, 300u);
    EXPECT_EQ(half.camera.height, 200u);
    EXPECT_LT((Project(half, point) - 0.5 * pixel).norm(), 1e-9);
    const RenderView shifted = ShiftView(view, 7.5);
    EXPECT_LT(
        (Project(shifted, point) - pixel - Eigen::Vector2d(7.5, 0)).norm(),
        1e-9);
  }
}

TEST(Views, StereoPairConvergesOnTheModelCentre) {
  Viewpoint viewpoint;
  viewpoint.view.camera =
      Camera::Create(CameraModelId::kPinhole, 1000, 800, 600);
  viewpoint.view.cam_from_world = LookAt(Eigen::Vector3d(0, -20, 0),
                                         Eigen::Vector3d::Zero(),
                                         Eigen::Vector3d::UnitZ());
  viewpoint.convergence_depth_m = 20;
  viewpoint.nearest_depth_m = 15;
  const StereoPair pair = MakeStereoPair(viewpoint, StereoOptions());
  EXPECT_NEAR(pair.base_m, 0.5, 1e-12);  // 15 m / 30
  EXPECT_NEAR(
      (pair.left.cam_from_world.Center() - pair.right.cam_from_world.Center())
          .norm(),
      0.5,
      1e-12);
  // The left camera is on the left (-x in the world here).
  EXPECT_LT(pair.left.cam_from_world.Center().x(), 0);
  // No parallax at the convergence depth, crossed (x left > x right) in
  // front of it, uncrossed behind.
  auto parallax = [&](const Eigen::Vector3d& point) {
    return Project(pair.left, point).x() - Project(pair.right, point).x();
  };
  EXPECT_NEAR(parallax(Eigen::Vector3d(1, 0, 1)), 0, 1e-9);
  EXPECT_GT(parallax(Eigen::Vector3d(0, -5, 0)), 1);
  EXPECT_LT(parallax(Eigen::Vector3d(0, 5, 0)), -1);
  StereoOptions fixed;
  fixed.base_m = 2;
  EXPECT_EQ(MakeStereoPair(viewpoint, fixed).base_m, 2);
}

TEST(Views, StationsAreThePhotographsThatSeeTheModel) {
  Scene scene;
  Camera camera =
      Camera::Create(CameraModelId::kSimpleRadial, 3000, 4000, 3000);
  camera.camera_id = 1;
  scene.cameras.Set(1, camera);
  const std::vector<Eigen::Vector3d> points = TowerCorners();
  Image facing;
  facing.image_id = 1;
  facing.camera_id = 1;
  facing.name = "day1/IMG_0001.JPG";
  facing.cam_from_world = LookAt(Eigen::Vector3d(102, 20, 8),
                                 Eigen::Vector3d(102, 51, 8),
                                 Eigen::Vector3d::UnitZ());
  Image away = facing;
  away.image_id = 2;
  away.name = "away.jpg";
  away.cam_from_world = LookAt(Eigen::Vector3d(102, 20, 8),
                               Eigen::Vector3d(102, 0, 8),
                               Eigen::Vector3d::UnitZ());
  scene.images.Set(1, facing);
  scene.images.Set(2, away);
  const std::vector<Viewpoint> viewpoints =
      StationViewpoints(scene, points, 1000);
  ASSERT_EQ(viewpoints.size(), 1u);
  EXPECT_EQ(viewpoints[0].name, "day1_IMG_0001");
  EXPECT_EQ(viewpoints[0].view.camera.width, 1000u);
  EXPECT_EQ(viewpoints[0].view.camera.height, 750u);
  EXPECT_NEAR(viewpoints[0].nearest_depth_m, 30, 1e-9);
  EXPECT_NEAR(viewpoints[0].convergence_depth_m, 31, 1.0 + 1e-9);
  EXPECT_EQ(StationViewpoints(scene, points, 0)[0].view.camera.width, 4000u);

  // Names that would share a picture: the later one gets its image id.
  Image twin = facing;
  twin.image_id = 3;
  twin.name = "day1_IMG_0001.tif";
  scene.images.Set(3, twin);
  const std::vector<Viewpoint> both = StationViewpoints(scene, points, 1000);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_EQ(both[0].name, "day1_IMG_0001");
  EXPECT_EQ(both[1].name, "day1_IMG_0001_3");
}

}  // namespace
}  // namespace bayon
