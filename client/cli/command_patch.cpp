// `gridshell patch MESH --corners ... --out DIR`: cut, check and smooth the target patch.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <numbers>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/errors.h"
#include "gridshell/target_patch.h"
#include "gridshell/v1/reports.pb.h"

namespace gridshell::cli {
namespace {

struct PatchArguments {
  std::string mesh;
  std::string corners;
  std::string out;
  std::string method = "fast";
  double eta_max = 1.0015;
  int max_iterations = 60;
  bool no_smoothing = false;
  bool quiet = false;
};

int run_patch(const PatchArguments& args) {
  const auto start = std::chrono::steady_clock::now();
  const InputMesh input = load_input(args.mesh);
  const CornerSpec spec = resolve_corners(input, args.corners, nullptr);
  TargetPatchOptions options;
  options.cut.method = options.coverability.method = parse_geodesic_method(args.method);
  if (options.cut.method == GeodesicMethod::Heat)
    throw InvalidInput("--method: the patch needs exact geodesics; use fast or cgal, not heat");
  if (!(args.eta_max >= 1.0))
    throw InvalidInput("--eta-max: must be >= 1 (it is a ratio of path lengths)");
  if (args.max_iterations < 0) throw InvalidInput("--max-smoothing-iterations: must be >= 0");
  options.coverability.eta_max = args.eta_max;
  options.coverability.max_smoothing_iterations = args.max_iterations;
  options.smooth = !args.no_smoothing;

  std::filesystem::create_directories(args.out);
  const Progress progress = make_progress(args.quiet);
  const TargetPatch result = make_target_patch(input.mesh, spec, options, progress);
  finish_progress();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  v1::PatchReport report;
  report.set_input(std::filesystem::path(args.mesh).filename().string());
  report.set_input_vertex_count(input.mesh.vertex_count());
  report.set_vertex_count(result.patch.mesh.vertex_count());
  report.set_face_count(result.patch.mesh.face_count());
  for (int i = 0; i < 4; ++i) {
    v1::Corner* corner = report.add_corners();
    const int pv = result.patch.corners[i];
    const Vec3& p = result.patch.mesh.vertices[pv];
    corner->add_position(p.x());
    corner->add_position(p.y());
    corner->add_position(p.z());
    corner->set_patch_vertex(pv);
    int input_vertex = result.patch.input_vertex[pv];
    // Report file-order indices so the user can pass them back to --corners.
    if (input_vertex >= 0) {
      const auto& map = input.report.vertex_of_file_vertex;
      const auto it = std::find(map.begin(), map.end(), input_vertex);
      input_vertex = it == map.end() ? -1 : static_cast<int>(it - map.begin());
    }
    corner->set_input_vertex(input_vertex);
    report.add_corner_angles(result.corner_angles[i]);
    report.add_boundary_lengths(result.boundary_lengths[i]);
  }
  report.set_area(result.area);
  const CoverabilityReport& cov = result.coverability;
  report.set_gaussian_curvature_max(cov.gaussian_curvature_max);
  report.set_gaussian_curvature_max_vertex(cov.gaussian_curvature_max_vertex);
  report.set_injectivity_bound(cov.injectivity_bound);
  report.set_longest_member_distance(cov.longest_member_distance);
  report.set_injectivity_ok(cov.injectivity_ok);
  report.set_eta_before(result.smoothing.eta_before);
  report.set_eta_after(result.smoothing.eta_after);
  report.set_eta_max(args.eta_max);
  report.set_smoothing_iterations(result.smoothing.iterations);
  report.set_max_smoothing_displacement(result.smoothing.max_displacement);
  report.set_geodesic_method(to_string(options.cut.method));
  report.set_seconds(seconds);
  for (const std::string& w : input.report.warnings) report.add_warnings(w);
  if (result.patch.corners_reversed)
    report.add_warnings("corners were given clockwise; the patch uses them counter-clockwise");
  if (!cov.injectivity_ok)
    report.add_warnings("longest member distance exceeds the injectivity bound pi/sqrt(Kmax)");
  for (int i = 0; i < 4; ++i) {
    v1::Side* side = report.add_sides();
    for (int v : result.patch.sides[i]) side->add_vertices(v);
    side->set_length(result.boundary_lengths[i]);
  }
  for (const auto& [stage, s] : result.stage_seconds) (*report.mutable_stage_seconds())[stage] = s;

  const std::filesystem::path out(args.out);
  save_obj(result.patch.mesh, (out / "patch.obj").string());
  write_file_atomically((out / "patch.json").string(), to_json(report) + "\n");

  const double deg = 180 / std::numbers::pi;
  std::printf("patch %s -> %s\n", args.mesh.c_str(), args.out.c_str());
  std::printf("  vertices        %d (input %d), faces %d, area %.4g\n",
              result.patch.mesh.vertex_count(), input.mesh.vertex_count(),
              result.patch.mesh.face_count(), result.area);
  std::printf("  corner angles   %.2f %.2f %.2f %.2f deg\n", result.corner_angles[0] * deg,
              result.corner_angles[1] * deg, result.corner_angles[2] * deg,
              result.corner_angles[3] * deg);
  std::printf("  boundary        %.4g %.4g %.4g %.4g\n", result.boundary_lengths[0],
              result.boundary_lengths[1], result.boundary_lengths[2], result.boundary_lengths[3]);
  std::printf("  K max           %.4g  injectivity bound %.4g  longest member %.4g (%s)\n",
              cov.gaussian_curvature_max, cov.injectivity_bound, cov.longest_member_distance,
              cov.injectivity_ok ? "ok" : "exceeds bound");
  std::printf("  gap factor eta  %.6f -> %.6f after %d smoothing iterations (eta_max %.4f)\n",
              result.smoothing.eta_before, result.smoothing.eta_after, result.smoothing.iterations,
              args.eta_max);
  std::printf("  time            %.3f s\n", seconds);
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
  sub->add_option("--out", args->out, "output folder")->required();
  sub->add_option("--method", args->method, "geodesic engine: fast | cgal")->capture_default_str();
  sub->add_option("--eta-max", args->eta_max, "gap factor threshold")->capture_default_str();
  sub->add_option("--max-smoothing-iterations", args->max_iterations, "smoothing cap")
      ->capture_default_str();
  sub->add_flag("--no-smoothing", args->no_smoothing, "report eta but do not smooth");
  sub->add_flag("--quiet", args->quiet, "no progress line");
  return [args] { return run_patch(*args); };
}

}  // namespace gridshell::cli
