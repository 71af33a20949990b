// SPDX-License-Identifier: GPL-3.0-or-later
#include "job_queue.h"

#include <algorithm>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <ctime>
#include <new>
#include <nlohmann/json.hpp>

#include "gridshell/application/requests.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::server {

class Job {
 public:
  JobRequest request;
  JobInfo info;
  std::atomic<bool> cancel_flag{false};

  // Guarded by the queue's mutex.
  enum class State { Waiting, Running, Done } state = State::Waiting;
  StatusCode cancel_reason = StatusCode::Ok;  // Ok = no cancel requested
  std::string cancel_message;
  Clock::time_point cancel_time;
  std::optional<double> cancel_latency_ms;

  Clock::time_point submitted = Clock::now();
  Clock::time_point started, stopped;

  /// Time per stage group ("patch", "distance maps", ...): the part of the kernel's stage name
  /// before ':'; stages interleaved from several threads are charged to the latest reported.
  /// Whether a progress event is forwarded (JobQueue::Options::progress_interval_ms): the first
  /// of a stage, the first at fraction 1, and others at most once per interval.
  bool forward_progress(std::string_view stage, double fraction,
                        std::chrono::milliseconds interval) {
    const Clock::time_point now = Clock::now();
    std::lock_guard lock(progress_mutex_);
    if (stage != progress_stage_) {
      progress_stage_.assign(stage);
      progress_complete_ = false;
    } else if (fraction >= 1 ? progress_complete_ : now - progress_sent_ < interval) {
      return false;  // too soon, or the stage's completion was already forwarded
    }
    progress_complete_ = progress_complete_ || fraction >= 1;
    progress_sent_ = now;
    return true;
  }

  void note_stage(std::string_view stage) {
    const std::string group(stage.substr(0, stage.find(':')));
    std::lock_guard lock(stage_mutex_);
    if (group == stage_) return;
    close_stage_locked();
    stage_ = group;
    stage_start_ = Clock::now();
  }
  std::vector<std::pair<std::string, double>> stages() {
    std::lock_guard lock(stage_mutex_);
    close_stage_locked();
    return stage_ms_;
  }

 private:
  void close_stage_locked() {
    if (stage_.empty()) return;
    const double ms =
        std::chrono::duration<double, std::milli>(Clock::now() - stage_start_).count();
    auto it = std::find_if(stage_ms_.begin(), stage_ms_.end(),
                           [&](const auto& entry) { return entry.first == stage_; });
    if (it == stage_ms_.end())
      stage_ms_.emplace_back(stage_, ms);
    else
      it->second += ms;
    stage_.clear();
  }

  std::mutex progress_mutex_;
  std::string progress_stage_;
  Clock::time_point progress_sent_;
  bool progress_complete_ = false;  // fraction 1 of progress_stage_ was forwarded
  std::mutex stage_mutex_;
  std::string stage_;
  Clock::time_point stage_start_;
  std::vector<std::pair<std::string, double>> stage_ms_;
};

namespace {

int lane_of(const Job& job) { return job.request.light ? 1 : 0; }

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

}  // namespace

std::string utc_timestamp() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()) % 1000;
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<int>(ms.count()));
  return buffer;
}

namespace {

std::string default_message(StatusCode reason) {
  switch (reason) {
    case StatusCode::DeadlineExceeded:
      return "deadline exceeded";
    case StatusCode::Unavailable:
      return "the daemon is shutting down";
    default:
      return "cancelled by the client";
  }
}

}  // namespace

JobQueue::JobQueue(const Options& options) : options_(options) {
  if (options_.workers <= 0)
    options_.workers = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  options_.capacity = std::max(0, options_.capacity);
  stats_.workers = options_.workers;
  options_.light_workers = std::max(1, options_.light_workers);
  options_.light_capacity = std::max(0, options_.light_capacity);
  for (int i = 0; i < options_.workers; ++i) workers_.emplace_back([this] { work(0); });
  for (int i = 0; i < options_.light_workers; ++i) workers_.emplace_back([this] { work(1); });
  watchdog_ = std::thread([this] { watch_deadlines(); });
}

JobQueue::~JobQueue() { shutdown(std::chrono::milliseconds(0)); }

