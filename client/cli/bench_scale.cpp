// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell bench scale` (issue 17 item 4): whole `gridshell design` runs on examples written at
// several vertex counts, each in its own process (this program, or a --baseline build side by
// side in the same run), with its wall time, CPU time (all threads, from wait4: independent of
// what else the shared machine runs) and peak resident memory (ru_maxrss), and the growth
// exponent of the CPU time between consecutive sizes. Section "scale" of docs/benchmarks.md.
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "bench_support.h"
#include "commands.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"

extern char** environ;

namespace gridshell::cli {
namespace {

// The baseline (a pre-issue-17 build) took 215 s and 5.3 GB at 59k vertices: not run above this.
constexpr int kMaxBaselineVertices = 20000;

struct Run {
  bool ok = false;
  double wall = 0, cpu = 0, peak_mib = 0;
  double map_error = 0;
};

/// Runs `argv` to the end; its wall time, CPU time and peak RSS from wait4.
Run run_process(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  const auto start = std::chrono::steady_clock::now();
  pid_t pid = 0;
  Run run;
  const int spawned = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return run;
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid) return run;
  run.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.cpu = usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
            1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  run.peak_mib = usage.ru_maxrss / 1024.0;  // KiB
  run.ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  return run;
}

std::string format(const char* pattern, double value) {
  char text[64];
  std::snprintf(text, sizeof text, pattern, value);
  return text;
}

}  // namespace

int bench_scale(const std::vector<std::string>& examples, const std::vector<int>& sizes,
                int largest_examples, const std::string& baseline, const std::string& out,
                bool no_write) {
  if (examples.empty()) throw InvalidInput("--examples", "give at least one example");
  if (largest_examples < 0) throw InvalidInput("--largest-examples", "must be >= 0");
  if (!baseline.empty() && !std::filesystem::exists(baseline))
    throw InvalidInput("--baseline", "no such program: " + baseline);
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("gridshell-bench-scale-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::ifstream load_in("/proc/loadavg");
  double load_start = -1;
  load_in >> load_start;

  std::ostringstream table;
  // The heading and the command, so that a rerun writes the whole section again.
  std::string command = "gridshell bench scale --sizes";
  for (std::size_t k = 0; k < sizes.size(); ++k)
    command += (k ? "," : " ") + std::to_string(sizes[k]);
  command += " --examples";
  for (std::size_t k = 0; k < examples.size(); ++k) command += (k ? "," : " ") + examples[k];
  command += " --largest-examples " + std::to_string(largest_examples);
  if (!baseline.empty()) command += " --baseline " + baseline;
  table << "## Designs at scale (issue 17)\n\n`" << command << "`\n\n";
  table << "Whole `gridshell design` (default options) in its own process on " << cpu_name() << ", "
        << today() << ". CPU = user + system time of the process (all threads, wait4), "
        << "independent of the machine's load; peak = its maximal resident memory; exponent = "
           "growth of the CPU time with the vertex count between consecutive sizes (t ~ n^k)."
        << (baseline.empty() ? "" : " Baseline: `" + baseline + "`, run side by side.")
        << "\n\n| example | vertices | wall s | CPU s | peak MiB | k | map error |"
        << (baseline.empty() ? "" : " baseline wall s | baseline CPU s | baseline peak MiB |")
        << "\n|---|---:|---:|---:|---:|---:|---:|" << (baseline.empty() ? "" : "---:|---:|---:|")
        << "\n";
  for (std::size_t e = 0; e < examples.size(); ++e) {
    const double base_vertices = make_example(examples[e]).mesh.vertex_count();
    double last_n = 0, last_cpu = 0;
    for (std::size_t s = 0; s < sizes.size(); ++s) {
      // The largest size only for the first `largest_examples` examples (a 64k design of every
      // example is minutes of a shared machine).
      if (s + 1 == sizes.size() && sizes.size() > 1 &&
          e >= static_cast<std::size_t>(largest_examples))
        continue;
      const ExampleSurface example = make_example(examples[e], std::sqrt(sizes[s] / base_vertices));
      const std::string mesh = (dir / (examples[e] + std::to_string(sizes[s]) + ".obj")).string();
      save_obj(example.mesh, mesh);
      std::string corners;
      for (int c : example.corners) corners += (corners.empty() ? "" : ",") + std::to_string(c);
      const auto design = [&](const std::string& program, const std::string& tag) {
        const std::string folder = (dir / tag).string();
        Run run = run_process(
            {program, "design", mesh, "--corners", corners, "--out", folder, "--quiet"});
        std::ifstream report(folder + "/report.json");
        if (run.ok && report) {
          const auto json = nlohmann::json::parse(report, nullptr, false);
          if (json.is_object() && json.contains("map_error"))
            run.map_error = json["map_error"].get<double>();
        }
        return run;
      };
      const Run run = design(self, "new");
      const int n = example.mesh.vertex_count();
      table << "| " << examples[e] << " | " << n << " | ";
      if (!run.ok) {
        table << "failed | | | | |";
      } else {
        table << format("%.2f", run.wall) << " | " << format("%.2f", run.cpu) << " | "
              << format("%.0f", run.peak_mib) << " | "
              << (last_n > 0 ? format("%.2f", std::log(run.cpu / last_cpu) / std::log(n / last_n))
                             : std::string(""))
              << " | " << format("%.1e", run.map_error) << " |";
        last_n = n, last_cpu = run.cpu;
      }
      if (!baseline.empty() && n > kMaxBaselineVertices) {
        table << " not run | | |";  // minutes and gigabytes: see the note under the table
      } else if (!baseline.empty()) {
        const Run base = design(baseline, "baseline");
        if (base.ok)
          table << " " << format("%.2f", base.wall) << " | " << format("%.2f", base.cpu) << " | "
                << format("%.0f", base.peak_mib) << " |";
        else
          table << " failed | | |";
      }
      table << "\n";
      std::cerr << "bench scale: " << examples[e] << " " << n << " vertices done\n";
    }
  }
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
  std::ifstream load_out("/proc/loadavg");
  double load_end = -1;
  load_out >> load_end;
  if (!baseline.empty())
    table << "\nThe baseline is not run above " << kMaxBaselineVertices
          << " vertices (before issue 17: 215 s and 5.3 GB for double-vault at 59k vertices).\n";
  table << "\n1-minute load average of the shared machine: " << format("%.2f", load_start)
        << " at the start, " << format("%.2f", load_end) << " at the end.\n";
  publish_section(out, "scale", table.str(), no_write);
  return 0;
}

}  // namespace gridshell::cli
