// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell sweep MANIFEST --out DIR`, `gridshell sweep status DIR`, `gridshell sweep collect
// DIR` (and the array task `gridshell sweep task`, which Slurm runs): design sweeps, one
// `gridshell run` per manifest row, on this machine or as a Slurm job array (sweep.h).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/batch/sweep.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::cli {
namespace {

namespace fs = std::filesystem;

struct SweepArguments {
  std::string manifest;
  std::string out;
  std::string engine = "local";
  sweep::EngineOptions options;
  RemoteOptions remote;
  // status, collect, task
  std::string dir;
  int submission = 0;
  int task = 0;
};

std::string absolute(const std::string& path) {
  return path.empty() ? path : fs::absolute(path).lexically_normal().string();
}

std::string self_executable() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? "gridshell" : self.string();
}

/// Counts by status, in a fixed order.
std::string counts(const std::vector<sweep::RowStatus>& statuses) {
  std::map<std::string, int> by_status;
  for (const auto& s : statuses) ++by_status[s.status];
  std::string text;
  for (const char* name : {"ok", "invalid", "infeasible", "unconverged", "failed", "pending"})
    if (by_status.count(name))
      text += (text.empty() ? "" : ", ") + std::to_string(by_status[name]) + " " + name;
  return text;
}

void print_rows_not_ok(const std::vector<sweep::RowStatus>& statuses, size_t limit) {
  size_t shown = 0, not_ok = 0;
  for (const auto& s : statuses) {
    if (s.status == "ok") continue;
    ++not_ok;
    if (shown++ >= limit) continue;
    std::printf("  %-16s %-10s %s%s%s\n", s.id.c_str(), s.status.c_str(),
                s.status == "pending" ? "" : ("exit " + std::to_string(s.exit_code)).c_str(),
                s.error.empty() ? "" : "  ", s.error.c_str());
  }
  if (not_ok > limit) std::printf("  ... and %zu more (summary.csv)\n", not_ok - limit);
}

/// Rows that finished with values other than the manifest's now: their results would be
/// mixed into the new sweep.
void check_finished_rows_match(const std::string& dir, const sweep::Manifest& manifest) {
  std::vector<std::string> changed;
  for (const sweep::Row& row : manifest.rows) {
    const auto status = sweep::read_status(sweep::row_dir(dir, row.id) + "/status.json");
    if (!status || !status->finished_for_good()) continue;
    if (status->options != row.values) changed.push_back(row.id);
  }
  if (changed.empty()) return;
  for (const std::string& id : changed)
    std::cerr << "  row " << id << ": finished in " << dir << " with other values\n";
  throw InvalidInput("--out", std::to_string(changed.size()) +
                                  " finished rows have other values than the manifest's "
                                  "(listed above): use another --out, or remove their rows/ID "
                                  "folders to run them again");
}

/// The manifest, checked whole; InvalidInput after listing every problem on stderr.
sweep::Manifest checked_manifest(const std::string& path) {
  if (path.empty()) throw InvalidInput("MANIFEST", "give a manifest (CSV or JSON Lines)");
  const sweep::Manifest manifest = sweep::read_manifest(path);
  const std::vector<sweep::Problem> problems = sweep::validate(manifest, *run_row_checker());
  if (!problems.empty()) {
    finish_progress();
    std::set<std::string> rows;
    for (const auto& p : problems) {
      std::cerr << "  " << p.describe() << "\n";
      if (!p.id.empty()) rows.insert(p.id);
    }
    throw InvalidInput(
        path, std::to_string(problems.size()) + " problem" + (problems.size() == 1 ? "" : "s") +
                  (rows.empty() ? "" : " in " + std::to_string(rows.size()) + " rows") +
                  " (listed above); nothing was started");
  }
  return manifest;
}

/// `gridshell sweep check MANIFEST`: the check `gridshell sweep` makes before it starts.
int run_check(const SweepArguments& args) {
  const sweep::Manifest manifest = checked_manifest(args.manifest);
  std::printf("manifest %s: %zu rows, columns %s: no problems\n", manifest.path.c_str(),
              manifest.rows.size(),
              [&] {
                std::string list;
                for (const std::string& c : manifest.columns)
                  list += (list.empty() ? "" : ", ") + c;
                return list;
              }()
                  .c_str());
  return 0;
}

int run_sweep(SweepArguments& args) {
  if (args.out.empty()) throw InvalidInput("--out", "give the sweep folder");
  const sweep::Manifest manifest = checked_manifest(args.manifest);
  if (args.remote.remote()) {
    args.remote.tls_ca = absolute(args.remote.tls_ca);
    args.remote.token_file = absolute(args.remote.token_file);
    RemoteClient check(args.remote);  // HOST:PORT, --timeout and the token file, before any row
  }
  const std::string dir = absolute(args.out);
  prepare_output_folder(dir);
  sweep::FolderLock lock(dir);
  check_finished_rows_match(dir, manifest);
  sweep::write_sweep_file(dir, manifest);

  sweep::EngineOptions& options = args.options;
  options.progress = make_progress(options.quiet);
  options.end_progress = finish_progress;
  options.row.gridshell = self_executable();
  options.row.remote = args.remote;
  options.row.engine = args.engine;
  const int unfinished = args.engine == "slurm" ? sweep::run_slurm(dir, manifest, options)
                                                : sweep::run_local(dir, manifest, options);
  if (args.engine == "slurm" && options.no_wait) return 0;
  const std::vector<sweep::RowStatus> statuses = sweep::collect(dir);
  std::printf("sweep %s -> %s (%s engine)\n", args.manifest.c_str(), dir.c_str(),
              args.engine.c_str());
  std::printf("  rows           %zu: %s\n", statuses.size(), counts(statuses).c_str());
  print_rows_not_ok(statuses, 20);
  std::printf("  wrote          summary.csv summary.json summary.svg\n");
  if (unfinished > 0)
    throw std::runtime_error(std::to_string(unfinished) + " rows did not finish (failed or " +
                             "killed " + std::to_string(options.retries + 1) +
                             " times); run the same command again to retry them, or see "
                             "gridshell sweep status " +
                             dir);
  return 0;
}

