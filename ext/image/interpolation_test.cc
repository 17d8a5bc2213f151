// SPDX-License-Identifier: BSD-3-Clause
#include "ext/image/interpolation.h"

#include "ext/core/errors.h"
#include "ext/image/pyramid.h"

#include <gtest/gtest.h>

#include <functional>

namespace bayon {
namespace {

cv::Mat ImageOf(int width,
                int height,
                const std::function<double(double, double)>& f) {
  cv::Mat image(height, width, CV_32F);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      image.at<float>(r, c) = static_cast<float>(f(c + 0.5, r + 0.5));
    }
  }
  return image;
}

TEST(Interpolation, BilinearIsExactOnPlanes) {
  const cv::Mat image =
      ImageOf(20, 16, [](double x, double y) { return 3 + 2 * x - 0.5 * y; });
  for (const auto& [x, y] : {std::pair{5.3, 7.9}, {2.0, 2.0}, {17.4, 13.2}}) {
    ImageSample sample;
    ASSERT_TRUE(SampleImage(image, x, y, Interpolation::kBilinear, &sample));
    EXPECT_NEAR(sample.value, 3 + 2 * x - 0.5 * y, 1e-4);
    EXPECT_NEAR(sample.dx, 2.0, 1e-5);
    EXPECT_NEAR(sample.dy, -0.5, 1e-5);
  }
}

TEST(Interpolation, BicubicIsExactOnQuadratics) {
  auto f = [](double x, double y) {
    return 1 + 0.3 * x * x - 0.2 * x * y + 0.1 * y * y + x;
  };
  const cv::Mat image = ImageOf(20, 16, f);
  for (const auto& [x, y] : {std::pair{5.3, 7.9}, {9.77, 4.01}}) {
    ImageSample sample;
    ASSERT_TRUE(SampleImage(image, x, y, Interpolation::kBicubic, &sample));
    EXPECT_NEAR(sample.value, f(x, y), 1e-3);
    EXPECT_NEAR(sample.dx, 0.6 * x - 0.2 * y + 1, 1e-3);
    EXPECT_NEAR(sample.dy, -0.2 * x + 0.2 * y, 1e-3);
  }
}

TEST(Interpolation, PixelCentresReturnThePixel) {
  cv::Mat image(10, 10, CV_32F);
  cv::randu(image, 0, 255);
  for (Interpolation method :
       {Interpolation::kBilinear, Interpolation::kBicubic}) {
    ImageSample sample;
    ASSERT_TRUE(SampleImage(image, 4.5, 6.5, method, &sample));
    EXPECT_NEAR(sample.value, image.at<float>(6, 4), 1e-4);
  }
}

TEST(Interpolation, RefusesPointsWhoseFootprintLeavesTheImage) {
  const cv::Mat image(10, 12, CV_32F, cv::Scalar(1));
  ImageSample sample;
  EXPECT_FALSE(SampleImage(image, 1.4, 5, Interpolation::kBilinear, &sample));
  EXPECT_TRUE(SampleImage(image, 1.5, 5, Interpolation::kBilinear, &sample));
  EXPECT_FALSE(SampleImage(image, 9.5, 5, Interpolation::kBicubic, &sample));
  EXPECT_TRUE(SampleImage(image, 9.49, 5, Interpolation::kBicubic, &sample));
  EXPECT_FALSE(SampleImage(image, 2.4, 5, Interpolation::kBicubic, &sample));
  EXPECT_FALSE(SampleImage(image, 5, -3, Interpolation::kBicubic, &sample));
}

TEST(Pyramid, LevelsNestInColmapPixelCoordinates) {
  // A linear ramp keeps its value at every level where the coordinates
  // are scaled by 2^-level: value(x_full) = value_level(x_full / 2^level).
  auto f = [](double x, double y) { return 10 + 2 * x + 3 * y; };
  const ImagePyramid pyramid = BuildImagePyramid(ImageOf(64, 48, f), 3, 8);
  ASSERT_EQ(pyramid.num_levels(), 3);
  EXPECT_EQ(pyramid.levels[1].cols, 32);
  EXPECT_EQ(pyramid.levels[2].rows, 12);
  const Eigen::Vector2d full(30.3, 21.7);
  for (int level = 1; level < 3; ++level) {
    const Eigen::Vector2d xy = ImagePyramid::LevelFromFull(full, level);
    ImageSample sample;
    ASSERT_TRUE(SampleImage(pyramid.levels[level],
                            xy.x(),
                            xy.y(),
                            Interpolation::kBilinear,
                            &sample));
    EXPECT_NEAR(sample.value, f(full.x(), full.y()), 1e-3) << level;
    EXPECT_NEAR(sample.dx, 2.0 / ImagePyramid::Scale(level), 1e-3);
  }
}

}  // namespace
}  // namespace bayon
