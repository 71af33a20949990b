// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell bench solver` (issue 36): where a deployment simulation's time goes as the grid
// grows. The double vault designed with n x n members (lamella width 9 / n, so that they fit),
// simulated without notches with each factorization of the Newton systems side by side in one
// run: the block kernel and CHOLMOD (supernodal, nested dissection), and the default (CHOLMOD
// from SimulationOptions::cholmod_from unknowns). Writes section "solver" of docs/benchmarks.md.
//
// A benchmark, not a test: times are single runs on a shared machine (the iterations, factor
// sizes and RMS are deterministic); read ratios within a row.
#include <sys/resource.h>

#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.h"
#include "gridshell/design/design.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/simulation/simulation.h"

namespace gridshell::cli {

int bench_solver(const std::vector<int>& members, int max_iterations, bool notches,
                 const std::string& out, bool no_write) {
  std::ostringstream table;
  const SimulationOptions defaults;
  table << "## Simulation at growing grid sizes" << (notches ? ", with notches" : "")
        << ": where the time goes (issue 36)\n\n"
        << "Measured " << today() << " on " << cpu_name() << ", "
        << std::thread::hardware_concurrency()
        << " hardware threads, one run each (deterministic iterations and factor sizes; times "
           "from a shared machine). `example:double-vault` designed with n x n inner members "
           "and lamella width 9 / n, simulated "
        << (notches ? "with notches (sliding connections: the system is rebuilt as they move) "
                    : "without notches (the longer of the two runs) ")
        << "with each factorization of the Newton systems: the block kernel (block), CHOLMOD "
           "supernodal with nested dissection of the parameter blocks (cholmod), each for every "
           "system. The default takes CHOLMOD from "
        << defaults.cholmod_from
        << " unknowns. Columns: unknowns of the Newton system, entries of the factor, "
           "iterations (= factorizations, failed ones in parentheses), and seconds in the "
           "ordering and symbolic analysis, the assembly of gradient and Hessian, the "
           "factorizations (per factorization in parentheses), the solves and the trial "
           "costs; total wall time of the run; RMS to the target and the energy at the "
           "equilibrium.\n\n"
        << "| members | factorization | unknowns | factor entries | iterations | analysis s | "
           "assembly s | factorization s (each ms) | solves s | trial costs s | total s | RMS | "
           "energy | converged |\n"
        << "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  const ExampleSurface example = make_example("double-vault");
  for (int n : members) {
    std::cerr << "bench solver: " << n << " x " << n << " members: design\n";
    DesignOptions design_options;
    design_options.members_g = design_options.members_h = n;
    design_options.members.lamella_width = 9.0 / n;
    const Design design =
        make_design(example.mesh, CornerSpec::at_vertices(example.corners), design_options);
    for (const auto& [name, from] : {std::pair{"block", 0}, std::pair{"cholmod", 1}}) {
      std::cerr << "bench solver: " << n << " x " << n << " members, " << name << "\n";
      SimulationOptions options;
      options.notches = notches;
      options.cholmod_from = from;
      options.max_iterations = max_iterations;
      const DeploymentRun run =
          simulate_deployment(design.grid, design.anchors, design.target.patch.mesh,
                              design.lamella_width, design.lamella_thickness, options);
      const SolverProfile& p = run.profile;
      double energy = 0;  // elastic and constraint energies at the equilibrium
      for (const auto& [term, value] : run.energies) energy += value;
      char row[512];
      std::snprintf(row, sizeof row,
                    "| %d | %s | %ld | %ld | %d (%d) | %.2f | %.2f | %.2f (%.1f) | %.2f | %.2f | "
                    "%.2f | %.4f | %.6g | %s |\n",
                    n, name, p.unknowns, p.factor_nonzeros, p.factorizations,
                    p.failed_factorizations, p.analyze_seconds, p.evaluate_seconds,
                    p.factorize_seconds,
                    p.factorizations ? 1e3 * p.factorize_seconds / p.factorizations : 0.0,
                    p.solve_seconds, p.cost_seconds, run.seconds, run.rms, energy,
                    run.converged ? "yes" : ("**no**: " + run.termination).c_str());
      table << row;
      std::cerr << row;
    }
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  table << "\nPeak resident memory of the whole benchmark process: " << usage.ru_maxrss / 1024
        << " MiB.\n\nCommand: `gridshell bench solver --members ";
  for (size_t i = 0; i < members.size(); ++i) table << (i ? "," : "") << members[i];
  table << " --max-iterations " << max_iterations << (notches ? " --notches" : "") << "`\n";
  publish_section(out, notches ? "solver-notches" : "solver", table.str(), no_write);
  return 0;
}

}  // namespace gridshell::cli
