// Subcommands of the gridshell CLI; each registers itself on the CLI11 app and returns the
// function that runs it (exit code).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <optional>
#include <string>

#include "gridshell/deployment_job.h"

namespace gridshell::cli {

using Command = std::function<int()>;

Command add_patch_command(CLI::App& app);
Command add_geodesic_command(CLI::App& app);
Command add_design_command(CLI::App& app);
Command add_examples_command(CLI::App& app);
Command add_bench_command(CLI::App& app);
Command add_simulate_command(CLI::App& app);

/// Simulation options shared by `simulate` and `run`.
struct SimulationFlags {
  std::string notches = "both";
  std::string material;  // empty: lime-wood, or custom when --young/--shear are given
  std::optional<double> young, shear;
  std::string unit;
  double mu = 0.1;
  double edges_per_interval = 2;
  int max_iterations = 2000;
  std::string solver = "newton";
  int threads = 0;
};
void add_simulation_flags(CLI::App* sub, SimulationFlags& flags);
/// Resolved and validated (InvalidInput names the flag).
v1::SimulationOptions simulation_options_from_flags(const SimulationFlags& flags);
/// deployment.json, deployed.obj, deviation.ply (+ the without-notches views), atomically.
void write_deployment_files(const DeploymentJob& job, const std::string& out);
void print_deployment_summary(const DeploymentJob& job, const std::string& input,
                              const std::string& out);
Command add_health_command(CLI::App& app);

/// `gridshell bench service` (bench_service.cpp): `repeats` scales the requests per client
/// count; `write_section` replaces a marked section of the benchmarks file.
using SectionWriter = void (*)(const std::string& path, const std::string& name,
                               const std::string& body);
int bench_service(const std::string& out, bool no_write, int repeats, SectionWriter write_section);

}  // namespace gridshell::cli
