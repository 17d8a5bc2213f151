// SPDX-License-Identifier: BSD-3-Clause
//
// Radiometric pre-processing that makes photographs taken under different
// light agree in colour balance and local contrast before their colours are
// combined (the Bayon paper's sec. 3.5, step 1). Each works on every
// channel of an 8-bit image separately and returns a new image; the input
// is never changed.
//
// - High pass + equalisation (the paper's choice): the channel minus its
//   Gaussian low pass of sigma `radius` (what image editors call a high-pass
//   filter of that radius), offset to mid-grey, then histogram-equalised.
//   The low pass carries the illumination (sun and shadow over tens of
//   pixels); what stays is the texture of the surface, which every
//   photograph shares.
// - Wallis (1976): every pixel's local mean and standard deviation (a
//   Gaussian window of sigma `radius`) are pulled towards a target mean and
//   standard deviation:
//     g' = (g - m) * c s_t / (c s + (1 - c) s_t) + b m_t + (1 - b) m,
//   with contrast weight c and brightness weight b in [0, 1].
#pragma once

#include <opencv2/core.hpp>

namespace bayon {

struct WallisOptions {
  double radius_px = 50;
  double target_mean = 127;
  double target_stddev = 50;
  double contrast = 0.8;    // c: 1 forces the target standard deviation
  double brightness = 0.9;  // b: 1 forces the target mean
};

// `image`: CV_8UC1 or CV_8UC3. Throws InputError for other types or a
// radius below 1. `mask` (CV_8U, non-zero = counted; empty: every pixel)
// selects the pixels whose histogram is equalised, e.g. the object's own:
// a large dark background would otherwise take most of the grey range and
// wash the object out. Every pixel is mapped.
cv::Mat HighPassEqualize(const cv::Mat& image,
                         double radius_px,
                         const cv::Mat& mask = cv::Mat());
cv::Mat WallisFilter(const cv::Mat& image, const WallisOptions& options);

}  // namespace bayon
