// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <algorithm>
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

}  // namespace bayon
