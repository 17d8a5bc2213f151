// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/model_statistics.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bayon {
namespace {

// 4 images in a row along x looking down +z through one SIMPLE_RADIAL
// camera with distortion, 10 points 5 units in front, every point seen in
// every image. Observation j is the exact projection moved by (3, 4) px
// (|r| = 5) for even j and left exact (|r| = 0) for odd j.
Scene TinyModel() {
  Scene model;
  Camera camera = Camera::Create(CameraModelId::kSimpleRadial, 150.0, 200, 200);
  camera.camera_id = 1;
  camera.params[3] = 0.05;  // k: the residuals must go through it
  model.cameras.Set(1, camera);
  for (image_t image_id = 1; image_id <= 4; ++image_id) {
    Image image;
    image.image_id = image_id;
    image.name = "image" + std::to_string(image_id) + ".png";
    image.camera_id = 1;
    image.cam_from_world.translation =
        Eigen::Vector3d(-0.5 * (image_id - 1.0), 0, 0);
    model.images.Set(image_id, image);
  }
  int j = 0;
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector3d xyz(0.2 * k, 0.1 * (k % 3) - 0.1, 5.0);
    std::vector<TrackElement> track;
    for (auto& [image_id, image] : model.images) {
      Eigen::Vector2d pixel;
      EXPECT_TRUE(model.Project(image, xyz, &pixel));
      Point2D point;
      point.xy = pixel + (j++ % 2 == 0 ? Eigen::Vector2d(3, 4)
                                       : Eigen::Vector2d::Zero());
      track.push_back(
          {image_id, static_cast<point2D_t>(image.points2D.size())});
      image.points2D.push_back(point);
    }
    model.AddPoint3D(xyz, track);
  }
  return model;
}

TEST(ModelStatistics, KnownReprojectionErrors) {
  const ModelStatistics stats = ComputeModelStatistics(TinyModel());
  EXPECT_EQ(stats.num_cameras, 1);
  EXPECT_EQ(stats.num_images, 4);
  EXPECT_EQ(stats.num_points3D, 10);
  EXPECT_EQ(stats.num_observations, 40);
  EXPECT_EQ(stats.num_unprojected, 0);
  EXPECT_DOUBLE_EQ(stats.mean_track_length, 4.0);
  // 20 residuals of 5 px and 20 of 0 px.
  EXPECT_NEAR(stats.mean_reprojection_error_px, 2.5, 1e-9);
  EXPECT_NEAR(stats.rms_reprojection_error_px, std::sqrt(12.5), 1e-9);
  EXPECT_NEAR(stats.median_reprojection_error_px, 5.0, 1e-9);
  EXPECT_NEAR(stats.max_reprojection_error_px, 5.0, 1e-9);
  // u = 6 x 4 images + 3 x 10 points + 4 camera parameters (f, cx, cy, k)
  //   = 58; 2n - u = 80 - 58 = 22; sum r^2 = 20 x 25 = 500.
  EXPECT_EQ(stats.num_camera_params, 4);
  EXPECT_EQ(stats.num_unknowns, 58);
  EXPECT_EQ(stats.redundancy, 22);
  EXPECT_NEAR(stats.sigma0_px, std::sqrt(500.0 / 22.0), 1e-9);
}

TEST(ModelStatistics, PointsBehindTheCameraAreLeftOutOfTheErrors) {
  Scene model = TinyModel();
  // A point behind every camera, observed in image 1 and 2 at far-off
  // pixels: counted as observations, but not in the errors or in n.
  std::vector<TrackElement> track;
  for (image_t image_id : {1, 2}) {
    Image& image = model.images.at(image_id);
    Point2D point;
    point.xy = Eigen::Vector2d(1000, 1000);
    track.push_back({image_id, static_cast<point2D_t>(image.points2D.size())});
    image.points2D.push_back(point);
  }
  model.AddPoint3D(Eigen::Vector3d(0, 0, -5), track);
  const ModelStatistics stats = ComputeModelStatistics(model);
  EXPECT_EQ(stats.num_points3D, 11);
  EXPECT_EQ(stats.num_observations, 42);
  EXPECT_EQ(stats.num_unprojected, 2);
  EXPECT_NEAR(stats.mean_reprojection_error_px, 2.5, 1e-9);
  EXPECT_NEAR(stats.max_reprojection_error_px, 5.0, 1e-9);
  // u = 58 + 3 = 61; 2n - u = 80 - 61 = 19.
  EXPECT_EQ(stats.redundancy, 19);
  EXPECT_NEAR(stats.sigma0_px, std::sqrt(500.0 / 19.0), 1e-9);
}

TEST(ModelStatistics, NoRedundancyGivesNoSigma0) {
  Scene model = TinyModel();
  // 2 images x 10 points: 2n - u = 40 - (12 + 30 + 4) < 0.
  model.images.Erase(3);
  model.images.Erase(4);
  for (auto& [point3D_id, point] : model.points3D) point.track.resize(2);
  const ModelStatistics stats = ComputeModelStatistics(model);
  EXPECT_EQ(stats.num_observations, 20);
  EXPECT_EQ(stats.redundancy, -6);
  EXPECT_EQ(stats.sigma0_px, 0.0);
  EXPECT_NEAR(stats.rms_reprojection_error_px, std::sqrt(12.5), 1e-9);

  const ModelStatistics empty = ComputeModelStatistics(Scene());
  EXPECT_EQ(empty.num_observations, 0);
  EXPECT_EQ(empty.mean_reprojection_error_px, 0.0);
  EXPECT_EQ(empty.sigma0_px, 0.0);
}

}  // namespace
}  // namespace bayon
