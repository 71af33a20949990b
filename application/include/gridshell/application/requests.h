// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the computations behind `gridshell patch|design|simulate|run|geodesic` and the
// daemon's RPCs: request message -> checked kernel inputs -> kernel -> result message.
//
// The CLI's in-process runs and gridshelld call the same functions, so a local and a remote run
// produce the same result messages (and, through files.h, the same files). Nothing here knows
// about gRPC or HTTP; a request is plain data and never names a file to open.
//
// Every field of a request is checked before the kernel runs: sizes, indices, NaN/Inf, counts,
// option ranges. Problems throw InvalidInput whose field is the request's path
// ("mesh.positions[7]", "options.eta_max"); the kernel adds Infeasible and Cancelled, with
// fields in the same vocabulary. Clients render the fields in their own terms.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "gridshell/design/design.h"
#include "gridshell/design/layout.h"
#include "gridshell/design/target_patch.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/geodesic/geodesic.h"
#include "gridshell/mesh/mesh_io.h"
#include "gridshell/v1/requests.pb.h"

namespace gridshell {

class PatchCache;

struct RunSettings {
  /// Kernel worker threads inside one request; 0 = all cores. Results do not depend on it.
  int threads = 0;
  /// Per-patch work shared by the designs of one daemon (patch_cache.h); null = none.
  PatchCache* patch_cache = nullptr;
  /// Kernel threads of a redesign on cached patch work (its grid stage: one geodesic solve per
  /// member), where a client waits for the answer while a slider moves; 0 = all cores, -1 = as
  /// `threads`. Results do not depend on it.
  int redesign_threads = -1;
};

/// The request's mesh, however it was given: packed arrays (mesh_from_arrays), the bytes of a
/// file (read_mesh, the CLI's parser; errors name `mesh.file` and the line) or an example's name
/// (its suggested corners into `example_corners`). `report` receives the repairs and the map
/// from sent vertex index to mesh vertex.
TriangleMesh to_mesh(const v1::Mesh& mesh, LoadReport* report,
                     std::array<int, 4>* example_corners = nullptr);

/// Load: the mesh as loaded (packed arrays to send back), what the loader did, and an example's
/// corners.
v1::LoadResult run_load(const v1::LoadRequest& request, const Progress& progress = {},
                        const RunSettings& settings = {});

/// Examples: the built-in example surfaces.
v1::ExamplesResult run_examples(const v1::ExamplesRequest& request, const Progress& progress = {},
                                const RunSettings& settings = {});

/// The mesh vertex that sent vertex `v` (an index into the request's mesh as sent) became;
/// InvalidInput naming `field` if it is out of range or was removed.
int loaded_vertex(const LoadReport& load, int v, const std::string& field);

/// Index of the sent vertex that became mesh vertex `v` (the first one, for welded
/// duplicates); -1 for none.
int sent_vertex(const LoadReport& load, int v);

/// Mesh -> packed arrays.
v1::Mesh to_proto(const TriangleMesh& mesh, const std::string& name);

/// Corner spec of the loaded mesh (vertex indices translated through `load`).
CornerSpec to_corner_spec(const v1::Corners& corners, const LoadReport& load);

/// Parses a planar angle: "min", "max", or an angle in radians ("1.2") or degrees ("70deg").
/// Throws InvalidInput (field "options.alpha").
void parse_alpha(const std::string& text, DesignOptions& options);

/// A Corners message for a spec on a mesh sent as is, with the label recorded in design.json.
v1::Corners to_proto(const CornerSpec& spec, const std::string& label);

// Patch ------------------------------------------------------------------------------------------

/// A patch request checked and converted into kernel inputs.
struct PatchInputs {
  TriangleMesh mesh;
  LoadReport load;
  CornerSpec corners;
  TargetPatchOptions options;
};

/// Checks every field; throws InvalidInput naming the first bad one.
PatchInputs prepare_patch(const v1::PatchRequest& request);

/// The patch stage (make_target_patch) on a request: patch.json's report and the patch mesh.
/// Corner `input_vertex` values are indices into the request's mesh.
v1::PatchResult run_patch(const v1::PatchRequest& request, const Progress& progress = {},
                          const RunSettings& settings = {});

// Design -----------------------------------------------------------------------------------------

/// A design request checked and converted into kernel inputs.
/// An infeasible design with the ranked feasible suggestions computed for it (issue 18): the
/// daemon puts them in ErrorDetail.suggestions, the CLI prints them after the error line.
class InfeasibleWithSuggestions : public Infeasible {
 public:
  InfeasibleWithSuggestions(const std::string& field, const std::string& message,
                            std::vector<v1::Suggestion> suggestions)
      : Infeasible(field, message), suggestions_(std::move(suggestions)) {}
  const std::vector<v1::Suggestion>& suggestions() const { return suggestions_; }

