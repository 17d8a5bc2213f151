// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/pixel_rays.h"

#include "ext/core/errors.h"
#include "ext/core/random.h"
#include "ext/synth/synthetic_camera.h"

#include <gtest/gtest.h>

#include <random>

namespace bayon {
namespace {

// A scanned film frame: rotated by 0.7 degrees and shifted in a larger scan.
ImageFrame ScanFrame(double pitch_mm, double width, double height) {
  const double angle = 0.7 * M_PI / 180;
  ImageFrame frame;
  frame.pixel_from_frame << std::cos(angle) / pitch_mm,
      -std::sin(angle) / pitch_mm, 0.5 * width + 13.2,
      -std::sin(angle) / pitch_mm, -std::cos(angle) / pitch_mm,
      0.5 * height - 7.9;
  return frame;
}

void ExpectExactRays(const Camera& camera,
                     const std::optional<ImageFrame>& frame) {
  const PixelRays rays(camera, frame);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(0, camera.width),
      y(0, camera.height);
  const ImageFrame* frame_ptr = frame ? &*frame : nullptr;
  double max_residual = 0, max_difference = 0;
  for (int i = 0; i < 2000; ++i) {
    const double row = y(rng);  // y first: a fixed order of draws
    const Eigen::Vector2d pixel(x(rng), row);
    Eigen::Vector2d uv;
    double residual = -1;
    ASSERT_TRUE(rays.Ray(pixel, &uv, &residual));
    // Re-projection through the camera model gives the position back.
    const Eigen::Vector2d back =
        camera.ImgFromCam(Eigen::Vector3d(uv.x(), uv.y(), 1), frame_ptr);
    max_residual = std::max(max_residual, (back - pixel).norm());
    EXPECT_NEAR((back - pixel).norm(), residual, 1e-9);
    // The same ray as the camera's own inverse.
    const Eigen::Vector3d reference = camera.CamFromImg(pixel, frame_ptr);
    max_difference =
        std::max(max_difference, (reference.head<2>() - uv).norm());
    EXPECT_TRUE(rays.bounds().contains(uv));
  }
  EXPECT_LT(max_residual, 1e-6);
  // Both inversions stop within 1e-6 px: 1e-8 in normalized units is
  // 5e-6 px at f = 500 px.
  EXPECT_LT(max_difference, 1e-8);
}

TEST(PixelRays, BrownBeyerRaysReprojectExactly) {
  const Camera camera = SyntheticCamera(SyntheticCameraOptions());
  ExpectExactRays(camera, std::nullopt);
}

TEST(PixelRays, FilmScanFrameRaysReprojectExactly) {
  SyntheticCameraOptions options;
  options.width = 2000;
  options.height = 1400;
  const Camera camera = SyntheticCamera(options);
  ExpectExactRays(camera, ScanFrame(options.pixel_pitch_mm, 2000, 1400));
}

TEST(PixelRays, ColmapModelRaysReprojectExactly) {
  Camera camera = Camera::Create(CameraModelId::kOpenCV, 500, 640, 480);
  camera.params[4] = -0.2;   // k1
  camera.params[5] = 0.05;   // k2
  camera.params[6] = 1e-3;   // p1
  camera.params[7] = -2e-3;  // p2
  ExpectExactRays(camera, std::nullopt);
}

// The renderer extrapolates the rays of the supersamples of a pixel from
// the exact pixel-centre ray and its derivative: within a third of a pixel
// that stays far below anything an image can show (1e-4 px).
TEST(PixelRays, DerivativeExtrapolatesWithinAPixel) {
  SyntheticCameraOptions options;
  options.width = 2000;
  options.height = 1400;
  const Camera camera = SyntheticCamera(options);
  const ImageFrame frame = ScanFrame(options.pixel_pitch_mm, 2000, 1400);
  const PixelRays rays(camera, frame);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> x(1, camera.width - 1),
      y(1, camera.height - 1), offset(-0.5, 0.5);
  double max_miss_px = 0;
  for (int i = 0; i < 2000; ++i) {
    const double row = y(rng);  // y first: a fixed order of draws
    const Eigen::Vector2d center(x(rng), row);
    Eigen::Vector2d uv;
    Eigen::Matrix2d uv_from_pixel;
    ASSERT_TRUE(rays.Ray(center, &uv, nullptr, &uv_from_pixel));
    ASSERT_TRUE(uv_from_pixel.allFinite());
    const Eigen::Vector2d sample = center + RandomVector<2>(offset, rng);
    const Eigen::Vector2d extrapolated = uv + uv_from_pixel * (sample - center);
    const Eigen::Vector2d back = camera.ImgFromCam(
        Eigen::Vector3d(extrapolated.x(), extrapolated.y(), 1), &frame);
    max_miss_px = std::max(max_miss_px, (back - sample).norm());
  }
  EXPECT_LT(max_miss_px, 1e-4);
}

TEST(PixelRays, MagnificationIsTheFocalLengthForAPinhole) {
  const Camera camera = Camera::Create(CameraModelId::kPinhole, 800, 640, 480);
  const PixelRays rays(camera);
  EXPECT_NEAR(rays.max_magnification(), 800, 1e-3);
  EXPECT_LT(rays.bounds().min().x(), -320.0 / 800);
  EXPECT_GT(rays.bounds().max().y(), 240.0 / 800);
}

TEST(PixelRays, RejectsBadOptions) {
  const Camera camera = Camera::Create(CameraModelId::kPinhole, 800, 64, 48);
  PixelRaysOptions options;
  options.grid_step = 0;
  EXPECT_THROW(PixelRays(camera, std::nullopt, options), InputError);
}

}  // namespace
}  // namespace bayon
