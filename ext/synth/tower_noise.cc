// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/tower_noise.h"

#include <cmath>

namespace bayon {
namespace {

// A 64-bit mix (the finaliser of MurmurHash3 / SplitMix64): every input
// bit affects every output bit.
uint64_t Mix(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdULL;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ULL;
  x ^= x >> 33;
  return x;
}

uint64_t Hash(int64_t a, int64_t b, uint32_t seed) {
  return Mix(static_cast<uint64_t>(a) * 0x9e3779b97f4a7c15ULL ^
             Mix(static_cast<uint64_t>(b) + 0x632be59bd9b4e019ULL) ^
             (static_cast<uint64_t>(seed) << 17));
}

double Fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

// A cheap 32-bit hash of a lattice point (Wang/Jenkins-style integer
// mixing): noise evaluates it four times per call, so it must be fast; its
// period is 2^32 cells, so no pattern repeats within any scene.
uint32_t LatticeHash(int64_t ix, int64_t iy, uint32_t seed) {
  uint32_t h = static_cast<uint32_t>(ix) * 0x27d4eb2dU ^
               static_cast<uint32_t>(iy) * 0x165667b1U ^ seed * 0x9e3779b9U;
  h ^= h >> 15;
  h *= 0x85ebca6bU;
  h ^= h >> 13;
  h *= 0xc2b2ae35U;
  h ^= h >> 16;
  return h;
}

// Gradient at a lattice point: one of 16 directions on the unit circle.
double GradientDot(
    int64_t ix, int64_t iy, double dx, double dy, uint32_t seed) {
  static const double kCos[16] = {1,
                                  0.9238795,
                                  0.7071068,
                                  0.3826834,
                                  0,
                                  -0.3826834,
                                  -0.7071068,
                                  -0.9238795,
                                  -1,
                                  -0.9238795,
                                  -0.7071068,
                                  -0.3826834,
                                  0,
                                  0.3826834,
                                  0.7071068,
                                  0.9238795};
  const int index = static_cast<int>(LatticeHash(ix, iy, seed) >> 28);
  return kCos[index] * dx + kCos[(index + 12) & 15] * dy;
}

}  // namespace

double Hash01(int64_t a, int64_t b, uint32_t seed) {
  return static_cast<double>(Hash(a, b, seed) >> 11) *
         (1.0 / 9007199254740992.0);
}

double Hash01(int64_t a, int64_t b, int64_t c, uint32_t seed) {
  return static_cast<double>(
             Hash(a,
                  static_cast<int64_t>(Mix(static_cast<uint64_t>(b) * 31 + c)),
                  seed) >>
             11) *
         (1.0 / 9007199254740992.0);
}

double GradientNoise(double x, double y, uint32_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  const double dx = x - fx, dy = y - fy;
  const double n00 = GradientDot(ix, iy, dx, dy, seed);
  const double n10 = GradientDot(ix + 1, iy, dx - 1, dy, seed);
  const double n01 = GradientDot(ix, iy + 1, dx, dy - 1, seed);
  const double n11 = GradientDot(ix + 1, iy + 1, dx - 1, dy - 1, seed);
  const double u = Fade(dx), v = Fade(dy);
  // The extreme value of 2D gradient noise is sqrt(1/2); scale to ~[-1, 1].
  return 1.4142 *
         ((n00 * (1 - u) + n10 * u) * (1 - v) + (n01 * (1 - u) + n11 * u) * v);
}

double Fbm(double x, double y, int octaves, uint32_t seed, double gain) {
  double sum = 0, amplitude = 1, norm = 0;
  for (int octave = 0; octave < octaves; ++octave) {
    // Rotate each octave a little so lattice artefacts do not line up.
    sum += amplitude * GradientNoise(x, y, seed + 1013u * octave);
    norm += amplitude;
    amplitude *= gain;
    const double rx = 1.6 * x + 1.2 * y + 17.3;
    const double ry = -1.2 * x + 1.6 * y + 5.1;
    x = rx;
    y = ry;
  }
  return sum / norm;
}

double RidgedFbm(double x, double y, int octaves, uint32_t seed) {
  double sum = 0, amplitude = 1, norm = 0;
  for (int octave = 0; octave < octaves; ++octave) {
    const double ridge =
        1 - std::abs(GradientNoise(x, y, seed + 7919u * octave));
    sum += amplitude * ridge * ridge;
    norm += amplitude;
    amplitude *= 0.5;
    const double rx = 1.6 * x + 1.2 * y + 3.7;
    const double ry = -1.2 * x + 1.6 * y + 11.9;
    x = rx;
    y = ry;
  }
  return sum / norm;
}

}  // namespace bayon
