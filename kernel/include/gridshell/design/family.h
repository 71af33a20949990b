// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the two member families of a grid and how their boundaries are parametrized.
//
// Conventions (used by every grid-design stage):
//   patch.sides[i] runs from corner c_i to c_{i+1}.
//   Family G (members g_i, parameters u1,u2) joins side 0 and side 2:
//     u1 in [0,1] runs along side 0 from c0 to c1;  u2 in [0,1] along side 2 *reversed*, c3 to c2.
//     So (u1,u2) = (0,0) is the boundary member side 3 (c0-c3) and (1,1) is side 1 (c1-c2).
//   Family H (members h_j, parameters v1,v2) joins side 1 and side 3:
//     v1 runs along side 1 from c1 to c2;  v2 along side 3 reversed, c0 to c3.
//     So (v1,v2) = (0,0) is side 0 (c0-c1) and (1,1) is side 2 (c3-c2).
//   Parameters are normalized arc length on the boundary polylines (surface) and on the straight
//   sides (plane), so boundary correspondence (criterion ii) holds by construction.
#pragma once

namespace gridshell {

/// The two member families: G joins sides 0 and 2, H joins sides 1 and 3.
enum class Family { G = 0, H = 1 };

}  // namespace gridshell
