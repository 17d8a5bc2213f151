// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/image_compose.h"

#include <glog/logging.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace bayon {
namespace {

void CheckPair(const cv::Mat& left, const cv::Mat& right) {
  CHECK_EQ(left.type(), CV_8UC3);
  CHECK_EQ(right.type(), CV_8UC3);
  CHECK(left.size() == right.size()) << "stereo images differ in size";
}

}  // namespace

cv::Mat ToneMap8(const cv::Mat& color) {
  CHECK_EQ(color.type(), CV_32FC3);
  cv::Mat out;
  // convertTo rounds and saturates: the clamp to [0, 255].
  color.convertTo(out, CV_8UC3, 255.0);
  return out;
}

int WireframeLineWidth(const cv::Mat& triangle_id, int scale) {
  CHECK_EQ(triangle_id.type(), CV_32S);
  std::vector<int32_t> ids;
  ids.reserve(triangle_id.total());
  for (int y = 0; y < triangle_id.rows; ++y) {
    const int32_t* row = triangle_id.ptr<int32_t>(y);
    for (int x = 0; x < triangle_id.cols; ++x) {
      if (row[x] >= 0) ids.push_back(row[x]);
    }
  }
  if (ids.empty()) return scale;
  const double area_px = double(ids.size()) / (double(scale) * scale);
  std::sort(ids.begin(), ids.end());
  const double num_faces =
      double(std::unique(ids.begin(), ids.end()) - ids.begin());
  const double edge_px = std::sqrt(4 * (area_px / num_faces) / std::sqrt(3.0));
  return std::clamp(int(std::lround(scale * edge_px / 6)), 1, scale);
}

cv::Mat WireframeCoverage(const cv::Mat& triangle_id,
                          int scale,
                          int line_width) {
  CHECK_EQ(triangle_id.type(), CV_32S);
  CHECK_GE(scale, 1);
  CHECK(line_width >= 1 && line_width <= scale);
  CHECK(triangle_id.cols % scale == 0 && triangle_id.rows % scale == 0)
      << "the id buffer must be a whole multiple of the output size";
  cv::Mat lines = cv::Mat::zeros(triangle_id.size(), CV_8U);
  for (int y = 0; y < triangle_id.rows; ++y) {
    const int32_t* row = triangle_id.ptr<int32_t>(y);
    const int32_t* below =
        y + 1 < triangle_id.rows ? triangle_id.ptr<int32_t>(y + 1) : nullptr;
    uint8_t* out = lines.ptr<uint8_t>(y);
    for (int x = 0; x < triangle_id.cols; ++x) {
      const bool edge = (x + 1 < triangle_id.cols && row[x + 1] != row[x]) ||
                        (below != nullptr && below[x] != row[x]);
      if (edge) out[x] = 255;
    }
  }
  if (line_width > 1) {
    // The marked pixel lies beside the edge: the widened line is centred
    // on it, half a fine pixel off the edge.
    const cv::Mat kernel = cv::Mat::ones(line_width, line_width, CV_8U);
    cv::dilate(lines, lines, kernel, cv::Point(line_width / 2, line_width / 2));
  }
  cv::Mat coverage;
  lines.convertTo(coverage, CV_32F, 1.0 / 255.0);
  if (scale > 1) {
    cv::resize(coverage,
               coverage,
               cv::Size(triangle_id.cols / scale, triangle_id.rows / scale),
               0,
               0,
               cv::INTER_AREA);
  }
  return coverage;
}

cv::Mat PaintLines(const cv::Mat& coverage,
                   const cv::Mat& background,
                   const Eigen::Vector3f& line_bgr) {
  CHECK_EQ(coverage.type(), CV_32F);
  cv::Mat out = background.empty()
                    ? cv::Mat(coverage.size(), CV_32FC3, cv::Scalar::all(1))
                    : background.clone();
  CHECK_EQ(out.type(), CV_32FC3);
  CHECK(out.size() == coverage.size());
  const cv::Vec3f line(line_bgr.x(), line_bgr.y(), line_bgr.z());
  for (int y = 0; y < out.rows; ++y) {
    const float* a = coverage.ptr<float>(y);
    cv::Vec3f* row = out.ptr<cv::Vec3f>(y);
    for (int x = 0; x < out.cols; ++x) {
      row[x] = (1.0f - a[x]) * row[x] + a[x] * line;
    }
  }
  return out;
}

cv::Mat Anaglyph(const cv::Mat& left, const cv::Mat& right, AnaglyphType type) {
  CheckPair(left, right);
  cv::Mat left_channels[3], right_channels[3];
  if (type == AnaglyphType::kGray) {
    cv::Mat left_gray, right_gray;
    cv::cvtColor(left, left_gray, cv::COLOR_BGR2GRAY);
    cv::cvtColor(right, right_gray, cv::COLOR_BGR2GRAY);
    for (int c = 0; c < 3; ++c) {
      left_channels[c] = left_gray;
      right_channels[c] = right_gray;
    }
  } else {
    cv::split(left, left_channels);
    cv::split(right, right_channels);
  }
  // BGR: blue and green from the right eye, red from the left.
  const cv::Mat channels[3] = {
      right_channels[0], right_channels[1], left_channels[2]};
  cv::Mat out;
  cv::merge(channels, 3, out);
  return out;
}

cv::Mat SideBySide(const cv::Mat& left, const cv::Mat& right) {
  CheckPair(left, right);
  cv::Mat out;
  cv::hconcat(left, right, out);
  return out;
}

cv::Mat RowInterleaved(const cv::Mat& left, const cv::Mat& right) {
  CheckPair(left, right);
  cv::Mat out = left.clone();
  for (int y = 1; y < out.rows; y += 2) right.row(y).copyTo(out.row(y));
  return out;
}

}  // namespace bayon
