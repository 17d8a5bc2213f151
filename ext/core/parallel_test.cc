// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace bayon {
namespace {

TEST(Parallel, EveryIndexOnce) {
  for (int threads : {1, 2, -1}) {
    std::vector<std::atomic<int>> counts(1000);
    ParallelFor(1000, threads, [&](int i) { ++counts[i]; });
    for (const auto& count : counts) EXPECT_EQ(count.load(), 1);
  }
}

TEST(Parallel, RespectsThreadCount) {
  std::mutex mutex;
  std::set<std::thread::id> ids;
  ParallelFor(64, 1, [&](int) {
    std::lock_guard<std::mutex> lock(mutex);
    ids.insert(std::this_thread::get_id());
  });
  EXPECT_EQ(ids.size(), 1u);
  EXPECT_EQ(EffectiveNumThreads(3), 3);
  EXPECT_GE(EffectiveNumThreads(-1), 1);
}

TEST(Parallel, PropagatesExceptions) {
  EXPECT_THROW(ParallelFor(100,
                           2,
                           [](int i) {
                             if (i == 37) throw std::runtime_error("item 37");
                           }),
               std::runtime_error);
}

}  // namespace
}  // namespace bayon
