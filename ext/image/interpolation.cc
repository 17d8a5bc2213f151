// SPDX-License-Identifier: BSD-3-Clause
#include "ext/image/interpolation.h"

#include "ext/core/errors.h"

#include <cmath>
#include <string>

namespace bayon {
namespace {

// Keys' cubic convolution kernel (a = -0.5) at the four taps t = f + 1, f,
// 1 - f, 2 - f for a fraction f in [0, 1), and its derivative d/df.
void CubicWeights(float f, float w[4], float dw[4]) {
  const float f2 = f * f;
  const float f3 = f2 * f;
  w[0] = -0.5f * f3 + f2 - 0.5f * f;
  w[1] = 1.5f * f3 - 2.5f * f2 + 1.0f;
  w[2] = -1.5f * f3 + 2.0f * f2 + 0.5f * f;
  w[3] = 0.5f * f3 - 0.5f * f2;
  dw[0] = -1.5f * f2 + 2.0f * f - 0.5f;
  dw[1] = 4.5f * f2 - 5.0f * f;
  dw[2] = -4.5f * f2 + 4.0f * f + 0.5f;
  dw[3] = 1.5f * f2 - f;
}

}  // namespace

const char* InterpolationName(Interpolation interpolation) {
  return interpolation == Interpolation::kBicubic ? "bicubic" : "bilinear";
}

double InterpolationNoiseGain(Interpolation interpolation, double x, double y) {
  const double fx = x - 0.5 - std::floor(x - 0.5);
  const double fy = y - 0.5 - std::floor(y - 0.5);
  if (interpolation == Interpolation::kBicubic) {
    float wx[4], dwx[4], wy[4], dwy[4];
    CubicWeights(static_cast<float>(fx), wx, dwx);
    CubicWeights(static_cast<float>(fy), wy, dwy);
    double sx = 0, sy = 0;
    for (int k = 0; k < 4; ++k) {
      sx += wx[k] * wx[k];
      sy += wy[k] * wy[k];
    }
    return sx * sy;
  }
  return ((1 - fx) * (1 - fx) + fx * fx) * ((1 - fy) * (1 - fy) + fy * fy);
}

bool SampleImage(const cv::Mat& image,
                 double x,
                 double y,
                 Interpolation interpolation,
                 ImageSample* sample) {
  if (!InsideSampleFootprint(image, x, y)) return false;
  if (interpolation == Interpolation::kBilinear) {
    SampleBilinearInside(image, x, y, sample);
    return true;
  }
  // Cubic convolution of the values and of their central differences
  // (which need one more pixel on each side: a 6 x 6 footprint).
  if (!InsideBicubicGradientFootprint(image, x, y)) return false;
  const double u = x - 0.5;
  const double v = y - 0.5;
  const int ix = static_cast<int>(std::floor(u));
  const int iy = static_cast<int>(std::floor(v));
  const float fx = static_cast<float>(u - ix);
  const float fy = static_cast<float>(v - iy);
  // rows[k] points at pixel (ix - 1, iy - 1 + k).
  const float* rows[4];
  for (int k = 0; k < 4; ++k) {
    rows[k] = image.ptr<float>(iy - 1 + k) + (ix - 1);
  }
  float wx[4], dwx[4], wy[4], dwy[4];
  CubicWeights(fx, wx, dwx);
  CubicWeights(fy, wy, dwy);
  float value = 0, dx = 0, dy = 0;
  for (int k = 0; k < 4; ++k) {
    const float* r = rows[k];
    const float* up = image.ptr<float>(iy - 2 + k) + (ix - 1);
    const float* down = image.ptr<float>(iy + k) + (ix - 1);
    float row_value = 0, row_dx = 0, row_dy = 0;
    for (int c = 0; c < 4; ++c) {
      row_value += wx[c] * r[c];
      row_dx += wx[c] * 0.5f * (r[c + 1] - r[c - 1]);
      row_dy += wx[c] * 0.5f * (down[c] - up[c]);
    }
    value += wy[k] * row_value;
    dx += wy[k] * row_dx;
    dy += wy[k] * row_dy;
  }
  sample->value = value;
  sample->dx = dx;
  sample->dy = dy;
  return true;
}

}  // namespace bayon
