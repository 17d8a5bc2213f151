// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/progress.h"

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace bayon {
namespace {
std::atomic<bool> g_enabled{true};
}  // namespace

void Progress::SetEnabled(bool enabled) { g_enabled = enabled; }

Progress::Progress(std::string label, size_t total, std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_),
      tty_(::isatty(STDERR_FILENO) != 0) {}

Progress::~Progress() {
  if (!finished_) Finish();
}

double Progress::ElapsedSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() -
                                       start_)
      .count();
}

void Progress::Add(size_t n) {
  done_ += n;
  if (!g_enabled) return;
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  if (tty_) {
    if (now - last_draw_ < std::chrono::milliseconds(200)) return;
    last_draw_ = now;
    Draw(false);
  } else if (total_ > 0) {
    // Logs get a line per 10 %, at most one every 5 s.
    const int decile = static_cast<int>(10 * done_ / total_);
    if (decile > last_decile_ && decile < 10 &&
        now - last_draw_ >= std::chrono::seconds(5)) {
      last_decile_ = decile;
      last_draw_ = now;
      Draw(false);
    }
  }
}

void Progress::Finish() {
  if (finished_) return;
  finished_ = true;
  if (!g_enabled) return;
  std::lock_guard<std::mutex> lock(mutex_);
  Draw(true);
}

void Progress::Draw(bool final) {
  const double seconds = ElapsedSeconds();
  const size_t done = done_;
  const double rate = seconds > 0 ? done / seconds : 0.0;
  if (tty_) {
    const int width = 30;
    const int filled =
        total_ > 0 ? static_cast<int>(
                         width * std::min<double>(1.0, double(done) / total_))
                   : 0;
    std::string bar(filled, '#');
    bar.resize(width, '.');
    std::fprintf(stderr,
                 "\r%-22s [%s] %zu/%zu %s  %.1f s  %.1f %s/s%s",
                 label_.c_str(),
                 bar.c_str(),
                 done,
                 total_,
                 unit_.c_str(),
                 seconds,
                 rate,
                 unit_.c_str(),
                 final ? "\n" : "");
  } else {
    std::fprintf(stderr,
                 "%s: %zu/%zu %s, %.1f s, %.1f %s/s%s\n",
                 label_.c_str(),
                 done,
                 total_,
                 unit_.c_str(),
                 seconds,
                 rate,
                 unit_.c_str(),
                 final ? " (done)" : "");
  }
  std::fflush(stderr);
}

}  // namespace bayon
