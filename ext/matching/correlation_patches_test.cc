// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/correlation_patches.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace bayon {
namespace {

TEST(CorrelationPatches, QuarterTurnsPermuteWindowsExactly) {
  // A single bright sample at (u, v) = (1, 0) in a 3 x 3 window.
  float window[9] = {0, 0, 0, 0, 0, 1, 0, 0, 0};
  float rotated[9];
  RotateWindow(window, 3, 1, rotated);
  // R_1 (1, 0) = (0, 1): one row down, centre column.
  EXPECT_EQ(rotated[2 * 3 + 1], 1.f);
  const Eigen::Vector2d moved = QuarterRotation(1) * Eigen::Vector2d(1, 0);
  EXPECT_NEAR(moved.x(), 0, 1e-12);
  EXPECT_NEAR(moved.y(), 1, 1e-12);
  float values[49], turned[49], back[49];
  for (int i = 0; i < 49; ++i) values[i] = static_cast<float>(i * i % 17);
  for (int r = 0; r < 4; ++r) {
    RotateWindow(values, 7, r, turned);
    RotateWindow(turned, 7, 4 - r, back);
    for (int i = 0; i < 49; ++i) ASSERT_EQ(back[i], values[i]) << r;
  }
  EXPECT_TRUE(QuarterRotation(4).isIdentity());
  EXPECT_TRUE((QuarterRotation(1) * QuarterRotation(3)).isIdentity());
}

TEST(CorrelationPatches, RotatedImageGivesRotatedWindows) {
  cv::Mat image(60, 80, CV_32F);
  cv::RNG rng(4);
  rng.fill(image, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(0, 0), 1.0);
  for (int r = 0; r < 4; ++r) {
    cv::Mat turned = image.clone();
    if (r == 1) cv::rotate(image, turned, cv::ROTATE_90_CLOCKWISE);
    if (r == 2) cv::rotate(image, turned, cv::ROTATE_180);
    if (r == 3) cv::rotate(image, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
    // Pixel (x, y) of `image` lands at pixel q of `turned`.
    const Eigen::Vector2i p(37, 25);
    Eigen::Vector2i q = p;
    if (r == 1) q = Eigen::Vector2i(59 - p.y(), p.x());
    if (r == 2) q = Eigen::Vector2i(79 - p.x(), 59 - p.y());
    if (r == 3) q = Eigen::Vector2i(p.y(), 79 - p.x());
    PatchOptions options;
    const ImagePatches a =
        ExtractImagePatches(image, {p.cast<double>().array() + 0.5}, options);
    const ImagePatches b =
        ExtractImagePatches(turned, {q.cast<double>().array() + 0.5}, options);
    ASSERT_TRUE(a.valid[0] && b.valid[0]);
    std::vector<float> rotated(options.FineDim());
    RotateWindow(a.Fine(0), options.window_size, r, rotated.data());
    for (int i = 0; i < options.FineDim(); ++i) {
      EXPECT_NEAR(rotated[i], b.Fine(0)[i], 1e-5) << "r=" << r << " i=" << i;
    }
    float dot = 0;
    for (int i = 0; i < options.FineDim(); ++i)
      dot += a.Fine(0)[i] * a.Fine(0)[i];
    EXPECT_NEAR(dot, 1.f, 1e-5);  // normalised: NCC is a dot product
  }
}

TEST(CorrelationPatches, ShiftedWindowsAreTheFineWindowsOfNearbyPixels) {
  cv::Mat image(60, 80, CV_32F);
  cv::RNG rng(5);
  rng.fill(image, cv::RNG::UNIFORM, 0, 255);
  PatchOptions options;
  const int shift = 1, dim = options.FineDim();
  // The keypoint and its eight neighbours, each with its own fine window.
  std::vector<Eigen::Vector2d> xy;
  for (int dv = -shift; dv <= shift; ++dv) {
    for (int du = -shift; du <= shift; ++du) {
      xy.emplace_back(30.5 + du, 25.5 + dv);
    }
  }
  const ImagePatches patches = ExtractImagePatches(image, xy, options);
  std::vector<float> shifted(9 * dim);
  ShiftedWindows(patches, 4, shift, shifted.data());  // the middle one
  for (int k = 0; k < 9; ++k) {
    ASSERT_TRUE(patches.valid[k]);
    for (int i = 0; i < dim; ++i) {
      EXPECT_NEAR(shifted[k * dim + i], patches.Fine(k)[i], 1e-5) << k;
    }
  }
}

TEST(CorrelationPatches, FlatAndBorderWindowsAreInvalid) {
  cv::Mat image(40, 40, CV_32F, cv::Scalar(100));
  image(cv::Rect(20, 0, 20, 40)).setTo(150);
  PatchOptions options;
  const ImagePatches patches = ExtractImagePatches(
      image, {{5.5, 20.5}, {10.5, 20.5}, {20.5, 20.5}, {38.5, 20.5}}, options);
  EXPECT_FALSE(patches.valid[0]);  // too close to the border
  EXPECT_FALSE(patches.valid[1]);  // flat
  EXPECT_TRUE(patches.valid[2]);   // on the edge
  EXPECT_FALSE(patches.valid[3]);
  EXPECT_EQ(patches.NumValid(), 1);
}

}  // namespace
}  // namespace bayon
