// SPDX-License-Identifier: BSD-3-Clause
//
// A synthetic scene with known truth for the dense tests (mpgc_test,
// dense_test): a textured plane z = 0 (texture coordinates: object metres /
// texel) seen from above by a master and four convergent search cameras with
// the distortion of SyntheticCamera, rendered exactly through the camera
// model (one ray per pixel centre) with Gaussian noise.
#pragma once

#include "ext/core/scene.h"
#include "ext/dense/mpgc.h"
#include "ext/synth/synthetic_camera.h"
#include "ext/synth/texture_patches.h"

#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace bayon {
namespace testing {

struct PlaneScene {
  static constexpr double kTexel = 0.0023;  // about a pixel at 4 m
  Camera camera;
  std::vector<Rigid3d> poses;
  std::vector<cv::Mat> images;
  const WaveTexture texture{[] {
    WaveTextureOptions options;
    options.seed = 3;
    return options;
  }()};

  explicit PlaneScene(double noise_sigma, uint32_t seed = 1) {
    SyntheticCameraOptions camera_options;
    camera_options.width = 320;
    camera_options.height = 240;
    camera = SyntheticCamera(camera_options);
    camera.camera_id = 1;
    const Eigen::Vector3d target(0, 0, 0);
    for (const Eigen::Vector3d& centre : {Eigen::Vector3d(0, 0, 4),
                                          Eigen::Vector3d(1.1, 0.1, 3.9),
                                          Eigen::Vector3d(-1.0, 0.2, 3.8),
                                          Eigen::Vector3d(0.1, 1.1, 3.9),
                                          Eigen::Vector3d(-0.2, -1.0, 4.1)}) {
      poses.push_back(LookAt(centre, target, Eigen::Vector3d::UnitY()));
    }
    for (size_t j = 0; j < poses.size(); ++j) {
      images.push_back(Render(poses[j]));
      AddGaussianNoise(
          noise_sigma, seed + static_cast<uint32_t>(j), &images[j]);
    }
  }

  std::optional<Eigen::Vector3d> OnPlane(const Rigid3d& pose,
                                         const Eigen::Vector2d& pixel) const {
    Eigen::Vector3d ray;
    if (!camera.CamFromImg(pixel, &ray)) return std::nullopt;
    const Eigen::Vector3d d = pose.rotation.inverse() * ray;
    const Eigen::Vector3d c = pose.Center();
    if (std::abs(d.z()) < 1e-12) return std::nullopt;
    return c + d * (-c.z() / d.z());
  }

  cv::Mat Render(const Rigid3d& pose) const {
    cv::Mat image(camera.height, camera.width, CV_32F, cv::Scalar(0));
    for (int y = 0; y < image.rows; ++y) {
      for (int x = 0; x < image.cols; ++x) {
        const auto point = OnPlane(pose, Eigen::Vector2d(x + 0.5, y + 0.5));
        if (point) {
          image.at<float>(y, x) =
              static_cast<float>(texture.Value(point->head<2>() / kTexel));
        }
      }
    }
    return image;
  }

  MpgcView View(int j) const {
    MpgcView view;
    view.image = &images[j];
    view.camera = &camera;
    view.cam_from_world = poses[j];
    return view;
  }
  std::vector<MpgcView> SearchViews() const {
    std::vector<MpgcView> views;
    for (size_t j = 1; j < poses.size(); ++j) views.push_back(View(j));
    return views;
  }

  // The scene as an oriented model: image ids 1..5 (the master first),
  // names image_1.png ..., and sparse points on the plane seen by all
  // images (a grid under the master), as tie points would be.
  Scene ToScene() const {
    Scene scene;
    scene.cameras.Set(camera.camera_id, camera);
    for (size_t j = 0; j < poses.size(); ++j) {
      Image image;
      image.image_id = static_cast<image_t>(j + 1);
      image.name = "image_" + std::to_string(j + 1) + ".png";
      image.camera_id = camera.camera_id;
      image.cam_from_world = poses[j];
      scene.images.Set(image.image_id, image);
    }
    for (int y = 40; y <= 200; y += 40) {
      for (int x = 40; x <= 280; x += 40) {
        const std::optional<Eigen::Vector3d> point =
            OnPlane(poses[0], Eigen::Vector2d(x, y));
        if (!point) continue;
        std::vector<TrackElement> track;
        for (size_t j = 0; j < poses.size(); ++j) {
          Eigen::Vector2d xy;
          if (!camera.ImgFromCam(poses[j] * *point, &xy)) continue;
          Image& image = scene.images.at(static_cast<image_t>(j + 1));
          Point2D observation;
          observation.xy = xy;
          image.points2D.push_back(observation);
          TrackElement element;
          element.image_id = image.image_id;
          element.point2D_idx =
              static_cast<point2D_t>(image.points2D.size() - 1);
          track.push_back(element);
        }
        scene.AddPoint3D(*point, track);
      }
    }
    return scene;
  }
};

}  // namespace testing
}  // namespace bayon