int run_status(const SweepArguments& args) {
  const std::string dir = absolute(args.dir);
  const sweep::Manifest manifest = sweep::read_sweep_file(dir);
  const std::vector<sweep::RowStatus> statuses = sweep::row_statuses(dir, manifest);
  std::printf("sweep %s\n", dir.c_str());
  std::printf("  rows           %zu: %s\n", statuses.size(), counts(statuses).c_str());
  print_rows_not_ok(statuses, 1000);
  return 0;
}

int run_collect(const SweepArguments& args) {
  const std::string dir = absolute(args.dir);
  const std::vector<sweep::RowStatus> statuses = sweep::collect(dir);
  std::printf("sweep %s\n", dir.c_str());
  std::printf("  rows           %zu: %s\n", statuses.size(), counts(statuses).c_str());
  std::printf("  wrote          summary.csv summary.json summary.svg\n");
  return 0;
}

}  // namespace

Command add_sweep_command(CLI::App& app) {
  auto args = std::make_shared<SweepArguments>();
  CLI::App* sub = app.add_subcommand(
      "sweep",
      "Run many designs from a manifest (CSV or JSON Lines: id, mesh and gridshell run's "
      "options), each row a `gridshell run` into DIR/rows/ID, here or on Slurm; resumable");
  sub->add_option("MANIFEST", args->manifest, "the rows: a .csv or .jsonl file");
  sub->add_option("--out", args->out, "the sweep folder (rerun the same command to resume)");
  sub->add_option("--engine", args->engine, "local (worker processes here) | slurm (job array)")
      ->check(CLI::IsMember({"local", "slurm"}))
      ->capture_default_str();
  sub->add_option("--workers", args->options.workers, "local: rows at once (0 = cores)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  sub->add_option("--threads", args->options.row.threads,
                  "kernel threads of each row (slurm: --cpus-per-task)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  sub->add_option("--retries", args->options.retries,
                  "run failed or killed rows again up to this many times")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  sub->add_flag("--quiet", args->options.quiet, "no progress line");
  const char* slurm = "Slurm (--engine slurm)";
  sub->add_option("--partition", args->options.partition, "sbatch --partition")->group(slurm);
  sub->add_option("--time", args->options.time, "sbatch --time of one array task")->group(slurm);
  sub->add_option("--mem", args->options.mem, "sbatch --mem of one array task")->group(slurm);
  sub->add_option("--max-parallel", args->options.max_parallel,
                  "array tasks at once: --array=0-N%K (0 = as the cluster allows)")
      ->check(CLI::Range(0, 1000000))
      ->group(slurm);
  sub->add_option("--rows-per-task", args->options.rows_per_task,
                  "rows of one array task (then it takes rows no task has started)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str()
      ->group(slurm);
  sub->add_option("--sbatch-arg", args->options.sbatch_args,
                  "another #SBATCH line for the array, e.g. --sbatch-arg=--account=abc")
      ->group(slurm);
  sub->add_flag("--no-wait", args->options.no_wait,
                "print the array's job id and return; a dependent job collects the summary")
      ->group(slurm);
  sub->add_option("--poll-seconds", args->options.poll_seconds,
                  "how often to ask squeue while waiting")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str()
      ->group(slurm);
  add_remote_options(sub, args->remote);

  CLI::App* check = sub->add_subcommand(
      "check", "Check a manifest as a sweep would before it starts, and run nothing");
  check->add_option("MANIFEST", args->manifest, "the rows: a .csv or .jsonl file")->required();
  CLI::App* status = sub->add_subcommand("status", "Counts of a sweep's rows and every row not ok");
  status->add_option("DIR", args->dir, "the sweep folder")->required();
  CLI::App* collect =
      sub->add_subcommand("collect", "Write DIR/summary.csv, summary.json and summary.svg");
  collect->add_option("DIR", args->dir, "the sweep folder")->required();
  CLI::App* task = sub->add_subcommand("task", "One Slurm array task of a sweep (run by Slurm)");
  task->group("");  // not listed: sbatch scripts call it
  task->add_option("DIR", args->dir, "the sweep folder")->required();
  task->add_option("--submission", args->submission, "submission number")->required();
  task->add_option("--task", args->task, "array task index")->required();

  return [args, check, status, collect, task] {
    if (check->parsed()) return run_check(*args);
    if (status->parsed()) return run_status(*args);
    if (collect->parsed()) return run_collect(*args);
    if (task->parsed())
      return sweep::run_task(args->dir, args->submission, args->task, cancel_flag());
    return run_sweep(*args);
  };
}

}  // namespace gridshell::cli
