// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell::parallel_for (gridshell/foundation/parallel.h): every job runs exactly once, results
// do not depend on the thread count, the first exception wins and stops the other jobs, the
// caller's cancellation flag stops the run, and progress comes from the calling thread only.
//
// Nothing here asserts on wall-clock durations: jobs that wait for something wait with a generous
// deadline (kDeadline), and the tests assert that the deadline was NOT what ended them (a flag set
// by the job), and on counts of jobs run.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"
#include "gridshell/foundation/progress.h"

namespace gridshell {
namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kDeadline = std::chrono::seconds(10);

ParallelOptions with_threads(int threads) {
  ParallelOptions options;
  options.threads = threads;
  return options;
}

/// Waits (yielding) until `ready()` holds or the deadline passes; returns whether it held.
template <class Ready>
bool wait_until(Ready ready, std::chrono::milliseconds limit = kDeadline) {
  const auto end = Clock::now() + limit;
  while (!ready()) {
    if (Clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return true;
}

/// A job body that runs until `inner` throws (abandonment or cancellation) or the deadline
/// passes. Returns true if it was stopped by `inner`, false if the deadline ended it.
template <class Poll>
bool run_until_stopped(Poll poll) {
  const auto end = Clock::now() + kDeadline;
  while (Clock::now() < end) {
    try {
      poll();
    } catch (...) {
      return true;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// Every job once, deterministic results

TEST(ParallelFor, EveryIndexRunsExactlyOnce) {
  for (int threads : {1, 2, 7})
    for (std::size_t count : {std::size_t{0}, std::size_t{1}, std::size_t{1000}}) {
      SCOPED_TRACE("threads " + std::to_string(threads) + ", count " + std::to_string(count));
      std::vector<std::atomic<int>> runs(count);
      std::atomic<int> calls{0};
      parallel_for(
          count,
          [&](std::size_t i, const Progress&) {
            ASSERT_LT(i, count);
            runs[i].fetch_add(1);
            calls.fetch_add(1);
          },
          {}, with_threads(threads));
      EXPECT_EQ(calls.load(), static_cast<int>(count));
      for (std::size_t i = 0; i < count; ++i) ASSERT_EQ(runs[i].load(), 1) << "index " << i;
    }
}

TEST(ParallelFor, ResultsDoNotDependOnTheThreadCount) {
  const std::size_t count = 1000;
  auto run = [&](int threads) {
    std::vector<double> out(count, -1.0);
    parallel_for(
        count,
        [&](std::size_t i, const Progress&) {
          double x = static_cast<double>(i) * 0.37;
          for (int k = 0; k < 200; ++k) x = std::sin(x) + 0.001 * k;
          out[i] = x;
        },
        {}, with_threads(threads));
    return out;
  };
  const std::vector<double> one = run(1);
  for (int threads : {2, 7}) {
    const std::vector<double> many = run(threads);
    for (std::size_t i = 0; i < count; ++i) ASSERT_EQ(many[i], one[i]) << "index " << i;
  }
}

// With 7 threads and 7 jobs the jobs really run concurrently: each waits until all 7 have
// started. Sequential execution would leave every job waiting for the others.
TEST(ParallelFor, JobsRunConcurrentlyOnWorkerThreads) {
  std::atomic<int> started{0};
  std::mutex mutex;
  std::set<std::thread::id> ids;
  std::atomic<int> timed_out{0};
  parallel_for(
      7,
      [&](std::size_t, const Progress&) {
        {
          std::lock_guard lock(mutex);
          ids.insert(std::this_thread::get_id());
        }
        started.fetch_add(1);
        if (!wait_until([&] { return started.load() == 7; })) timed_out.fetch_add(1);
      },
      {}, with_threads(7));
  EXPECT_EQ(timed_out.load(), 0);
  EXPECT_EQ(ids.size(), 7u);
  EXPECT_EQ(ids.count(std::this_thread::get_id()), 0u) << "a job ran on the calling thread";
}

TEST(ParallelFor, NeverMoreThreadsThanJobs) {
  std::mutex mutex;
  std::set<std::thread::id> ids;
  parallel_for(
      3,
      [&](std::size_t, const Progress&) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
        std::lock_guard lock(mutex);
        ids.insert(std::this_thread::get_id());
      },
      {}, with_threads(7));
  EXPECT_LE(ids.size(), 3u);
  EXPECT_GE(ids.size(), 1u);
}

TEST(ParallelFor, OneThreadRunsInOrderOnTheCallingThread) {
  std::vector<std::size_t> order;
  parallel_for(
      50, [&](std::size_t i, const Progress&) { order.push_back(i); }, {}, with_threads(1));
  ASSERT_EQ(order.size(), 50u);
  for (std::size_t i = 0; i < order.size(); ++i) EXPECT_EQ(order[i], i);
  const auto caller = std::this_thread::get_id();
  bool on_caller = true;
  parallel_for(
      5, [&](std::size_t, const Progress&) { on_caller &= std::this_thread::get_id() == caller; },
      {}, with_threads(1));
  EXPECT_TRUE(on_caller);
}

TEST(ParallelFor, ResolveThreads) {
  EXPECT_GE(resolve_threads(0), 1);
  const unsigned hardware = std::thread::hardware_concurrency();
  if (hardware > 0) {
    EXPECT_EQ(resolve_threads(0), static_cast<int>(hardware));
  }
  EXPECT_EQ(resolve_threads(1), 1);
  EXPECT_EQ(resolve_threads(3), 3);
  EXPECT_EQ(resolve_threads(64), 64);
}

// ---------------------------------------------------------------------------------------------
// Exceptions

TEST(ParallelFor, OneThreadRethrowsAndRunsNothingAfterTheFailingJob) {
  std::vector<std::size_t> ran;
  try {
    parallel_for(
        100,
        [&](std::size_t i, const Progress&) {
          ran.push_back(i);
          if (i == 3) throw std::runtime_error("job 3 failed");
        },
        {}, with_threads(1));
    FAIL() << "nothing thrown";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "job 3 failed");
  }
  EXPECT_EQ(ran, (std::vector<std::size_t>{0, 1, 2, 3}));
}

// Two threads, two jobs that fail: the second fails only after it has seen (through `inner`)
// that the first one has. The first one's exception is rethrown, with its type, and no third
// job starts.
TEST(ParallelFor, FirstExceptionWinsAndNoJobStartsAfterIt) {
  std::atomic<int> started{0};
  std::atomic<bool> first_running{false}, second_running{false};
  std::atomic<bool> second_saw_stop{false};
  std::atomic<int> timed_out{0};
  try {
    parallel_for(
        1000,
        [&](std::size_t, const Progress& inner) {
          const int k = started.fetch_add(1);
          if (k == 0) {
            first_running = true;
            if (!wait_until([&] { return second_running.load(); })) timed_out.fetch_add(1);
            throw std::invalid_argument("first");
          }
          if (k == 1) {
            second_running = true;
            const bool stopped = run_until_stopped([&] { inner.report("inner", 0.5); });
            second_saw_stop = stopped;
            if (!stopped) timed_out.fetch_add(1);
            throw std::logic_error("second");
          }
          ADD_FAILURE() << "job " << k << " started after the first exception";
        },
        {}, with_threads(2));
    FAIL() << "nothing thrown";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "first");
  } catch (const std::exception& e) {
    FAIL() << "the wrong exception was rethrown: " << e.what();
  }
  EXPECT_EQ(timed_out.load(), 0);
  EXPECT_TRUE(second_saw_stop.load());
  EXPECT_EQ(started.load(), 2);
}

// Seven workers all inside a job when one fails: the six others see the failure at their next
// inner.report() (they swallow it and return normally, so their workers go on looking for
// jobs), and none of the 993 remaining jobs starts. The error is an Error subclass and keeps its
// field.
TEST(ParallelFor, RunningJobsAreAbandonedThroughInnerReport) {
  const int threads = 7;
  std::atomic<int> started{0}, abandoned{0}, timed_out{0};
  const auto begin = Clock::now();
  try {
    parallel_for(
        1000,
        [&](std::size_t, const Progress& inner) {
          const int k = started.fetch_add(1);
          if (k >= threads) {
            ADD_FAILURE() << "job " << k << " started after the first exception";
            return;
          }
          if (!wait_until([&] { return started.load() >= threads; })) timed_out.fetch_add(1);
          if (k == 0) throw InvalidInput("options.x", "job failed");
          if (run_until_stopped([&] { inner.report("inner", 0.5); }))
            abandoned.fetch_add(1);
          else
            timed_out.fetch_add(1);
        },
        {}, with_threads(threads));
    FAIL() << "nothing thrown";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), "options.x");
    EXPECT_EQ(e.message(), "job failed");
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - begin).count();
  std::printf("  abandoned %d jobs through inner.report(); parallel_for returned after %.3f s\n",
              abandoned.load(), seconds);
  EXPECT_EQ(timed_out.load(), 0);
  EXPECT_EQ(abandoned.load(), threads - 1);
  EXPECT_EQ(started.load(), threads);
}

// After the first exception, running jobs stop at their next inner.check(), not only at their
// next report: long kernel computations poll check() far more often than they report (the fast
// geodesic engine: check() every 4096 events, report() every 262144). Before the fix these three
// jobs ran until the 10 s deadline.
TEST(ParallelFor, RunningJobsAreAbandonedThroughInnerCheck) {
  const int threads = 4;
  std::atomic<int> started{0}, abandoned{0}, timed_out{0};
  const auto begin = Clock::now();
  EXPECT_THROW(parallel_for(
                   threads,
                   [&](std::size_t, const Progress& inner) {
                     const int k = started.fetch_add(1);
                     wait_until([&] { return started.load() >= threads; });
                     if (k == 0) throw std::runtime_error("job failed");
                     if (run_until_stopped([&] { inner.check(); }))
                       abandoned.fetch_add(1);
                     else
                       timed_out.fetch_add(1);
                   },
                   {}, with_threads(threads)),
               std::runtime_error);
  const double seconds = std::chrono::duration<double>(Clock::now() - begin).count();
  std::printf("  inner.check(): %d abandoned, %d ran to the deadline; %.3f s\n", abandoned.load(),
              timed_out.load(), seconds);
  EXPECT_EQ(timed_out.load(), 0);
  EXPECT_EQ(abandoned.load(), threads - 1);
}

// ---------------------------------------------------------------------------------------------
// Cancellation through the caller's flag

TEST(ParallelFor, PreCancelledRunsNothing) {
  std::atomic<bool> cancel{true};
  const Progress progress(nullptr, &cancel);
  for (int threads : {1, 2})
    for (std::size_t count : {std::size_t{0}, std::size_t{5}}) {
      std::atomic<int> ran{0};
      EXPECT_THROW(parallel_for(
                       count, [&](std::size_t, const Progress&) { ran.fetch_add(1); }, progress,
                       with_threads(threads)),
                   Cancelled);
      EXPECT_EQ(ran.load(), 0);
    }
}

// A job sets the caller's flag when it is the 20th to start. The flag is set and read under the
// same mutex as the start count, so a job "started after the cancel" is one whose worker had
// already passed its cancellation check: at most one per other worker.
TEST(ParallelFor, CancelFlagStopsFurtherJobs) {
  for (int threads : {1, 2, 7}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    std::atomic<bool> cancel{false};
    const Progress progress(nullptr, &cancel);
    std::mutex mutex;
    int started = 0, after_cancel = 0;
    EXPECT_THROW(parallel_for(
                     1000,
                     [&](std::size_t, const Progress&) {
                       {
                         std::lock_guard lock(mutex);
                         if (cancel.load()) ++after_cancel;
                         if (++started == 20) cancel = true;
                       }
                       std::this_thread::sleep_for(std::chrono::microseconds(300));
                     },
                     progress, with_threads(threads)),
                 Cancelled);
    EXPECT_LE(after_cancel, threads - 1);
    EXPECT_LE(started, 20 + threads - 1);
    EXPECT_GE(started, 20);
  }
}

// Long jobs polling inner.check() stop when the caller cancels from another thread while they
// run; no further job starts.
TEST(ParallelFor, CancelStopsLongRunningJobs) {
  for (int threads : {1, 3}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    std::atomic<bool> cancel{false};
    const Progress progress(nullptr, &cancel);
    std::atomic<int> started{0}, stopped{0}, timed_out{0};
    std::thread canceller([&] {
      wait_until([&] { return started.load() >= threads; });
      cancel = true;
    });
    EXPECT_THROW(parallel_for(
                     100,
                     [&](std::size_t, const Progress& inner) {
                       started.fetch_add(1);
                       if (run_until_stopped([&] { inner.check(); }))
                         stopped.fetch_add(1);
                       else
                         timed_out.fetch_add(1);
                     },
                     progress, with_threads(threads)),
                 Cancelled);
    canceller.join();
    EXPECT_EQ(timed_out.load(), 0);
    EXPECT_EQ(stopped.load(), threads);
    EXPECT_EQ(started.load(), threads);
  }
}

// Jobs that never look at `inner`: once the flag is set no further job starts (the running ones
// finish).
TEST(ParallelFor, CancelStopsJobsThatIgnoreInner) {
  std::atomic<bool> cancel{false};
  const Progress progress(nullptr, &cancel);
  std::atomic<int> started{0};
  std::thread canceller([&] {
    wait_until([&] { return started.load() >= 4; });
    cancel = true;
  });
  EXPECT_THROW(parallel_for(
                   10000,
                   [&](std::size_t, const Progress&) {
                     started.fetch_add(1);
                     std::this_thread::sleep_for(std::chrono::milliseconds(2));
                   },
                   progress, with_threads(2)),
               Cancelled);
  canceller.join();
  EXPECT_LT(started.load(), 1000) << "far fewer than all jobs should have run";
}

// ---------------------------------------------------------------------------------------------
// Progress

struct Report {
  std::thread::id thread;
  std::string stage;
  double fraction;
};

/// Runs 200 short jobs with progress stage "jobs" over [from, to] and returns the reports.
std::vector<Report> progress_reports(int threads, double from, double to) {
  std::mutex mutex;
  std::vector<Report> reports;
  const Progress progress([&](std::string_view stage, double fraction) {
    std::lock_guard lock(mutex);
    reports.push_back({std::this_thread::get_id(), std::string(stage), fraction});
  });
  ParallelOptions options = with_threads(threads);
  options.stage = "jobs";
  options.from = from;
  options.to = to;
  parallel_for(
      200,
      [&](std::size_t, const Progress& inner) {
        inner.report("inner stage", 0.5);  // reports nowhere
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      },
      progress, options);
  return reports;
}

// Ranges whose end fraction from + (to - from) x 1 is exact in floating point.
TEST(ParallelFor, ProgressFromTheCallingThreadMonotoneUpToTo) {
  const auto caller = std::this_thread::get_id();
  for (int threads : {1, 2, 7})
    for (const auto& [from, to] :
         {std::pair{0.0, 1.0}, std::pair{0.25, 0.75}, std::pair{0.5, 1.0}, std::pair{0.1, 1.0}}) {
      SCOPED_TRACE("threads " + std::to_string(threads) + ", [" + std::to_string(from) + ", " +
                   std::to_string(to) + "]");
      const std::vector<Report> reports = progress_reports(threads, from, to);
      ASSERT_FALSE(reports.empty());
      EXPECT_LE(reports.size(), 201u);
      for (std::size_t k = 0; k < reports.size(); ++k) {
        EXPECT_EQ(reports[k].thread, caller) << "report " << k << " from another thread";
        EXPECT_EQ(reports[k].stage, "jobs");
        EXPECT_GE(reports[k].fraction, from);
        EXPECT_LE(reports[k].fraction, to);
        if (k > 0) {
          EXPECT_GE(reports[k].fraction, reports[k - 1].fraction) << "report " << k;
        }
      }
      EXPECT_EQ(reports.back().fraction, to);
      if (threads == 1) {
        EXPECT_EQ(reports.size(), 200u);  // one per finished job
      }
    }
}

// The last fraction is `to` itself, not from + (to - from) x 1 (which is 0.9000000000000001 for
// [0.3, 0.9], outside the range, and 0.8999999999999999 for [0.2, 0.9]).
TEST(ParallelFor, LastProgressFractionIsExactlyTo) {
  for (int threads : {1, 2})
    for (const auto& [from, to] : {std::pair{0.3, 0.9}, std::pair{0.2, 0.9}}) {
      const std::vector<Report> reports = progress_reports(threads, from, to);
      ASSERT_FALSE(reports.empty());
      for (const Report& report : reports) EXPECT_LE(report.fraction, to);
      EXPECT_EQ(reports.back().fraction, to) << std::setprecision(17) << "[" << from << ", " << to
                                             << "] ended at " << reports.back().fraction;
    }
}

TEST(ParallelFor, EmptyStageReportsNothing) {
  int calls = 0;
  const Progress progress([&](std::string_view, double) { ++calls; });
  for (int threads : {1, 3})
    parallel_for(
        50, [&](std::size_t, const Progress& inner) { inner.report("inner", 0.5); }, progress,
        with_threads(threads));
  EXPECT_EQ(calls, 0);
}

}  // namespace
}  // namespace gridshell
