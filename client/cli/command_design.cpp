// `gridshell design MESH --corners ... --out DIR`: the grid design of paper Section 4, in
// process or on a daemon (--server).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/files.h"
#include "gridshell/requests.h"
#include "remote.h"

namespace gridshell::cli {
namespace {

struct DesignArguments {
  std::string mesh;
  std::string corners;
  std::string out;
  std::string alpha = "min";
  int members_u = 0;
  int members_v = 0;
  double lamella_width = 0;      // 0 = 1% of the longest patch side
  double lamella_thickness = 0;  // 0 = width / 10
  int resolution = 100;
  std::string method = "fast";
  double eta_max = 1.0015;
  int threads = 0;
  bool quiet = false;
  RemoteOptions remote;
};

int run_design(const DesignArguments& args) {
  const InputMesh input = load_input(args.mesh);
  std::string corners_used;
  const CornerSpec spec = resolve_corners(input, args.corners, &corners_used);
  v1::DesignRequest request;
  *request.mutable_mesh() = request_mesh(input);
  *request.mutable_corners() = to_proto(spec, corners_used);
  v1::DesignRequest::Options& options = *request.mutable_options();
  options.set_alpha(args.alpha);
  options.set_members_u(args.members_u);
  options.set_members_v(args.members_v);
  options.set_lamella_width(args.lamella_width);
  options.set_lamella_thickness(args.lamella_thickness);
  options.set_resolution(args.resolution);
  options.set_geodesic_method(args.method);
  options.set_eta_max(args.eta_max);

  std::filesystem::create_directories(args.out);  // fail early on an unusable --out
  const Progress progress = make_progress(args.quiet);
  v1::DesignResult result;
  if (args.remote.remote()) {
    prepare_design(request, FieldNames::CommandLine);  // the CLI's own messages for bad options
    result = RemoteClient(args.remote).design(request, progress);
  } else {
    result = gridshell::run_design(request, progress, {FieldNames::CommandLine, args.threads});
  }
  finish_progress();
  write_files(design_files(result), args.out);

  const v1::Design& d = result.design();
  const v1::DesignReport& r = result.report();
  const double deg = 180 / std::numbers::pi;
  std::printf("design %s -> %s%s\n", args.mesh.c_str(), args.out.c_str(),
              args.remote.remote() ? (" on " + args.remote.server).c_str() : "");
  std::printf("  patch           %d vertices, eta %.5f -> %.5f (%d smoothing iterations)\n",
              r.patch_vertices(), r.eta_before(), r.eta_after(), r.smoothing_iterations());
  std::printf("  alpha           %.2f deg on the surface; planar %.2f deg in [%.2f, %.2f]\n",
              d.alpha() * deg, d.alpha_bar() * deg, d.alpha_bar_range(0) * deg,
              d.alpha_bar_range(1) * deg);
  std::printf("  members         %d g + %d h inner (+ 4 boundary), %d crossings, %d anchors\n",
              r.members_g(), r.members_h(), r.crossings(), d.anchors_size());
  std::printf("  max notch       %.4g   max length mismatch %.2e\n", r.max_notch(),
              r.max_length_mismatch());
  std::printf("  time            %.3f s (t_smooth %.3f s, t_grid %.3f s)\n", r.seconds(),
              r.t_smooth(), r.t_grid());
  std::printf("  wrote           design.json report.json planar.svg spatial.obj maps.svg\n");
  return 0;
}

}  // namespace

Command add_design_command(CLI::App& app) {
  auto args = std::make_shared<DesignArguments>();
  CLI::App* sub = app.add_subcommand(
      "design", "Design the planar grid for a target patch (patch stage runs first)");
  sub->add_option("MESH", args->mesh, "input mesh (.obj .off .ply .stl) or example:NAME")
      ->required();
  sub->add_option(
      "--corners", args->corners,
      "i,j,k,l | \"x,y,z;x,y,z;x,y,z;x,y,z\" | auto (default: example corners or auto)");
  sub->add_option("--out", args->out, "output folder")->required();
  sub->add_option("--alpha", args->alpha, "planar corner angle: min | max | radians | NNdeg")
      ->capture_default_str();
  sub->add_option("--members-u", args->members_u, "inner g-members (0 = automatic)")
      ->capture_default_str();
  sub->add_option("--members-v", args->members_v, "inner h-members (0 = automatic)")
      ->capture_default_str();
  sub->add_option("--lamella-width", args->lamella_width,
                  "lamella width, mesh units (0 = 1% of the longest patch side)")
      ->capture_default_str();
  sub->add_option("--lamella-thickness", args->lamella_thickness,
                  "lamella thickness, mesh units (0 = width / 10)")
      ->capture_default_str();
  sub->add_option("--resolution", args->resolution, "distance map resolution R (0 = adaptive)")
      ->capture_default_str();
  sub->add_option("--method", args->method, "geodesic engine: fast | cgal")->capture_default_str();
  sub->add_option("--eta-max", args->eta_max, "gap factor threshold")->capture_default_str();
  sub->add_option("--threads", args->threads, "worker threads, in-process only (0 = all cores)")
      ->capture_default_str();
  sub->add_flag("--quiet", args->quiet, "no progress line");
  add_remote_options(sub, args->remote);
  return [args] { return run_design(*args); };
}

}  // namespace gridshell::cli
