// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell simulate DIR/design.json --out DIR2`: the deployment simulation of paper Section 5,
// in process or on a daemon (--server). The simulation flags are shared with `gridshell run`.
#include <google/protobuf/util/json_util.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/deployment_job.h"
#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/foundation/errors.h"
#include "remote.h"

namespace gridshell::cli {

void add_simulation_flags(CLI::App* sub, SimulationFlags& flags) {
  add_described_flags(sub, "simulation", flags.options, {"unit", "interior_anchors"});
  sub->add_option("--unit", flags.unit, described_help("simulation", "unit"));
}

/// The request's options from the flags as given; their checks are the request's
/// (resolve_simulation_options), whose fields the CLI shows as these flags. Without --material
/// the moduli override the default material's (the request then calls it "custom"); 0 means
/// the material's.
v1::SimulationOptions simulation_options_from_flags(const SimulationFlags& flags) {
  v1::SimulationOptions o;
  set_described(flags.options, o);
  o.set_unit(flags.unit);
  o.set_unit_in_meters(parse_length_unit(flags.unit, "--unit"));
  if (!flags.interior_anchors.empty() && flags.interior_anchors != "auto")
    throw InvalidInput("--interior-anchors", "expected auto, got '" + flags.interior_anchors + "'");
  o.set_interior_anchors(flags.interior_anchors);
  return o;
}

// "max normal stress 41.2 MPa = 69% of 60 MPa, max torsion stress ..." (Pa in the file).
static std::string stress_line(const v1::SimulationRun& r, const v1::SimulationOptions& o) {
  char buffer[512];
  std::string line;
  auto percent = [&](double strength, bool known, double utilization) {
    if (!known) return std::string(" (strength unknown)");
    std::snprintf(buffer, sizeof buffer, " = %.0f%% of %.3g MPa%s", 100 * utilization,
                  strength / 1e6, utilization > 1 ? " EXCEEDED" : "");
    return std::string(buffer);
  };
  std::snprintf(buffer, sizeof buffer, "max normal stress %.1f MPa", r.max_normal_stress() / 1e6);
  line = buffer;
  line += percent(o.bending_strength(), r.has_bending_utilization(), r.bending_utilization());
  std::snprintf(buffer, sizeof buffer, ", max torsion stress %.1f MPa",
                r.max_torsion_stress() / 1e6);
  line += buffer;
  line += percent(o.shear_strength(), r.has_shear_utilization(), r.shear_utilization());
  if (r.overstressed_lamellas() > 0)
    line += ", " + std::to_string(r.overstressed_lamellas()) + " lamellas overstressed";
  return line + " (" + o.material() + ")";
}

void print_deployment_summary(const v1::Deployment& d) {
  for (const v1::SimulationRun* r : {&d.without_notches(), &d.with_notches()}) {
    if (r->grid_vertices() == 0) continue;  // not run
    std::printf(
        "  %-16s RMS %.4f (max %.4f)  %d rod vertices  %d iterations  %.3f s  %s (|g| %.1e)\n",
        r->notches() ? "with notches" : "without notches", r->rms(), r->max_deviation(),
        r->grid_vertices(), r->iterations(), r->seconds(),
        r->converged() ? "converged" : "NOT converged", r->gradient_norm());
    std::printf("  %-16s %s\n", "", stress_line(*r, d.options()).c_str());
  }
  if (d.options().interior_anchors() == "auto") {
    std::string trials;
    char buffer[64];
    for (double rms : d.anchor_trial_rms()) {
      std::snprintf(buffer, sizeof buffer, "%s%.4f", trials.empty() ? "" : " -> ", rms);
      trials += buffer;
    }
    std::string goal = "no goal";
    if (d.anchor_goal_rms() > 0) {
      std::snprintf(buffer, sizeof buffer, "until RMS <= %.4g = %.4g%% of the patch diagonal",
                    d.anchor_goal_rms(), d.options().anchor_goal());
      goal = buffer;
    }
    std::printf(
        "  inner anchors   %d added automatically (RMS of the trials %s; kept while it "
        "fell by 5%% or more, %s)\n",
        d.added_anchors_size(), trials.c_str(), goal.c_str());
    for (const v1::Anchor& a : d.added_anchors())
      std::printf("                  g%d x h%d at (%.4g, %.4g, %.4g)\n", a.g(), a.h(),
                  a.position(0), a.position(1), a.position(2));
  } else if (d.has_rms_with_notches() && d.has_rms_without_notches() &&
             d.rms_with_notches() > d.rms_without_notches())
    std::printf(
        "  note            the grid with notches deviates more than without: it has likely "
        "snapped into\n"
        "                  another shape than the target's (an inner bump popping through); "
        "inner anchors\n"
        "                  can hold it (--interior-anchors auto finds them, see "
        "docs/decisions.md)\n");
}

namespace {

/// What to change for a run that stopped this way.
std::string advice(const std::string& termination) {
  if (termination.rfind("iteration cap", 0) == 0) return "raise --max-iterations";
  return "the solver found no step that lowers the energy: try a finer rod (--edges-per-interval "
         "3) or the reference solver (--solver ceres); docs/solver.md";
}

int unconverged_error(const std::vector<std::string>& runs, const std::string& out) {
  if (runs.empty()) return 0;
  std::string line = "error: not converged: ";
  for (size_t i = 0; i < runs.size(); ++i) line += (i ? "; " : "") + runs[i];
  std::cerr << line << ". The files in " << out
            << " are kept for diagnosis, marked \"converged\": false; they are not a result.\n";
  return 4;
}

}  // namespace

int unconverged_exit(const v1::Deployment& d, const std::string& out) {
  std::vector<std::string> runs;
  char buffer[160];
  for (const v1::SimulationRun* r : {&d.without_notches(), &d.with_notches()}) {
    if (r->grid_vertices() == 0 || r->converged()) continue;
    std::snprintf(buffer, sizeof buffer, " after %d iterations, tolerance %.1e", r->iterations(),
                  r->gradient_tolerance());
    runs.push_back(std::string(r->notches() ? "with notches: " : "without notches: ") +
                   r->termination() + buffer + ": " + advice(r->termination()));
  }
  return unconverged_error(runs, out);
}

int unconverged_exit(const v1::LayoutDeployment& d, const std::string& out) {
  if (d.converged()) return 0;
  std::vector<std::string> runs;
  for (const auto& p : d.patches())
    if (!p.converged())
      runs.push_back("patch " + p.name() + " alone (its deployment.json in patches/" + p.name() +
                     "/ says why)");
  for (const auto& [joined, what] :
       {std::pair{&d.joined_without_notches(), "the whole joined without notches: "},
        std::pair{&d.joined_with_notches(), "the whole joined with notches: "}})
    if (joined->iterations() > 0 && !joined->converged())
      runs.push_back(what + joined->termination() + ": " + advice(joined->termination()));
  if (runs.empty()) runs.push_back("a run of the layout (deployment.json)");
  return unconverged_error(runs, out);
}

namespace {

struct SimulateArguments {
  std::string design;
  OutputFlags output;
  SimulationFlags flags;
};

int run_simulate(const SimulateArguments& args) {
  v1::SimulateRequest request;
  *request.mutable_design() = read_design_file(args.design);
  *request.mutable_options() = simulation_options_from_flags(args.flags);
  request.set_design_name(std::filesystem::path(args.design).filename().string());
  prepare_output_folder(args.output.out);  // fail early on an unusable --out
  const Progress progress = make_progress(args.output.quiet);
  v1::SimulateResult result;
  field_context().design = args.design;  // problems inside the design file name the file
  if (args.output.remote.remote()) {
    prepare_simulation_options(request.options());  // checked here, before sending
    result = RemoteClient(args.output.remote).simulate(request, progress);
  } else {
    result = gridshell::run_simulate(request, progress, {args.output.threads});
  }
  finish_progress();
  write_files(simulate_files(result), args.output.out);
  print_heading("simulate", args.design, args.output);
  print_deployment_summary(result.deployment());
  std::string written = "deployment.json";
  for (const v1::File& view : result.views()) written += " " + view.name();
  std::printf("  wrote           %s\n", written.c_str());
  return unconverged_exit(result.deployment(), args.output.out);
}

}  // namespace

Command add_simulate_command(CLI::App& app) {
  auto args = std::make_shared<SimulateArguments>();
  CLI::App* sub = app.add_subcommand(
      "simulate", "Simulate the deployment of a design (discrete elastic rods, paper Section 5)");
  sub->add_option("DESIGN", args->design, "design.json written by 'gridshell design'")->required();
  add_simulation_flags(sub, args->flags);
  // `run` has --interior-anchors among its design flags (N or auto).
  sub->add_option("--interior-anchors", args->flags.interior_anchors,
                  "auto: add inner anchors one at a time where the deployment strays farthest "
                  "while RMS falls by 5% or more; writes design-anchored.json with them")
      ->check(CLI::IsMember({"auto"}));
  add_output_flags(sub, args->output);
  return [args] { return run_simulate(*args); };
}

}  // namespace gridshell::cli
