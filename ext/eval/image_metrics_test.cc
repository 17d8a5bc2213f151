// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/image_metrics.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>

namespace bayon {
namespace {

cv::Mat Texture(int seed) {
  cv::Mat image(64, 80, CV_32FC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0.2, 0.8);
  return image;
}

TEST(ImageMetrics, IdenticalImagesAreOneAndInfinite) {
  const cv::Mat image = Texture(1);
  const ImageComparison c = CompareImages(image, image);
  EXPECT_EQ(c.num_pixels, 64u * 80u);
  EXPECT_EQ(c.rmse, 0);
  EXPECT_EQ(c.psnr_db, 100.0);
  EXPECT_NEAR(c.ssim, 1.0, 1e-9);
}

TEST(ImageMetrics, ConstantOffsetGivesItsPsnrAndNoiseLowersSsim) {
  const cv::Mat image = Texture(2);
  const cv::Mat brighter = image + cv::Scalar::all(0.1);
  const ImageComparison offset = CompareImages(brighter, image);
  EXPECT_NEAR(offset.rmse, 0.1, 1e-6);
  EXPECT_NEAR(offset.psnr_db, 20.0, 1e-4);
  // A luminance offset changes only SSIM's luminance term, a little.
  EXPECT_GT(offset.ssim, 0.9);

  cv::Mat noise(image.size(), image.type());
  cv::RNG rng(3);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.1);
  const ImageComparison noisy = CompareImages(image + noise, image);
  EXPECT_NEAR(noisy.rmse, 0.1, 0.005);
  EXPECT_LT(noisy.ssim, 0.9);
  const ImageComparison unrelated = CompareImages(Texture(4), image);
  EXPECT_LT(unrelated.ssim, 0.1);
}

TEST(ImageMetrics, MaskSelectsThePixelsCompared) {
  const cv::Mat image = Texture(5);
  cv::Mat other = image.clone();
  other(cv::Rect(0, 0, 40, 64)).setTo(cv::Scalar::all(0));
  cv::Mat mask(image.size(), CV_8U, cv::Scalar(0));
  mask(cv::Rect(50, 0, 30, 64)).setTo(255);
  const ImageComparison right = CompareImages(other, image, mask);
  EXPECT_EQ(right.num_pixels, 30u * 64u);
  EXPECT_EQ(right.rmse, 0);
  const ImageComparison all = CompareImages(other, image);
  EXPECT_GT(all.rmse, 0.2);
}

TEST(ImageMetrics, RefusesMismatchedImagesAndEmptyMasks) {
  const cv::Mat image = Texture(6);
  EXPECT_THROW(CompareImages(image, image(cv::Rect(0, 0, 10, 10)).clone()),
               InputError);
  cv::Mat grey(image.size(), CV_32F, cv::Scalar(0));
  EXPECT_THROW(CompareImages(image, grey), InputError);
  const cv::Mat none(image.size(), CV_8U, cv::Scalar(0));
  EXPECT_THROW(CompareImages(image, image, none), InputError);
}

}  // namespace
}  // namespace bayon
