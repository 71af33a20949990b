// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — conversions between kernel values and the proto messages of proto/gridshell/v1.
// The one place where the CLI (and later the daemon) turn results into files and replies.
#pragma once

#include <functional>
#include <string>

#include "gridshell/design/design.h"
#include "gridshell/v1/design.pb.h"

namespace gridshell {

/// The deterministic design file (no timings).
v1::Design to_proto(const Design& design, const v1::DesignOptions& options,
                    const std::string& input_name);

/// One anchor as design.json writes it (also a deployment's added inner anchors).
void to_proto(const Anchor& anchor, v1::Anchor* out);

/// Timings and summary numbers of a design run.
v1::DesignReport to_report(const Design& design, const std::string& input_name, int mesh_vertices,
                           double seconds);

/// How the automatic corners were chosen; `sent_vertex` maps a mesh vertex to the caller's
/// numbering (-1 if none).
v1::AutoCornerSearch to_proto(const AutoCornerReport& report, const TriangleMesh& mesh,
                              const std::function<int(int)>& sent_vertex);

}  // namespace gridshell
