// progress_bar.h: a bar on stderr for long runs, "[=====     ]  40% label", redrawn only
// when the percentage (or the label) changes, so that it costs nothing per step. Off
// when stderr is not a terminal (the caller decides), so logs stay clean.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <mutex>
#include <string>

namespace glaze {

class ProgressBar {
 public:
  ProgressBar(bool enabled, int total) : enabled_(enabled && total > 0), total_(total) {}
  // One more of `total` steps done; safe to call from several threads.
  void advance(int steps = 1) {
    if (!enabled_) return;
    const int done = done_ += steps;
    std::lock_guard lock(mutex_);
    draw(done);
  }
  // What is being done now, shown after the percentage.
  void label(const std::string& text) {
    if (!enabled_) return;
    std::lock_guard lock(mutex_);
    label_ = text;
    shown_ = -1;
    draw(done_);
  }

 private:
  void draw(int done) {
    const int percent = 100 * std::min(done, total_) / total_;
    if (percent == shown_) return;
    shown_ = percent;
    const int bar = percent / 4;
    // The label is padded so that a shorter one overwrites a longer one.
    std::fprintf(stderr, "\r[%.*s%*s] %3d%%%s%-*.*s", bar, "=========================", 25 - bar, "", percent,
                 label_.empty() ? "" : " ", label_.empty() ? 0 : 40, 40, label_.c_str());
    if (done >= total_) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }

  bool enabled_;
  int total_;
  std::atomic<int> done_{0};
  std::mutex mutex_;
  int shown_ = -1;
  std::string label_;
};

}  // namespace glaze
