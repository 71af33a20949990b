// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell design MESH --corners ... --out DIR`: the grid design of paper Section 4, in
// process or on a daemon (--server). The design flags are shared with `gridshell run`.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numbers>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/files.h"
#include "gridshell/application/options.h"
#include "gridshell/application/requests.h"
#include "remote.h"

namespace gridshell::cli {

void add_output_flags(CLI::App* sub, OutputFlags& flags, bool with_threads) {
  sub->add_option("--out", flags.out, "output folder")->required();
  if (with_threads)
    sub->add_option("--threads", flags.threads, "worker threads, in-process only (0 = all cores)")
        ->check(CLI::Range(0, 4096))
        ->capture_default_str();
  sub->add_flag("--quiet", flags.quiet, "no progress line");
  add_remote_options(sub, flags.remote);
}

void print_heading(const char* command, const std::string& input, const OutputFlags& flags) {
  std::printf("%s %s -> %s%s\n", command, input.c_str(), flags.out.c_str(),
              flags.remote.remote() ? (" on " + flags.remote.server).c_str() : "");
}

void add_design_flags(CLI::App* sub, DesignFlags& flags) {
  sub->add_option("MESH", flags.mesh, "input mesh (.obj .off .ply .stl) or example:NAME")
      ->required();
  sub->add_option(
      "--corners", flags.corners,
      "i,j,k,l | \"x,y,z;x,y,z;x,y,z;x,y,z\" | auto (default: example corners or auto)");
  add_described_flags(sub, "design", flags.options, {"interior_anchors", "auto_corner_angles"});
  sub->add_option("--interior-anchors", flags.interior_anchors,
                  described_help("design", "interior_anchors") + "; or (run only) " +
                      option_spec("simulation", "interior_anchors").help)
      ->capture_default_str();
  add_corner_angles_flag(sub, flags.corner_angles);
}

bool automatic_interior_anchors(const DesignFlags& flags) {
  return flags.interior_anchors == "auto";
}

v1::DesignRequest design_request(const DesignFlags& flags) {
  return design_request(flags, load_input(flags.mesh));
}

v1::DesignRequest design_request(const DesignFlags& flags, const InputMesh& input) {
  std::string corners_used;
  const CornerSpec spec = resolve_corners(input, flags.corners, &corners_used);
  v1::DesignRequest request;
  *request.mutable_mesh() = request_mesh(input);
  *request.mutable_corners() = to_proto(spec, corners_used);
  *request.mutable_options() = design_options(flags);
  return request;
}

v1::DesignRequest::Options design_options(const DesignFlags& flags) {
  v1::DesignRequest::Options options;
  set_described(flags.options, options);
  // auto: the design places none; the simulation adds them (run, simulate).
  if (!automatic_interior_anchors(flags)) {
    char* end = nullptr;
    const long n = std::strtol(flags.interior_anchors.c_str(), &end, 10);
    if (flags.interior_anchors.empty() || *end != '\0' || n < 0 || n > 100)
      throw InvalidInput("--interior-anchors", "expected a number from 0 to 100 or auto, got '" +
                                                   flags.interior_anchors + "'");
    options.set_interior_anchors(static_cast<int>(n));
  }
  set_corner_angles(flags.corner_angles, options.mutable_auto_corner_angles());
  return options;
}

void print_design_summary(const v1::DesignResult& result) {
  const v1::Design& d = result.design();
  const v1::DesignReport& r = result.report();
  const double deg = 180 / std::numbers::pi;
  std::printf("  patch           %d vertices, eta %.5f -> %.5f (%d smoothing iterations%s)\n",
              r.patch_vertices(), r.eta_before(), r.eta_after(), r.smoothing_iterations(),
              r.recuts() > 0 ? (", " + std::to_string(r.recuts()) + " re-cuts").c_str() : "");
  print_auto_corners(r.auto_corners());
  for (const std::string& warning : r.warnings())
    std::fprintf(stderr, "warning: %s\n", warning.c_str());
  std::printf("  alpha           %.2f deg on the surface; planar %.2f deg in [%.2f, %.2f]\n",
              d.alpha() * deg, d.alpha_bar() * deg, d.alpha_bar_range(0) * deg,
              d.alpha_bar_range(1) * deg);
  int inner = 0;
  for (const v1::Anchor& a : d.anchors()) inner += a.side() < 0;
  std::printf("  members         %d g + %d h inner (+ 4 boundary), %d crossings, %d anchors%s\n",
              r.members_g(), r.members_h(), r.crossings(), d.anchors_size(),
              inner ? (" (" + std::to_string(inner) + " inner)").c_str() : "");
  std::printf("  max notch       %.4g   max length mismatch %.2e\n", r.max_notch(),
              r.max_length_mismatch());
  std::printf("  time            %.3f s (t_smooth %.3f s, t_grid %.3f s)\n", r.seconds(),
              r.t_smooth(), r.t_grid());
}

namespace {

struct DesignArguments {
  DesignFlags design;
  OutputFlags output;
};

int run_design(const DesignArguments& args) {
  if (automatic_interior_anchors(args.design))
    throw InvalidInput("--interior-anchors",
                       "auto finds inner anchors by simulating the deployment: use gridshell run "
                       "... --interior-anchors auto, or gridshell simulate DESIGN.json "
                       "--interior-anchors auto");
  const v1::DesignRequest request = design_request(args.design);
  prepare_output_folder(args.output.out);  // fail early on an unusable --out
  const Progress progress = make_progress(args.output.quiet);
  v1::DesignResult result;
  if (args.output.remote.remote()) {
    // design() checks the request (prepare_design) before the call: bad options fail first.
    result = RemoteClient(args.output.remote).design(request, progress);
  } else {
    result = gridshell::run_design(request, progress, {args.output.threads});
  }
  finish_progress();
  write_files(design_files(result), args.output.out);
  print_heading("design", args.design.mesh, args.output);
  print_design_summary(result);
  std::printf("  wrote           design.json report.json planar.svg spatial.obj maps.svg\n");
  return 0;
}

}  // namespace

Command add_design_command(CLI::App& app) {
  auto args = std::make_shared<DesignArguments>();
  CLI::App* sub = app.add_subcommand(
      "design", "Design the planar grid for a target patch (patch stage runs first)");
  add_design_flags(sub, args->design);
  add_output_flags(sub, args->output);
  return [args] { return run_design(*args); };
}

}  // namespace gridshell::cli
