// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/image_metrics.h"

#include "ext/core/errors.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace bayon {
namespace {

// PSNR is capped at 100 dB (identical images), so that reports stay finite.
constexpr double kMinMse = 1e-10;

cv::Mat Luminance(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

cv::Mat Blur(const cv::Mat& image) {
  cv::Mat blurred;
  cv::GaussianBlur(
      image, blurred, cv::Size(11, 11), 1.5, 1.5, cv::BORDER_REFLECT);
  return blurred;
}

}  // namespace

ImageComparison CompareImages(const cv::Mat& image,
                              const cv::Mat& reference,
                              const cv::Mat& mask) {
  if (image.size() != reference.size() || image.type() != reference.type()) {
    ThrowInputError("images to compare differ in size or type (",
                    image.cols,
                    "x",
                    image.rows,
                    " vs ",
                    reference.cols,
                    "x",
                    reference.rows,
                    ")");
  }
  if (image.depth() != CV_32F ||
      (image.channels() != 1 && image.channels() != 3)) {
    ThrowInputError("images to compare must be float grey or BGR");
  }
  cv::Mat selected =
      mask.empty() ? cv::Mat(image.size(), CV_8U, cv::Scalar(255)) : mask;
  if (selected.size() != image.size() || selected.type() != CV_8U) {
    ThrowInputError("the comparison mask must be 8-bit and of image size");
  }
  ImageComparison result;
  result.num_pixels = static_cast<size_t>(cv::countNonZero(selected));
  if (result.num_pixels == 0) {
    ThrowInputError("the comparison mask selects no pixel");
  }

  cv::Mat difference;
  cv::subtract(image, reference, difference);
  cv::Mat squared = difference.mul(difference);
  const cv::Scalar sum = cv::sum(squared.setTo(0, selected == 0));
  const double mse =
      (sum[0] + sum[1] + sum[2]) / (result.num_pixels * image.channels());
  result.rmse = std::sqrt(mse);
  result.psnr_db = 10.0 * std::log10(1.0 / std::max(mse, kMinMse));

  // SSIM map on the luminance, then its mean over the mask.
  constexpr double kC1 = (0.01 * 1.0) * (0.01 * 1.0);
  constexpr double kC2 = (0.03 * 1.0) * (0.03 * 1.0);
  cv::Mat x, y;
  Luminance(image).convertTo(x, CV_64F);
  Luminance(reference).convertTo(y, CV_64F);
  const cv::Mat mu_x = Blur(x), mu_y = Blur(y);
  const cv::Mat mu_xx = mu_x.mul(mu_x), mu_yy = mu_y.mul(mu_y),
                mu_xy = mu_x.mul(mu_y);
  const cv::Mat var_x = Blur(x.mul(x)) - mu_xx;
  const cv::Mat var_y = Blur(y.mul(y)) - mu_yy;
  const cv::Mat cov_xy = Blur(x.mul(y)) - mu_xy;
  cv::Mat numerator = (2 * mu_xy + kC1).mul(2 * cov_xy + kC2);
  cv::Mat denominator = (mu_xx + mu_yy + kC1).mul(var_x + var_y + kC2);
  cv::Mat ssim_map;
  cv::divide(numerator, denominator, ssim_map);
  result.ssim = cv::mean(ssim_map, selected)[0];
  return result;
}

}  // namespace bayon
