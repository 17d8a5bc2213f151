// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/correlation_patches.h"

#include "ext/core/errors.h"

#include <glog/logging.h>
#include <opencv2/imgproc.hpp>

#include <cmath>

namespace bayon {

void PatchOptions::Register(OptionRegistry* r) {
  r->Add("window_size", &window_size, "Correlation window side, pixels (odd)");
  r->Add("refine_radius",
         &refine_radius,
         "Sub-pixel search range around a matched keypoint, pixels");
}

void PatchOptions::Check() const {
  CheckOption(window_size >= 3 && window_size % 2 == 1,
              "window_size",
              "odd and >= 3",
              window_size);
  CheckOption(refine_radius >= 1 && refine_radius <= 8,
              "refine_radius",
              "in [1, 8]",
              refine_radius);
  CheckOption(refine_window_size >= 3 && refine_window_size % 2 == 1,
              "refine_window_size",
              "odd and >= 3",
              refine_window_size);
  CheckOption(coarse_stride >= 1, "coarse_stride", ">= 1", coarse_stride);
  CheckOption(coarse_radius >= coarse_stride,
              "coarse_radius",
              ">= coarse_stride",
              coarse_radius);
  CheckOption(min_std >= 0, "min_std", ">= 0", min_std);
}

int ImagePatches::NumValid() const {
  int n = 0;
  for (uint8_t v : valid) n += v;
  return n;
}

Eigen::Matrix2d QuarterRotation(int quarter_turns) {
  const int r = ((quarter_turns % 4) + 4) % 4;
  static const int kCos[4] = {1, 0, -1, 0};
  static const int kSin[4] = {0, 1, 0, -1};
  Eigen::Matrix2d rotation;
  rotation << kCos[r], -kSin[r], kSin[r], kCos[r];
  return rotation;
}

void RotateWindow(const float* in, int side, int quarter_turns, float* out) {
  const int r = ((quarter_turns % 4) + 4) % 4;
  const int half = side / 2;
  for (int v = -half; v <= half; ++v) {
    for (int u = -half; u <= half; ++u) {
      // (su, sv) = R_r^T (u, v).
      int su = u, sv = v;
      switch (r) {
        case 1:
          su = v;
          sv = -u;
          break;
        case 2:
          su = -u;
          sv = -v;
          break;
        case 3:
          su = -v;
          sv = u;
          break;
        default:
          break;
      }
      out[(v + half) * side + (u + half)] =
          in[(sv + half) * side + (su + half)];
    }
  }
}

bool NormalizeWindow(float* values, int n, double min_std) {
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    sum += values[i];
    sum2 += static_cast<double>(values[i]) * values[i];
  }
  const double mean = sum / n;
  const double variance = std::max(0.0, sum2 / n - mean * mean);
  if (std::sqrt(variance) < std::max(min_std, 1e-6)) {
    std::fill(values, values + n, 0.f);
    return false;
  }
  const double scale = 1.0 / std::sqrt(variance * n);
  for (int i = 0; i < n; ++i) {
    values[i] = static_cast<float>((values[i] - mean) * scale);
  }
  return true;
}

void ShiftedWindows(const ImagePatches& patches,
                    int idx,
                    int shift,
                    float* out) {
  const PatchOptions& options = patches.options;
  const int w = options.window_size, half = w / 2, dim = w * w;
  const int raw_side = options.RawSide(), center = raw_side / 2;
  CHECK_LE(2 * shift + w, raw_side) << "shift " << shift << " too large";
  const float* raw = patches.Raw(idx);
  for (int dv = -shift; dv <= shift; ++dv) {
    for (int du = -shift; du <= shift; ++du) {
      for (int v = -half; v <= half; ++v) {
        const float* row = raw + (center + dv + v) * raw_side + center + du;
        for (int u = -half; u <= half; ++u) {
          out[(v + half) * w + (u + half)] = row[u];
        }
      }
      NormalizeWindow(out, dim, options.min_std);
      out += dim;
    }
  }
}

ImagePatches ExtractImagePatches(const cv::Mat& gray,
                                 const std::vector<Eigen::Vector2d>& keypoints,
                                 const PatchOptions& options) {
  options.Check();
  CV_Assert(gray.type() == CV_32FC1);
  ImagePatches patches;
  patches.width = gray.cols;
  patches.height = gray.rows;
  patches.options = options;
  patches.xy = keypoints;
  const int n = static_cast<int>(keypoints.size());
  const int fine_dim = options.FineDim();
  const int coarse_dim = options.CoarseDim();
  const int raw_side = options.RawSide();
  patches.valid.assign(n, 0);
  patches.fine.assign(static_cast<size_t>(n) * fine_dim, 0.f);
  patches.coarse.assign(static_cast<size_t>(n) * coarse_dim, 0.f);
  patches.raw.assign(static_cast<size_t>(n) * raw_side * raw_side, 0.f);

  cv::Mat smooth;
  cv::GaussianBlur(gray, smooth, cv::Size(0, 0), 1.0);
  const int margin = options.Margin();
  const int half = options.window_size / 2;
  const int raw_half = raw_side / 2;
  const int coarse_steps = options.coarse_radius / options.coarse_stride;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2i p = PixelOf(keypoints[i]);
    if (p.x() < margin || p.y() < margin || p.x() >= gray.cols - margin ||
        p.y() >= gray.rows - margin) {
      continue;
    }
    float* raw =
        patches.raw.data() + static_cast<size_t>(i) * raw_side * raw_side;
    for (int v = -raw_half; v <= raw_half; ++v) {
      const float* row = gray.ptr<float>(p.y() + v);
      for (int u = -raw_half; u <= raw_half; ++u) {
        raw[(v + raw_half) * raw_side + (u + raw_half)] = row[p.x() + u];
      }
    }
    float* fine = patches.fine.data() + static_cast<size_t>(i) * fine_dim;
    for (int v = -half; v <= half; ++v) {
      for (int u = -half; u <= half; ++u) {
        fine[(v + half) * options.window_size + (u + half)] =
            raw[(v + raw_half) * raw_side + (u + raw_half)];
      }
    }
    float* coarse = patches.coarse.data() + static_cast<size_t>(i) * coarse_dim;
    const int coarse_side = options.CoarseSide();
    for (int v = -coarse_steps; v <= coarse_steps; ++v) {
      const float* row = smooth.ptr<float>(p.y() + v * options.coarse_stride);
      for (int u = -coarse_steps; u <= coarse_steps; ++u) {
        coarse[(v + coarse_steps) * coarse_side + (u + coarse_steps)] =
            row[p.x() + u * options.coarse_stride];
      }
    }
    const bool fine_ok = NormalizeWindow(fine, fine_dim, options.min_std);
    const bool coarse_ok = NormalizeWindow(coarse, coarse_dim, options.min_std);
    patches.valid[i] = fine_ok && coarse_ok;
  }
  return patches;
}

}  // namespace bayon
