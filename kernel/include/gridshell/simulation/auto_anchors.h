// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <vector>

#include "gridshell/design/anchors.h"
#include "gridshell/design/grid.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/mesh/mesh.h"
#include "gridshell/simulation/simulation.h"

namespace gridshell {

/// `--interior-anchors auto` (issue 18): inner anchors added one at a time where the deployed
/// grid strays farthest from its target, for as long as each one lowers the deviation enough.
struct AutoAnchorOptions {
  /// An added anchor is kept only if the RMS deviation falls by at least this fraction.
  double min_improvement = 0.05;
  int max_anchors = 8;  ///< at most this many inner anchors added
  /// No (further) anchor once the RMS deviation is at most this (0: no goal). Every anchor is a
  /// support to build: a grid that deploys well enough on the design's anchors gets none.
  double goal_rms = 0;
};

struct AutoAnchorResult {
  std::vector<Anchor> anchors;  ///< the design's anchors plus the inner ones kept
  int added = 0;                ///< inner anchors kept
  DeploymentRun run;            ///< the deployment with `anchors`
  /// RMS of each simulation in order: the design's anchors first, then one per trial anchor
  /// (the last one not kept unless `added` == max_anchors).
  std::vector<double> rms_trials;
};

/// Simulates the grid held at `anchors`, then repeatedly pins the inner crossing (not on a
/// boundary member, not yet anchored) whose deployed position lies farthest from the target to
/// its target position and surface normal and simulates again; the anchor is kept if the RMS
/// deviation fell by at least `min_improvement`, else the search stops; it also stops (or does
/// not start) once the RMS deviation is at most `goal_rms`. Progress spans all
/// simulations; cancelling stops after the current one.
AutoAnchorResult auto_interior_anchors(const Grid& grid, std::vector<Anchor> anchors,
                                       const TriangleMesh& target, double lamella_width,
                                       double lamella_thickness,
                                       const SimulationOptions& options = {},
                                       const AutoAnchorOptions& auto_options = {},
                                       const Progress& progress = {});

}  // namespace gridshell
