// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/texture_patches.h"

#include <Eigen/LU>

#include <cmath>
#include <random>

namespace bayon {

WaveTexture::WaveTexture(const WaveTextureOptions& options)
    : mean_(options.mean) {
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> unit(0, 1);
  // Wavelengths uniform in log between the bounds, directions uniform;
  // equal amplitudes scaled to the requested standard deviation (a cosine
  // of amplitude A has variance A^2 / 2).
  const double amplitude =
      options.stddev * std::sqrt(2.0 / std::max(1, options.num_waves));
  for (int k = 0; k < options.num_waves; ++k) {
    const double wavelength =
        options.min_wavelength_px *
        std::pow(options.max_wavelength_px / options.min_wavelength_px,
                 unit(rng));
    const double angle = 2 * M_PI * unit(rng);
    Wave wave;
    wave.frequency = (2 * M_PI / wavelength) *
                     Eigen::Vector2d(std::cos(angle), std::sin(angle));
    wave.phase = 2 * M_PI * unit(rng);
    wave.amplitude = amplitude;
    waves_.push_back(wave);
  }
}

double WaveTexture::Value(const Eigen::Vector2d& p) const {
  double value = mean_;
  for (const Wave& wave : waves_) {
    value += wave.amplitude * std::cos(wave.frequency.dot(p) + wave.phase);
  }
  return value;
}

Eigen::Vector2d WaveTexture::Gradient(const Eigen::Vector2d& p) const {
  Eigen::Vector2d gradient = Eigen::Vector2d::Zero();
  for (const Wave& wave : waves_) {
    gradient -= wave.amplitude * std::sin(wave.frequency.dot(p) + wave.phase) *
                wave.frequency;
  }
  return gradient;
}

cv::Mat RenderTemplateImage(const WaveTexture& texture, int width, int height) {
  cv::Mat image(height, width, CV_32F);
  for (int r = 0; r < height; ++r) {
    float* row = image.ptr<float>(r);
    for (int c = 0; c < width; ++c) {
      row[c] =
          static_cast<float>(texture.Value(Eigen::Vector2d(c + 0.5, r + 0.5)));
    }
  }
  return image;
}

cv::Mat RenderSearchImage(const WaveTexture& texture,
                          const TexturePairTruth& truth,
                          int width,
                          int height) {
  const Eigen::Matrix2d inverse = truth.shape.inverse();
  cv::Mat image(height, width, CV_32F);
  for (int r = 0; r < height; ++r) {
    float* row = image.ptr<float>(r);
    for (int c = 0; c < width; ++c) {
      const Eigen::Vector2d q(c + 0.5, r + 0.5);
      const Eigen::Vector2d p =
          truth.template_xy + inverse * (q - truth.search_xy);
      row[c] = static_cast<float>((texture.Value(p) - truth.r0) / truth.r1);
    }
  }
  return image;
}

void AddGaussianNoise(double sigma, uint32_t seed, cv::Mat* image) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(sigma));
  for (int r = 0; r < image->rows; ++r) {
    float* row = image->ptr<float>(r);
    for (int c = 0; c < image->cols; ++c) row[c] += noise(rng);
  }
}

}  // namespace bayon
