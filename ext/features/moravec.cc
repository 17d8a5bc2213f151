// SPDX-License-Identifier: BSD-3-Clause
#include "ext/features/moravec.h"

#include "ext/core/errors.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace bayon {

void MoravecOptions::Register(OptionRegistry* r) {
  r->Add("window_size", &window_size, "Operator window side, pixels (odd)");
  r->Add("patch_size",
         &patch_size,
         "Thinning patch side, pixels; 0 = from max_num_features");
  r->Add("min_interest",
         &min_interest,
         "Smallest interest value kept (squared grey values, 0..255)");
  r->Add("max_num_features",
         &max_num_features,
         "At most this many points per image (0 = no limit)");
  r->Add("border_px", &border_px, "No points this close to the border");
}

void MoravecOptions::Check() const {
  CheckOption(window_size >= 3 && window_size % 2 == 1,
              "window_size",
              "odd and >= 3",
              window_size);
  CheckOption(patch_size == 0 || patch_size >= 2,
              "patch_size",
              "0 (automatic) or >= 2",
              patch_size);
  CheckOption(min_interest >= 0, "min_interest", ">= 0", min_interest);
  CheckOption(
      max_num_features >= 0, "max_num_features", ">= 0", max_num_features);
  CheckOption(patch_size > 0 || max_num_features > 0,
              "patch_size",
              "> 0 when max_num_features is 0 (no limit)",
              patch_size);
  CheckOption(border_px >= 0, "border_px", ">= 0", border_px);
}

cv::Mat MoravecInterest(const cv::Mat& gray, int window_size) {
  CV_Assert(gray.type() == CV_32FC1);
  const int width = gray.cols, height = gray.rows;
  cv::Mat interest(
      height, width, CV_32F, cv::Scalar(std::numeric_limits<float>::max()));
  if (width < window_size + 1 || height < window_size + 1) {
    interest.setTo(0);
    return interest;
  }
  cv::Mat squared(height, width, CV_32F);
  const int directions[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
  for (const auto& d : directions) {
    const int dx = d[0], dy = d[1];
    squared.setTo(0);
    // The difference g(q + d) - g(q) over the rows and columns where both
    // pixels exist; the rest stays 0 and lies in the discarded border.
    const int y0 = std::max(0, -dy), y1 = height - std::max(0, dy);
    const cv::Rect from(0, y0, width - dx, y1 - y0);
    const cv::Rect to(dx, y0 + dy, width - dx, y1 - y0);
    cv::Mat target = squared(from);
    cv::subtract(gray(to), gray(from), target);
    cv::multiply(target, target, target);
    cv::boxFilter(squared,
                  squared,
                  -1,
                  cv::Size(window_size, window_size),
                  cv::Point(-1, -1),
                  /*normalize=*/true,
                  cv::BORDER_CONSTANT);
    cv::min(interest, squared, interest);
  }
  // Windows that leave the image (or read the zero fill) are not trusted.
  const int margin = window_size / 2 + 1;
  interest.rowRange(0, std::min(margin, height)).setTo(0);
  interest.rowRange(std::max(0, height - margin), height).setTo(0);
  interest.colRange(0, std::min(margin, width)).setTo(0);
  interest.colRange(std::max(0, width - margin), width).setTo(0);
  return interest;
}

namespace {

// A patch keeps its maximum only if no stronger pixel lies within `radius`
// across its edge; on plateaus (equal values) the first pixel in raster
// order wins, so two patches never keep the two sides of one corner.
bool IsLocalMaximum(const cv::Mat& interest, int x, int y, int radius) {
  const float value = interest.at<float>(y, x);
  const int y0 = std::max(0, y - radius);
  const int y1 = std::min(interest.rows - 1, y + radius);
  const int x0 = std::max(0, x - radius);
  const int x1 = std::min(interest.cols - 1, x + radius);
  for (int v = y0; v <= y1; ++v) {
    const float* row = interest.ptr<float>(v);
    for (int u = x0; u <= x1; ++u) {
      if (row[u] > value) return false;
      const bool before = v < y || (v == y && u < x);
      if (before && row[u] == value) return false;
    }
  }
  return true;
}

}  // namespace

int ThinningPatchSize(const MoravecOptions& options, int width, int height) {
  if (options.patch_size > 0) return options.patch_size;
  const double usable_w = std::max(1, width - 2 * options.border_px);
  const double usable_h = std::max(1, height - 2 * options.border_px);
  const double side = std::sqrt(usable_w * usable_h / options.max_num_features);
  return std::max(options.window_size + 1, static_cast<int>(std::ceil(side)));
}

std::vector<InterestPoint> DetectMoravecPoints(const cv::Mat& gray,
                                               const MoravecOptions& options) {
  options.Check();
  CV_Assert(gray.type() == CV_32FC1);
  const int width = gray.cols, height = gray.rows;
  const int border = std::max(options.border_px, options.window_size / 2 + 1);
  std::vector<InterestPoint> points;
  if (width <= 2 * border || height <= 2 * border) return points;

  const cv::Mat interest = MoravecInterest(gray, options.window_size);
  const int radius = options.window_size / 2;
  const int patch = ThinningPatchSize(options, width, height);
  const float threshold = static_cast<float>(options.min_interest);
  for (int py = border; py < height - border; py += patch) {
    const int py_end = std::min(py + patch, height - border);
    for (int px = border; px < width - border; px += patch) {
      const int px_end = std::min(px + patch, width - border);
      float best = -1;
      int best_x = -1, best_y = -1;
      for (int y = py; y < py_end; ++y) {
        const float* row = interest.ptr<float>(y);
        for (int x = px; x < px_end; ++x) {
          if (row[x] > best) {
            best = row[x];
            best_x = x;
            best_y = y;
          }
        }
      }
      if (best_x < 0 || best < threshold || best <= 0) continue;
      if (!IsLocalMaximum(interest, best_x, best_y, radius)) continue;
      InterestPoint point;
      point.xy = Eigen::Vector2f(best_x + 0.5f, best_y + 0.5f);
      point.interest = best;
      points.push_back(point);
    }
  }
  // Strongest first; ties by position so the order is deterministic.
  std::stable_sort(points.begin(),
                   points.end(),
                   [](const InterestPoint& a, const InterestPoint& b) {
                     return a.interest > b.interest;
                   });
  if (options.max_num_features > 0 &&
      static_cast<int>(points.size()) > options.max_num_features) {
    points.resize(options.max_num_features);
  }
  return points;
}

}  // namespace bayon
