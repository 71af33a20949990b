// `gridshell design MESH --corners ... --out DIR`: the grid design of paper Section 4.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/convert.h"
#include "gridshell/design.h"
#include "gridshell/design_export.h"
#include "gridshell/errors.h"

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
};

int run_design(const DesignArguments& args) {
  const auto start = std::chrono::steady_clock::now();
  const InputMesh input = load_input(args.mesh);
  std::string corners_used;
  const CornerSpec spec = resolve_corners(input, args.corners, &corners_used);
  DesignOptions options;
  options.patch.cut.method = options.patch.coverability.method = parse_geodesic_method(args.method);
  if (options.patch.cut.method == GeodesicMethod::Heat)
    throw InvalidInput("--method: the design needs exact geodesics; use fast or cgal, not heat");
  if (!(args.eta_max >= 1.0)) throw InvalidInput("--eta-max: must be >= 1");
  options.patch.coverability.eta_max = args.eta_max;
  parse_alpha(args.alpha, options);
  if (args.members_u < 0) throw InvalidInput("--members-u: must be >= 0 (0 = automatic)");
  if (args.members_v < 0) throw InvalidInput("--members-v: must be >= 0 (0 = automatic)");
  if (!(args.lamella_width >= 0) || !std::isfinite(args.lamella_width))
    throw InvalidInput("--lamella-width: must be positive (or 0 for 1% of the longest side)");
  if (!(args.lamella_thickness >= 0) || !std::isfinite(args.lamella_thickness))
    throw InvalidInput("--lamella-thickness: must be positive (or 0 for a tenth of the width)");
  if (args.resolution != 0 && (args.resolution < 8 || args.resolution > 1000))
    throw InvalidInput("--resolution: must be 0 (adaptive) or 8..1000");
  options.members_g = args.members_u;
  options.members_h = args.members_v;
  options.members.lamella_width = args.lamella_width;
  options.members.lamella_thickness = args.lamella_thickness;
  options.maps.resolution = args.resolution;
  options.maps.threads = options.grid.threads = args.threads;

  std::filesystem::create_directories(args.out);
  const Progress progress = make_progress(args.quiet);
  const Design design = make_design(input.mesh, spec, options, progress);
  finish_progress();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  v1::DesignOptions used;
  used.set_corners(corners_used);
  used.set_alpha(args.alpha);
  used.set_members_u(args.members_u);
  used.set_members_v(args.members_v);
  used.set_lamella_width(design.lamella_width);
  used.set_lamella_thickness(design.lamella_thickness);
  used.set_map_resolution(design.maps.g.resolution());
  used.set_eta_max(args.eta_max);
  used.set_max_smoothing_iterations(options.patch.coverability.max_smoothing_iterations);
  used.set_k_min(options.cladding.k_min);
  used.set_k_max(options.cladding.k_max);
  used.set_max_spacing(options.members.max_spacing);
  used.set_min_members(options.members.min_members);
  used.set_max_members(options.members.max_members);
  used.set_geodesic_method(args.method);
  used.set_length_tolerance(options.grid.length_tolerance);
  const std::string name = std::filesystem::path(args.mesh).filename().string();
  const v1::Design message = to_proto(design, used, name);
  const v1::DesignReport report = to_report(design, name, input.mesh.vertex_count(), seconds);

  const std::filesystem::path out(args.out);
  write_file_atomically((out / "design.json").string(), to_json(message) + "\n");
  write_file_atomically((out / "report.json").string(), to_json(report) + "\n");
  write_file_atomically((out / "planar.svg").string(), planar_svg(design, design.lamella_width));
  write_file_atomically((out / "spatial.obj").string(), spatial_obj(design));
  write_file_atomically((out / "maps.svg").string(), maps_svg(design));

  const double deg = 180 / std::numbers::pi;
  std::printf("design %s -> %s\n", args.mesh.c_str(), args.out.c_str());
  std::printf("  patch           %d vertices, eta %.5f -> %.5f (%d smoothing iterations)\n",
              design.target.patch.mesh.vertex_count(), design.target.smoothing.eta_before,
              design.target.smoothing.eta_after, design.target.smoothing.iterations);
  std::printf("  alpha           %.2f deg on the surface; planar %.2f deg in [%.2f, %.2f]\n",
              design.alpha * deg, design.alpha_bar * deg, design.alpha_range.min * deg,
              design.alpha_range.max * deg);
  std::printf("  members         %d g + %d h inner (+ 4 boundary), %d crossings, %zu anchors\n",
              report.members_g(), report.members_h(), report.crossings(), design.anchors.size());
  std::printf("  max notch       %.4g   max length mismatch %.2e\n", report.max_notch(),
              report.max_length_mismatch());
  std::printf("  time            %.3f s (t_smooth %.3f s, t_grid %.3f s)\n", seconds,
              report.t_smooth(), report.t_grid());
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
  sub->add_option("--threads", args->threads, "worker threads (0 = all cores)")
      ->capture_default_str();
  sub->add_flag("--quiet", args->quiet, "no progress line");
  return [args] { return run_design(*args); };
}

}  // namespace gridshell::cli
