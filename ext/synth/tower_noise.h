// SPDX-License-Identifier: BSD-3-Clause
//
// Deterministic procedural noise for the synthetic tower's stone: gradient
// noise (Perlin 2002, "Improving Noise", with the quintic fade), its fractal
// sums (fBm and ridged), integer hashes for per-block random values, and the
// smooth step functions the carving is built from. Everything is a pure
// function of its arguments and the seed, so a scene is the same on every
// machine and thread count.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace bayon {

// Uniform in [0, 1) from integer coordinates and a seed.
double Hash01(int64_t a, int64_t b, uint32_t seed);
double Hash01(int64_t a, int64_t b, int64_t c, uint32_t seed);

// Gradient noise in about [-1, 1], zero at integer lattice points, smooth
// (C2) everywhere; one unit = one lattice cell.
double GradientNoise(double x, double y, uint32_t seed);

// Fractal sum of `octaves` noise layers, each at twice the frequency and
// `gain` times the amplitude of the previous one, normalised so that the
// result stays in about [-1, 1]. `x`, `y` are in cells of the first octave.
double Fbm(double x, double y, int octaves, uint32_t seed, double gain = 0.5);
// Ridged variant (1 - |noise|, squared): thin bright ridges along the zero
// lines of the noise, in [0, 1]; used for cracks and veins.
double RidgedFbm(double x, double y, int octaves, uint32_t seed);

// 0 below edge0, 1 above edge1, Hermite in between (edge0 != edge1).
inline double SmoothStep(double edge0, double edge1, double x) {
  const double t = std::clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}
// exp(-x^2 / (2 sigma^2)).
inline double Gaussian(double x, double sigma) {
  return std::exp(-0.5 * x * x / (sigma * sigma));
}

}  // namespace bayon
