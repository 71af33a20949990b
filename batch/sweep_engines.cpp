// SPDX-License-Identifier: GPL-3.0-or-later
// The two ways a sweep's rows run: N worker processes on this machine, or Slurm job arrays
// (sbatch, squeue, sacct, scancel: the cluster's own commands, nothing of our own scheduling).
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "gridshell/batch/sweep.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"

namespace gridshell::sweep {
namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

namespace {

bool finished(const std::string& dir, const std::string& id) {
  const auto status = read_status(row_dir(dir, id) + "/status.json");
  return status && status->finished_for_good();
}

std::vector<const Row*> pending_rows(const std::string& dir, const Manifest& manifest) {
  std::vector<const Row*> pending;
  for (const Row& row : manifest.rows)
    if (!finished(dir, row.id)) pending.push_back(&row);
  return pending;
}

/// The caller's cancellation flag, or one that is never set.
const std::atomic<bool>* cancel_of(const EngineOptions& options) {
  static const std::atomic<bool> never{false};
  const std::atomic<bool>* flag = options.progress.cancel_flag();
  return flag ? flag : &never;
}

void end_progress(const EngineOptions& options) {
  if (options.end_progress) options.end_progress();
}

/// Draws the progress line (the cancellation flag is checked by the caller).
void draw(const Progress& progress, const std::string& stage, double fraction) {
  try {
    progress.report(stage, fraction);
  } catch (const Cancelled&) {
  }
}

std::string shell_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

fs::path slurm_dir(const std::string& dir) { return fs::path(dir) / "slurm"; }

/// Job ids of the sweep's earlier submissions (slurm/jobs.txt, one a line).
std::vector<std::string> recorded_jobs(const std::string& dir) {
  std::vector<std::string> jobs;
  std::ifstream in(slurm_dir(dir) / "jobs.txt");
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) jobs.push_back(line);
  return jobs;
}

/// The recorded jobs that Slurm still has queued or running.
std::vector<std::string> active_jobs(const std::string& dir) {
  const std::vector<std::string> jobs = recorded_jobs(dir);
  if (jobs.empty()) return {};
  std::string list;
  for (const std::string& job : jobs) list += (list.empty() ? "" : ",") + job;
  const CommandOutput out = run_command({"squeue", "-h", "-j", list, "-o", "%F"});
  std::set<std::string> active;
  std::istringstream lines(out.out);
  std::string line;
  while (std::getline(lines, line))
    if (!line.empty()) active.insert(line);
  return {active.begin(), active.end()};
}

}  // namespace

// Local engine -----------------------------------------------------------------------------------

int run_local(const std::string& dir, const Manifest& manifest, const EngineOptions& options) {
  if (fs::exists(slurm_dir(dir) / "jobs.txt")) {
    const auto active = active_jobs(dir);
    if (!active.empty())
      throw InvalidInput("--out", "Slurm job " + active.front() + " of this sweep is still " +
                                      "queued or running; wait for it or scancel it first");
  }
  const std::vector<const Row*> pending = pending_rows(dir, manifest);
  const int workers = options.workers > 0
                          ? options.workers
                          : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<std::pair<const Row*, int>> queue;  // row, runs so far in this sweep
  for (const Row* row : pending) queue.emplace_back(row, 0);
  int running = 0, done = 0, failed = 0, unfinished = 0;
  const int total = static_cast<int>(manifest.rows.size());
  const int already = total - static_cast<int>(pending.size());
  std::exception_ptr error;
  const std::atomic<bool>* cancel = cancel_of(options);

  auto worker = [&] {
    std::unique_lock lock(mutex);
    for (;;) {
      changed.wait(lock, [&] { return !queue.empty() || running == 0 || cancel->load(); });
      if (cancel->load() || error || (queue.empty() && running == 0)) break;
      if (queue.empty()) continue;
      auto [row, runs] = queue.front();
      queue.pop_front();
      ++running;
      lock.unlock();
      RowStatus status;
      std::exception_ptr caught;
      try {
        status = run_row(dir, *row, options.row, cancel);
      } catch (...) {
        caught = std::current_exception();
      }
      lock.lock();
      --running;
      if (caught) {
        if (!error) error = caught;
      } else if (status.finished_for_good()) {
        ++done;
        if (status.status != "ok") ++failed;
      } else if (status.status != "cancelled" && runs < options.retries) {
        queue.emplace_back(row, runs + 1);  // failed or killed: once more, at the end
      } else {
        ++unfinished;
      }
      changed.notify_all();
    }
    changed.notify_all();
  };
  std::vector<std::thread> threads;
  for (int i = 0; i < std::min<int>(workers, static_cast<int>(pending.size())); ++i)
    threads.emplace_back(worker);
  const Progress& progress = options.progress;
  {
    std::unique_lock lock(mutex);
    while (!changed.wait_for(lock, std::chrono::milliseconds(250), [&] {
      return (queue.empty() && running == 0) || error || cancel->load();
    })) {
      const std::string stage = "sweep: " + std::to_string(already + done) + "/" +
                                std::to_string(total) + " rows (" + std::to_string(running) +
                                " running, " + std::to_string(failed) + " not ok)";
      lock.unlock();
      draw(progress, stage, (already + done) / double(total));
      lock.lock();
    }
  }
  changed.notify_all();
  for (std::thread& t : threads) t.join();
  end_progress(options);
  if (error) std::rethrow_exception(error);
  if (cancel->load()) throw Cancelled();
  return unfinished;
}

