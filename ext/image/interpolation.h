// SPDX-License-Identifier: BSD-3-Clause
//
// Grey values and their gradients between pixel centres, for least-squares
// matching (ext/matching/lsm.h) and everything else that resamples an image
// at sub-pixel positions and needs the derivative of what it resampled.
//
// Coordinates are COLMAP pixel coordinates of the image being sampled: the
// centre of pixel (col, row) is (col + 0.5, row + 0.5), x right, y down.
// Images are one channel, CV_32F.
//
//   kBilinear  value: bilinear interpolation of the four nearest pixels;
//              gradient: central differences (g(i+1) - g(i-1)) / 2 at those
//              four pixels, interpolated bilinearly (a smooth gradient, as
//              in Gruen 1985, rather than the piecewise constant derivative
//              of the bilinear surface itself).
//   kBicubic   value: cubic convolution (Keys 1981, a = -0.5) on the 4 x 4
//              nearest pixels; gradient: the same convolution of the central
//              differences. Both reproduce quadratics exactly. (The exact
//              derivative of the cubic interpolant amplifies pixel noise,
//              and in least-squares matching that noise, shared with the
//              resampled values, biases the shifts; measured in
//              ext/matching/lsm_test.cc.)
//
// Bilinear reads the 4 x 4 pixels around the point, so a sample exists
// where x - 0.5 lies in [1, width - 2) (likewise y; InsideSampleFootprint);
// bicubic reads 6 x 6, x - 0.5 in [2, width - 3).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <string>

namespace bayon {

enum class Interpolation { kBilinear, kBicubic };

// "bilinear" / "bicubic".
const char* InterpolationName(Interpolation interpolation);

struct ImageSample {
  float value = 0;
  float dx = 0;  // d value / d x, grey values per pixel
  float dy = 0;
};

// True where SampleImage has the pixels it needs for kBilinear.
inline bool InsideSampleFootprint(const cv::Mat& image, double x, double y) {
  const double u = x - 0.5;
  const double v = y - 0.5;
  return u >= 1.0 && v >= 1.0 && u < image.cols - 2.0 && v < image.rows - 2.0;
}

// The bicubic gradient reads one more pixel on each side (6 x 6).
inline bool InsideBicubicGradientFootprint(const cv::Mat& image,
                                           double x,
                                           double y) {
  const double u = x - 0.5;
  const double v = y - 0.5;
  return u >= 2.0 && v >= 2.0 && u < image.cols - 3.0 && v < image.rows - 3.0;
}

// SampleImage's bilinear value and gradient at (x, y), where
// InsideSampleFootprint holds (not tested here: a patch's loop tests its
// corners once, the footprint's region being convex), and, where asked
// for, the noise gain there (InterpolationNoiseGain).
inline void SampleBilinearInside(const cv::Mat& image,
                                 double x,
                                 double y,
                                 ImageSample* sample,
                                 float* noise_gain = nullptr) {
  const double u = x - 0.5;
  const double v = y - 0.5;
  const int ix = static_cast<int>(u);  // u, v >= 1: truncation is floor
  const int iy = static_cast<int>(v);
  const float fx = static_cast<float>(u - ix);
  const float fy = static_cast<float>(v - iy);
  // The 4 x 4 pixels from (ix - 1, iy - 1); the 2 x 2 interpolated are
  // rows 1..2, columns 1..2.
  const float* r0 = image.ptr<float>(iy - 1) + (ix - 1);
  const float* r1 = image.ptr<float>(iy) + (ix - 1);
  const float* r2 = image.ptr<float>(iy + 1) + (ix - 1);
  const float* r3 = image.ptr<float>(iy + 2) + (ix - 1);
  const float w00 = (1 - fx) * (1 - fy);
  const float w10 = fx * (1 - fy);
  const float w01 = (1 - fx) * fy;
  const float w11 = fx * fy;
  sample->value = w00 * r1[1] + w10 * r1[2] + w01 * r2[1] + w11 * r2[2];
  sample->dx = 0.5f * (w00 * (r1[2] - r1[0]) + w10 * (r1[3] - r1[1]) +
                       w01 * (r2[2] - r2[0]) + w11 * (r2[3] - r2[1]));
  sample->dy = 0.5f * (w00 * (r2[1] - r0[1]) + w10 * (r2[2] - r0[2]) +
                       w01 * (r3[1] - r1[1]) + w11 * (r3[2] - r1[2]));
  if (noise_gain != nullptr) {
    *noise_gain =
        ((1 - fx) * (1 - fx) + fx * fx) * ((1 - fy) * (1 - fy) + fy * fy);
  }
}

// The value and gradient at (x, y). Returns false (and leaves `sample`
// unchanged) where the footprint leaves the image.
bool SampleImage(const cv::Mat& image,
                 double x,
                 double y,
                 Interpolation interpolation,
                 ImageSample* sample);

// How much of the variance of white pixel noise survives interpolation at
// (x, y): the sum of the squared interpolation weights (1 at pixel
// centres, down to 0.25 for bilinear midway between four pixels).
double InterpolationNoiseGain(Interpolation interpolation, double x, double y);

// The value alone by bilinear interpolation at (u, v) = (x - 0.5, y - 0.5)
// where its 2 x 2 footprint lies in the image (not tested here).
inline float BilinearValueInside(const cv::Mat& image, double u, double v) {
  const int ix = static_cast<int>(u);  // u, v >= 0: truncation is floor
  const int iy = static_cast<int>(v);
  const float fx = static_cast<float>(u - ix);
  const float fy = static_cast<float>(v - iy);
  const float* r0 = image.ptr<float>(iy) + ix;
  const float* r1 = image.ptr<float>(iy + 1) + ix;
  return (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) +
         fy * ((1 - fx) * r1[0] + fx * r1[1]);
}

// The value alone by bilinear interpolation (2 x 2 footprint: x - 0.5 in
// [0, width - 1), likewise y). Returns false outside.
inline bool SampleBilinear(const cv::Mat& image,
                           double x,
                           double y,
                           float* value) {
  const double u = x - 0.5;
  const double v = y - 0.5;
  if (!(u >= 0.0 && v >= 0.0 && u < image.cols - 1.0 && v < image.rows - 1.0)) {
    return false;
  }
  *value = BilinearValueInside(image, u, v);
  return true;
}

// The same for an 8-bit BGR image (CV_8UC3), each channel in 0..255.
inline bool SampleBilinear(const cv::Mat& bgr,
                           double x,
                           double y,
                           Eigen::Vector3f* color) {
  const double u = x - 0.5;
  const double v = y - 0.5;
  if (!(u >= 0.0 && v >= 0.0 && u < bgr.cols - 1.0 && v < bgr.rows - 1.0)) {
    return false;
  }
  const int ix = static_cast<int>(u);
  const int iy = static_cast<int>(v);
  const float fx = static_cast<float>(u - ix);
  const float fy = static_cast<float>(v - iy);
  const cv::Vec3b* r0 = bgr.ptr<cv::Vec3b>(iy) + ix;
  const cv::Vec3b* r1 = bgr.ptr<cv::Vec3b>(iy + 1) + ix;
  for (int c = 0; c < 3; ++c) {
    (*color)[c] = (1 - fy) * ((1 - fx) * r0[0][c] + fx * r0[1][c]) +
                  fy * ((1 - fx) * r1[0][c] + fx * r1[1][c]);
  }
  return true;
}

}  // namespace bayon
