// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — a patch layout request -> cut_layout -> layout.json and layout.obj (issue 35,
// docs/multi-patch.md): what `gridshell layout` runs.
#pragma once

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/v1/layout.pb.h"

namespace gridshell {

/// Checks the request (the mesh as every request's; corner vertices are indices as sent; the
/// patch options as PatchRequest's) and cuts the layout. A malformed layout throws InvalidInput
/// naming the field ("layout.corners[3].point"), overlapping patches Infeasible; a patch that
/// cannot be cut or misses a check is reported in its PatchSummary (ok false), not thrown.
v1::LayoutResult run_layout(const v1::LayoutRequest& request, const Progress& progress = {},
                            const RunSettings& settings = {});

/// layout.json (the report), layout.obj (the cut patches, one object each, named) and
/// layout.svg (the plan).
FileBundle layout_files(const v1::LayoutResult& result);

}  // namespace gridshell
