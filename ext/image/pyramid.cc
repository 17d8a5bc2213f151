// SPDX-License-Identifier: BSD-3-Clause
#include "ext/image/pyramid.h"

#include <glog/logging.h>

#include <algorithm>

namespace bayon {

cv::Mat DownsampleByTwo(const cv::Mat& gray) {
  CHECK_EQ(gray.type(), CV_32F);
  const int width = gray.cols / 2;
  const int height = gray.rows / 2;
  // Columns first: out(r, c) = [1 3 3 1] / 8 over columns 2c - 1 .. 2c + 2,
  // clamped at the border.
  cv::Mat columns(gray.rows, width, CV_32F);
  auto clamp_col = [&](int c) { return std::clamp(c, 0, gray.cols - 1); };
  for (int r = 0; r < gray.rows; ++r) {
    const float* in = gray.ptr<float>(r);
    float* out = columns.ptr<float>(r);
    for (int c = 0; c < width; ++c) {
      out[c] = 0.125f * (in[clamp_col(2 * c - 1)] + in[clamp_col(2 * c + 2)]) +
               0.375f * (in[2 * c] + in[2 * c + 1]);
    }
  }
  cv::Mat result(height, width, CV_32F);
  auto clamp_row = [&](int r) { return std::clamp(r, 0, gray.rows - 1); };
  for (int r = 0; r < height; ++r) {
    const float* a = columns.ptr<float>(clamp_row(2 * r - 1));
    const float* b = columns.ptr<float>(2 * r);
    const float* c = columns.ptr<float>(2 * r + 1);
    const float* d = columns.ptr<float>(clamp_row(2 * r + 2));
    float* out = result.ptr<float>(r);
    for (int k = 0; k < width; ++k) {
      out[k] = 0.125f * (a[k] + d[k]) + 0.375f * (b[k] + c[k]);
    }
  }
  return result;
}

ImagePyramid BuildImagePyramid(const cv::Mat& gray,
                               int num_levels,
                               int min_size) {
  CHECK_EQ(gray.type(), CV_32F);
  CHECK_GE(num_levels, 1);
  ImagePyramid pyramid;
  pyramid.levels.push_back(gray);
  while (pyramid.num_levels() < num_levels) {
    const cv::Mat& last = pyramid.levels.back();
    if (std::min(last.cols, last.rows) / 2 < min_size) break;
    pyramid.levels.push_back(DownsampleByTwo(last));
  }
  return pyramid;
}

}  // namespace bayon
