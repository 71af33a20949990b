// `gridshell geodesic MESH --source V [--method ..] [--compare cgal] [--repeat N] [--json]`:
// one single-source distance field, timed, optionally compared with a reference engine.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/errors.h"
#include "gridshell/geodesic.h"
#include "gridshell/v1/reports.pb.h"

namespace gridshell::cli {
namespace {

struct GeodesicArguments {
  std::string mesh;
  int source = 0;
  std::string method = "fast";
  std::string compare;
  int repeat = 1;
  bool json = false;
  std::string distances_out;
};

struct Timed {
  std::vector<double> distances;
  double ms = 0;
};

Timed time_method(const TriangleMesh& mesh, GeodesicMethod method, const SurfacePoint& source,
                  int repeat, const Progress& progress) {
  const GeodesicSolver solver(mesh, GeodesicOptions{method});
  std::vector<double> times;
  Timed result;
  for (int r = 0; r < repeat; ++r) {
    const auto start = std::chrono::steady_clock::now();
    result.distances = solver.distances(source, progress);
    times.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  }
  result.ms = median(times);
  return result;
}

int run_geodesic(const GeodesicArguments& args) {
  if (args.repeat < 1) throw InvalidInput("--repeat: must be at least 1");
  const InputMesh input = load_input(args.mesh);
  const int source_vertex = mesh_vertex(input, args.source, "--source");
  const SurfacePoint source = SurfacePoint::at_vertex(input.mesh, source_vertex);
  const GeodesicMethod method = parse_geodesic_method(args.method);
  const Progress progress = make_progress(true);
  const Timed main = time_method(input.mesh, method, source, args.repeat, progress);

  v1::GeodesicReport report;
  report.set_input(std::filesystem::path(args.mesh).filename().string());
  report.set_vertices(input.mesh.vertex_count());
  report.set_source(args.source);
  report.set_method(to_string(method));
  report.set_ms_per_source(main.ms);
  report.set_repeats(args.repeat);
  double max_distance = 0;
  for (double d : main.distances)
    if (std::isfinite(d)) max_distance = std::max(max_distance, d);
  report.set_max_distance(max_distance);
  if (!args.compare.empty()) {
    const GeodesicMethod reference = parse_geodesic_method(args.compare);
    const Timed ref = time_method(input.mesh, reference, source, args.repeat, progress);
    const double floor = 1e-12 * std::max(1.0, bounding_box_size(input.mesh).norm());
    double max_abs = 0, max_rel = 0;
    for (size_t v = 0; v < main.distances.size(); ++v) {
      const double a = main.distances[v], b = ref.distances[v];
      if (std::isinf(a) && std::isinf(b)) continue;
      const double diff = std::abs(a - b);
      max_abs = std::max(max_abs, diff);
      max_rel = std::max(max_rel, diff / std::max(std::abs(b), floor));
    }
    report.set_reference(to_string(reference));
    report.set_reference_ms_per_source(ref.ms);
    report.set_max_abs_diff(max_abs);
    report.set_max_rel_diff(max_rel);
    report.set_speedup(main.ms > 0 ? ref.ms / main.ms : 0);
  }
  if (!args.distances_out.empty()) {
    std::string text;
    char line[64];
    for (double d : main.distances) {
      std::snprintf(line, sizeof line, "%.17g\n", d);
      text += line;
    }
    write_file_atomically(args.distances_out, text);
  }
  if (args.json) {
    std::cout << to_json(report, false) << "\n";
  } else {
    std::printf("%s: %d vertices, source %d, %s: %.3f ms per source (median of %d)\n",
                args.mesh.c_str(), input.mesh.vertex_count(), args.source, report.method().c_str(),
                main.ms, args.repeat);
    if (!args.compare.empty())
      std::printf(
          "reference %s: %.3f ms per source (%.1fx), max abs diff %.3g, max rel diff %.3g\n",
          report.reference().c_str(), report.reference_ms_per_source(), report.speedup(),
          report.max_abs_diff(), report.max_rel_diff());
  }
  return 0;
}

}  // namespace

Command add_geodesic_command(CLI::App& app) {
  auto args = std::make_shared<GeodesicArguments>();
  CLI::App* sub =
      app.add_subcommand("geodesic", "Exact geodesic distances from one source vertex, timed");
  sub->add_option("MESH", args->mesh, "input mesh or example:NAME")->required();
  sub->add_option("--source", args->source, "source vertex (file order, from 0)")->required();
  sub->add_option("--method", args->method, "fast | cgal | heat")->capture_default_str();
  sub->add_option("--compare", args->compare, "reference method to compare with (e.g. cgal)");
  sub->add_option("--repeat", args->repeat, "repeats; the median time is reported")
      ->capture_default_str();
  sub->add_flag("--json", args->json, "print one JSON object");
  sub->add_option("--distances", args->distances_out, "write the distances, one per line");
  return [args] { return run_geodesic(*args); };
}

}  // namespace gridshell::cli
