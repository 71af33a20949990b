// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — a coarser copy of a large patch on which its distance maps are computed (issue 17).
//
// A design needs about 200 exact single-source fields for its distance maps (R = 100 sources per
// family), each costing ~n^1.5 on an n-vertex patch: 70 s of CPU at 60k vertices. The maps are
// a sampled approximation anyway (the cladding functions interpolate them bilinearly), so above
// a size they are computed on a copy of the patch simplified to a few thousand vertices, whose
// boundary carries the maps' sample points exactly: the sources and targets are the same surface
// points as on the patch, and only the interior is approximated. Members, crossings and notches
// are still traced exactly on the patch itself (grid.h); the copy only moves where they start and
// the feasible range of the planar angle, by amounts reported with the design.
//
// The simplification is CGAL's edge collapse with the Lindstrom-Turk cost and placement (CGAL's
// default, memoryless and shape preserving); the sample points are pinned by the placement. Other
// collapse costs were not compared (docs/decisions.md, issue 17): the measured error of this one
// (5e-5 relative at 15k -> 4k vertices) is already below the maps' own sampling error.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "gridshell/design/family.h"
#include "gridshell/design/patch.h"
#include "gridshell/foundation/progress.h"

namespace gridshell {

/// The maps' sample points per boundary chain when nothing else is asked (DistanceMapOptions's
/// default resolution).
constexpr int kDefaultMapSamples = 100;

/// Patches with more vertices than this get their distance maps (and the coverability's longest
/// member estimate) on a copy simplified to about this many vertices (DistanceMapOptions and
/// CoverabilityOptions::max_vertices default to it).
constexpr int kDefaultMapVertices = 4000;

/// A simplified copy of a patch. Its boundary holds, as vertices at their exact positions, the
/// `samples` points at normalized arc length i/(samples-1) along each of the patch's four family
/// boundary chains (family_boundary: G start = side 0, H start = side 1, G end = side 2
/// reversed, H end = side 3 reversed), computed with point_on_chain exactly as the maps on the
/// patch itself compute their sources and targets. Between them the boundary is straight.
struct MapCopy {
  /// The copy as a patch: same corners (as vertices of the copy), sides as copy vertex chains.
  Patch patch;
  /// chains[c][i]: the copy vertex at u = i/(samples-1) on family boundary chain c, c = 0: G
  /// start, 1: H start, 2: G end, 3: H end.
  std::array<std::vector<int>, 4> chains;
  int samples = 0;         ///< points per chain
  int max_vertices = 0;    ///< the vertex count it was simplified towards
  int patch_vertices = 0;  ///< vertices of the patch it is a copy of
  std::size_t memory_bytes() const;
};

/// Inputs with more vertices are searched on a simplified copy where a search only ranks
/// candidates (automatic corners, the suggestions' moved-corner screens).
constexpr int kSimplifiedSearchAbove = 2 * kDefaultMapVertices;

/// A whole surface simplified by the same edge collapse (for searches that only rank candidates).
struct SimplifiedMesh {
  TriangleMesh mesh;
  /// of_input[v]: the copy's vertex at the input's vertex v if v was kept, else -1.
  std::vector<int> of_input;
};

/// Copies `mesh` and simplifies the copy to about `max_vertices` vertices under the rules above:
/// the vertices `keep` (repeats allowed) never move and are never collapsed into each other,
/// boundary vertices only collapse along the boundary. Deterministic. The copy is the input
/// itself when it has no more than `max_vertices` vertices. Throws InvalidInput for a vertex
/// outside the mesh, max_vertices < 1, or a surface CGAL's mesh cannot hold (TriangleMesh's own
/// checks already refuse non-manifold and inconsistently oriented faces).
SimplifiedMesh simplify_mesh(const TriangleMesh& mesh, int max_vertices,
                             const std::vector<int>& keep, const Progress& progress = {});

/// Copies `patch` and simplifies the copy to about `max_vertices` vertices (never below what its
/// boundary samples need), keeping the 4 x `samples` boundary sample points as vertices at their
/// exact positions. Deterministic. Checks cancellation every few hundred collapses. Throws
/// InvalidInput for samples < 2 or max_vertices < 1.
MapCopy make_map_copy(const Patch& patch, int max_vertices, int samples,
                      const Progress& progress = {});

/// An exact geodesic distance on the patch between two boundary points: from u1 on `family`'s
/// start chain to u2 on its end chain (for a member: its start, its refined end, its length).
struct BoundaryDistance {
  Family family = Family::G;
  double u1 = 0, u2 = 0;
  double distance = 0;
};

/// The copy's error where the design reads the maps: the largest relative difference, over
/// `checks`, between the distance on the copy between the same two points and the exact
/// `distance`. Each point is located on the copy's boundary at the closest point between the two
/// samples around it. The copy solves run on `threads` threads (0 = all).
double map_copy_error(const MapCopy& copy, const Patch& patch,
                      const std::vector<BoundaryDistance>& checks, int threads = 0,
                      const Progress& progress = {});

}  // namespace gridshell
