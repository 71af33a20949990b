// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the deployment of a layout's patches taken together (issue 35,
// docs/multi-patch.md): each patch deploys on its own, then the whole is measured: its RMS over
// every patch's rod vertices, and how far apart the two boundary lamellas of each seam are at its
// joints (the gaps the seam bolts have to close); and the inputs of the whole's joined
// simulation (simulate_joined): the anchors that hold the whole and the seams' bolts.
#pragma once

#include <vector>

#include "gridshell/design/layout.h"
#include "gridshell/simulation/simulation.h"

namespace gridshell {

/// The gaps of one seam's joints between the two patches' deployed boundary lamellas.
struct SeamGaps {
  int seam = 0;              ///< index into LayoutResult::seams
  std::vector<double> gaps;  ///< per joint, in SeamJoints::joints order
  double max_gap = 0;
  double rms_gap = 0;
};

/// For each seam of `joints`, the distance at each joint between the point at its arc length on
/// one patch's deployed boundary lamella and on the other's. `runs[j]` is patch j's run (null
/// when it has none; its seams are skipped). A lamella's arc length is taken along its deployed
/// centerline, scaled by its rest length (the lamellas barely stretch).
std::vector<SeamGaps> seam_gaps(const std::vector<SeamJoints>& joints,
                                const std::vector<const DeploymentRun*>& runs);

/// The runs of several patches as one: their lamellas in patch order, the RMS over all their
/// rod vertices (each run's RMS weighted by its grid vertices), the largest deviation, the
/// iterations and seconds added up; converged only if every run did. Null runs are skipped.
DeploymentRun combine_runs(const std::vector<const DeploymentRun*>& runs);

/// The seam joints as bolts between parts: `part_of[j]` is patch j's part (-1: none, its seams
/// are skipped). End 0 is the lamella of the patch that comes first in the layout, each end's
/// arc length along its own lamella. Each lamella keeps the height its own patch gives it (a g
/// member half a thickness below the surface, an h member above, as every rod starts): a bolt's
/// offset is their difference, -1, 0 or 1 thickness. So every bolt is closed at the start, and no
/// loop of bolts, crossings and anchors (around a corner inside the whole, or two patches
/// anchored at one outer corner) asks for heights that cannot all hold.
std::vector<PartBolt> seam_bolts(const std::vector<SeamJoints>& joints,
                                 const std::vector<int>& part_of);

/// The meshes as one (their disjoint union, vertices and faces in order).
TriangleMesh merge_meshes(const std::vector<const TriangleMesh*>& meshes);

}  // namespace gridshell
