// SPDX-License-Identifier: BSD-3-Clause
//
// Image similarity for judging renders of a reconstructed, textured model
// against renders of the truth from the same viewpoint:
//
// - PSNR = 10 log10(1 / MSE) over the masked pixels, colours in [0, 1],
//   at most 100 dB (identical images).
// - SSIM (Wang, Bovik, Sheikh, Simoncelli, "Image quality assessment: from
//   error visibility to structural similarity", IEEE TIP 13(4), 2004) on the
//   luminance, with the paper's constants: Gaussian window sigma 1.5
//   (11 x 11), K1 = 0.01, K2 = 0.03, dynamic range L = 1; the mean of the
//   SSIM map over the masked pixels.
//
// Both take BGR float images (CV_32FC3, as ext/render produces them) or
// grey ones (CV_32F), and a mask (CV_8U, non-zero = compared) of the same
// size; an empty mask compares every pixel.
#pragma once

#include <opencv2/core.hpp>

namespace bayon {

struct ImageComparison {
  size_t num_pixels = 0;  // pixels inside the mask
  double rmse = 0;        // over all channels, [0, 1] units
  double psnr_db = 0;     // 100 for identical images (the cap)
  double ssim = 0;        // 1 for identical images
};

// Throws InputError if the images differ in size or type, or the mask
// selects no pixel.
ImageComparison CompareImages(const cv::Mat& image,
                              const cv::Mat& reference,
                              const cv::Mat& mask = cv::Mat());

}  // namespace bayon
