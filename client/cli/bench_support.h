// SPDX-License-Identifier: GPL-3.0-or-later
// Shared pieces of `gridshell bench`: machine description and the marked sections of
// docs/benchmarks.md.
#pragma once

#include <string>
#include <vector>

namespace gridshell::cli {

/// The CPU model from /proc/cpuinfo.
std::string cpu_name();
/// Today's date, YYYY-MM-DD (UTC).
std::string today();
/// Replaces the text between `<!-- bench NAME begin/end -->` in the file (or appends it).
void write_section(const std::string& path, const std::string& name, const std::string& body);
/// Prints a benchmark's table on stdout and, unless `no_write`, writes it as section `name` of
/// the file `path` (saying so on stderr).
void publish_section(const std::string& path, const std::string& name, const std::string& table,
                     bool no_write);

/// `gridshell bench simulate`: the seven paper-like examples designed with default options and
/// simulated without and with notches, `repeats` times each; medians next to Table 1.
int bench_simulate(int repeats, const std::string& out, bool no_write);
/// The rod resolution study: the seven examples simulated at each of `edges` rod edges per
/// interval between crossings (section "resolution").
int bench_resolution(const std::vector<double>& edges, int repeats, const std::string& out,
                     bool no_write);

/// `gridshell bench solver` (bench_solver.cpp, issue 36): double-vault with n x n members for
/// each of `members`, simulated without (or with) notches with the block kernel and with
/// CHOLMOD side by side, the solver's profile per run; section "solver" ("solver-notches").
int bench_solver(const std::vector<int>& members, int max_iterations, bool notches,
                 const std::string& out, bool no_write);

/// `gridshell bench fabricate` (bench_fabricate.cpp): kits of the seven examples and compare on
/// synthetic scans of `scan_points` points; section "fabricate".
int bench_fabricate(int repeats, int scan_points, const std::vector<std::string>& scan_examples,
                    const std::vector<double>& scan_noise, const std::string& out, bool no_write,
                    bool compare_only = false);

/// `gridshell bench scale` (bench_scale.cpp, issue 17): whole designs of `examples` at each of
/// `sizes` vertices in their own processes (the largest size for the first `largest_examples`
/// only), side by side with `baseline` if given; section "scale".
int bench_scale(const std::vector<std::string>& examples, const std::vector<int>& sizes,
                int largest_examples, const std::string& baseline, const std::string& out,
                bool no_write);

}  // namespace gridshell::cli
