// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <thread>

namespace bayon {

int EffectiveNumThreads(int num_threads) {
  if (num_threads > 0) return num_threads;
  const unsigned int hardware = std::thread::hardware_concurrency();
  return hardware > 0 ? static_cast<int>(hardware) : 1;
}

void ParallelFor(int n, int num_threads, const std::function<void(int)>& fn) {
  if (n <= 0) return;
  const int threads = EffectiveNumThreads(num_threads);
  if (threads == 1 || n == 1) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  tbb::task_arena arena(threads);
  arena.execute([&] {
    // Grain size 1: items are whole images or pairs of very uneven cost.
    tbb::parallel_for(
        tbb::blocked_range<int>(0, n, 1),
        [&](const tbb::blocked_range<int>& range) {
          for (int i = range.begin(); i < range.end(); ++i) fn(i);
        },
        tbb::simple_partitioner());
  });
}

void ParallelBatches(int n,
                     int num_threads,
                     const std::function<void(int)>& compute,
                     const std::function<void(int, int)>& store) {
  const int batch = 8 * EffectiveNumThreads(num_threads);
  for (int start = 0; start < n; start += batch) {
    const int end = std::min(n, start + batch);
    ParallelFor(end - start, num_threads, [&](int k) { compute(start + k); });
    store(start, end);
  }
}

}  // namespace bayon
