// SPDX-License-Identifier: BSD-3-Clause
#include "ext/image/radiometry.h"

#include "ext/core/errors.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdint>
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

// Gaussian low pass of sigma `radius_px` (CV_32F). OpenCV reflects at the
// border, which keeps the mean level there. A wide kernel is computed on
// the image shrunk by radius / 8 (area averaging) and enlarged back
// bilinearly: what a sigma of 50 px keeps varies over tens of pixels, so the
// shortcut changes nothing visible, and a 6-megapixel photograph takes a
// fraction of a second instead of ten.
cv::Mat LowPass(const cv::Mat& channel, double radius_px) {
  const int factor = std::max(1, static_cast<int>(radius_px / 8.0));
  cv::Mat low;
  if (factor == 1) {
    cv::GaussianBlur(channel,
                     low,
                     cv::Size(0, 0),
                     radius_px,
                     radius_px,
                     cv::BORDER_REFLECT101);
    return low;
  }
  cv::Mat small;
  cv::resize(channel,
             small,
             cv::Size(std::max(1, channel.cols / factor),
                      std::max(1, channel.rows / factor)),
             0,
             0,
             cv::INTER_AREA);
  const double sigma_x = radius_px * small.cols / channel.cols;
  const double sigma_y = radius_px * small.rows / channel.rows;
  cv::GaussianBlur(
      small, small, cv::Size(0, 0), sigma_x, sigma_y, cv::BORDER_REFLECT101);
  cv::resize(small, low, channel.size(), 0, 0, cv::INTER_LINEAR);
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

cv::Mat HighPassEqualize(const cv::Mat& image,
                         double radius_px,
                         const cv::Mat& mask) {
  CheckInput(image, radius_px, "high-pass filter");
  if (!mask.empty() &&
      (mask.type() != CV_8UC1 || mask.size() != image.size())) {
    ThrowInputError(
        "high-pass filter: the mask must be 8-bit, one channel, "
        "of the image's size");
  }
  return ForEachChannel(image, [&](const cv::Mat& channel) {
    cv::Mat value;
    channel.convertTo(value, CV_32F);
    cv::Mat high = value - LowPass(value, radius_px) + 128.0;
    cv::Mat high8;
    high.convertTo(high8, CV_8U);  // saturating
    // Equalisation: each value to its rank in the (masked) histogram,
    // the lowest occupied value to 0 and the highest to 255.
    int histogram[256] = {0};
    for (int y = 0; y < high8.rows; ++y) {
      const uint8_t* v = high8.ptr<uint8_t>(y);
      const uint8_t* m = mask.empty() ? nullptr : mask.ptr<uint8_t>(y);
      for (int x = 0; x < high8.cols; ++x) {
        if (!m || m[x]) ++histogram[v[x]];
      }
    }
    int64_t total = 0, lowest = 0;
    for (int count : histogram) {
      if (total == 0) lowest = count;
      total += count;
    }
    cv::Mat lut(1, 256, CV_8U);
    int64_t below = 0;
    for (int i = 0; i < 256; ++i) {
      below += histogram[i];
      lut.at<uint8_t>(i) =
          total > lowest ? cv::saturate_cast<uint8_t>(255.0 * (below - lowest) /
                                                      double(total - lowest))
                         : static_cast<uint8_t>(i);
    }
    cv::Mat equalized;
    cv::LUT(high8, lut, equalized);
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
    // A flat window with c = 1 would divide by zero: no gain beyond 1e6.
    cv::Mat gain =
        (c * st) / cv::max(c * stddev + (1.0 - c) * st, c * st * 1e-6);
    cv::Mat result =
        (value - mean).mul(gain) + b * options.target_mean + (1.0 - b) * mean;
    cv::Mat result8;
    result.convertTo(result8, CV_8U);
    return result8;
  });
}

}  // namespace bayon
