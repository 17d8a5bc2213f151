// SPDX-License-Identifier: BSD-3-Clause
#include "ext/image/radiometry.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace bayon {
namespace {

// A fine random texture, one channel, values around 128.
cv::Mat Texture(int size) {
  cv::Mat texture(size, size, CV_32F);
  cv::theRNG().state = 5;
  cv::randn(texture, 0.0, 20.0);
  cv::GaussianBlur(texture, texture, cv::Size(0, 0), 1.5);
  return texture + 128.0;
}

// The texture under light falling off from left to right (`left` to
// `right` times), with an exposure gain: two photographs of one surface at
// different times of day.
cv::Mat Lit(const cv::Mat& texture, double left, double right, double gain) {
  cv::Mat lit = texture.clone();
  for (int x = 0; x < lit.cols; ++x) {
    const double light = left + (right - left) * x / (lit.cols - 1.0);
    lit.col(x) *= gain * light;
  }
  cv::Mat bgr8;
  lit.convertTo(bgr8, CV_8U);
  cv::cvtColor(bgr8, bgr8, cv::COLOR_GRAY2BGR);
  return bgr8;
}

// Mean absolute difference in grey levels, away from the borders.
double MeanDifference(const cv::Mat& a, const cv::Mat& b) {
  const cv::Rect inner(40, 40, a.cols - 80, a.rows - 80);
  cv::Mat diff;
  cv::absdiff(a(inner), b(inner), diff);
  return cv::mean(diff)[0];
}

TEST(Radiometry, HighPassEqualizationMakesDifferentLightAgree) {
  const cv::Mat texture = Texture(256);
  const cv::Mat morning = Lit(texture, 1.3, 0.5, 1.0);
  const cv::Mat evening = Lit(texture, 0.6, 1.2, 0.8);
  const double before = MeanDifference(morning, evening);
  const cv::Mat a = HighPassEqualize(morning, 20);
  const cv::Mat b = HighPassEqualize(evening, 20);
  ASSERT_EQ(a.type(), CV_8UC3);
  ASSERT_EQ(a.size(), morning.size());
  const double after = MeanDifference(a, b);
  // The light multiplies the texture's contrast too, which a high pass
  // cannot undo locally (Wallis can): the difference about halves.
  EXPECT_LT(after, 0.6 * before) << "before " << before << ", after " << after;
  // Equalised: the values spread over the whole range.
  double lo = 0, hi = 0;
  cv::minMaxLoc(a.reshape(1), &lo, &hi);
  EXPECT_LT(lo, 10);
  EXPECT_GT(hi, 245);
}

TEST(Radiometry, EqualisationCountsOnlyTheMaskedObject) {
  // An object in the middle of a black background three times its area.
  const cv::Mat texture = Texture(256);
  cv::Mat photo = Lit(texture, 1.0, 1.0, 1.0);
  cv::Mat mask(photo.size(), CV_8U, cv::Scalar(0));
  const cv::Rect object(64, 64, 128, 128);
  mask(object).setTo(255);
  photo.setTo(cv::Scalar::all(0), ~mask);
  const cv::Mat whole = HighPassEqualize(photo, 20);
  const cv::Mat masked = HighPassEqualize(photo, 20, mask);
  // Without the mask the background's values take most of the range and
  // the object is pressed into the bright end (washed out); with it, the
  // object's values spread (its rim, where the high pass sees the dark
  // background, takes the brightest ranks).
  cv::Scalar mean_whole, stddev_whole, mean_masked, stddev_masked;
  const cv::Rect inner(80, 80, 96, 96);
  cv::meanStdDev(whole(inner).clone().reshape(1), mean_whole, stddev_whole);
  cv::meanStdDev(masked(inner).clone().reshape(1), mean_masked, stddev_masked);
  EXPECT_GT(mean_whole[0], 190.0);
  EXPECT_LT(mean_masked[0], mean_whole[0] - 60.0);
  EXPECT_GT(stddev_masked[0], 1.3 * stddev_whole[0]);
  EXPECT_THROW(HighPassEqualize(photo, 20, cv::Mat(8, 8, CV_8U)), InputError);
}

TEST(Radiometry, WallisPullsLocalMeanAndContrastToTheTarget) {
  const cv::Mat texture = Texture(256);
  const cv::Mat dark = Lit(texture, 0.4, 0.4, 1.0);
  WallisOptions options;
  options.radius_px = 20;
  options.contrast = 1.0;
  options.brightness = 1.0;
  const cv::Mat filtered = WallisFilter(dark, options);
  const cv::Rect inner(40, 40, 176, 176);
  cv::Scalar mean, stddev;
  cv::meanStdDev(filtered(inner).clone().reshape(1), mean, stddev);
  EXPECT_NEAR(mean[0], options.target_mean, 3.0);
  EXPECT_NEAR(stddev[0], options.target_stddev, 8.0);
  // The input is untouched.
  EXPECT_EQ(cv::norm(dark, Lit(texture, 0.4, 0.4, 1.0), cv::NORM_INF), 0.0);
}

TEST(Radiometry, RejectsWhatItCannotFilter) {
  EXPECT_THROW(HighPassEqualize(cv::Mat(), 50), InputError);
  EXPECT_THROW(HighPassEqualize(cv::Mat(8, 8, CV_32FC3), 50), InputError);
  EXPECT_THROW(HighPassEqualize(cv::Mat(8, 8, CV_8UC3), 0.5), InputError);
  WallisOptions bad;
  bad.contrast = 2;
  EXPECT_THROW(WallisFilter(cv::Mat(8, 8, CV_8UC1), bad), InputError);
}

}  // namespace
}  // namespace bayon