std::shared_ptr<Job> JobQueue::submit(JobRequest request) {
  auto job = std::make_shared<Job>();
  job->request = std::move(request);
  if (job->request.id == 0) job->request.id = next_id();
  Status refusal;
  v1::Progress queued;
  {
    std::lock_guard lock(mutex_);
    const int lane = lane_of(*job);
    auto& waiting = waiting_[lane];
    const int workers = lane == 0 ? options_.workers : options_.light_workers;
    const int capacity = lane == 0 ? options_.capacity : options_.light_capacity;
    if (!accepting_) {
      refusal = {StatusCode::Unavailable, "the daemon is shutting down"};
    } else if (static_cast<int>(waiting.size()) + running_in_[lane] >= workers + capacity) {
      refusal = {StatusCode::ResourceExhausted,
                 "the queue is full (" + std::to_string(waiting.size()) + " waiting, " +
                     std::to_string(running_in_[lane]) + " running); retry later"};
    }
    if (!refusal.ok()) {
      job->state = Job::State::Done;
    } else {
      ++stats_.accepted;
      waiting.push_back(job);
      if (job->request.deadline) {
        deadlines_.emplace(*job->request.deadline, job);
        deadline_changed_.notify_all();
      }
      if (running_in_[lane] + static_cast<int>(waiting.size()) > workers) {
        queued.set_stage("queued");
        queued.set_message("waiting for a worker, " + std::to_string(waiting.size() - 1) +
                           " ahead");
      }
    }
  }
  if (!refusal.ok()) {
    job->started = job->stopped = Clock::now();
    finish(job, std::move(refusal), nullptr, Count::Rejected);
    return nullptr;
  }
  work_ready_.notify_all();  // the workers of both lanes wait on it
  // Outside the lock: sinks never run while the queue is locked. (A worker that frees up in
  // between may start the job first; the stale "queued" event is harmless.)
  if (!queued.stage().empty()) job->request.sink->progress(queued);
  return job;
}

void JobQueue::refuse(JobRequest request, Status status) {
  auto job = std::make_shared<Job>();
  job->request = std::move(request);
  if (job->request.id == 0) job->request.id = next_id();
  job->state = Job::State::Done;
  job->started = job->stopped = Clock::now();
  finish(job, std::move(status), nullptr, Count::Rejected);
}

void JobQueue::cancel(const std::shared_ptr<Job>& job, StatusCode reason, std::string message) {
  if (!job) return;
  bool finish_now = false;
  {
    std::lock_guard lock(mutex_);
    if (job->state == Job::State::Done || job->cancel_reason != StatusCode::Ok) return;
    job->cancel_reason = reason;
    job->cancel_message = message.empty() ? default_message(reason) : std::move(message);
    job->cancel_time = Clock::now();
    job->cancel_flag = true;
    if (job->state == Job::State::Waiting) {
      auto& waiting = waiting_[lane_of(*job)];
      waiting.erase(std::find(waiting.begin(), waiting.end(), job));
      job->state = Job::State::Done;
      job->started = job->stopped = job->cancel_time;
      finish_now = true;
      idle_.notify_all();
    }
  }
  if (finish_now) finish(job, {reason, job->cancel_message}, nullptr, Count::Cancelled);
}

void JobQueue::work(int lane) {
  auto& waiting = waiting_[lane];
  for (;;) {
    std::shared_ptr<Job> job;
    {
      std::unique_lock lock(mutex_);
      work_ready_.wait(lock, [&] { return stopping_ || !waiting.empty(); });
      if (waiting.empty()) return;  // stopping
      job = waiting.front();
      waiting.pop_front();
      job->state = Job::State::Running;
      job->started = Clock::now();
      running_.push_back(job);
      ++running_in_[lane];
    }
    Status status;
    std::unique_ptr<google::protobuf::Message> result;
    const Progress progress(
        [&job, interval = std::chrono::milliseconds(options_.progress_interval_ms)](
            std::string_view stage, double fraction) {
          job->note_stage(stage);
          if (!job->forward_progress(stage, fraction, interval)) return;
          v1::Progress event;
          event.set_stage(std::string(stage));
          event.set_fraction(fraction);
          job->request.sink->progress(event);
        },
        &job->cancel_flag);
    try {
      result = job->request.run(progress, job->info);
      if (!result) status = {StatusCode::Internal, "internal error: no result"};
    } catch (const Cancelled&) {
      status = {StatusCode::Cancelled, "cancelled"};  // the reason is filled in below
    } catch (const Error& e) {
      const StatusCode code = e.code() == ErrorCode::InvalidInput ? StatusCode::InvalidArgument
                              : e.code() == ErrorCode::Infeasible ? StatusCode::FailedPrecondition
                                                                  : StatusCode::Internal;
      status = {code, e.message(), e.field()};
      if (const auto* s = dynamic_cast<const InfeasibleWithSuggestions*>(&e))
        status.suggestions = s->suggestions();
    } catch (const std::bad_alloc&) {
      status = {StatusCode::ResourceExhausted, "out of memory"};
    } catch (const std::exception& e) {
      status = {StatusCode::Internal, std::string("internal error: ") + e.what()};
    } catch (...) {
      status = {StatusCode::Internal, "internal error: unknown exception"};
    }
    {
      std::lock_guard lock(mutex_);
      job->stopped = Clock::now();
      job->state = Job::State::Done;
      if (job->cancel_reason != StatusCode::Ok && !status.ok()) {
        const double latency = ms_between(job->cancel_time, job->stopped);
        job->cancel_latency_ms = latency;
        stats_.cancel_latency_ms.push_back(latency);
        if (stats_.cancel_latency_ms.size() > 1000)
          stats_.cancel_latency_ms.erase(stats_.cancel_latency_ms.begin());
        if (status.code == StatusCode::Cancelled)
          status = {job->cancel_reason, job->cancel_message};
      }
    }
    finish(job, std::move(status), std::move(result), Count::Running);
#ifdef __GLIBC__
    // Hand the request's freed memory back to the system: glibc keeps it in the worker's arena
    // otherwise, and a daemon whose cache evicts multi-MiB maps would hold about 1.5x its cache
    // bound in RSS (measured: docs/benchmarks.md). After the answer, so nobody waits for it.
    malloc_trim(0);
#endif
  }
}

