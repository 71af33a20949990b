// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — views of a simulated deployment: the lamellas as solid boxes (OBJ) and the rod
// centerlines coloured by their distance to the target (PLY).
#pragma once

#include <string>

#include "gridshell/simulation/simulation.h"

namespace gridshell {

/// Every lamella as a thin box of its real width and thickness swept along the deployed
/// centerline (width along the material frame's width direction, thickness along the material
/// normal), one OBJ object per lamella (`g0`, `h3`, ...), with end caps. Faces are oriented
/// outwards.
std::string deployed_obj(const DeploymentRun& run, double lamella_width, double lamella_thickness);

/// The rod centerlines as an ASCII PLY: vertices with their distance to the target as a float
/// property `deviation` and as a colour (blue = 0 to red = `max_deviation`, or the run's own
/// maximum when `max_deviation` <= 0), and the rod edges as PLY edges.
std::string deviation_ply(const DeploymentRun& run, double max_deviation = 0);

}  // namespace gridshell
