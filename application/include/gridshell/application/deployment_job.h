// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the simulation as one job from proto messages to proto messages, shared by the
// CLI (`gridshell simulate`, `gridshell run`) and the daemon (Simulate, Run): options resolved
// and validated in one place, both runs, deployment.json and its views.
#pragma once

#include <optional>
#include <string>

#include "gridshell/foundation/progress.h"
#include "gridshell/simulation/simulation.h"
#include "gridshell/v1/deployment.pb.h"
#include "gridshell/v1/design.pb.h"
#include "gridshell/v1/requests.pb.h"

namespace gridshell {

/// Length units the simulation knows: "mm", "cm", "m", "in", "ft" or a number of metres.
/// Returns metres per unit; "" gives 0 (unknown). Throws InvalidInput naming `field`.
double parse_length_unit(const std::string& unit, const std::string& field = "unit");

/// Fills unset fields of `options` with their defaults (material lime-wood, notches both, the
/// paper's notch terms ...) and validates every field, throwing InvalidInput whose field names
/// it as a field of SimulationOptions ("friction_mu"; callers put it where it came from).
/// On return every field holds the effective value.
v1::SimulationOptions resolve_simulation_options(v1::SimulationOptions options);

/// Kernel options for one run from resolved proto options.
SimulationOptions kernel_simulation_options(const v1::SimulationOptions& resolved, bool notches);

struct DeploymentJob {
  v1::Deployment deployment;  ///< deployment.json
  std::optional<DeploymentRun> without_notches, with_notches;
  std::string deployed_obj;  ///< the main run (with notches if it ran)
  std::string deviation_ply;
  std::string deployed_without_notches_obj;  ///< only when both ran
  std::string deviation_without_notches_ply;
  /// options.interior_anchors = "auto": design.json with the inner anchors added, else empty.
  std::string anchored_design;
  /// The anchors as simulated: the design's, and the inner ones the search added.
  std::vector<Anchor> anchors;
};

/// Simulates the design (runs without and/or with notches as options.notches says) with
/// `threads` worker threads (0 = all cores; the result does not depend on it). Errors name
/// "design.<field>" or "options.<field>".
DeploymentJob run_deployment_job(const v1::Design& design, const v1::SimulationOptions& options,
                                 const std::string& design_name, const Progress& progress = {},
                                 int threads = 0);

/// The job as a Simulate answer: deployment.json's message and the views that were made
/// (deployed.obj, deviation.ply, their *_without_notches twins, design-anchored.json).
v1::SimulateResult simulate_result(DeploymentJob job);

}  // namespace gridshell
