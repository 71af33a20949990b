// SPDX-License-Identifier: GPL-3.0-or-later
// Shared pieces of the gridshell CLI: input meshes, progress line, JSON output.
#pragma once

#include <google/protobuf/message.h>
#include <google/protobuf/repeated_field.h>

#include <array>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cli_syntax.h"
#include "gridshell/design/patch.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/mesh/mesh.h"
#include "gridshell/mesh/mesh_io.h"
#include "gridshell/v1/design.pb.h"
#include "gridshell/v1/layout.pb.h"
#include "gridshell/v1/requests.pb.h"

// CLI11 is heavy (4 s of compile time per file that includes it): declared here, included only
// by the files that build the command line.
namespace CLI {
class App;
}  // namespace CLI

namespace gridshell::cli {

/// A mesh named on the command line: a file path (OBJ/OFF/PLY/STL) or `example:NAME`.
struct InputMesh {
  std::string name;  ///< as given
  TriangleMesh mesh;
  LoadReport report;
  std::optional<std::array<int, 4>> example_corners;  ///< suggested corners of a built-in example
};

/// Loads the mesh, printing the load report's warnings on stderr. Throws InvalidInput.
InputMesh load_input(const std::string& name);

/// Maps a file-order vertex index to the loaded mesh (InvalidInput if removed or out of range).
int mesh_vertex(const InputMesh& input, int file_vertex, const std::string& field);

/// The corners named by --corners (file-order vertex indices translated to the loaded mesh);
/// with no --corners: a built-in example's own corners, else auto. `used` receives a
/// description for the output files ("example", "auto" or the text given).
CornerSpec resolve_corners(const InputMesh& input, const std::string& text, std::string* used);

/// What the CLI's error messages call the parts of a request (cli_errors.cpp).
struct FieldContext {
  std::string mesh;    ///< the MESH argument (a file or example:NAME), for "mesh.*" fields
  std::string design;  ///< the DESIGN file of `gridshell simulate`, for "design.*" fields
  /// The MESH's loader map (file vertex -> mesh vertex), to show suggested corners in file order.
  std::vector<int> vertex_of_file_vertex;
};
/// The "suggestion N: ..." lines after an infeasible design's error line, each with the flags
/// that make it.
void print_suggestions(const std::vector<v1::Suggestion>& suggestions);
/// The context of this run, filled in by the command.
FieldContext& field_context();
/// A request field ("options.lamella_width", "corners.vertices[2]") in the CLI's terms
/// ("--lamella-width", "--corners (corner 3)"); flags and file names stay as they are.
std::string cli_field(const std::string& field, const FieldContext& context);
/// Prints the one "error:" line for `error` on stderr (ending the progress line first) and
/// returns the exit code: 2 invalid input, 3 infeasible, 130 cancelled, 1 internal.
int report_error(const Error& error);

/// Set by SIGINT/SIGTERM (on_interrupt); every computation polls it through Progress.
const std::atomic<bool>* cancel_flag();
/// The signal handler main() installs: sets the cancellation flag (async-signal-safe).
void on_interrupt(int signal);

/// A progress line on stderr ("\r stage  42%") when stderr is a terminal, plain lines every
/// few seconds otherwise; `quiet` silences it.
Progress make_progress(bool quiet);
/// Ends the progress line.
void finish_progress();

/// Protobuf message as JSON with the proto field names (snake_case), pretty-printed
/// (gridshell::to_json, the format of every file).
std::string to_json(const google::protobuf::Message& message, bool pretty = true);

/// The loaded mesh as a request mesh: packed arrays as loaded (so vertex indices of the loaded
/// mesh stay valid), named by the file name, with the loader's warnings.
v1::Mesh request_mesh(const InputMesh& input);

/// The file-order index of a loaded mesh vertex (the first, for welded duplicates), or -1.
int file_vertex(const InputMesh& input, int mesh_vertex);
/// The flags of one group of request options (gridshell/options.h: "patch", "design",
/// "simulation", "fabrication"), added from the one description: every described option with a
/// flag gets it, with its help, unit, range and default, unless the command handles it itself
/// (`except`). A new described option is a new flag with no change here. Values stay text until
/// set_described puts them into the request; an option not given stays unset there, so the
/// request's default applies, and the request check names the flag when a value is out of range
/// (cli_errors.cpp maps the field through the description).
struct DescribedFlags {
  std::string group;
  std::map<std::string, std::optional<std::string>> values;  ///< field name -> text as given
  std::map<std::string, bool> switches;                      ///< boolean options
};
void add_described_flags(CLI::App* sub, const char* group, DescribedFlags& flags,
                         const std::set<std::string>& except = {});
/// Sets each given option in `options` (the group's options message) by its field name; a value
/// that is not of the option's type throws InvalidInput naming the flag.
void set_described(const DescribedFlags& flags, google::protobuf::Message& options);
/// The help line of a described option: "lamella width; positive, in mesh units (or 0: 1% of the
/// longest patch side); default 0".
std::string described_help(const char* group, const char* name);
/// --corner-angles MIN,MAX (degrees) of the automatic corners' search.
void add_corner_angles_flag(CLI::App* sub, std::string& text);
/// Parses it into radians (nothing for ""); InvalidInput naming --corner-angles.
void set_corner_angles(const std::string& text, google::protobuf::RepeatedField<double>* out);
/// The automatic corners' candidates with vertex indices in file order (as sent -> file).
void auto_corners_to_file_order(const InputMesh& input, v1::AutoCornerSearch* search);
/// One summary line for the automatic corners' choice (nothing without a search).
void print_auto_corners(const v1::AutoCornerSearch& search);

/// A design.json (gridshell.v1.Design in JSON; unknown fields rejected). Throws InvalidInput
/// naming the file.
v1::Design read_design_file(const std::string& path);

/// A layout run's design.json (gridshell.v1.LayoutDesign) and each designed patch's design,
/// read from the files it names (relative to it); nullopt for a file that is not one.
struct LayoutDesignFiles {
  v1::LayoutDesign layout;
  std::vector<v1::Design> patches;
};
std::optional<LayoutDesignFiles> read_layout_design_file(const std::string& path);

/// Median of a list of numbers.
double median(std::vector<double> values);

/// Creates the output folder `--out` names (with its parents) and checks that files can be
/// written into it, before any work is done (also before a remote run). Throws InvalidInput
/// naming --out otherwise.
void prepare_output_folder(const std::string& out);
/// After a failed command: removes the folders prepare_output_folder created if nothing was
/// written into them (bad input leaves no empty --out behind; an --out that existed stays).
void remove_unused_output_folder();

}  // namespace gridshell::cli
