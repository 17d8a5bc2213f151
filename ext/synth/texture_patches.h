// SPDX-License-Identifier: BSD-3-Clause
//
// Image pairs with a known local affine and radiometric relation, for
// testing and benchmarking least-squares matching (ext/matching/lsm.h): a
// band-limited random texture s(x, y) (a sum of cosines whose wavelengths
// lie between `min_wavelength_px` and `max_wavelength_px`, so that
// resampling is nearly exact and the gradients are known analytically),
// sampled with Gaussian noise as the template image, and its transformed
// copy as the search image:
//
//   template  f(p) = s(p) + n,
//   search    g(q) = (s(p0 + M^-1 (q - q0)) - r0) / r1 + m,
//
// i.e. f(p0 + w) = r0 + r1 g(q0 + M w) without noise: the template point p0
// has its conjugate at q0, M is the patch shape (a1 a2; b1 b2) and r0, r1
// the radiometric parameters of Gruen's model. Pixel coordinates are
// COLMAP's (pixel centres at +0.5); grey values 0..255 scale, not clipped.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

namespace bayon {

struct WaveTextureOptions {
  int num_waves = 16;
  double min_wavelength_px = 5.0;
  double max_wavelength_px = 20.0;
  double mean = 120.0;
  double stddev = 25.0;  // of the noise-free texture
  uint32_t seed = 1;
};

// A random texture, evaluated anywhere with its exact gradient.
class WaveTexture {
 public:
  explicit WaveTexture(const WaveTextureOptions& options);
  double Value(const Eigen::Vector2d& p) const;
  Eigen::Vector2d Gradient(const Eigen::Vector2d& p) const;

 private:
  struct Wave {
    Eigen::Vector2d frequency;  // radians per pixel
    double phase = 0;
    double amplitude = 0;
  };
  double mean_ = 0;
  std::vector<Wave> waves_;
};

struct TexturePairTruth {
  Eigen::Vector2d template_xy = Eigen::Vector2d::Zero();  // p0
  Eigen::Vector2d search_xy = Eigen::Vector2d::Zero();    // q0
  Eigen::Matrix2d shape = Eigen::Matrix2d::Identity();    // M
  double r0 = 0;
  double r1 = 1;
};

// The noise-free template and search images (CV_32F, width x height) of a
// texture and truth; add noise with AddGaussianNoise.
cv::Mat RenderTemplateImage(const WaveTexture& texture, int width, int height);
cv::Mat RenderSearchImage(const WaveTexture& texture,
                          const TexturePairTruth& truth,
                          int width,
                          int height);
void AddGaussianNoise(double sigma, uint32_t seed, cv::Mat* image);

}  // namespace bayon
