// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>

namespace bayon {

// Progress of long work: a bar redrawn in place on a terminal, and plain
// lines (every 10 %) when stderr is a file or pipe, so logs stay readable.
// Thread-safe: workers call Add() concurrently.
class Progress {
 public:
  // `unit` names what is counted ("images", "points") for the rate display.
  Progress(std::string label, size_t total, std::string unit = "items");
  ~Progress();

  void Add(size_t n = 1);
  // Ends the display with a final line: total, time and rate.
  void Finish();

  size_t done() const { return done_; }
  double ElapsedSeconds() const;

  // Globally silences progress output (tests, --quiet).
  static void SetEnabled(bool enabled);

 private:
  void Draw(bool final);

  std::string label_;
  std::string unit_;
  size_t total_;
  std::atomic<size_t> done_{0};
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  int last_decile_ = -1;
  bool finished_ = false;
  bool tty_ = false;
  std::mutex mutex_;
};

// Wall-clock timer for summaries.
class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  double Seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() -
                                         start_)
        .count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace bayon