// Slurm engine -----------------------------------------------------------------------------------

namespace {

struct Submission {
  int number = 0;
  std::vector<std::string> rows;
  int rows_per_task = 1;
  int tasks = 0;
  std::string job;  ///< the array job's id
};

int next_submission(const std::string& dir) {
  int last = 0;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(slurm_dir(dir), ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("submission-", 0) == 0 && entry.path().extension() == ".json")
      last = std::max(last, std::atoi(name.c_str() + 11));
  }
  return last + 1;
}

void write_submission(const std::string& dir, const Submission& s, const RowSettings& settings) {
  ordered_json j;
  j["number"] = s.number;
  j["rows"] = s.rows;
  j["rows_per_task"] = s.rows_per_task;
  j["tasks"] = s.tasks;
  j["gridshell"] = settings.gridshell;
  j["threads"] = settings.threads;
  ordered_json remote;
  remote["server"] = settings.remote.server;
  remote["tls"] = settings.remote.tls;
  remote["tls_ca"] = settings.remote.tls_ca;
  remote["token_file"] = settings.remote.token_file;
  remote["timeout"] = settings.remote.timeout;
  j["remote"] = remote;
  if (!s.job.empty()) j["job"] = s.job;
  write_file_atomically(
      (slurm_dir(dir) / ("submission-" + std::to_string(s.number) + ".json")).string(),
      j.dump(1) + "\n");
}

std::string sbatch_script(const std::string& dir, const Submission& s,
                          const EngineOptions& options) {
  std::string array = "0-" + std::to_string(s.tasks - 1);
  if (options.max_parallel > 0) array += "%" + std::to_string(options.max_parallel);
  std::string script = "#!/bin/bash\n";
  script += "# gridshell sweep " + dir + ", submission " + std::to_string(s.number) + ": " +
            std::to_string(s.rows.size()) + " rows in " + std::to_string(s.tasks) +
            " array tasks (written by gridshell sweep --engine slurm; docs/deploy.md)\n";
  script += "#SBATCH --job-name=gridshell-sweep\n";
  script += "#SBATCH --array=" + array + "\n";
  script += "#SBATCH --ntasks=1\n";
  script += "#SBATCH --cpus-per-task=" + std::to_string(std::max(1, options.row.threads)) + "\n";
  script += "#SBATCH --output=" + (slurm_dir(dir) / "task-%A_%a.log").string() + "\n";
  if (!options.partition.empty()) script += "#SBATCH --partition=" + options.partition + "\n";
  if (!options.time.empty()) script += "#SBATCH --time=" + options.time + "\n";
  if (!options.mem.empty()) script += "#SBATCH --mem=" + options.mem + "\n";
  for (const std::string& extra : options.sbatch_args) script += "#SBATCH " + extra + "\n";
  script += "exec " + shell_quote(options.row.gridshell) + " sweep task " + shell_quote(dir) +
            " --submission " + std::to_string(s.number) + " --task \"$SLURM_ARRAY_TASK_ID\"\n";
  return script;
}

/// sbatch --parsable: "JOBID" or "JOBID;CLUSTER".
std::string submit(const std::vector<std::string>& arguments) {
  const CommandOutput out = run_command(arguments);
  std::string job = out.out.substr(0, out.out.find_first_of(";\n"));
  if (out.exit_code != 0 || job.empty() || job.find_first_not_of("0123456789") != std::string::npos)
    throw std::runtime_error("sbatch failed (exit " + std::to_string(out.exit_code) +
                             "): " + out.err + out.out);
  return job;
}

struct TaskState {
  std::string id;  ///< JOBID_TASK
  std::string state;
  std::string exit_code;  ///< "code:signal"
};

