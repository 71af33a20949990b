// gridshell — independent jobs on worker threads (private header, kernel/src only).
#pragma once

#include <cstddef>
#include <functional>

namespace gridshell::detail {

/// Runs job(i) for every i in [0, count) on `threads` threads (0 = hardware concurrency; never
/// more than `count`), the calling thread being one of them. Jobs must be independent and
/// write only their own results, so the outcome does not depend on the thread count. After the
/// first exception no further job starts; that exception is rethrown once all threads ended.
void parallel_for(std::size_t count, int threads, const std::function<void(std::size_t)>& job);

}  // namespace gridshell::detail
