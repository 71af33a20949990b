// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell run MESH --corners ... --out DIR`: patch, design and simulation in one go, with a
// summary like the paper's Table 1 (next to the paper's values for its seven models).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/files.h"
#include "gridshell/application/layout.h"
#include "gridshell/application/options.h"
#include "gridshell/application/requests.h"
#include "paper_table1.h"
#include "remote.h"

namespace gridshell::cli {
namespace {

struct RunArguments {
  LayoutFlags layout;  // auto or a layout file: several patches (docs/multi-patch.md)
  DesignFlags design;
  SimulationFlags simulation;
  OutputFlags output;
};

void row(const char* label, const std::string& ours, const std::string& paper) {
  if (paper.empty())
    std::printf("  %-22s %20s\n", label, ours.c_str());
  else
    std::printf("  %-22s %20s   %s\n", label, ours.c_str(), paper.c_str());
}

std::string number(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

void print_table(const v1::RunResult& result, const std::string& input) {
  const PaperModel* paper = paper_model_for(input);
  auto theirs = [&](double value, int decimals) {
    return paper ? number(value, decimals) : std::string();
  };
  const v1::DesignReport& r = result.design().report();
  const v1::Deployment& d = result.simulation().deployment();
  // The patch's extent, sorted like Table 1 (width >= depth; height last).
  Vec3 lo = Vec3::Constant(1e300), hi = -lo;
  const auto& vertices = result.design().design().patch().vertices();
  for (const auto& v : vertices.values()) {
    const auto& p = v.list_value();
    const Vec3 q(p.values(0).number_value(), p.values(1).number_value(),
                 p.values(2).number_value());
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const Vec3 size = hi - lo;
  std::printf("\n  %-22s %20s   %s\n", "", "gridshell",
              paper ? ("paper, Table 1 (" + std::string(paper->name) + ")").c_str() : "");
  row("width x depth x height",
      number(std::max(size.x(), size.y()), 1) + " x " + number(std::min(size.x(), size.y()), 1) +
          " x " + number(size.z(), 1),
      paper ? number(paper->width, 1) + " x " + number(paper->depth, 1) + " x " +
                  number(paper->height, 1)
            : "");
  row("|M_V| patch vertices", std::to_string(r.patch_vertices()),
      paper ? std::to_string(paper->mesh_vertices) : "");
  row("|G_V| grid vertices", std::to_string(d.grid_vertices()),
      paper ? std::to_string(paper->grid_vertices) : "");
  row("t_smooth s", number(r.t_smooth(), 3),
      paper ? (paper->t_smooth > 0 ? number(paper->t_smooth, 2) : "-") : "");
  row("t_grid s", number(r.t_grid(), 3), theirs(paper ? paper->t_grid : 0, 2));
  if (d.has_rms_without_notches())
    row("RMS1 (no notches)", number(d.rms_without_notches(), 3),
        theirs(paper ? paper->rms1 : 0, 2));
  if (d.has_rms_with_notches())
    row("RMS2 (notches)", number(d.rms_with_notches(), 3), theirs(paper ? paper->rms2 : 0, 2));
  if (d.has_seconds_without_notches())
    row("t1 s", number(d.seconds_without_notches(), 2), theirs(paper ? paper->t1 : 0, 2));
  if (d.has_seconds_with_notches())
    row("t2 s", number(d.seconds_with_notches(), 2), theirs(paper ? paper->t2 : 0, 2));
  row("converged", d.converged() ? "yes" : "NO", "");
}

/// `run MESH --layout FILE`: every patch of the layout designed and simulated, the whole measured.
int run_layout(const RunArguments& args) {
  const InputMesh input = load_input(args.design.mesh);
  const v1::LayoutRunRequest request =
      layout_run_request(args.layout, args.design, args.simulation, input);
  prepare_output_folder(args.output.out);
  const Progress progress = make_progress(args.output.quiet);
  v1::LayoutRunResult result = args.output.remote.remote()
                                   ? RemoteClient(args.output.remote).run_layout(request, progress)
                                   : run_layout_run(request, progress, {args.output.threads});
  finish_progress();
  write_layout_as_given(*result.mutable_layout()->mutable_report(), input);
  write_layout_as_given(*result.mutable_design()->mutable_layout(), input);
  const LayoutRunFiles files = layout_run_files(result);
  write_files(files.whole, args.output.out);
  const std::filesystem::path out(args.output.out);
  for (const auto& [name, bundle] : files.patches)
    write_files(bundle, (out / "patches" / name).string());

  print_heading("run", args.design.mesh, args.output);
  std::printf("  layout          %s\n", args.layout.layout.c_str());
  print_automatic_layout(result.design().layout());
  const v1::LayoutReport::PatchSummary* failed = print_layout_report(result.design().layout());
  const v1::LayoutDeployment& d = result.deployment();
  const double percent = d.diagonal() > 0 ? 100 / d.diagonal() : 0;
  for (const v1::LayoutDeployment::PatchDeployment& p : d.patches()) {
    const double alone = p.has_rms_with_notches() ? p.rms_with_notches() : p.rms_without_notches();
    std::printf("  %-6s deployed %d grid vertices, alone RMS%s %.4g (%.3f %% of the diagonal)%s",
                p.name().c_str(), p.grid_vertices(),
                p.has_rms_with_notches() ? "2 (notches)" : "1 (no notches)", alone, percent * alone,
                p.converged() ? "" : ", NOT converged");
    if (p.has_joined_rms())
      std::printf(", in the whole %.4g (%.3f %%)", p.joined_rms(), percent * p.joined_rms());
    std::printf("\n");
  }
  std::printf("  seam bolts      %d on %d seams\n", result.design().seam_bolts(),
              result.design().seams_size());
  if (d.seams_joined()) {
    std::printf(
        "  seam gaps       largest %.4g (%.3f %% of the diagonal) after joining, %.4g "
        "(%.3f %%) before\n",
        d.max_seam_gap(), percent * d.max_seam_gap(), d.max_seam_gap_before_joining(),
        percent * d.max_seam_gap_before_joining());
    std::printf("  joining force   largest bolt %.4g %s\n", d.max_bolt_force(),
                d.force_unit().c_str());
  } else {
    std::printf(
        "  seam gaps       largest %.4g (%.3f %% of the diagonal), before joining: the "
        "seams are not joined%s\n",
        d.max_seam_gap(), percent * d.max_seam_gap(),
        d.joined_with_notches().termination().empty() &&
                d.joined_without_notches().termination().empty()
            ? ""
            : (" (" + d.joined_with_notches().termination() +
               d.joined_without_notches().termination() + ")")
                  .c_str());
  }
  for (const auto& [joined, what] : {std::pair{&d.joined_without_notches(), "RMS1"},
                                     std::pair{&d.joined_with_notches(), "RMS2"}})
    if (joined->iterations() > 0)
      std::printf("  whole joined    %s, %d iterations, %d anchors%s, %.2f s%s\n", what,
                  joined->iterations(), joined->anchors(),
                  joined->held_by().empty()
                      ? ""
                      : (" (closed: it stands on " + joined->held_by() + ")").c_str(),
                  joined->seconds(),
                  joined->converged() ? "" : (", NOT converged: " + joined->termination()).c_str());
  if (d.has_rms_without_notches())
    std::printf("  whole RMS1      %.4g (%.3f %% of the diagonal %.4g), no notches\n",
                d.rms_without_notches(), percent * d.rms_without_notches(), d.diagonal());
  if (d.has_rms_with_notches())
    std::printf("  whole RMS2      %.4g (%.3f %% of the diagonal %.4g), notches\n",
                d.rms_with_notches(), percent * d.rms_with_notches(), d.diagonal());
  if (d.has_rms_before_joining())
    std::printf("  patches alone   RMS %.4g (%.3f %%), each deployed on its own\n",
                d.rms_before_joining(), percent * d.rms_before_joining());
  std::printf("  converged       %s\n", d.converged() ? "yes" : "NO");
  std::printf("  time            %.2f s\n", d.seconds());
  std::printf(
      "  wrote           layout.json layout.obj layout.svg design.json deployment.json "
      "deployed.obj deviation.ply, patches/<name>/ for %zu patches\n",
      files.patches.size());
  if (failed)
    throw Infeasible(failed->problem_field(), failed->problem() + " (patch " + failed->name() +
                                                  "; every patch's checks: layout.json)");
  return unconverged_exit(d, args.output.out);
}

int run_run(const RunArguments& args) {
  if (!args.layout.layout.empty()) return run_layout(args);
  check_no_layout_flags(args.layout);
  // Both requests are checked before any work; the design is written as soon as it exists, so
  // a simulation that is cancelled or fails leaves it in --out.
  const v1::DesignRequest design_request_message = design_request(args.design);
  v1::SimulateRequest simulate_request;
  SimulationFlags simulation = args.simulation;
  if (automatic_interior_anchors(args.design)) simulation.interior_anchors = "auto";
  *simulate_request.mutable_options() = simulation_options_from_flags(simulation);
  simulate_request.set_design_name("design.json");
  prepare_output_folder(args.output.out);  // fail early on an unusable --out
  const Progress progress = make_progress(args.output.quiet);
  prepare_simulation_options(simulate_request.options());
  const bool remote = args.output.remote.remote();
  std::optional<RemoteClient> client;
  v1::RunResult result;
  if (remote) {
    // design() checks the request (prepare_design) before its call: bad options fail first.
    client.emplace(args.output.remote);
    *result.mutable_design() = client->design(design_request_message, progress);
  } else {
    *result.mutable_design() =
        gridshell::run_design(design_request_message, progress, {args.output.threads});
  }
  write_files(design_files(result.design()), args.output.out);
  *simulate_request.mutable_design() = result.design().design();
  if (remote)
    *result.mutable_simulation() = client->simulate(simulate_request, progress);
  else
    *result.mutable_simulation() =
        gridshell::run_simulate(simulate_request, progress, {args.output.threads});
  finish_progress();
  write_files(simulate_files(result.simulation()), args.output.out);
  print_heading("run", args.design.mesh, args.output);
  print_design_summary(result.design());
  print_deployment_summary(result.simulation().deployment());
  print_table(result, args.design.mesh);
  std::string written;
  for (const auto& [name, contents] : run_files(result)) written += " " + name;
  std::printf("\n  wrote          %s\n", written.c_str());
  return unconverged_exit(result.simulation().deployment(), args.output.out);
}

}  // namespace

v1::LayoutRunRequest layout_run_request(const LayoutFlags& layout, const DesignFlags& design,
                                        SimulationFlags simulation, const InputMesh& input) {
  if (!design.corners.empty())
    throw InvalidInput("--corners", "give either --corners (one patch) or --layout (several)");
  v1::LayoutRunRequest request;
  LayoutChoice choice = layout_choice(layout.layout, layout.automatic, input);
  *request.mutable_layout() = std::move(choice.layout);
  if (choice.automatic) {
    *request.mutable_automatic() = *choice.automatic;
    prepare_auto_layout_options(*choice.automatic);
  }
  *request.mutable_mesh() = request_mesh(input);
  *request.mutable_design() = design_options(design);
  DesignInputs checked;
  prepare_design_options(request.design(), checked);
  if (automatic_interior_anchors(design)) simulation.interior_anchors = "auto";
  *request.mutable_simulation() = simulation_options_from_flags(simulation);
  prepare_simulation_options(request.simulation());
  return request;
}

void check_no_layout_flags(const LayoutFlags& layout) {
  for (const auto& [name, value] : layout.automatic.values)
    if (value) throw InvalidInput(option_spec("layout", name).flag, "only with --layout auto");
}

void add_layout_flags(CLI::App* sub, LayoutFlags& flags) {
  sub->add_option("--layout", flags.layout,
                  std::string("several patches instead of one (--corners), writing the whole and "
                              "patches/<name>/: ") +
                      kLayoutHelp);
  add_described_flags(sub, "layout", flags.automatic);
}

Command add_run_command(CLI::App& app) {
  auto args = std::make_shared<RunArguments>();
  CLI::App* sub = app.add_subcommand(
      "run", "Patch, design and simulate in one go, with a Table 1-like summary");
  add_design_flags(sub, args->design);
  add_layout_flags(sub, args->layout);
  add_simulation_flags(sub, args->simulation);
  add_output_flags(sub, args->output);
  return [args] { return run_run(*args); };
}

}  // namespace gridshell::cli