bool terminal(const std::string& state) {
  return !(state == "PENDING" || state == "RUNNING" || state == "REQUEUED" || state == "RESIZING" ||
           state == "SUSPENDED" || state == "COMPLETING" || state == "CONFIGURING" ||
           state.empty());
}

/// The array's tasks as accounting (sacct) has them; nullopt when sacct does not answer
/// (a cluster without accounting).
std::optional<std::vector<TaskState>> task_states(const std::string& job) {
  // With the steps: a cancelled task's own record says exit code 0:0, its batch step has the
  // signal that ended the script (scancel --signal=KILL reaches it as SIGTERM, then SIGKILL).
  const CommandOutput out =
      run_command({"sacct", "-j", job, "-n", "-P", "-o", "JobID,State,ExitCode"});
  if (out.exit_code != 0) return std::nullopt;
  std::vector<TaskState> states;
  std::map<std::string, std::string> batch_exit;
  std::istringstream lines(out.out);
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<std::string> parts;
    std::istringstream fields(line);
    std::string field;
    while (std::getline(fields, field, '|')) parts.push_back(field);
    if (parts.size() < 3) continue;
    const auto dot = parts[0].find('.');
    if (dot != std::string::npos) {
      if (parts[0].substr(dot + 1) == "batch") batch_exit[parts[0].substr(0, dot)] = parts[2];
      continue;
    }
    // "CANCELLED by 0" -> "CANCELLED"
    states.push_back({parts[0], parts[1].substr(0, parts[1].find(' ')), parts[2]});
  }
  for (TaskState& t : states)
    if (batch_exit.count(t.id) && batch_exit[t.id] != "0:0") t.exit_code = batch_exit[t.id];
  return states;
}

/// Which task claimed which row in a submission (claims/<n>/<id> holds the task's JOBID_TASK).
std::map<std::string, std::vector<std::string>> claims_by_task(const std::string& dir,
                                                               int submission) {
  std::map<std::string, std::vector<std::string>> by_task;
  std::error_code ec;
  for (const auto& entry :
       fs::directory_iterator(slurm_dir(dir) / "claims" / std::to_string(submission), ec)) {
    std::ifstream in(entry.path());
    std::string task;
    std::getline(in, task);
    by_task[task.substr(0, task.find(' '))].push_back(entry.path().filename().string());
  }
  return by_task;
}

