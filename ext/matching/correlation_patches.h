// SPDX-License-Identifier: BSD-3-Clause
//
// The grey values around each keypoint that correlation matching needs,
// cut out once per image so that the pairs of an image do not read it again
// and every correlation coefficient is a dot product:
//
//   fine    the w x w correlation window (the paper's 7 x 7), reduced to
//           zero mean and unit norm, so that NCC(a, b) = a . b;
//   coarse  a wider window (13 x 13 pixels sampled every 2nd pixel of the
//           image smoothed by a Gaussian of sigma 1), normalised the same
//           way, for the global search that finds the in-plane rotation and
//           the approximate mapping between two images;
//   raw     the (v + 2 m) x (v + 2 m) grey values around the keypoint, for
//           the sub-pixel refinement of a conjugate point within +-m pixels
//           on v x v windows (wider than w: the correlation peak of a 7 x 7
//           window locates a conjugate point to about 0.15 pixel, an 11 x 11
//           one to about 0.07, measured on shifted textures).
//
// Windows are centred on the pixel that contains the keypoint (COLMAP pixel
// coordinates: pixel (col, row) covers [col, col + 1) x [row, row + 1)).
// Windows are stored row-major, upright. The in-plane rotation by a multiple
// of 90 degrees is a permutation of the window (RotateWindow), exact on the
// pixel grid: the matcher rotates one side on the fly.
#pragma once

#include "ext/core/option_registry.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace bayon {

struct PatchOptions {
  // Side of the correlation window, pixels (odd). 7: the paper's 7 x 7.
  int window_size = 7;
  // Sub-pixel refinement searches +- this many pixels around the matched
  // keypoint, on windows of this side (odd).
  int refine_radius = 2;
  int refine_window_size = 11;
  // Coarse window: (2 coarse_radius / coarse_stride + 1)^2 samples.
  int coarse_radius = 6;
  int coarse_stride = 2;
  // Windows flatter than this (standard deviation, grey values 0..255) carry
  // no signal to correlate and are marked invalid.
  double min_std = 1.0;
  void Register(OptionRegistry* registry);
  void Check() const;

  int FineDim() const { return window_size * window_size; }
  int CoarseSide() const { return 2 * (coarse_radius / coarse_stride) + 1; }
  int CoarseDim() const { return CoarseSide() * CoarseSide(); }
  int RawSide() const {
    return std::max(window_size, refine_window_size) + 2 * refine_radius;
  }
  // Distance from the border a keypoint's pixel needs for every window.
  int Margin() const {
    return std::max(RawSide() / 2,
                    (coarse_radius / coarse_stride) * coarse_stride);
  }
};

struct ImagePatches {
  int width = 0;
  int height = 0;
  PatchOptions options;
  std::vector<Eigen::Vector2d> xy;  // the keypoints, pixel coordinates
  // Per keypoint: 1 if all windows exist and are not flat.
  std::vector<uint8_t> valid;
  std::vector<float> fine;    // FineDim() per keypoint, normalised
  std::vector<float> coarse;  // CoarseDim() per keypoint, normalised
  std::vector<float> raw;     // RawSide()^2 per keypoint, grey values

  int size() const { return static_cast<int>(xy.size()); }
  const float* Fine(int idx) const {
    return fine.data() + static_cast<size_t>(idx) * options.FineDim();
  }
  const float* Coarse(int idx) const {
    return coarse.data() + static_cast<size_t>(idx) * options.CoarseDim();
  }
  const float* Raw(int idx) const {
    return raw.data() +
           static_cast<size_t>(idx) * options.RawSide() * options.RawSide();
  }
  int NumValid() const;
};

// Cuts the windows of every keypoint out of a grey image (CV_32F, 0..255).
ImagePatches ExtractImagePatches(const cv::Mat& gray,
                                 const std::vector<Eigen::Vector2d>& keypoints,
                                 const PatchOptions& options);

// The pixel that contains a point in COLMAP pixel coordinates.
inline Eigen::Vector2i PixelOf(const Eigen::Vector2d& xy) {
  return Eigen::Vector2i(static_cast<int>(std::floor(xy.x())),
                         static_cast<int>(std::floor(xy.y())));
}

// The centre of that pixel: where the windows of a keypoint are centred, and
// so the reference point of its conjugate.
inline Eigen::Vector2d PixelCentreOf(const Eigen::Vector2d& xy) {
  return PixelOf(xy).cast<double>() + Eigen::Vector2d(0.5, 0.5);
}

// In-plane rotation by quarter turns, in pixel coordinates (x right, y
// down): RotationQuarter(r) * (u, v) rotates by r * 90 degrees, i.e.
// (u, v) -> (-v, u) for r = 1.
Eigen::Matrix2d QuarterRotation(int quarter_turns);

// `out`(w) = `in`(R_r^T w) for a side x side row-major window: the window of
// the first image as it appears in a second image rotated by r quarter turns
// (where img2(p2 + R_r d) = img1(p1 + d)).
void RotateWindow(const float* in, int side, int quarter_turns, float* out);

// Zero mean and unit norm in place; returns false (and leaves zeros) where
// the standard deviation is below `min_std`.
bool NormalizeWindow(float* values, int n, double min_std);

// The fine (w x w) windows of keypoint `idx` with their centres shifted by
// (du, dv), |du|, |dv| <= shift, cut from its raw window and normalised like
// the fine one (flat ones all zero): (2 shift + 1)^2 windows of FineDim()
// values into `out`, dv outer, du inner, from (-shift, -shift).
// Requires 2 shift + window_size <= RawSide().
void ShiftedWindows(const ImagePatches& patches,
                    int idx,
                    int shift,
                    float* out);

}  // namespace bayon
