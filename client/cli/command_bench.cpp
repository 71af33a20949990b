// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell bench geodesic`: fast engine vs CGAL vs heat method, side by side in one run, on a
// paper-like surface at several resolutions. Writes a table into docs/benchmarks.md.
//
// Benchmarks, not tests: timings are medians over several sources measured in the same run,
// and the headline numbers are ratios, which survive a noisy shared machine better.
#include <sys/resource.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "bench_support.h"
#include "cli_support.h"
#include "commands.h"
#include "gridshell/design/design.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/geodesic/geodesic.h"
#include "gridshell/mesh/mesh_io.h"

namespace gridshell::cli {
namespace {

struct BenchArguments {
  std::string what;
  std::vector<int> sizes{1000, 4000, 16000, 64000};
  std::vector<int> members{15, 30, 60};  // solver
  int max_iterations = 2000;             // solver
  bool notches = false;                  // solver
  std::string surface = "waves-bump";
  int sources = 5;
  int cgal_sources = 3;
  int cgal_max_vertices = 70000;
  std::string out;
  bool no_write = false;
  int repeats = 3;
  std::vector<double> edges{1, 2, 3, 4};
  bool quick = false;         // abuse: a 2 s stall timeout (the CI test)
  std::string json;           // abuse: the rows as JSON too
  std::string server;         // interactive: an existing gridshelld instead of a new one
  int request_threads = 1;    // interactive: --request-threads of the daemon it starts
  int redesign_threads = 0;   // interactive: --redesign-threads of the daemon it starts
  int scan_points = 1000000;  // fabricate: points of the synthetic scans
  // fabricate: the deployments the synthetic scans are taken of, and their noise (sigma per
  // coordinate, in lamella thicknesses; 0 is an exact scan)
  std::vector<std::string> scan_examples{"double-vault", "hypar", "sphere"};
  std::vector<double> scan_noise{0.1, 0};
  bool compare_only = false;  // fabricate: the scan comparison alone
  std::vector<std::string> examples{"double-vault", "waves-bump", "sphere"};  // scale
  int largest_examples = 1;  // scale: examples that also run the largest size
  std::string baseline;      // scale: another gridshell build, run side by side
};

/// CPU time of the whole process (all threads) in s.
double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// The machine's 1-minute load average (/proc/loadavg), or -1 if unknown. The machine is
/// shared: the tables record it so that wall-clock times can be read in context.
double load_average() {
  std::ifstream in("/proc/loadavg");
  double load = -1;
  in >> load;
  return load;
}

/// The line that states the machine's load over a benchmark.
std::string load_line(double load_start) {
  char line[160];
  std::snprintf(line, sizeof line,
                "\n1-minute load average of the shared machine: %.2f at the start, %.2f at the "
                "end.\n",
                load_start, load_average());
  return line;
}

/// CPU time of the calling thread in ms. The geodesic solves are single-threaded, so this is
/// their cost without the time other processes take on a shared machine (equal to wall time on
/// an idle one); all engines are timed the same way.
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

int bench_geodesic(const BenchArguments& args) {
  std::ostringstream table;
  table << "## Geodesic engines: fast (ours, exact) vs CGAL Surface_mesh_shortest_path (exact) vs "
           "CGAL heat method (approximate)\n\n"
        << "Measured " << today() << " on " << cpu_name() << ", "
        << std::thread::hardware_concurrency()
        << " hardware threads (shared), single-threaded solves timed in thread CPU time. "
        << "Surface `" << args.surface << "` at several resolutions; sources spread over the "
        << "vertex list; each engine solves the same sources in the same run, one after the "
           "other after one untimed warm-up solve (as a design's distance maps do). Times are "
           "medians per source in ms; *fast* computes the vertex distances (what `distances()` and "
           "`gridshell geodesic` ask for: no windows kept), *fast + windows* a complete field that "
           "also answers distances to any surface point and shortest paths (windows kept and "
           "indexed); CGAL always builds its complete sequence tree. *setup* is the per-mesh "
           "precomputation (for heat: the factorizations). Diffs are the max over all vertices "
           "and sources compared.\n\n"
        << "| vertices | fast ms | fast + windows ms | CGAL ms | heat ms | fast setup ms | heat "
           "setup ms | CGAL / fast | CGAL / (fast + windows) | heat / fast | max rel diff fast "
           "vs CGAL | max rel diff heat vs fast |\n"
        << "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  const double load_start = load_average();
  std::vector<std::pair<int, double>> growth, growth_full;
  const int base = make_example(args.surface).mesh.vertex_count();
  for (int target : args.sizes) {
    const double scale = std::sqrt(static_cast<double>(target) / base);
    const ExampleSurface example = make_example(args.surface, scale);
    const TriangleMesh& mesh = example.mesh;
    const int n = mesh.vertex_count();
    std::cerr << "bench geodesic: " << n << " vertices\n";
    double start = thread_cpu_ms();
    const GeodesicSolver fast(mesh, GeodesicOptions{GeodesicMethod::Fast});
    const double fast_setup = thread_cpu_ms() - start;
    start = thread_cpu_ms();
    const GeodesicSolver heat(mesh, GeodesicOptions{GeodesicMethod::Heat});
    const double heat_setup = thread_cpu_ms() - start;
    const bool run_cgal = n <= args.cgal_max_vertices && args.cgal_sources > 0;
    std::optional<GeodesicSolver> cgal;
    if (run_cgal) cgal.emplace(mesh, GeodesicOptions{GeodesicMethod::Cgal});
    std::vector<double> fast_ms, full_ms, cgal_ms, heat_ms;
    double rel_cgal = 0, rel_heat = 0;
    const double floor = 1e-12 * bounding_box_size(mesh).norm();
    std::vector<SurfacePoint> sources;
    for (int k = 0; k < args.sources; ++k)
      sources.push_back(
          SurfacePoint::at_vertex(mesh, static_cast<int>((k + 0.5) * n / args.sources)));
    // Each engine solves its sources one after the other, as a design's distance maps do, after
    // one untimed solve from vertex 0 (not among the sources): interleaving the engines would
    // make each one start from caches the others have just filled, and the first solve pays
    // for fresh memory.
    const SurfacePoint warm_up = SurfacePoint::at_vertex(mesh, 0);
    std::vector<std::vector<double>> d_fast;
    (void)fast.distances(warm_up);
    for (const SurfacePoint& source : sources) {
      start = thread_cpu_ms();
      d_fast.push_back(fast.distances(source));
      fast_ms.push_back(thread_cpu_ms() - start);
    }
    (void)fast.solve(warm_up);
    for (std::size_t k = 0; k < sources.size(); ++k) {
      start = thread_cpu_ms();
      const DistanceField full = fast.solve(sources[k]);
      full_ms.push_back(thread_cpu_ms() - start);
      if (full.vertex_distances() != d_fast[k])
        throw std::logic_error("bench geodesic: solves with and without windows differ");
    }
    (void)heat.distances(warm_up);
    for (std::size_t k = 0; k < sources.size(); ++k) {
      start = thread_cpu_ms();
      const std::vector<double> d_heat = heat.distances(sources[k]);
      heat_ms.push_back(thread_cpu_ms() - start);
      for (int u = 0; u < n; ++u)
        rel_heat =
            std::max(rel_heat, std::abs(d_heat[u] - d_fast[k][u]) / std::max(d_fast[k][u], floor));
    }
    if (run_cgal) {
      (void)cgal->distances(warm_up);
      for (int k = 0; k < std::min(args.cgal_sources, args.sources); ++k) {
        start = thread_cpu_ms();
        const std::vector<double> d_cgal = cgal->distances(sources[k]);
        cgal_ms.push_back(thread_cpu_ms() - start);
        for (int u = 0; u < n; ++u)
          rel_cgal =
              std::max(rel_cgal, std::abs(d_fast[k][u] - d_cgal[u]) / std::max(d_cgal[u], floor));
      }
    }
    const double f = median(fast_ms), w = median(full_ms), h = median(heat_ms);
    growth.push_back({n, f});
    growth_full.push_back({n, w});
    char row[512];
    if (run_cgal) {
      const double c = median(cgal_ms);
      std::snprintf(row, sizeof row,
                    "| %d | %.3f | %.3f | %.1f | %.3f | %.1f | %.1f | %.1f | %.1f | %.2f | %.1e | "
                    "%.1e |\n",
                    n, f, w, c, h, fast_setup, heat_setup, c / f, c / w, h / f, rel_cgal, rel_heat);
    } else {
      std::snprintf(row, sizeof row,
                    "| %d | %.3f | %.3f | (skipped) | %.3f | %.1f | %.1f | – | – | %.2f | – | %.1e "
                    "|\n",
                    n, f, w, h, fast_setup, heat_setup, h / f, rel_heat);
    }
    table << row;
    std::cerr << row;
  }
  if (growth.size() >= 2) {
    const auto exponent = [](const std::vector<std::pair<int, double>>& g) {
      return std::log(g.back().second / g.front().second) /
             std::log(static_cast<double>(g.back().first) / g.front().first);
    };
    char line[384];
    std::snprintf(line, sizeof line,
                  "\nCost growth of the fast engine per source from %d to %d vertices: "
                  "t ~ n^%.2f (%.3f ms -> %.3f ms); with windows kept t ~ n^%.2f.\n",
                  growth.front().first, growth.back().first, exponent(growth),
                  growth.front().second, growth.back().second, exponent(growth_full));
    table << line;
  }
  table << load_line(load_start);
  table << "\nCommand: `gridshell bench geodesic --sources " << args.sources << " --cgal-sources "
        << args.cgal_sources << "`\n";
  publish_section(args.out, "geodesic", table.str(), args.no_write);
  return 0;
}

// Paper Table 1 (Xeon E5-2687W v4): |M_V|, t_smooth (0 = not needed), t_grid in seconds.
struct PaperRow {
  const char* name;
  int vertices;
  double t_smooth, t_grid;
};
constexpr PaperRow kTable1[] = {{"torus-wide", 2122, 0, 5.33},  {"waves-bump", 3385, 31.63, 5.62},
                                {"sphere", 1083, 0, 1.29},      {"double-vault", 571, 0, 0.68},
                                {"waves", 1929, 10.22, 2.10},   {"archway", 975, 4.14, 1.50},
                                {"triple-vault", 1322, 0, 1.67}};

int bench_design(const BenchArguments& args) {
  std::ostringstream table;
  const double deg = 180 / 3.14159265358979323846;
  table << "## Grid design on the seven paper-like examples, next to the paper's Table 1\n\n"
        << "Measured " << today() << " on " << cpu_name() << ", "
        << std::thread::hardware_concurrency() << " hardware threads. Median of " << args.repeats
        << " runs of `make_design` per example (default options: R = 100, ᾱ = ᾱ_min). t_grid is "
        << "patch -> design (distance maps, ᾱ range, cladding, members, grid, anchors), "
           "excluding cutting and smoothing (wall clock; the distance maps and members run on all "
           "hardware threads). *t_grid CPU* is the CPU time of the same work summed over threads "
           "(median): unlike wall clock it is not inflated by other processes on the shared "
           "machine, and on an idle machine t_grid is about t_grid CPU / threads. Paper values in "
           "parentheses (MATLAB, Xeon E5-2687W v4).\n\n"
        << "| example | \\|M_V\\| (paper) | t_smooth s (paper) | t_grid s (paper) | t_grid CPU s | "
           "speed-up t_grid | members g + h | ᾱ range deg | ᾱ deg |\n"
        << "|---|---:|---:|---:|---:|---:|---:|---|---:|\n";
  const double load_start = load_average();
  for (const PaperRow& row : kTable1) {
    const ExampleSurface example = make_example(row.name);
    const CornerSpec corners = CornerSpec::at_vertices(example.corners);
    std::vector<double> t_grid, t_smooth, t_cpu;
    std::string line;
    for (int r = 0; r < args.repeats; ++r) {
      std::cerr << "bench design: " << row.name << " run " << r + 1 << "\n";
      try {
        const DesignOptions options;
        TargetPatch target = make_target_patch(example.mesh, corners, options.patch);
        const double cpu = process_cpu_s();
        const Design design = design_grid(std::move(target), options);
        t_cpu.push_back(process_cpu_s() - cpu);
        double grid = 0;
        for (const auto& [stage, s] : design.stage_seconds)
          if (stage != "patch") grid += s;
        t_grid.push_back(grid);
        t_smooth.push_back(design.target.stage_seconds.at("smoothing"));
        char buffer[512];
        std::snprintf(buffer, sizeof buffer, "%zu + %zu | %.1f – %.1f | %.1f",
                      design.grid.g.size() - 2, design.grid.h.size() - 2,
                      design.alpha_range.min * deg, design.alpha_range.max * deg,
                      design.alpha_bar * deg);
        line = buffer;
      } catch (const std::exception& e) {
        line = std::string("infeasible: ") + e.what() + " | | ";
        break;
      }
    }
    char buffer[1024];
    const double g = median(t_grid);
    std::snprintf(buffer, sizeof buffer,
                  "| %s | %d (%d) | %.3f (%s) | %.3f (%.2f) | %.3f | %.1fx | %s |\n", row.name,
                  example.mesh.vertex_count(), row.vertices, median(t_smooth),
                  row.t_smooth > 0 ? std::to_string(row.t_smooth).substr(0, 5).c_str() : "–", g,
                  row.t_grid, median(t_cpu), g > 0 ? row.t_grid / g : 0.0, line.c_str());
    table << buffer;
    std::cerr << buffer;
  }
  table << load_line(load_start);
  table << "\nCommand: `gridshell bench design --repeats " << args.repeats << "`\n";
  publish_section(args.out, "design", table.str(), args.no_write);
  return 0;
}

}  // namespace

Command add_bench_command(CLI::App& app) {
  auto args = std::make_shared<BenchArguments>();
  args->out = std::string(GRIDSHELL_SOURCE_DIR) + "/docs/benchmarks.md";
  CLI::App* sub = app.add_subcommand("bench", "Benchmarks (not tests); results go to docs/");
  sub->add_option("WHAT", args->what,
                  "geodesic | design | simulate | solver | resolution | service | interactive | "
                  "sweep | fabricate | scale | abuse")
      ->required()
      ->check(CLI::IsMember({"geodesic", "design", "simulate", "solver", "resolution", "service",
                             "interactive", "sweep", "fabricate", "scale", "abuse"}));
  sub->add_flag("--quick", args->quick, "abuse: a 2 s stall timeout instead of 10 s");
  sub->add_option("--json", args->json, "abuse: also write the rows to this JSON file");
  sub->add_option("--examples", args->examples, "scale: examples to design")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--largest-examples", args->largest_examples,
                  "scale: how many of the examples also run the largest size")
      ->capture_default_str();
  sub->add_option("--baseline", args->baseline,
                  "scale: another gridshell program run side by side (e.g. an older build)");
  sub->add_option("--scan-points", args->scan_points, "fabricate: points of the synthetic scans")
      ->capture_default_str();
  sub->add_option("--scan-examples", args->scan_examples,
                  "fabricate: examples whose deployments the synthetic scans are taken of")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--scan-noise", args->scan_noise,
                  "fabricate: noise of the synthetic scans (sigma per coordinate in lamella "
                  "thicknesses; 0: exact)")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_flag("--compare-only", args->compare_only,
                "fabricate: the scan comparison alone (printed, not written)");
  sub->add_option("--edges", args->edges,
                  "rod edges per interval between crossings to compare (resolution)")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--sizes", args->sizes, "target vertex counts")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--members", args->members, "solver: members per family of each grid")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--max-iterations", args->max_iterations, "solver: iteration cap of each run")
      ->capture_default_str();
  sub->add_flag("--notches", args->notches, "solver: simulate with notches (sliding connections)");
  sub->add_option("--surface", args->surface, "example surface")->capture_default_str();
  sub->add_option("--sources", args->sources, "sources per size")->capture_default_str();
  sub->add_option("--cgal-sources", args->cgal_sources, "sources also solved by CGAL")
      ->capture_default_str();
  sub->add_option("--cgal-max-vertices", args->cgal_max_vertices, "skip CGAL above this size")
      ->capture_default_str();
  sub->add_option("--out", args->out, "markdown file to update")->capture_default_str();
  sub->add_flag("--no-write", args->no_write, "print only");
  sub->add_option("--server", args->server,
                  "interactive: gridshelld at HOST:PORT (default: start one on loopback)");
  sub->add_option("--request-threads", args->request_threads,
                  "interactive: kernel threads per request of the daemon it starts (0 = all)")
      ->capture_default_str();
  sub->add_option("--repeats", args->repeats,
                  "runs per example (design, simulate); rounds of all client levels (service)")
      ->capture_default_str();
  sub->add_option(
         "--redesign-threads", args->redesign_threads,
         "interactive: kernel threads of a warm redesign in the daemon it starts (0 = all)")
      ->capture_default_str();
  return [args] {
    if (args->sources < 1) throw InvalidInput("--sources", "must be at least 1");
    for (int s : args->sizes)
      if (s < 100 || s > 2000000) throw InvalidInput("--sizes", "each size must be 100..2000000");
    if (args->repeats < 1) throw InvalidInput("--repeats", "must be at least 1");
    if (args->what == "simulate") return bench_simulate(args->repeats, args->out, args->no_write);
    if (args->what == "solver") {
      if (args->members.empty()) throw InvalidInput("--members", "give at least one grid size");
      for (int m : args->members)
        if (m < 2 || m > 200) throw InvalidInput("--members", "each must be 2..200");
      if (args->max_iterations < 1) throw InvalidInput("--max-iterations", "must be at least 1");
      return bench_solver(args->members, args->max_iterations, args->notches, args->out,
                          args->no_write);
    }
    if (args->what == "fabricate") {
      if (args->scan_points < 1000 || args->scan_points > 100000000)
        throw InvalidInput("--scan-points", "must be 1000..100000000");
      return bench_fabricate(args->repeats, args->scan_points, args->scan_examples,
                             args->scan_noise, args->out, args->no_write, args->compare_only);
    }
    if (args->what == "resolution") {
      if (args->edges.empty()) throw InvalidInput("--edges", "give at least one resolution");
      for (double e : args->edges)
        if (!(e >= 1 && e <= 64)) throw InvalidInput("--edges", "each must be between 1 and 64");
      return bench_resolution(args->edges, args->repeats, args->out, args->no_write);
    }
    if (args->what == "service") return bench_service(args->out, args->no_write, args->repeats);
    if (args->what == "abuse")
      return bench_abuse(args->out, args->no_write, args->repeats, args->quick, args->json);
    if (args->what == "scale")
      return bench_scale(args->examples, args->sizes, args->largest_examples, args->baseline,
                         args->out, args->no_write);
    if (args->what == "sweep") return bench_sweep(args->out, args->no_write, args->repeats);
    if (args->what == "interactive") {
      if (args->request_threads < 0 || args->request_threads > 1024)
        throw InvalidInput("--request-threads", "must be 0..1024");
      if (args->redesign_threads < 0 || args->redesign_threads > 1024)
        throw InvalidInput("--redesign-threads", "must be 0..1024");
      return bench_interactive(args->out, args->no_write, args->server, args->request_threads,
                               args->redesign_threads);
    }
    return args->what == "design" ? bench_design(*args) : bench_geodesic(*args);
  };
}

}  // namespace gridshell::cli
