// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>

namespace bayon {

// A vector of N draws from one distribution, in a fixed order.
//
// Eigen::Vector2d(noise(rng), noise(rng)) leaves the order of the two draws
// to the compiler (GCC draws the last argument first, Clang the first), so
// one seed made different scenes and test data under each. This draws the
// last component first, as the GCC builds did, so that the scenes behind
// the figures recorded so far stay the same.
template <int N, typename Distribution, typename Engine>
Eigen::Matrix<double, N, 1> RandomVector(Distribution& distribution,
                                         Engine& engine) {
  Eigen::Matrix<double, N, 1> vector;
  for (int i = N - 1; i >= 0; --i) vector[i] = distribution(engine);
  return vector;
}

}  // namespace bayon
