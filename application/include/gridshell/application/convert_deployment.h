// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — conversions for the deployment simulation: design.json back into the kernel's
// grid, and simulation results into deployment.json.
#pragma once

#include <string>

#include "gridshell/design/design.h"
#include "gridshell/simulation/simulation.h"
#include "gridshell/v1/deployment.pb.h"
#include "gridshell/v1/design.pb.h"

namespace gridshell {

/// What the simulation needs from a design file: the target patch mesh and corners, the grid
/// (members with their surface polylines and planar segments, crossings), the anchors, the
/// lamella width and thickness and the angles. Validates every field it reads and throws
/// InvalidInput naming it ("members[3].surface: ...").
Design design_from_proto(const v1::Design& design);

/// deployment.json from one or two runs (either may be null, not both).
v1::Deployment to_proto(const DeploymentRun* without_notches, const DeploymentRun* with_notches,
                        const v1::SimulationOptions& options, const std::string& design_name);

/// Adds the run's lamellas (deployment.json's `rods`) to `out`.
void fill_lamellas(const DeploymentRun& run, google::protobuf::RepeatedPtrField<v1::Lamella>* out);

}  // namespace gridshell
