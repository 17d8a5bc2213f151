// SPDX-License-Identifier: BSD-3-Clause
#include "ext/image/radiometry.h"

#include "ext/core/errors.h"

#include <opencv2/imgproc.hpp>

#include <vector>

namespace bayon {
namespace {

void CheckInput(const cv::Mat& image, double radius_px, const char* what) {
  if (image.empty() || (image.type() != CV_8UC1 && image.type() != CV_8UC3)) {
    ThrowInputError(what, ": needs an 8-bit image with 1 or 3 channels");
  }
  if (!(radius_px >= 1.0)) {
    ThrowInputError(
        what, ": the radius must be at least 1 px (got ", radius_px, ")");
  }
}

// Gaussian low pass of sigma `radius_px`. A kernel of +-3 sigma reaches far
// past small images; OpenCV reflects at the border, which keeps the mean
// level there.
cv::Mat LowPass(const cv::Mat& channel, double radius_px) {
  cv::Mat low;
  cv::GaussianBlur(channel,
                   low,
                   cv::Size(0, 0),
                   radius_px,
                   radius_px,
                   cv::BORDER_REFLECT101);
  return low;
}

template <typename PerChannel>
cv::Mat ForEachChannel(const cv::Mat& image, PerChannel&& filter) {
  std::vector<cv::Mat> channels;
  cv::split(image, channels);
  for (cv::Mat& channel : channels) channel = filter(channel);
  cv::Mat result;
  cv::merge(channels, result);
  return result;
}

}  // namespace

cv::Mat HighPassEqualize(const cv::Mat& image, double radius_px) {
  CheckInput(image, radius_px, "high-pass filter");
  return ForEachChannel(image, [&](const cv::Mat& channel) {
    cv::Mat value;
    channel.convertTo(value, CV_32F);
    cv::Mat high = value - LowPass(value, radius_px) + 128.0;
    cv::Mat high8;
    high.convertTo(high8, CV_8U);  // saturating
    cv::Mat equalized;
    cv::equalizeHist(high8, equalized);
    return equalized;
  });
}

cv::Mat WallisFilter(const cv::Mat& image, const WallisOptions& options) {
  CheckInput(image, options.radius_px, "Wallis filter");
  const double c = options.contrast;
  const double b = options.brightness;
  if (!(c >= 0 && c <= 1 && b >= 0 && b <= 1 && options.target_stddev > 0)) {
    ThrowInputError(
        "Wallis filter: contrast and brightness weights must lie "
        "in [0, 1] and the target standard deviation be positive");
  }
  return ForEachChannel(image, [&](const cv::Mat& channel) {
    cv::Mat value;
    channel.convertTo(value, CV_32F);
    const cv::Mat mean = LowPass(value, options.radius_px);
    cv::Mat variance =
        LowPass(value.mul(value), options.radius_px) - mean.mul(mean);
    cv::Mat stddev;
    cv::sqrt(cv::max(variance, 0.0), stddev);
    const double st = options.target_stddev;
    cv::Mat gain = (c * st) / (c * stddev + (1.0 - c) * st);
    cv::Mat result =
        (value - mean).mul(gain) + b * options.target_mean + (1.0 - b) * mean;
    cv::Mat result8;
    result.convertTo(result8, CV_8U);
    return result8;
  });
}

}  // namespace bayon