void JobQueue::finish(const std::shared_ptr<Job>& job, Status status,
                      std::unique_ptr<google::protobuf::Message> result, Count count) {
  if (options_.log) {
    nlohmann::json line;
    line["time"] = utc_timestamp();
    line["id"] = job->request.id;
    line["method"] = job->request.method;
    line["transport"] = job->request.transport;
    line["peer"] = job->request.peer;
    line["vertices"] = job->info.vertices.load();
    line["faces"] = job->info.faces.load();
    line["status"] = code_name(status.code);
    if (!status.ok()) {
      line["message"] = status.message.substr(0, 500);
      if (!status.field.empty()) line["field"] = status.field.substr(0, 200);
    }
    line["queue_ms"] = ms_between(job->submitted, job->started);
    line["run_ms"] = ms_between(job->started, job->stopped);
    nlohmann::json stages = nlohmann::json::object();
    for (const auto& [stage, ms] : job->stages()) stages[stage] = ms;
    line["stages_ms"] = stages;
    if (job->cancel_latency_ms) line["cancel_ms"] = *job->cancel_latency_ms;
    write_log(line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  }
  // The statistics count a job as ended only once its log line is written, so whoever sees
  // the count change also finds the line.
  if (count == Count::Rejected) {
    std::lock_guard lock(mutex_);
    ++stats_.rejected;
  } else if (count == Count::Cancelled) {
    std::lock_guard lock(mutex_);
    ++stats_.cancelled;
  } else if (count == Count::Running) {
    std::lock_guard lock(mutex_);
    running_.erase(std::find(running_.begin(), running_.end(), job));
    --running_in_[lane_of(*job)];
    if (status.ok())
      ++stats_.succeeded;
    else if (status.code == StatusCode::Cancelled || status.code == StatusCode::DeadlineExceeded ||
             (status.code == StatusCode::Unavailable && job->cancel_reason != StatusCode::Ok))
      ++stats_.cancelled;
    else
      ++stats_.failed;
    idle_.notify_all();
  }
  job->request.sink->finish(status, std::move(result));
}

void JobQueue::watch_deadlines() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    if (deadlines_.empty()) {
      deadline_changed_.wait(lock);
      continue;
    }
    const auto first = deadlines_.begin()->first;
    if (Clock::now() < first) {
      deadline_changed_.wait_until(lock, first);
      continue;
    }
    std::vector<std::shared_ptr<Job>> expired;
    while (!deadlines_.empty() && deadlines_.begin()->first <= Clock::now()) {
      if (auto job = deadlines_.begin()->second.lock()) expired.push_back(std::move(job));
      deadlines_.erase(deadlines_.begin());
    }
    lock.unlock();
    for (const auto& job : expired) cancel(job, StatusCode::DeadlineExceeded);
    lock.lock();
  }
}

void JobQueue::shutdown(std::chrono::milliseconds grace) {
  std::lock_guard once(shutdown_mutex_);  // a second caller waits, then finds it done
  std::vector<std::shared_ptr<Job>> remaining;
  {
    std::unique_lock lock(mutex_);
    if (stopping_) return;
    accepting_ = false;
    const auto idle = [&] {
      return waiting_[0].empty() && waiting_[1].empty() && running_.empty();
    };
    idle_.wait_for(lock, grace, idle);
    remaining.assign(waiting_[0].begin(), waiting_[0].end());
    remaining.insert(remaining.end(), waiting_[1].begin(), waiting_[1].end());
    remaining.insert(remaining.end(), running_.begin(), running_.end());
  }
  for (const auto& job : remaining) cancel(job, StatusCode::Unavailable);
  {
    std::unique_lock lock(mutex_);
    idle_.wait(lock,
               [&] { return waiting_[0].empty() && waiting_[1].empty() && running_.empty(); });
    stopping_ = true;
  }
  work_ready_.notify_all();
  deadline_changed_.notify_all();
  for (std::thread& worker : workers_) worker.join();
  watchdog_.join();
}

void JobQueue::write_log(const std::string& line) {
  if (!options_.log) return;
  std::lock_guard lock(log_mutex_);
  *options_.log << line << '\n' << std::flush;
}

JobQueue::Stats JobQueue::stats() const {
  std::lock_guard lock(mutex_);
  Stats stats = stats_;
  stats.running = static_cast<int>(running_.size());
  stats.queued = static_cast<int>(waiting_[0].size() + waiting_[1].size());
  return stats;
}

}  // namespace gridshell::server
