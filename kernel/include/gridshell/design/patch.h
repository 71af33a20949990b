// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the target patch (paper Sections 3.2-3.3, 4.1 criterion (iv)): four corners on the
// target surface, joined by exact shortest geodesics; the mesh is cut along them and the
// outside dropped.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "gridshell/foundation/progress.h"
#include "gridshell/geodesic/geodesic.h"
#include "gridshell/mesh/mesh.h"

namespace gridshell {

/// How the user named the four corners (the API's `corners`; the CLI's --corners text is parsed
/// into one by the CLI).
struct CornerSpec {
  enum class Kind {
    Vertices,  ///< vertex indices of the mesh
    Points,    ///< points, snapped to the closest surface point
    Auto,      ///< the four boundary vertices with the sharpest turning angle
  };
  Kind kind = Kind::Auto;
  std::array<int, 4> vertices{};
  std::array<Vec3, 4> points{};
  /// Corners given as vertex indices (e.g. an example surface's suggested corners).
  static CornerSpec at_vertices(const std::array<int, 4>& vertices) {
    CornerSpec spec;
    spec.kind = Kind::Vertices;
    spec.vertices = vertices;
    return spec;
  }
};

/// Four boundary vertices with the largest turning angle (pi minus the interior angle sum), in
/// boundary order. Throws InvalidInput if the mesh has no boundary or fewer than 4 boundary
/// vertices (field "corners").
std::array<int, 4> auto_corners(const TriangleMesh& mesh);

struct PatchCutOptions {
  /// Path points closer than this fraction of their edge's length to an edge end snap to that
  /// vertex instead of creating a sliver triangle. Default 1e-6.
  double snap_fraction = 1e-6;
};

/// A patch cut out of a mesh: its own mesh, its four corners and four sides.
struct Patch {
  TriangleMesh mesh;
  /// Corner vertices in `mesh`, counter-clockwise around the patch (interior to the left).
  std::array<int, 4> corners{};
  /// sides[i]: boundary vertex chain from corners[i] to corners[(i+1)%4], both included.
  std::array<std::vector<int>, 4> sides;
  /// For each patch vertex: the input-mesh vertex it came from, or -1 for vertices created by
  /// the cut (points on edges, corners inside faces).
  std::vector<int> input_vertex;
  /// True when the user's corner order was clockwise and it was reversed to make it ccw.
  bool corners_reversed = false;
};

/// Cuts the patch bounded by the exact shortest geodesics c0->c1->c2->c3->c0 out of `mesh`
/// (computed with `geodesic`). Faces crossed by a boundary geodesic are split so the patch
/// boundary consists of mesh edges. Throws Infeasible (field "corners") when the boundary
/// geodesics touch or cross each other (criterion (iv)) and InvalidInput ("corners[i]") when
/// corners coincide or name no face.
Patch cut_patch(const TriangleMesh& mesh, const std::array<SurfacePoint, 4>& corners,
                const GeodesicOptions& geodesic = {}, const PatchCutOptions& options = {},
                const Progress& progress = {});

/// A mesh with given surface points made vertices (faces or edges split where a point lies
/// inside), and the vertex of each point.
struct MeshWithCorners {
  TriangleMesh mesh;
  std::vector<int> corners;
};
/// Inserts `points` (on `mesh`) as vertices; InvalidInput "<field>[i]" for a point on no face or
/// two points at one spot.
MeshWithCorners insert_corners(const TriangleMesh& mesh, const std::vector<SurfacePoint>& points,
                               const std::string& field, const PatchCutOptions& options = {});

/// The exact shortest geodesic between two vertices, as cut_patch computes a side (Infeasible
/// when no geodesic joins them).
std::vector<SurfacePoint> side_geodesic(const GeodesicSolver& solver, const TriangleMesh& mesh,
                                        int from, int to, const Progress& progress = {});

/// Cuts the patch of the corner vertices `corners` of `mesh` along the given sides (sides[i] from
/// corners[i] to corners[i+1], e.g. side_geodesic's): for patches that share a side (layouts),
/// which is computed once and given to both. `input_vertex_count`: vertices of the mesh the
/// caller's indices refer to (Patch::input_vertex); Infeasible as cut_patch.
Patch cut_patch_along(const TriangleMesh& mesh, const std::array<int, 4>& corners,
                      const std::array<std::vector<SurfacePoint>, 4>& sides, int input_vertex_count,
                      const PatchCutOptions& options = {}, const Progress& progress = {});

/// Inner angle of the patch at each corner (sum of incident face angles), radians.
std::array<double, 4> corner_angles(const Patch& patch);
/// Length of each side (polyline length of sides[i]).
std::array<double, 4> side_lengths(const Patch& patch);
/// Criterion (iv): throws Infeasible naming the corner ("corners[i]") if an inner corner angle is
/// >= pi.
void check_convex_corners(const Patch& patch);

}  // namespace gridshell