/// Waits until Slurm no longer has the job queued or running, drawing the rows' progress.
void wait_for_job(const std::string& dir, const Submission& s, const EngineOptions& options,
                  int total) {
  const Progress& progress = options.progress;
  const std::atomic<bool>* cancel = cancel_of(options);
  auto last_query = std::chrono::steady_clock::now() - std::chrono::hours(1);
  int failures = 0;
  for (;;) {
    if (cancel->load()) {
      run_command({"scancel", s.job});
      end_progress(options);
      std::cerr << "sweep: cancelled Slurm job " << s.job
                << "; run the same command again to resume\n";
      throw Cancelled();
    }
    int finished_rows = 0, with_folder = 0;
    for (const std::string& id : s.rows) {
      const auto status = read_status(row_dir(dir, id) + "/status.json");
      if (status) ++with_folder;
      if (status && status->finished_for_good()) ++finished_rows;
    }
    draw(progress,
         "sweep: job " + s.job + ": " + std::to_string(finished_rows) + "/" +
             std::to_string(s.rows.size()) + " rows of this submission, " + std::to_string(total) +
             " in all",
         finished_rows / double(std::max<size_t>(1, s.rows.size())));
    const auto now = std::chrono::steady_clock::now();
    // Every row has an outcome: the job ends in moments, so ask Slurm often; else every
    // poll interval (squeue asks the controller, which a big cluster shares with everyone).
    const bool all_rows_out = with_folder == static_cast<int>(s.rows.size());
    const double interval = all_rows_out ? 0.2 : options.poll_seconds;
    if (std::chrono::duration<double>(now - last_query).count() >= interval) {
      last_query = now;
      const CommandOutput out = run_command({"squeue", "-h", "-j", s.job, "-o", "%i"});
      if (out.exit_code == 0 && out.out.find_first_not_of(" \n") == std::string::npos) break;
      if (out.exit_code != 0 && out.err.find("Invalid job id") != std::string::npos) break;
      if (out.exit_code != 0 && ++failures > 30)
        throw std::runtime_error("squeue keeps failing (" + out.err +
                                 "); the job may still run: run the same command again later");
      if (out.exit_code == 0) failures = 0;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  end_progress(options);
}

/// Prints the tasks that did not complete, as accounting saw them, with the rows they held.
void report_tasks(const std::string& dir, const Submission& s, bool quiet) {
  // The tasks that started: Slurm creates a task's output file when it starts it. The others
  // were cancelled while pending (the first task that found every row taken cancels them), and
  // accounting lists them as one record "JOB_[range]".
  std::set<std::string> started;
  for (int task = 0; task < s.tasks; ++task)
    if (fs::exists(slurm_dir(dir) / ("task-" + s.job + "_" + std::to_string(task) + ".log")))
      started.insert(s.job + "_" + std::to_string(task));
  // Accounting learns of the last tasks' ends a moment after the controller: wait until every
  // started task is there in a final state (bounded: 20 s).
  std::optional<std::vector<TaskState>> states;
  std::map<std::string, TaskState> by_task;
  for (int i = 0; i < 100; ++i) {
    states = task_states(s.job);
    if (!states) break;
    by_task.clear();
    for (const TaskState& t : *states)
      if (t.id.find('[') == std::string::npos && terminal(t.state)) by_task[t.id] = t;
    bool all = true;
    for (const std::string& task : started) all = all && by_task.count(task);
    if (all) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  if (!states) {
    std::cerr << "sweep: sacct does not answer (no accounting on this cluster?): task states "
                 "unknown; rows without a result are submitted again\n";
    return;
  }
  std::map<std::string, int> counts;
  for (const auto& [task, t] : by_task) ++counts[t.state];
  const int not_started = s.tasks - static_cast<int>(by_task.size());
  if (!quiet) {
    std::cerr << "sweep: job " << s.job << ":";
    for (const auto& [state, count] : counts) std::cerr << " " << count << " " << state;
    if (not_started > 0)
      std::cerr << ", " << not_started
                << " not started (their rows were taken by tasks that ran first; cancelled "
                   "while pending)";
    std::cerr << "\n";
  }
  const auto claims = claims_by_task(dir, s.number);
  for (const auto& [task, t] : by_task) {
    if (t.state == "COMPLETED") continue;
    std::string rows;
    if (claims.count(task))
      for (const std::string& id : claims.at(task))
        if (!finished(dir, id)) rows += " " + id;
    const auto colon = t.exit_code.find(':');
    const std::string code = t.exit_code.substr(0, colon);
    const std::string signal = colon == std::string::npos ? "0" : t.exit_code.substr(colon + 1);
    std::cerr << "sweep: task " << task << " " << t.state << " (exit code " << code
              << (signal != "0" ? ", signal " + signal : std::string()) << ")"
              << (rows.empty() ? "" : "; rows without a result:" + rows) << "\n";
  }
}

}  // namespace

int run_slurm(const std::string& dir, const Manifest& manifest, const EngineOptions& options) {
  if (run_command({"sbatch", "--version"}).exit_code != 0)
    throw InvalidInput("--engine",
                       "slurm: sbatch cannot be run here (not a Slurm login node? "
                       "scripts/slurm-local.sh start makes a one-node cluster)");
  fs::create_directories(slurm_dir(dir));
  for (const std::string& job : active_jobs(dir)) {
    if (options.no_wait)
      throw InvalidInput("--out", "Slurm job " + job + " of this sweep is still queued or " +
                                      "running; wait for it or scancel it first");
    std::cerr << "sweep: waiting for job " << job << " of an earlier run of this sweep\n";
    Submission earlier;
    earlier.job = job;
    wait_for_job(dir, earlier, options, static_cast<int>(manifest.rows.size()));
  }
  for (int round = 0; round <= options.retries; ++round) {
    const std::vector<const Row*> pending = pending_rows(dir, manifest);
    if (pending.empty()) break;
    Submission s;
    s.number = next_submission(dir);
    for (const Row* row : pending) s.rows.push_back(row->id);
    s.rows_per_task = std::max(1, options.rows_per_task);
    s.tasks = static_cast<int>((s.rows.size() + s.rows_per_task - 1) / s.rows_per_task);
    write_submission(dir, s, options.row);
    const fs::path script = slurm_dir(dir) / ("submission-" + std::to_string(s.number) + ".sbatch");
    write_file_atomically(script.string(), sbatch_script(dir, s, options));
    s.job = submit({"sbatch", "--parsable", script.string()});
    write_submission(dir, s, options.row);
    {
      std::ofstream jobs(slurm_dir(dir) / "jobs.txt", std::ios::app);
      jobs << s.job << "\n";
    }
    if (!options.quiet || options.no_wait)
      std::cerr << "sweep: submitted " << s.rows.size() << " rows as Slurm job " << s.job << " ("
                << s.tasks << " array tasks" << (round ? ", retry " + std::to_string(round) : "")
                << ")\n";
    if (options.no_wait) {
      // The summary is written by a job of its own when the array has ended.
      const std::string collect_job =
          submit({"sbatch", "--parsable", "--job-name=gridshell-sweep-collect",
                  "--dependency=afterany:" + s.job, "--kill-on-invalid-dep=yes",
                  "--output=" + (slurm_dir(dir) / "collect-%j.log").string(),
                  "--wrap=exec " + shell_quote(options.row.gridshell) + " sweep collect " +
                      shell_quote(dir)});
      std::printf("%s\n", s.job.c_str());
      std::cerr << "sweep: job " << collect_job << " collects the summary when it ends; "
                << "gridshell sweep status " << dir << " shows the rows meanwhile\n";
      return 0;
    }
    wait_for_job(dir, s, options, static_cast<int>(manifest.rows.size()));
    report_tasks(dir, s, options.quiet);
  }
  return static_cast<int>(pending_rows(dir, manifest).size());
}

namespace {

/// A task that Slurm cancels (scancel, a time limit: SIGTERM, SIGKILL after KillWait) has stopped
/// its row's run; it then ends by SIGTERM itself, so that accounting records the signal
/// (a plain exit code showed up as "2:0" on the batch step, which says nothing).
int die_cancelled() {
  std::fflush(stdout);
  std::signal(SIGTERM, SIG_DFL);
  std::raise(SIGTERM);
  return 130;
}

}  // namespace

int run_task(const std::string& dir, int submission, int task, const std::atomic<bool>* cancel) {
  const fs::path file = slurm_dir(dir) / ("submission-" + std::to_string(submission) + ".json");
  std::ifstream in(file);
  if (!in)
    throw InvalidInput(dir,
                       "no submission " + std::to_string(submission) + " (" + file.string() + ")");
  const ordered_json j = ordered_json::parse(in);
  const Manifest manifest = read_sweep_file(dir);
  std::map<std::string, const Row*> by_id;
  for (const Row& row : manifest.rows) by_id[row.id] = &row;
  const std::vector<std::string> ids = j.at("rows").get<std::vector<std::string>>();
  const int per_task = std::max(1, j.at("rows_per_task").get<int>());
  RowSettings settings;
  settings.gridshell = j.at("gridshell").get<std::string>();
  settings.threads = j.at("threads").get<int>();
  const auto& remote = j.at("remote");
  settings.remote.server = remote.value("server", "");
  settings.remote.tls = remote.value("tls", false);
  settings.remote.tls_ca = remote.value("tls_ca", "");
  settings.remote.token_file = remote.value("token_file", "");
  settings.remote.timeout = remote.value("timeout", 0.0);
  settings.engine = "slurm";
  const char* array_job = std::getenv("SLURM_ARRAY_JOB_ID");
  settings.slurm_job = std::string(array_job ? array_job : "?") + "_" + std::to_string(task);
  const fs::path claims = slurm_dir(dir) / "claims" / std::to_string(submission);
  fs::create_directories(claims);

  // Its own rows first, then any row of the submission that no task has claimed: a task that
  // starts late (or never) does not hold the others up.
  const size_t first = static_cast<size_t>(task) * per_task;
  std::vector<std::string> order;
  for (size_t k = 0; k < ids.size(); ++k) order.push_back(ids[(first + k) % ids.size()]);
  bool all_finished = true;
  for (const std::string& id : order) {
    if (cancel->load()) return die_cancelled();
    if (!by_id.count(id) || finished(dir, id)) continue;
    const fs::path claim = claims / id;
    const int fd = ::open(claim.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) continue;  // another task has it
    const std::string holder = settings.slurm_job + " pid " + std::to_string(getpid()) + "\n";
    (void)!::write(fd, holder.data(), holder.size());
    ::close(fd);
    const RowStatus status = run_row(dir, *by_id[id], settings, cancel);
    std::printf("%s %s %s (exit %d, %.1f s)%s%s\n", now_iso8601().c_str(), id.c_str(),
                status.status.c_str(), status.exit_code, status.seconds,
                status.error.empty() ? "" : ": ", status.error.c_str());
    std::fflush(stdout);
    if (!status.finished_for_good()) all_finished = false;
    if (status.status == "cancelled") return die_cancelled();
  }
  // Every row of the submission is finished or being run by a task: the array's tasks that are
  // still waiting for a CPU would only start to find nothing (about half a second each), so
  // they are cancelled (the submitter does not count tasks that never ran as failures).
  if (array_job) run_command({"scancel", "--state=PENDING", array_job});
  return all_finished ? 0 : 1;
}

}  // namespace gridshell::sweep
