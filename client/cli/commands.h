// SPDX-License-Identifier: GPL-3.0-or-later
// Subcommands of the gridshell CLI; each registers itself on the CLI11 app and returns the
// function that runs it (exit code).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "cli_support.h"
#include "gridshell/v1/deployment.pb.h"
#include "gridshell/v1/layout.pb.h"
#include "gridshell/v1/requests.pb.h"
#include "remote.h"

// CLI11 is heavy (4 s of compile time per file that includes it): declared here, included only
// by the files that build the command line.
namespace CLI {
class App;
}  // namespace CLI

namespace gridshell::sweep {
class RowChecker;  // gridshell/batch/sweep.h
}  // namespace gridshell::sweep

namespace gridshell::cli {

using Command = std::function<int()>;
struct InputMesh;  // cli_support.h

Command add_patch_command(CLI::App& app);
Command add_geodesic_command(CLI::App& app);
Command add_design_command(CLI::App& app);
Command add_examples_command(CLI::App& app);
Command add_bench_command(CLI::App& app);
Command add_simulate_command(CLI::App& app);
Command add_run_command(CLI::App& app);
Command add_fabricate_command(CLI::App& app);
Command add_compare_command(CLI::App& app);
Command add_options_command(CLI::App& app);
Command add_layout_command(CLI::App& app);

/// Flags of every command that computes and writes a folder: --out, --threads (in-process only;
/// left out where a command has no parallel work), --quiet and the remote options.
struct OutputFlags {
  std::string out;
  int threads = 0;
  bool quiet = false;
  RemoteOptions remote;
};
void add_output_flags(CLI::App* sub, OutputFlags& flags, bool with_threads = true);
/// "COMMAND INPUT -> OUT[ on SERVER]", the first line of a command's summary.
void print_heading(const char* command, const std::string& input, const OutputFlags& flags);

/// Design flags shared by `design` and `run` (MESH, --corners, --alpha, ...).
/// The design flags. The described options (gridshell/options.h) stay unset unless given: their
/// defaults, ranges and checks are the request's.
struct DesignFlags {
  std::string mesh;
  std::string corners;
  DescribedFlags options;              // every described design option with a flag, but:
  std::string interior_anchors = "0";  // N (0..100) placed by the design, or auto (`run` only)
  std::string corner_angles;           // "MIN,MAX" degrees for automatic corners, "" = 45,135
};
void add_design_flags(CLI::App* sub, DesignFlags& flags);
/// Loads the mesh and builds the request (InvalidInput names the flag).
v1::DesignRequest design_request(const DesignFlags& flags);
/// The same with the mesh loaded already (`gridshell sweep` loads each mesh once for many rows).
v1::DesignRequest design_request(const DesignFlags& flags, const InputMesh& input);
/// A layout file (gridshell.v1.Layout in JSON; corner vertices in file order) with its corner
/// vertices as mesh vertices of `input` as loaded; InvalidInput names --layout or the corner.
v1::Layout read_layout_file(const std::string& file, const InputMesh& input);
/// --layout FILE or auto, with the automatic layout's flags (refused without auto).
struct LayoutChoice {
  v1::Layout layout;                               ///< from the file
  std::optional<v1::AutoLayoutOptions> automatic;  ///< --layout auto
};
LayoutChoice layout_choice(const std::string& layout, const DescribedFlags& automatic,
                           const InputMesh& input);
/// `run`'s --layout and the automatic layout's flags (also the sweep's columns).
struct SimulationFlags;
struct LayoutFlags {
  std::string layout;        ///< auto or a layout file; "" = one patch (--corners)
  DescribedFlags automatic;  ///< --layout auto's options
};
void add_layout_flags(CLI::App* sub, LayoutFlags& flags);
/// A one-patch run (no --layout): refuses the automatic layout's flags, naming the first given.
void check_no_layout_flags(const LayoutFlags& layout);
/// A layout run's request from `run`'s flags, checked as far as it is before any work (the
/// layout file read, every option against the description); InvalidInput names the flag.
v1::LayoutRunRequest layout_run_request(const LayoutFlags& layout, const DesignFlags& design,
                                        SimulationFlags simulation, const InputMesh& input);
/// --layout's help.
inline constexpr const char* kLayoutHelp =
    "auto (a layout computed for a surface with one boundary and no holes) or a layout file: "
    "gridshell.v1.Layout in JSON (corners by file-order vertex index or point; patches of four "
    "corners, all in the same turning sense), or the layout.json a run wrote";
/// The report's layout as the user gave it: corner vertices back in file order.
void write_layout_as_given(v1::LayoutReport& report, const InputMesh& input);
/// Prints how an automatic layout was found (nothing for a layout from a file).
void print_automatic_layout(const v1::LayoutReport& report);
/// Prints the coverage, each patch's checks, the seams and what is not covered; returns the
/// first failing patch.
const v1::LayoutReport::PatchSummary* print_layout_report(const v1::LayoutReport& report);

/// The design options of the flags (no mesh, no corners): what a layout's patches share.
v1::DesignRequest::Options design_options(const DesignFlags& flags);
void print_design_summary(const v1::DesignResult& result);
/// --interior-anchors asks for automatic inner anchors (found by simulating: `run`, `simulate`).
bool automatic_interior_anchors(const DesignFlags& flags);

/// Simulation flags shared by `simulate` and `run`.
/// The simulation flags (described options, unset unless given; see DesignFlags).
struct SimulationFlags {
  DescribedFlags options;        // every described simulation option with a flag, but:
  std::string unit;              // sets unit and unit_in_meters
  std::string interior_anchors;  // "auto" or "" (the design's anchors): --interior-anchors of run
};
void add_simulation_flags(CLI::App* sub, SimulationFlags& flags);
/// The options as given (the request check, resolve_simulation_options, names the flag).
v1::SimulationOptions simulation_options_from_flags(const SimulationFlags& flags);
void print_deployment_summary(const v1::Deployment& deployment);
/// Exit code 4 for a simulation that did not converge (docs/cli.md): one `error:` line on
/// stderr naming each run that did not, why it stopped and what to change; the files written
/// stay in `out` for diagnosis, marked "converged": false. 0 if every run converged.
int unconverged_exit(const v1::Deployment& deployment, const std::string& out);
/// The same for a layout's runs (each patch alone, the whole joined).
int unconverged_exit(const v1::LayoutDeployment& deployment, const std::string& out);

Command add_health_command(CLI::App& app);
/// `gridshell bench sweep` (bench_sweep.cpp): the local and Slurm engines on 32 rows, Slurm's
/// per-task overhead, `sweep collect` over 10 000 rows; section "sweep" of `out`.
int bench_sweep(const std::string& out, bool no_write, int repeats);
/// `gridshell sweep` (command_sweep.cpp; the engines are the batch layer's,
/// gridshell/batch/sweep.h).
Command add_sweep_command(CLI::App& app);
/// A sweep row checked as `gridshell run` checks its command line (sweep_check.cpp).
std::unique_ptr<sweep::RowChecker> run_row_checker();

/// `gridshell bench service` (bench_service.cpp): `repeats` scales the requests per client
/// count; the table goes to section "service" of `out`.
int bench_service(const std::string& out, bool no_write, int repeats);
/// `gridshell bench interactive` (bench_service.cpp): cold design then warm redesigns (ᾱ, member
/// counts) of the seven examples through gridshelld; `server` empty = start one.
int bench_interactive(const std::string& out, bool no_write, const std::string& server,
                      int request_threads, int redesign_threads);
/// `gridshell bench abuse` (bench_abuse.cpp, issue 33): attacks on fresh daemons, `repeats`
/// rounds; `quick`: a 2 s stall timeout instead of 10 s (the CI test); the rows also as JSON to
/// `json_path` if set. Table: section "abuse" of `out`.
int bench_abuse(const std::string& out, bool no_write, int repeats, bool quick,
                const std::string& json_path);

}  // namespace gridshell::cli
