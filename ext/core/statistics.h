// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace bayon {

// The median of a sample: the element at n / 2 in sorted order (the upper
// one of the middle two for even n), by partial sorting of the copy it
// takes; 0 for an empty sample.
inline double Median(std::vector<double> values) {
  if (values.empty()) return 0;
  const auto mid = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

// The nearest-rank q-quantile (q in [0, 1]): the element at
// ceil(q n) - 1 in sorted order (the smallest for q = 0), by partial
// sorting of the copy it takes; 0 for an empty sample.
inline double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const size_t k = std::min(
      values.size() - 1,
      static_cast<size_t>(std::ceil(q * static_cast<double>(values.size()))) -
          (q > 0 ? 1 : 0));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

}  // namespace bayon
