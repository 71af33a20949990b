// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — member placement along the cladding functions (paper Section 4.4).
//
// Every point of a cladding function F (a curve from (0,0) to (1,1) in the (u1,u2) square) is a
// candidate member: a geodesic from u1 on the family's first boundary to u2 on the second whose
// surface and planar lengths agree. Along the curve, C(s) is the member length (the distance map
// D at (u1(s), u2(s))). Members go first at the extrema of C (locally longest and shortest
// geodesics: the major surface features), then at the extrema of the curvature of C (finer
// features); they keep a minimum spacing derived from the lamella width and the angles between
// member and boundaries; too dense -> keep those with the largest |curvature of C|; too sparse
// -> fill the gaps and equalize the added members.
#pragma once

#include <string>
#include <vector>

#include "gridshell/design/cladding.h"
#include "gridshell/design/distance_map.h"
#include "gridshell/design/patch.h"
#include "gridshell/design/planar_patch.h"

namespace gridshell {

struct MemberPlacementOptions {
  /// w_m, mesh units; 0 = 1% of the longest patch side (the paper's models are 100 wide and
  /// their lamellas about 1). Default 0.
  double lamella_width = 0;
  double lamella_thickness = 0;  // t, mesh units; 0 = a tenth of the width (w:t = 10:1)
  double clearance = 0.5;        // extra gap between neighbouring lamellas, in widths
  /// Maximum spacing between neighbouring members along either boundary, as a fraction of that
  /// boundary's length; gaps wider than this are filled. Default 0.1 (about 9 inner members).
  double max_spacing = 0.1;
  int min_members = 3;  // inner members per family (boundaries not counted)
  int max_members = 60;
  /// Explicit inner member count per family (0 = automatic). Positions still follow the
  /// features of C(s) and are then equalized.
  int count = 0;
  /// Relative threshold below which extrema of C and of its curvature are ignored as noise.
  double feature_threshold = 0.02;
};

/// The lamella cross-section options ask for on `patch`: 0 resolved to its automatic value.
struct LamellaSize {
  double width = 0;
  double thickness = 0;
};
LamellaSize lamella_size(const Patch& patch, const MemberPlacementOptions& options);

/// One inner member of a family, given by its boundary parameters.
struct MemberPosition {
  double u1 = 0;  ///< parameter on the family's first boundary
  double u2 = 0;  ///< parameter on the second boundary (on the cladding function)
  double s = 0;   ///< normalized arc length along the cladding curve in [0,1]
  enum class Reason { LengthExtremum, CurvatureExtremum, GapFill } reason = Reason::GapFill;
};

/// Inner members of one family, sorted by u1 (and u2: the cladding function is monotone).
/// `surface_map` is the family's D; side_lengths(`patch`) gives the boundary lengths and
/// `planar` the angles between members and boundaries for the spacing rule (algorithm and
/// choices: kernel/design/members.cpp). Throws InvalidInput for inconsistent options (e.g.
/// min_members > max_members) or a cladding polyline not joining (0,0) to (1,1), and Infeasible
/// for an invalid cladding function or if even min_members (or count) cannot be placed.
std::vector<MemberPosition> place_members(const CladdingFunction& cladding,
                                          const DistanceMap& surface_map, const Patch& patch,
                                          const PlanarPatch& planar,
                                          const MemberPlacementOptions& options = {});

}  // namespace gridshell
