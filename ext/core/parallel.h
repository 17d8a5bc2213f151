// SPDX-License-Identifier: BSD-3-Clause
//
// Per-item parallelism for the stages (per image, per image pair): a
// parallel loop on TBB with an explicit thread count, so that thread counts
// stay options (style.md: no hidden globals). The machine is shared; stages
// expose `num_threads` and pass it here.
#pragma once

#include <functional>

namespace bayon {

// The number of threads `num_threads` stands for: itself when positive,
// otherwise every hardware thread (-1 and 0 mean "all cores").
int EffectiveNumThreads(int num_threads);

// Calls fn(i) for i in [0, n), on up to EffectiveNumThreads(num_threads)
// threads, one index at a time (items are coarse: an image, a pair). Blocks
// until all are done. The first exception thrown by fn is rethrown here after
// the loop stops.
void ParallelFor(int n, int num_threads, const std::function<void(int)>& fn);

// Items computed in parallel and stored by one thread (a stage that writes
// each result into the database as it comes, in one transaction per batch,
// instead of holding all of them): [0, n) in batches of 8 items per thread;
// compute(i) runs on the threads (ParallelFor), then store(begin, end) on
// the calling thread, before the next batch starts.
void ParallelBatches(int n,
                     int num_threads,
                     const std::function<void(int)>& compute,
                     const std::function<void(int, int)>& store);

}  // namespace bayon
