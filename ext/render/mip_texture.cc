// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/mip_texture.h"

#include "ext/core/errors.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace bayon {

MipTexture::MipTexture(const cv::Mat& image, int max_levels) {
  if (image.empty()) return;
  cv::Mat level;
  if (image.type() == CV_8UC3 || image.type() == CV_32FC3) {
    level = image.clone();
  } else if (image.type() == CV_8UC1) {
    cv::cvtColor(image, level, cv::COLOR_GRAY2BGR);
  } else {
    ThrowInputError("texture: expected an 8-bit gray or colour image or a ",
                    "3-channel float image (got OpenCV type ",
                    image.type(),
                    ")");
  }
  // 8-bit levels stay 8-bit: an atlas of tens of megatexels would take
  // four times the memory as floats.
  scale_ = level.depth() == CV_8U ? 1.0f / 255.0f : 1.0f;
  levels_.push_back(level);
  while (static_cast<int>(levels_.size()) < max_levels &&
         (levels_.back().cols > 1 || levels_.back().rows > 1)) {
    const cv::Mat& previous = levels_.back();
    cv::Mat next;
    cv::resize(previous,
               next,
               cv::Size(std::max(1, (previous.cols + 1) / 2),
                        std::max(1, (previous.rows + 1) / 2)),
               0,
               0,
               cv::INTER_AREA);
    levels_.push_back(next);
  }
}

namespace {

template <typename Texel>
Eigen::Vector3f Bilinear(const cv::Mat& image, float x, float y) {
  const float fx = std::floor(x), fy = std::floor(y);
  const float ax = x - fx, ay = y - fy;
  const int x0 = std::clamp(static_cast<int>(fx), 0, image.cols - 1);
  const int x1 = std::clamp(static_cast<int>(fx) + 1, 0, image.cols - 1);
  const int y0 = std::clamp(static_cast<int>(fy), 0, image.rows - 1);
  const int y1 = std::clamp(static_cast<int>(fy) + 1, 0, image.rows - 1);
  const Texel* row0 = image.ptr<Texel>(y0);
  const Texel* row1 = image.ptr<Texel>(y1);
  Eigen::Vector3f value;
  for (int c = 0; c < 3; ++c) {
    value(c) =
        (float(row0[x0][c]) * (1 - ax) + float(row0[x1][c]) * ax) * (1 - ay) +
        (float(row1[x0][c]) * (1 - ax) + float(row1[x1][c]) * ax) * ay;
  }
  return value;
}

}  // namespace

Eigen::Vector3f MipTexture::SampleLevel(const Eigen::Vector2f& uv,
                                        int level) const {
  const cv::Mat& image = levels_[level];
  const float x = uv.x() * image.cols - 0.5f;
  const float y = (1.0f - uv.y()) * image.rows - 0.5f;
  if (image.depth() == CV_8U) return scale_ * Bilinear<cv::Vec3b>(image, x, y);
  return Bilinear<cv::Vec3f>(image, x, y);
}

Eigen::Vector3f MipTexture::Sample(const Eigen::Vector2f& uv, float lod) const {
  if (!(lod > 0)) return SampleLevel(uv, 0);
  const int last = num_levels() - 1;
  if (lod >= last) return SampleLevel(uv, last);
  const int level = static_cast<int>(lod);
  const float t = lod - level;
  if (t < 1e-3f) return SampleLevel(uv, level);
  return (1 - t) * SampleLevel(uv, level) + t * SampleLevel(uv, level + 1);
}

}  // namespace bayon