 private:
  std::vector<v1::Suggestion> suggestions_;
};

struct DesignInputs {
  TriangleMesh mesh;
  LoadReport load;
  CornerSpec corners;
  DesignOptions options;
  v1::DesignOptions record;  ///< the options as recorded in design.json (completed after the run)
  int suggest = 3;           ///< ranked feasible suggestions to compute when infeasible
  /// DesignRequest.layout_patch: the layout (mesh vertices as loaded) and the index of the patch
  /// designed alone; `corners` is unused then.
  std::optional<PatchLayout> layout;
  int layout_patch = -1;
};

/// Checks every field; throws InvalidInput naming the first bad one.
DesignInputs prepare_design(const v1::DesignRequest& request);

/// The options part of prepare_design: checks `options` (fields "options.<name>") into
/// in.options, in.record (all but its corners) and in.suggest.
void prepare_design_options(const v1::DesignRequest::Options& options, DesignInputs& in);

/// A designed grid as a DesignResult: design.json's message (`record` completed with the
/// design's lamella size and map resolution), report.json's and the views planar.svg,
/// spatial.obj and maps.svg. `mesh_vertices` is the input's vertex count.
v1::DesignResult design_result(const Design& design, v1::DesignOptions record,
                               const std::string& name, int mesh_vertices, double seconds);

/// Patch stage and grid design (make_design) on a request: design.json, report.json and the
/// SVG/OBJ views (planar.svg, spatial.obj, maps.svg).
v1::DesignResult run_design(const v1::DesignRequest& request, const Progress& progress = {},
                            const RunSettings& settings = {});

// Simulate and Run ---------------------------------------------------------------------------

/// Simulation options checked and completed with their defaults (material moduli, unit);
/// throws InvalidInput naming `prefix`.field ("options.friction_mu").
v1::SimulationOptions prepare_simulation_options(const v1::SimulationOptions& options,
                                                 const std::string& prefix = "options");

/// The deployment simulation (paper Section 5) of a design message: deployment.json and the
/// views deployed.obj and deviation.ply (and their *_without_notches twins when both runs are
/// asked for). Bad options name `options.<field>`, a bad design `design.<field>`.
v1::SimulateResult run_simulate(const v1::SimulateRequest& request, const Progress& progress = {},
                                const RunSettings& settings = {});

// Geodesic ----------------------------------------------------------------------------------

/// A geodesic request checked and converted into kernel inputs.
struct GeodesicInputs {
  TriangleMesh mesh;
  int source = 0;  ///< vertex of `mesh`
  GeodesicMethod method = GeodesicMethod::Fast;
  std::optional<GeodesicMethod> reference;
  int repeat = 1;
};
/// Checks every field; throws InvalidInput naming the first bad one.
GeodesicInputs prepare_geodesic(const v1::GeodesicRequest& request);
/// One exact single-source distance field (`gridshell geodesic`): timed (median of `repeat`
/// solves), optionally compared with a reference engine; the distances of every vertex of the
/// mesh as loaded (the sent order unless the loader removed or welded vertices) on request.
v1::GeodesicResult run_geodesic(const v1::GeodesicRequest& request, const Progress& progress = {},
                                const RunSettings& settings = {});

/// Patch stage, grid design and simulation in one call.
v1::RunResult run_run(const v1::RunRequest& request, const Progress& progress = {},
                      const RunSettings& settings = {});

}  // namespace gridshell
