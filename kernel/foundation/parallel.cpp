// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/foundation/parallel.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace gridshell {

int resolve_threads(int requested) {
  if (requested > 0) return requested;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

void parallel_for(std::size_t count, const std::function<void(std::size_t, const Progress&)>& job,
                  const Progress& progress, const ParallelOptions& options) {
  auto report = [&](std::size_t finished) {
    if (options.stage.empty()) {
      progress.check();
      return;
    }
    const double fraction = static_cast<double>(finished) / static_cast<double>(count);
    progress.report(options.stage, finished == count
                                       ? options.to
                                       : options.from + (options.to - options.from) * fraction);
  };
  if (count == 0) {
    progress.check();
    return;
  }
  const int threads =
      static_cast<int>(std::min<std::size_t>(resolve_threads(options.threads), count));
  if (threads == 1) {
    const Progress inner = progress.checker();
    for (std::size_t i = 0; i < count; ++i) {
      progress.check();
      job(i, inner);
      report(i + 1);
    }
    return;
  }

  std::atomic<std::size_t> next{0};
  std::atomic<bool> stop{false};
  std::mutex mutex;
  std::condition_variable changed;
  std::size_t finished = 0;        // guarded by mutex
  int running = 0;                 // live workers, guarded by mutex
  std::exception_ptr first_error;  // guarded by mutex

  // What a job sees: the caller's cancellation flag and "another job failed", both polled by
  // every check() of the long computations (far more often than they report). A job stopped
  // because another failed throws Cancelled, which is ignored: the failure came first.
  const Progress inner = progress.checker_stopped_by(&stop);

  const auto worker = [&] {
    try {
      for (;;) {
        if (stop.load(std::memory_order_relaxed)) break;
        const std::size_t i = next.fetch_add(1);
        if (i >= count) break;
        progress.check();
        job(i, inner);
        {
          std::lock_guard lock(mutex);
          ++finished;
        }
        changed.notify_all();
      }
    } catch (...) {
      std::lock_guard lock(mutex);
      // A job abandoned after another's failure (stop was set then) is not the first error.
      if (!first_error) first_error = std::current_exception();
      stop = true;
    }
    {
      std::lock_guard lock(mutex);
      --running;
    }
    changed.notify_all();
  };

  std::vector<std::thread> pool;
  pool.reserve(threads);
  const auto stop_and_join = [&] {
    stop = true;
    for (std::thread& thread : pool)
      if (thread.joinable()) thread.join();
  };
  try {
    for (int t = 0; t < threads; ++t) {
      {
        std::lock_guard lock(mutex);
        ++running;
      }
      try {
        pool.emplace_back(worker);
      } catch (...) {
        std::lock_guard lock(mutex);
        --running;
        throw;
      }
    }
    // Report from this thread until every worker has ended.
    std::size_t reported = 0;
    std::unique_lock lock(mutex);
    while (running > 0) {
      changed.wait_for(lock, std::chrono::milliseconds(50),
                       [&] { return running == 0 || (!first_error && finished != reported); });
      if (running == 0 || first_error) continue;  // nothing to report; wait for the workers
      const bool advanced = finished != reported;
      reported = finished;
      lock.unlock();
      if (advanced)
        report(reported);
      else
        progress.check();  // notice cancellation even while long jobs run
      lock.lock();
    }
  } catch (...) {
    stop_and_join();
    throw;
  }
  stop_and_join();
  if (first_error) std::rethrow_exception(first_error);
  report(count);
}

}  // namespace gridshell
