// `gridshell simulate DIR/design.json --out DIR2`: the deployment simulation of paper Section 5.
#include <google/protobuf/util/json_util.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/deployment_job.h"
#include "gridshell/errors.h"
#include "gridshell/mesh_io.h"

namespace gridshell::cli {
namespace {

struct SimulateArguments {
  std::string design;
  std::string out;
  SimulationFlags flags;
  bool quiet = false;
};

v1::Design read_design(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidInput(path + ": cannot open the design file");
  std::stringstream text;
  text << in.rdbuf();
  v1::Design design;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(text.str(), &design, options);
  if (!status.ok())
    throw InvalidInput(path + ": not a gridshell design file: " + std::string(status.message()));
  return design;
}

int run_simulate(const SimulateArguments& args) {
  const v1::Design design = read_design(args.design);
  const v1::SimulationOptions options = simulation_options_from_flags(args.flags);
  std::filesystem::create_directories(args.out);
  const Progress progress = make_progress(args.quiet);
  const DeploymentJob job = run_deployment_job(
      design, options, std::filesystem::path(args.design).filename().string(), progress);
  finish_progress();
  write_deployment_files(job, args.out);
  print_deployment_summary(job, args.design, args.out);
  return 0;
}

}  // namespace

void add_simulation_flags(CLI::App* sub, SimulationFlags& flags) {
  sub->add_option("--notches", flags.notches, "simulate with notches, without, or both")
      ->check(CLI::IsMember({"on", "off", "both"}))
      ->capture_default_str();
  sub->add_option("--material", flags.material,
                  "lime-wood | birch-plywood | beech-wood | gfrp | "
                  "aluminium | steel | hdpe")
      ->capture_default_str();
  sub->add_option("--young", flags.young, "Young's modulus E in Pa (overrides the material's)");
  sub->add_option("--shear", flags.shear, "shear modulus G in Pa (overrides the material's)");
  sub->add_option("--unit", flags.unit,
                  "the model's length unit: mm | cm | m | in | ft | metres per unit (energies "
                  "in J)");
  sub->add_option("--mu", flags.mu, "pseudo-friction weight mu of E_p")->capture_default_str();
  sub->add_option("--edges-per-interval", flags.edges_per_interval,
                  "rod edges per interval between crossings")
      ->capture_default_str();
  sub->add_option("--max-iterations", flags.max_iterations, "solver iteration cap")
      ->capture_default_str();
  sub->add_option("--threads", flags.threads, "worker threads (0 = all cores)")
      ->capture_default_str();
  sub->add_option("--solver", flags.solver,
                  "newton (default) | ceres (Levenberg-Marquardt, the reference)")
      ->check(CLI::IsMember({"newton", "ceres"}))
      ->capture_default_str();
}

v1::SimulationOptions simulation_options_from_flags(const SimulationFlags& flags) {
  v1::SimulationOptions o;
  o.set_notches(flags.notches);
  o.set_solver(flags.solver);
  if (!flags.material.empty()) o.set_material(flags.material);
  if (flags.young) {
    if (!(*flags.young > 0)) throw InvalidInput("--young: must be a positive number of pascal");
    o.set_young_modulus(*flags.young);
  }
  if (flags.shear) {
    if (!(*flags.shear > 0)) throw InvalidInput("--shear: must be a positive number of pascal");
    o.set_shear_modulus(*flags.shear);
  }
  if ((flags.young || flags.shear) && flags.material.empty()) o.set_material("custom");
  o.set_unit(flags.unit);
  o.set_unit_in_meters(parse_length_unit(flags.unit, "--unit"));
  if (!(flags.mu > 0)) throw InvalidInput("--mu: must be a positive number");
  o.set_friction_mu(flags.mu);
  if (!(flags.edges_per_interval >= 1 && flags.edges_per_interval <= 64))
    throw InvalidInput("--edges-per-interval: must be between 1 and 64");
  o.set_edges_per_interval(flags.edges_per_interval);
  if (flags.max_iterations < 1) throw InvalidInput("--max-iterations: must be at least 1");
  if (flags.threads < 0) throw InvalidInput("--threads: must be >= 0 (0 = all cores)");
  o.set_max_iterations(flags.max_iterations);
  try {
    return resolve_simulation_options(o);
  } catch (const InvalidInput& e) {
    throw InvalidInput(std::string("--") + e.what());
  }
}

void write_deployment_files(const DeploymentJob& job, const std::string& out) {
  const std::filesystem::path dir(out);
  write_file_atomically((dir / "deployment.json").string(), to_json(job.deployment) + "\n");
  write_file_atomically((dir / "deployed.obj").string(), job.deployed_obj);
  write_file_atomically((dir / "deviation.ply").string(), job.deviation_ply);
  if (!job.deployed_without_notches_obj.empty()) {
    write_file_atomically((dir / "deployed_without_notches.obj").string(),
                          job.deployed_without_notches_obj);
    write_file_atomically((dir / "deviation_without_notches.ply").string(),
                          job.deviation_without_notches_ply);
  }
}

void print_deployment_summary(const DeploymentJob& job, const std::string& input,
                              const std::string& out) {
  std::printf("simulate %s -> %s\n", input.c_str(), out.c_str());
  for (const auto* run : {&job.without_notches, &job.with_notches}) {
    if (!*run) continue;
    const DeploymentRun& r = **run;
    double stress = 0;
    for (const SimulatedLamella& l : r.lamellas) stress = std::max(stress, l.max_bending_stress);
    std::printf(
        "  %-16s RMS %.4f (max %.4f)  %d rod vertices  %d iterations  %.3f s  %s (|g| %.1e)  "
        "max bending stress %.1f MPa\n",
        r.notches ? "with notches" : "without notches", r.rms, r.max_deviation, r.grid_vertices,
        r.iterations, r.seconds, r.converged ? "converged" : "NOT converged", r.gradient_norm,
        stress / 1e6);
  }
  std::printf("  wrote           deployment.json deployed.obj deviation.ply%s\n",
              job.deployed_without_notches_obj.empty()
                  ? ""
                  : " deployed_without_notches.obj deviation_without_notches.ply");
}

Command add_simulate_command(CLI::App& app) {
  auto args = std::make_shared<SimulateArguments>();
  CLI::App* sub = app.add_subcommand(
      "simulate", "Simulate the deployment of a design (discrete elastic rods, paper Section 5)");
  sub->add_option("DESIGN", args->design, "design.json written by 'gridshell design'")->required();
  sub->add_option("--out", args->out, "output folder")->required();
  add_simulation_flags(sub, args->flags);
  sub->add_flag("--quiet", args->quiet, "no progress line");
  return [args] { return run_simulate(*args); };
}

}  // namespace gridshell::cli
