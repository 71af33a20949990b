// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the kernel's one way to go parallel: independent jobs on worker threads, with
// cancellation and progress.
#pragma once

#include <cstddef>
#include <functional>
#include <string_view>

#include "gridshell/foundation/progress.h"

namespace gridshell {

struct ParallelOptions {
  /// Worker threads; 0 = hardware concurrency. Never more than the number of jobs. Default 0.
  int threads = 0;
  /// Progress stage the calling thread reports as jobs finish (fraction `from` + (to - from) x
  /// finished / count); empty = report nothing, only watch for cancellation. Default empty.
  std::string_view stage;
  double from = 0;  // fraction reported when no job has finished yet
  double to = 1;    // fraction reported when every job has finished
};

/// Runs job(i, inner) for every i in [0, count). Jobs must be independent and write only their
/// own results, so the outcome does not depend on the thread count.
///
/// With more than one thread the jobs run on worker threads while the calling thread reports
/// progress (the callback is then called from the calling thread only) and polls the
/// cancellation flag every 50 ms, so a cancel is seen even while long jobs run; with one thread
/// they run on the calling thread. `inner` is what a job passes to the long computations it
/// calls: it reports nowhere, stops when `progress` is cancelled, and also stops the job when
/// another job has failed (a private exception the helper swallows).
///
/// After the first exception (a job's, or Cancelled) no further job starts, running jobs stop
/// at their next check of `inner`, and that first exception is rethrown once every worker has
/// ended. Throws Cancelled when the caller cancels.
void parallel_for(std::size_t count, const std::function<void(std::size_t, const Progress&)>& job,
                  const Progress& progress = {}, const ParallelOptions& options = {});

/// The number of threads `requested` means: hardware concurrency (at least 1) for 0.
int resolve_threads(int requested);

}  // namespace gridshell
