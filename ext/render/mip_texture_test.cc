// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/mip_texture.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

namespace bayon {
namespace {

TEST(MipTexture, SamplesTexelCentresExactly) {
  cv::Mat image(4, 8, CV_8UC3);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 8; ++x) {
      image.at<cv::Vec3b>(y, x) = cv::Vec3b(x * 30, y * 60, 255);
    }
  }
  const MipTexture texture(image);
  EXPECT_EQ(texture.num_levels(), 4);  // 8x4, 4x2, 2x1, 1x1
  // Texel (column 3, row 1): u = 3.5 / 8, v = 1 - 1.5 / 4 (v up).
  const Eigen::Vector3f value =
      texture.Sample(Eigen::Vector2f(3.5f / 8, 1 - 1.5f / 4), 0);
  EXPECT_NEAR(value.x(), 90 / 255.0, 1e-6);
  EXPECT_NEAR(value.y(), 60 / 255.0, 1e-6);
  EXPECT_NEAR(value.z(), 1.0, 1e-6);
  // Half-way between two columns: the mean.
  const Eigen::Vector3f between =
      texture.Sample(Eigen::Vector2f(4.0f / 8, 1 - 1.5f / 4), 0);
  EXPECT_NEAR(between.x(), 105 / 255.0, 1e-6);
}

TEST(MipTexture, CoarseLevelsAverage) {
  cv::Mat image(64, 64, CV_8UC3);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const uint8_t v = (x + y) % 2 ? 200 : 0;
      image.at<cv::Vec3b>(y, x) = cv::Vec3b(v, v, v);
    }
  }
  const MipTexture texture(image);
  // A checkerboard of single texels is mid-grey from level 1 on.
  EXPECT_NEAR(
      texture.Sample(Eigen::Vector2f(0.3f, 0.6f), 2.0f).x(), 100 / 255.0, 1e-3);
  EXPECT_NEAR(texture.Sample(Eigen::Vector2f(0.3f, 0.6f), 20.0f).x(),
              100 / 255.0,
              1e-3);
}

TEST(MipTexture, RejectsUnsupportedTypes) {
  EXPECT_THROW(MipTexture(cv::Mat(4, 4, CV_16UC3)), InputError);
}

}  // namespace
}  // namespace bayon
