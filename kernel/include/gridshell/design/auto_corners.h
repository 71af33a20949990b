// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — automatic corners (issue 18): a bounded search over candidate corner quadruples
// for the largest patch that satisfies the design's criteria.
//
// Candidates, cheapest first:
//   1. boundary turning points: on every boundary loop, the vertices where the boundary turns
//      most (local maxima of pi minus the interior angle sum, at least 10 degrees), taken four
//      at a time in loop order, the sharpest quadruple first (the former rule's choice);
//   2. only if no boundary candidate is accepted (or the mesh is closed): points inside,
//      geodesic squares and 2:1 rectangles of several sizes about the point farthest from the
//      boundary, in two orientations.
// Every candidate is cut (four exact geodesics, cheap); those whose corner angles lie in
// [min_corner_angle, max_corner_angle] are then evaluated fully in order of decreasing area
// until one passes: coverability and smoothing with exact re-cut boundaries (eta <= eta_max),
// distance maps at the design's resolution and a non-empty feasible planar angle range. The
// first that passes is the largest acceptable candidate. Counts are bounded (max_cuts,
// max_evaluations); the report lists every candidate with its measures and the reason it was
// or was not taken.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gridshell/design/cladding.h"
#include "gridshell/design/distance_map.h"
#include "gridshell/design/distance_map_copy.h"
#include "gridshell/mesh/mesh.h"

namespace gridshell {

struct AutoCornerOptions {
  double min_corner_angle = 0.7853981633974483;  // 45 degrees: inner corner angle on the patch
  double max_corner_angle = 2.356194490192345;   // 135 degrees
  int max_cuts = 48;                             // candidate patches cut at most
  int max_evaluations = 6;                       // candidates evaluated fully at most
  /// Meshes with more vertices are searched on a copy simplified to `simplify_to` vertices
  /// (candidates cut and ranked there; each evaluated candidate cut again exactly).
  int simplify_above = kSimplifiedSearchAbove;
  int simplify_to = kDefaultMapVertices;
  DistanceMapOptions maps;   // for the planar angle check: the design's maps
  CladdingOptions cladding;  // for the planar angle check: the design's slope bounds
};

struct AutoCornerCandidate {
  std::array<int, 4> vertices{};  ///< corner vertices of the input mesh
  std::string kind;               ///< "boundary" | "inner"
  double area = 0;                ///< of the cut patch before smoothing; 0 if not cut
  /// Of the patch cut on the simplified copy (0 if the search ran on the input itself).
  double coarse_area = 0;
  std::array<double, 4> corner_angles{};
  double eta = 0;  ///< after smoothing, 0 if not reached
  std::optional<std::array<double, 2>> alpha_range;
  bool accepted = false;
  std::string reason;
};

struct AutoCornerReport {
  std::vector<AutoCornerCandidate> candidates;
  int chosen = -1;
  int cuts = 0;
  int evaluations = 0;
  double seconds = 0;
  double min_corner_angle = 0, max_corner_angle = 0;
  std::string rule;
  /// Vertices of the simplified copy the candidates were cut on and ranked by (0: the input);
  /// the largest relative difference between a candidate's area on the copy and on the input,
  /// over the candidates cut on both.
  int simplified_vertices = 0;
  double area_error = 0;
};

/// Candidate corner quadruples of the first kind (boundary turning points), best first:
/// vertices of one boundary loop in loop order. Empty for a closed mesh.
std::vector<std::array<int, 4>> boundary_corner_candidates(const TriangleMesh& mesh);

/// Candidate corner quadruples inside the surface (geodesic squares and rectangles about its
/// innermost point), largest first, each counter-clockwise about the surface normal.
std::vector<std::array<int, 4>> inner_corner_candidates(const TriangleMesh& mesh);

}  // namespace gridshell
