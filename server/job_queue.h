// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld — the worker pool every request runs on, whichever transport brought it.
//
// A fixed number of workers (one per core by default) take jobs from a bounded queue; a full
// queue refuses a job at once (RESOURCE_EXHAUSTED). Each job carries the kernel's cancellation
// flag: the transport cancels it when the client goes away, a watchdog when its deadline passes,
// shutdown when the daemon stops; the kernel polls the flag and stops. The queue measures how
// long that takes (cancel request -> worker free) and writes one JSON log line per request.
//
// No gRPC or HTTP here: transports hand in a JobRequest with a JobSink and get events back.
#pragma once

#include <google/protobuf/message.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <thread>
#include <vector>

#include "gridshell/foundation/progress.h"
#include "gridshell/v1/requests.pb.h"
#include "status.h"

namespace gridshell::server {

using Clock = std::chrono::steady_clock;

/// Receives what a job produces. Called from worker threads (and, for jobs that never start,
/// from the thread that refused or cancelled them); implementations must be thread-safe and
/// must not block.
class JobSink {
 public:
  virtual ~JobSink() = default;
  /// Progress of the running job; may be called often (the sink coalesces).
  virtual void progress(const v1::Progress& event) = 0;
  /// Exactly once, last. `result` is set if and only if the status is OK.
  virtual void finish(const Status& status, std::unique_ptr<google::protobuf::Message> result) = 0;
};

/// What a running job may tell the queue about itself (for the log line).
struct JobInfo {
  std::atomic<int> vertices{0};
  std::atomic<int> faces{0};
};

struct JobRequest {
  std::uint64_t id = 0;   ///< from JobQueue::next_id(), so the transport can announce it early
  std::string method;     ///< "Design", ...
  std::string transport;  ///< "grpc" | "http"
  std::string peer;       ///< client address
  std::optional<Clock::time_point> deadline;
  /// A light request (Examples: answered from tables, no kernel work): it runs in a lane of its
  /// own (JobQueue::Options::light_workers), so it never waits behind design jobs and a full
  /// design queue does not refuse it.
  bool light = false;
  /// The computation: request -> kernel -> result message. Throws the kernel's errors.
  std::function<std::unique_ptr<google::protobuf::Message>(const Progress&, JobInfo&)> run;
  std::shared_ptr<JobSink> sink;
};

class Job;

/// "2026-11-22T10:31:05.123Z", the time field of every log line.
std::string utc_timestamp();

class JobQueue {
 public:
  struct Options {
    int workers = 0;              ///< 0 = one per hardware thread
    int capacity = 16;            ///< jobs that may wait for a worker; one more is refused
    std::ostream* log = nullptr;  ///< one JSON line per request; null = no log
    /// Progress events of one job are forwarded at most this often within a stage; the first
    /// event of a stage and its first at fraction 1 always go out. The kernel reports ~240
    /// events per design, and each one forwarded wakes the transport and the client, which
    /// costs the computing cores more than it is worth. 0 = forward every event except a
    /// stage's repeated fraction 1.
    int progress_interval_ms = 100;
    int light_workers = 1;    ///< workers of the light lane (JobRequest::light)
    int light_capacity = 64;  ///< light jobs that may wait; one more is refused
  };

  struct Stats {
    std::uint64_t accepted = 0;  ///< queued (started or not)
    std::uint64_t rejected = 0;  ///< refused: queue full or shutting down
    std::uint64_t succeeded = 0;
    std::uint64_t failed = 0;     ///< finished with an error other than cancellation
    std::uint64_t cancelled = 0;  ///< cancelled, deadline exceeded or stopped by shutdown
    int running = 0;
    int queued = 0;
    int workers = 0;
    /// For every job cancelled while running (latest last, at most 1000): milliseconds from the
    /// cancel request (client gone, deadline, shutdown) until the worker was free again.
    std::vector<double> cancel_latency_ms;
  };

  explicit JobQueue(const Options& options);
  ~JobQueue();  ///< shutdown(0)
  JobQueue(const JobQueue&) = delete;
  JobQueue& operator=(const JobQueue&) = delete;

  std::uint64_t next_id() { return next_id_++; }

  /// Queues a job. When the queue is full or shutting down the sink is finished at once
  /// (RESOURCE_EXHAUSTED / UNAVAILABLE) and the result is null.
  std::shared_ptr<Job> submit(JobRequest request);

  /// Answers a request that never becomes a job (unauthenticated, unimplemented): logs it and
  /// finishes its sink with `status`.
  void refuse(JobRequest request, Status status);

  /// Asks a job to stop: a waiting job is finished at once, a running one when the kernel next
  /// polls its flag. `reason` is the status it finishes with (Cancelled, DeadlineExceeded,
  /// Unavailable). Safe to call any number of times, from any thread, also after it finished.
  void cancel(const std::shared_ptr<Job>& job, StatusCode reason, std::string message = {});

  /// Refuses new jobs, lets running and waiting ones finish for up to `grace`, cancels the rest
  /// (UNAVAILABLE) and joins the workers. Idempotent.
  void shutdown(std::chrono::milliseconds grace);

  Stats stats() const;

  /// Writes one line to the log (if any), serialized with the queue's own lines.
  void write_log(const std::string& line);

 private:
  void work(int lane);
  void watch_deadlines();
  /// How finish() counts the job in the statistics, after its log line is written: refused,
  /// cancelled while waiting, or ended by a worker (succeeded, failed or cancelled by status).
  enum class Count { Rejected, Cancelled, Running };
  void finish(const std::shared_ptr<Job>& job, Status status,
              std::unique_ptr<google::protobuf::Message> result, Count count);

  Options options_;
  std::atomic<std::uint64_t> next_id_{1};
  mutable std::mutex mutex_;
  std::condition_variable work_ready_;
  std::condition_variable idle_;
  std::condition_variable deadline_changed_;
  /// Per lane: 0 = the workers, 1 = light jobs.
  std::deque<std::shared_ptr<Job>> waiting_[2];
  int running_in_[2] = {0, 0};
  std::vector<std::shared_ptr<Job>> running_;  ///< both lanes
  std::multimap<Clock::time_point, std::weak_ptr<Job>> deadlines_;
  bool accepting_ = true;
  bool stopping_ = false;
  Stats stats_;
  std::vector<std::thread> workers_;
  std::thread watchdog_;
  std::mutex log_mutex_;
  std::mutex shutdown_mutex_;
};

}  // namespace gridshell::server
