// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — a patch layout request -> cut_layout -> layout.json and layout.obj (issue 35,
// docs/multi-patch.md): what `gridshell layout` runs.
#pragma once

#include <optional>
#include <string>

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/design/layout.h"
#include "gridshell/v1/layout.pb.h"

namespace gridshell {

/// Checks the request (the mesh as every request's; corner vertices are indices as sent; the
/// patch options as PatchRequest's) and cuts the layout. A malformed layout throws InvalidInput
/// naming the field ("layout.corners[3].point"), overlapping patches Infeasible; a patch that
/// cannot be cut or misses a check is reported in its PatchSummary (ok false), not thrown.
v1::LayoutResult run_layout(const v1::LayoutRequest& request, const Progress& progress = {},
                            const RunSettings& settings = {});

/// The layout message as kernel input: corner vertices are mesh vertices as loaded (`load` maps
/// the sent indices); InvalidInput names "layout.corners[i]" / "layout.patches[j].corners".
PatchLayout layout_from_proto(const v1::Layout& layout, const LoadReport& load);

/// A layout patch's own design choices (alpha, members_u, members_v: Layout.Patch) over the
/// run's `options` and `record`; InvalidInput names "<field>.alpha" ... (`field`:
/// "layout.patches[j]").
void apply_patch_design(const v1::Layout::Patch& patch, const std::string& field,
                        DesignOptions& options, v1::DesignOptions& record);

/// The automatic layout's options checked (fields "<prefix>.max_patches" ...), defaults filled.
AutoLayoutOptions prepare_auto_layout_options(const v1::AutoLayoutOptions& options,
                                              const std::string& prefix = "automatic");

/// A layout as requested, cut: the given one, or with `automatic` set (and `layout` empty) one
/// computed by auto_layout. `given` is the layout as the answer reports it (sent vertex indices;
/// an automatic one's inner corners as points).
struct RequestedLayout {
  LayoutResult cut;
  v1::Layout given;
  std::optional<v1::LayoutReport::Automatic> automatic;
};
RequestedLayout cut_requested_layout(const v1::Layout& layout,
                                     const v1::AutoLayoutOptions* automatic,
                                     const TriangleMesh& mesh, const LoadReport& load,
                                     const TargetPatchOptions& options, const Progress& progress);

/// A cut layout as the Layout answer: layout.json's report (the layout with names filled in,
/// coverage, each patch's checks, the seams, what is not covered and why, how an automatic
/// layout was found), each cut patch's mesh and layout.svg.
v1::LayoutResult layout_result(const RequestedLayout& layout, const TriangleMesh& mesh,
                               const std::string& input);

/// A mesh message's name for reports: its name, else its example's.
std::string mesh_label(const v1::Mesh& mesh);

/// OBJ texts as one: each part's objects named "<prefix>-<object>" (a part without objects is
/// one object named <prefix>), faces renumbered through the file.
std::string merge_obj(const std::string& heading,
                      const std::vector<std::pair<std::string, std::string>>& parts);

/// Each patch of the layout designed and simulated as a single patch is (its cut patch, no
/// smoothing yet; corners the layout's), then measured together: the seam joints, each seam's
/// gaps between the two patches' deployed boundary lamellas, the whole's RMS. A patch whose cut,
/// checks or design fail is reported in the layout report (ok false; coverage without it) and
/// has no design; the run goes on with the others. Errors name "layout.…", "design.…" (the
/// design options) or "simulation.…".
v1::LayoutRunResult run_layout_run(const v1::LayoutRunRequest& request,
                                   const Progress& progress = {}, const RunSettings& settings = {});

/// What `gridshell run --layout` writes: in the folder, layout_files, design.json
/// (LayoutDesign), deployment.json (LayoutDeployment) and the whole's deployed.obj (objects
/// "P1-g0" ...) and deviation.ply; in patches/<name>/, each designed patch's run files
/// (run_files).
struct LayoutRunFiles {
  FileBundle whole;
  std::vector<std::pair<std::string, FileBundle>> patches;  ///< (patch name, its files)
};
LayoutRunFiles layout_run_files(const v1::LayoutRunResult& result);

/// layout.json (the report), layout.obj (the cut patches, one object each, named) and
/// layout.svg (the plan).
FileBundle layout_files(const v1::LayoutResult& result);

}  // namespace gridshell
