// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell patch MESH --corners ... --out DIR`: cut, check and smooth the target patch, in
// process or on a daemon (--server).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "remote.h"

namespace gridshell::cli {
namespace {

struct PatchArguments {
  std::string mesh;
  std::string corners;
  OutputFlags output;
  DescribedFlags options;  // every described patch option with a flag but --corner-angles
  std::string corner_angles;
};

int run_patch(const PatchArguments& args) {
  const InputMesh input = load_input(args.mesh);
  const CornerSpec spec = resolve_corners(input, args.corners, nullptr);
  v1::PatchRequest request;
  *request.mutable_mesh() = request_mesh(input);
  *request.mutable_corners() = to_proto(spec, args.corners);
  v1::PatchRequest::Options& options = *request.mutable_options();
  set_described(args.options, options);
  set_corner_angles(args.corner_angles, options.mutable_auto_corner_angles());

  prepare_output_folder(args.output.out);  // fail early on an unusable --out
  const Progress progress = make_progress(args.output.quiet);
  v1::PatchResult result;
  if (args.output.remote.remote()) {
    prepare_patch(request);  // bad options fail here, before a remote call
    result = RemoteClient(args.output.remote).patch(request, progress);
  } else {
    result = gridshell::run_patch(request, progress, {});
  }
  finish_progress();
  // Corner indices in file order, so the user can pass them back to --corners.
  for (v1::Corner& corner : *result.mutable_report()->mutable_corners())
    corner.set_input_vertex(file_vertex(input, corner.input_vertex()));
  auto_corners_to_file_order(input, result.mutable_report()->mutable_auto_corners());
  write_files(patch_files(result), args.output.out);

  const v1::PatchReport& r = result.report();
  const double deg = 180 / std::numbers::pi;
  print_heading("patch", args.mesh, args.output);
  std::printf("  vertices        %d (input %d), faces %d, area %.4g\n", r.vertex_count(),
              r.input_vertex_count(), r.face_count(), r.area());
  std::printf("  corner angles   %.2f %.2f %.2f %.2f deg\n", r.corner_angles(0) * deg,
              r.corner_angles(1) * deg, r.corner_angles(2) * deg, r.corner_angles(3) * deg);
  std::printf("  boundary        %.4g %.4g %.4g %.4g\n", r.boundary_lengths(0),
              r.boundary_lengths(1), r.boundary_lengths(2), r.boundary_lengths(3));
  std::printf("  K max           %.4g  injectivity bound %.4g  longest member %.4g (%s)\n",
              r.gaussian_curvature_max(), r.injectivity_bound(), r.longest_member_distance(),
              r.injectivity_ok() ? "ok" : "exceeds bound");
  std::printf("  gap factor eta  %.6f -> %.6f after %d smoothing iterations (eta_max %.4f)\n",
              r.eta_before(), r.eta_after(), r.smoothing_iterations(), r.eta_max());
  double excess = 0;
  for (double e : r.boundary_geodesic_excess()) excess = std::max(excess, e);
  std::printf("  boundary        shortest geodesics of the patch to %.1e (%d re-cuts)\n", excess,
              r.recuts());
  for (const std::string& warning : r.warnings())
    if (warning.rfind("gap factor", 0) == 0 || warning.rfind("side c", 0) == 0)
      std::fprintf(stderr, "warning: %s\n", warning.c_str());
  print_auto_corners(r.auto_corners());
  std::printf("  time            %.3f s\n", r.seconds());
  const std::filesystem::path out(args.output.out);
  std::printf("  wrote           %s, %s\n", (out / "patch.obj").c_str(),
              (out / "patch.json").c_str());
  return 0;
}

}  // namespace

Command add_patch_command(CLI::App& app) {
  auto args = std::make_shared<PatchArguments>();
  CLI::App* sub = app.add_subcommand(
      "patch", "Cut the target patch along four boundary geodesics, check it and smooth it");
  sub->add_option("MESH", args->mesh, "input mesh (.obj .off .ply .stl) or example:NAME")
      ->required();
  sub->add_option("--corners", args->corners,
                  "i,j,k,l (vertex indices, file order from 0) | \"x,y,z;x,y,z;x,y,z;x,y,z\" | "
                  "auto (default: the example's corners, or auto)");
  add_described_flags(sub, "patch", args->options, {"auto_corner_angles"});
  add_corner_angles_flag(sub, args->corner_angles);
  add_output_flags(sub, args->output, false);
  return [args] { return run_patch(*args); };
}

}  // namespace gridshell::cli
