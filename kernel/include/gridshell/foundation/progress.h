// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — progress reporting and cooperative cancellation for long computations.
#pragma once

#include <atomic>
#include <functional>
#include <string_view>

#include "gridshell/foundation/errors.h"

namespace gridshell {

/// Passed by const reference into every long computation. `report` forwards (stage, fraction in
/// [0,1]) to the callback and throws `Cancelled` once the cancellation flag is set; `check` only
/// checks the flag. A default-constructed Progress reports nowhere and never cancels.
/// The callback may be invoked from worker threads; it must be thread-safe.
class Progress {
 public:
  using Callback = std::function<void(std::string_view stage, double fraction)>;

  Progress() = default;
  /// `also` is a second flag that stops the computation too (e.g. "another job failed").
  explicit Progress(Callback callback, const std::atomic<bool>* cancel = nullptr,
                    const std::atomic<bool>* also = nullptr)
      : callback_(std::move(callback)), cancel_(cancel), also_(also) {}

  /// A copy that keeps the cancellation flag but reports nowhere: for work split across threads
  /// or nested inside a stage that reports its own progress.
  Progress checker() const { return Progress(nullptr, cancel_, also_); }
  /// A copy that reports nowhere and stops when this one is cancelled or `stop` is set.
  Progress checker_stopped_by(const std::atomic<bool>* stop) const {
    return Progress(nullptr, cancel_, stop);
  }

  bool cancelled() const {
    return (cancel_ && cancel_->load(std::memory_order_relaxed)) ||
           (also_ && also_->load(std::memory_order_relaxed));
  }
  /// The cancellation flag itself (may be null), for a Progress that reports elsewhere but
  /// must stop with this one.
  const std::atomic<bool>* cancel_flag() const { return cancel_; }
  void check() const {
    if (cancelled()) throw Cancelled();
  }
  void report(std::string_view stage, double fraction) const {
    check();
    if (callback_) callback_(stage, fraction);
  }

 private:
  Callback callback_;
  const std::atomic<bool>* cancel_ = nullptr;
  const std::atomic<bool>* also_ = nullptr;
};

}  // namespace gridshell
