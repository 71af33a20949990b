// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — distance maps between opposite patch boundaries (paper Section 4.2).
//
// The parametrization of both families is in family.h.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

#include "gridshell/design/distance_map_copy.h"
#include "gridshell/design/family.h"
#include "gridshell/design/patch.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/geodesic/geodesic.h"

namespace gridshell {

/// The boundary a member family starts from (`end` 0) or ends on (`end` 1), as a chain of patch
/// vertices ordered by increasing parameter (see the conventions above).
std::vector<int> family_boundary(const Patch& patch, Family family, int end);

/// The surface point at normalized arc length t in [0,1] along a chain of patch vertices. The
/// point lies on a boundary edge (or at a vertex); t outside [0,1] throws InvalidInput.
SurfacePoint point_on_chain(const TriangleMesh& mesh, const std::vector<int>& chain, double t);

/// Polyline length of a chain of vertices.
double chain_length(const TriangleMesh& mesh, const std::vector<int>& chain);

struct DistanceMapOptions {
  /// Samples per boundary R (the map is R x R). 0 = adaptive: about the number of mesh edges
  /// along the longer boundary, clamped to [32, 200]. Default 100 (paper: "around 100 x 100").
  int resolution = 100;
  /// Worker threads for the R single-source solves per family; 0 = hardware concurrency.
  /// The result does not depend on it.
  int threads = 0;
  /// A patch with more vertices than this gets its maps on a copy simplified to about this many
  /// vertices (distance_map_copy.h): its R sample points per boundary are the patch's own, its
  /// interior is approximated. 0 = never: exact maps on every patch. Default 4000 (all seven
  /// paper examples at their own resolution are below it).
  int max_vertices = kDefaultMapVertices;
};

/// D(u1,u2) of one family on a grid: distances(i, j) = exact geodesic distance between the
/// points at u1 = i/(R-1) on the first boundary and u2 = j/(R-1) on the second.
struct DistanceMap {
  Family family = Family::G;
  Eigen::MatrixXd distances;  ///< R x R
  int resolution() const { return static_cast<int>(distances.rows()); }
};

struct DistanceMaps {
  DistanceMap g;  ///< D_u
  DistanceMap h;  ///< D_v
  /// Vertices of the mesh the maps were computed on: the patch's own count, or its copy's.
  int mesh_vertices = 0;
  /// The simplified copy they were computed on; null when they are exact (on the patch). Kept so
  /// that the design can measure the copy's error at its members' ends (map_copy_error).
  std::shared_ptr<const MapCopy> copy;
  /// On a copy: the largest relative difference between the copy's distance and the exact side
  /// length at the maps' four corner entries (0,0) and, which are then set to the exact
  /// side lengths (the cladding functions start and end there). 0 for exact maps.
  double corner_error = 0;
};

/// Both surface distance maps, computed in parallel over sources with `solver` (built on
/// patch.mesh), or on a simplified copy of a patch above options.max_vertices: `copy` if it is
/// one made with this many vertices and R samples (e.g. the coverability's), else a new one.
/// Reports progress; throws Cancelled when cancelled.
DistanceMaps compute_distance_maps(const Patch& patch, const GeodesicSolver& solver,
                                   const DistanceMapOptions& options = {},
                                   const Progress& progress = {},
                                   std::shared_ptr<const MapCopy> copy = nullptr);

/// The resolution `options` asks for on this patch (resolves 0 = adaptive).
int distance_map_resolution(const Patch& patch, const DistanceMapOptions& options);

}  // namespace gridshell
