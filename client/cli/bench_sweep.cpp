// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell bench sweep`: the sweep engines side by side on this machine (32 rows, local worker
// processes vs a Slurm job array on the same cores), Slurm's per-task overhead, and `sweep
// collect` over 10 000 synthetic finished rows. Section "sweep" of docs/benchmarks.md.
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include "bench_support.h"
#include "cli_support.h"
#include "commands.h"
#include "gridshell/batch/sweep.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::cli {
namespace {

namespace fs = std::filesystem;

struct Timed {
  double wall = 0;
  double cpu = 0;  ///< user + system CPU of the children that ended meanwhile
  int exit_code = 0;
  std::string err;
};

double children_cpu() {
  rusage usage{};
  getrusage(RUSAGE_CHILDREN, &usage);
  return usage.ru_utime.tv_sec + usage.ru_utime.tv_usec * 1e-6 + usage.ru_stime.tv_sec +
         usage.ru_stime.tv_usec * 1e-6;
}

Timed timed(const std::vector<std::string>& command) {
  const double cpu0 = children_cpu();
  const auto start = std::chrono::steady_clock::now();
  const sweep::CommandOutput out = sweep::run_command(command);
  Timed t;
  t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  t.cpu = children_cpu() - cpu0;
  t.exit_code = out.exit_code;
  t.err = out.err;
  return t;
}

std::string self() { return fs::read_symlink("/proc/self/exe").string(); }

/// 10 000 finished rows as status files (what `collect` reads), in a fresh folder.
std::string synthetic_sweep(const std::string& root, int rows) {
  const std::string dir = root + "/collect";
  fs::create_directories(dir);
  sweep::Manifest manifest;
  manifest.path = dir + "/rows.csv";
  manifest.columns = {"id", "mesh", "alpha", "members-u"};
  for (int i = 0; i < rows; ++i) {
    sweep::Row row;
    row.id = "row" + std::to_string(i);
    row.line = i + 2;
    row.mesh = "example:double-vault";
    row.values = {{"mesh", row.mesh},
                  {"alpha", std::to_string(30 + i % 40) + "deg"},
                  {"members-u", std::to_string(3 + i % 7)}};
    manifest.rows.push_back(row);
    sweep::RowStatus s;
    s.id = row.id;
    s.options = row.values;
    s.exit_code = i % 13 == 0 ? 3 : 0;
    s.status = sweep::status_of_exit_code(s.exit_code);
    s.attempt = 1;
    s.host = "node" + std::to_string(i % 100);
    s.engine = "slurm";
    s.slurm_job = "1000_" + std::to_string(i);
    s.started = "2026-12-04T12:00:00.000Z";
    s.finished = "2026-12-04T12:00:03.000Z";
    s.seconds = 3.0 + (i % 17) * 0.1;
    if (s.status == "ok")
      s.results = {{"alpha_bar", 0.5 + (i % 40) * 0.01},
                   {"members", 6.0 + i % 7},
                   {"crossings", 40.0 + i % 30},
                   {"rms_without_notches", 0.5 + (i % 97) * 1e-3},
                   {"rms_with_notches", 0.05 + (i % 89) * 1e-3},
                   {"max_bending_stress", 1e7 + i},
                   {"t_grid", 0.1},
                   {"t1", 1.2},
                   {"t2", 0.9}};
    else
      s.error = "infeasible: --alpha: 0.5 rad is outside the feasible range [0.6, 1.3] rad";
    fs::create_directories(dir + "/rows/" + row.id);
    std::ofstream(dir + "/rows/" + row.id + "/status.json") << sweep::to_json(s);
  }
  sweep::write_sweep_file(dir, manifest);
  return dir;
}

std::string fixed(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

}  // namespace

int bench_sweep(const std::string& out, bool no_write, int repeats) {
  const std::string root =
      fs::temp_directory_path() / ("gridshell-bench-sweep-" + std::to_string(getpid()));
  fs::create_directories(root);
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  std::string table = "Measured on " + today() + ", " + cpu_name() + ", " + std::to_string(cores) +
                      " cores, by `gridshell bench sweep --repeats " + std::to_string(repeats) +
                      "`.\n\n";

  // collect over 10 000 rows: the command as a whole process (what a user waits for).
  const std::string dir = synthetic_sweep(root, 10000);
  std::vector<double> walls, cpus;
  for (int r = 0; r < std::max(3, repeats); ++r) {
    const Timed t = timed({self(), "sweep", "collect", dir});
    if (t.exit_code != 0) throw std::runtime_error("sweep collect failed: " + t.err);
    walls.push_back(t.wall);
    cpus.push_back(t.cpu);
  }
  table += "| `gridshell sweep collect` | rows | wall s (median of " +
           std::to_string(walls.size()) + ") | CPU s (median) | target |\n|---|---|---|---|---|\n";
  table += "| 10 000 synthetic finished rows (status.json files) | 10000 | " +
           fixed(median(walls), 3) + " | " + fixed(median(cpus), 3) + " | < 2 s |\n\n";
  std::cerr << "bench sweep: collect " << median(walls) << " s\n";

  // The engines: the same 32 rows, local workers (one per core) and a Slurm array (one CPU per
  // task), in alternating rounds.
  const bool slurm = sweep::run_command({"sinfo", "-h"}).exit_code == 0;
  std::string manifest = "id,mesh,members-u,members-v\n";
  for (int i = 0; i < 32; ++i)
    manifest += "r" + std::to_string(i) + ",example:archway," + std::to_string(4 + i % 8) + "," +
                std::to_string(4 + i / 8) + "\n";
  const std::string manifest_path = root + "/rows.csv";
  std::ofstream(manifest_path) << manifest;
  std::vector<double> local_walls, slurm_walls, ratios;
  for (int r = 0; r < repeats; ++r) {
    const std::string local_dir = root + "/local-" + std::to_string(r);
    const Timed local = timed({self(), "sweep", manifest_path, "--out", local_dir, "--quiet",
                               "--workers", std::to_string(cores)});
    if (local.exit_code != 0) throw std::runtime_error("local sweep failed: " + local.err);
    local_walls.push_back(local.wall);
    std::cerr << "bench sweep: local " << local.wall << " s\n";
    if (!slurm) continue;
    const std::string slurm_dir = root + "/slurm-" + std::to_string(r);
    const Timed on_slurm = timed({self(), "sweep", manifest_path, "--out", slurm_dir, "--quiet",
                                  "--engine", "slurm", "--poll-seconds", "1"});
    if (on_slurm.exit_code != 0) throw std::runtime_error("slurm sweep failed: " + on_slurm.err);
    slurm_walls.push_back(on_slurm.wall);
    ratios.push_back(local.wall / on_slurm.wall);
    std::cerr << "bench sweep: slurm " << on_slurm.wall << " s\n";
    // The same results (RMS bit for bit) from both engines.
    const auto a = sweep::row_statuses(local_dir, sweep::read_sweep_file(local_dir));
    const auto b = sweep::row_statuses(slurm_dir, sweep::read_sweep_file(slurm_dir));
    for (size_t i = 0; i < a.size(); ++i)
      for (const char* result : {"alpha_bar", "members", "crossings", "rms_without_notches",
                                 "rms_with_notches", "max_bending_stress"})  // not the timings
        if (a[i].results.at(result) != b[i].results.at(result))
          throw std::runtime_error("row " + a[i].id + ": the engines disagree on " + result);
  }
  table +=
      "| 32 rows (archway at the default resolution, 4–11 × 4–7 members) | wall s (median of " +
      std::to_string(repeats) + ") | rows / minute | throughput vs local |\n|---|---|---|---|\n";
  table += "| local engine, " + std::to_string(cores) + " workers | " +
           fixed(median(local_walls), 1) + " | " + fixed(32 * 60 / median(local_walls), 1) +
           " | 1 |\n";
  if (slurm) {
    table += "| Slurm engine, job array on the same " + std::to_string(cores) +
             " CPUs (one-node cluster, scripts/slurm-local.sh) | " + fixed(median(slurm_walls), 1) +
             " | " + fixed(32 * 60 / median(slurm_walls), 1) + " | " + fixed(median(ratios), 3) +
             " (target ≥ 0.9) |\n\n";
    // Slurm's own cost of a task: arrays of empty tasks, wall time per task and CPU.
    std::vector<double> per_task;
    for (int r = 0; r < std::max(3, repeats); ++r) {
      const auto start = std::chrono::steady_clock::now();
      const sweep::CommandOutput job = sweep::run_command(
          {"sbatch", "--parsable", "--array=0-15", "--output=/dev/null", "--wrap=true"});
      if (job.exit_code != 0) throw std::runtime_error("sbatch failed: " + job.err);
      const std::string id = job.out.substr(0, job.out.find_first_of(";\n"));
      for (int i = 0; i < 6000; ++i) {  // every 0.1 s, at most 10 minutes
        const auto queue = sweep::run_command({"squeue", "-h", "-j", id, "-o", "%i"});
        if (queue.exit_code != 0 || queue.out.find_first_not_of(" \n") == std::string::npos) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
      per_task.push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() * cores /
          16);
    }
    table +=
        "Slurm's overhead per array task (an array of 16 tasks running `true`, submitted "
        "polling squeue every 0.1 s: wall time × CPUs / tasks, median of " +
        std::to_string(per_task.size()) + "): " + fixed(median(per_task), 2) +
        " s per task and CPU.\n";
  } else {
    table +=
        "\nNo Slurm here (`sinfo` does not answer): start one with "
        "`bash scripts/slurm-local.sh start` to compare the engines.\n";
  }
  fs::remove_all(root);
  publish_section(out, "sweep", table, no_write);
  return 0;
}

}  // namespace gridshell::cli
