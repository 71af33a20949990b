// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell bench simulate`: the deployment simulation on the seven paper-like examples next
// to the paper's Table 1 (|G_V|, RMS1, RMS2, t1, t2). Writes a table into docs/benchmarks.md.
//
// A benchmark, not a test: each example is designed once with default options, then simulated
// without and with notches `repeats` times, one run after the other (the Newton solver evaluates on
// one thread); times are medians. RMS and iterations are deterministic.
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.h"
#include "cli_support.h"
#include "gridshell/design/design.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/simulation/simulation.h"
#include "paper_table1.h"

namespace gridshell::cli {

namespace {

/// The design simulated without and with notches `repeats` times, one run after the other.
struct RunPair {
  DeploymentRun without, with;
  std::vector<double> t1, t2;
};

RunPair simulate_pair(const Design& design, SimulationOptions options, int repeats,
                      const std::string& label) {
  RunPair out;
  for (int r = 0; r < repeats; ++r) {
    std::cerr << "bench: " << label << " run " << r + 1 << "\n";
    options.notches = false;
    out.without = simulate_deployment(design.grid, design.anchors, design.target.patch.mesh,
                                      design.lamella_width, design.lamella_thickness, options);
    options.notches = true;
    out.with = simulate_deployment(design.grid, design.anchors, design.target.patch.mesh,
                                   design.lamella_width, design.lamella_thickness, options);
    out.t1.push_back(out.without.seconds);
    out.t2.push_back(out.with.seconds);
  }
  return out;
}

}  // namespace

int bench_simulate(int repeats, const std::string& out, bool no_write) {
  std::ostringstream table;
  const SimulationOptions defaults;
  table << "## Deployment simulation on the seven paper-like examples, next to the paper's "
           "Table 1\n\n"
        << "Measured " << today() << " on " << cpu_name() << ", "
        << std::thread::hardware_concurrency()
        << " hardware threads. Each example designed once with default options, then simulated "
           "without (1) and with (2) notches, "
        << repeats
        << " times each, one run after the other (Newton solver on one thread, default "
           "options: lime wood, mu = 0.1, 2 edges per interval between crossings, gradient "
           "tolerance "
        << defaults.gradient_tolerance
        << "). t1, t2 are medians in seconds; RMS is the root mean square distance of all rod "
           "vertices to the target patch (100 units wide). Paper values in parentheses. The last "
           "row is waves-bump designed with one inner anchor (`--interior-anchors 1`, at its "
           "bump; the paper's anchors are on the boundary only, see docs/decisions.md).\n\n"
        << "| example | \\|G_V\\| (paper) | RMS1 (paper) | RMS2 (paper) | t1 s (paper) | t2 s "
           "(paper) | iterations 1 / 2 | converged |\n"
        << "|---|---:|---:|---:|---:|---:|---:|---|\n";
  struct Variant {
    const PaperModel* row;
    int interior_anchors;
  };
  std::vector<Variant> variants;
  for (const PaperModel& row : kPaperTable1) variants.push_back({&row, 0});
  for (const PaperModel& row : kPaperTable1)
    if (std::string(row.name) == "waves-bump") variants.push_back({&row, 1});
  for (const auto& [model, interior_anchors] : variants) {
    const PaperModel& row = *model;
    const std::string label =
        interior_anchors ? std::string(row.name) + ", " + std::to_string(interior_anchors) +
                               " inner anchor" + (interior_anchors > 1 ? "s" : "")
                         : std::string(row.name);
    std::cerr << "bench simulate: " << label << ": design\n";
    const ExampleSurface example = make_example(row.name);
    const CornerSpec corners = CornerSpec::at_vertices(example.corners);
    char buffer[1024];
    try {
      DesignOptions design_options;
      design_options.anchors.interior = interior_anchors;
      const Design design = make_design(example.mesh, corners, design_options);
      const auto [without, with, t1, t2] = simulate_pair(design, {}, repeats, label);
      std::snprintf(buffer, sizeof buffer,
                    "| %s | %d (%d) | %.3f (%.2f) | %.3f (%.2f) | %.2f (%.2f) | %.2f (%.2f) | %d / "
                    "%d | %s |\n",
                    label.c_str(), with.grid_vertices, row.grid_vertices, without.rms, row.rms1,
                    with.rms, row.rms2, median(t1), row.t1, median(t2), row.t2, without.iterations,
                    with.iterations, without.converged && with.converged ? "yes" : "**no**");
    } catch (const std::exception& e) {
      std::snprintf(buffer, sizeof buffer, "| %s | failed: %s | | | | | | |\n", label.c_str(),
                    e.what());
    }
    table << buffer;
    std::cerr << buffer;
  }
  table << "\nCommand: `gridshell bench simulate --repeats " << repeats << "`\n";
  publish_section(out, "simulate", table.str(), no_write);
  return 0;
}

int bench_resolution(const std::vector<double>& edges, int repeats, const std::string& out,
                     bool no_write) {
  std::ostringstream table;
  table << "## Rod resolution: the seven examples at several rod edges per interval\n\n"
        << "Measured " << today() << " on " << cpu_name() << ", "
        << std::thread::hardware_concurrency()
        << " hardware threads. Each example designed once with default options, then simulated "
           "without (1) and with (2) notches at each resolution (`--edges-per-interval`: rod "
           "edges per interval between crossings; the default is 2), "
        << repeats
        << " time(s) each, times are medians in seconds. How far RMS changes with the "
           "resolution tells how far a result is the rods' equilibrium rather than the "
           "discretization's. The paper's |G_V| is in parentheses: between our one and two "
           "edges per interval (see docs/decisions.md, \"Rod resolution and the paper's "
           "|G_V|\").\n\n"
        << "| example | edges per interval | \\|G_V\\| (paper) | RMS1 (paper) | RMS2 (paper) | "
           "t1 s | t2 s | iterations 1 / 2 | converged |\n"
        << "|---|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const PaperModel& row : kPaperTable1) {
    std::cerr << "bench resolution: " << row.name << ": design\n";
    const ExampleSurface example = make_example(row.name);
    const Design design =
        make_design(example.mesh, CornerSpec::at_vertices(example.corners), DesignOptions{});
    for (const double epi : edges) {
      char buffer[1024];
      try {
        SimulationOptions options;
        options.edges_per_interval = epi;
        std::ostringstream label;
        label << row.name << ", " << epi << " edges per interval";
        const auto [without, with, t1, t2] = simulate_pair(design, options, repeats, label.str());
        std::snprintf(buffer, sizeof buffer,
                      "| %s | %g | %d (%d) | %.3f (%.2f) | %.3f (%.2f) | %.2f | %.2f | %d / %d | "
                      "%s |\n",
                      row.name, epi, with.grid_vertices, row.grid_vertices, without.rms, row.rms1,
                      with.rms, row.rms2, median(t1), median(t2), without.iterations,
                      with.iterations, without.converged && with.converged ? "yes" : "**no**");
      } catch (const std::exception& e) {
        std::snprintf(buffer, sizeof buffer, "| %s | %g | failed: %s | | | | | | |\n", row.name,
                      epi, e.what());
      }
      table << buffer;
      std::cerr << buffer;
    }
  }
  table << "\nCommand: `gridshell bench resolution --edges";
  for (size_t i = 0; i < edges.size(); ++i) table << (i ? "," : " ") << edges[i];
  table << " --repeats " << repeats << "`\n";
  publish_section(out, "resolution", table.str(), no_write);
  return 0;
}

}  // namespace gridshell::cli
