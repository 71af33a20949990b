// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — discrete curvature of a triangle mesh.
#pragma once

#include <vector>

#include "gridshell/mesh/mesh.h"

namespace gridshell {

/// #V discrete Gaussian curvature: angle defect (2*pi - sum of incident angles) divided by the
/// mixed Voronoi vertex area (Meyer et al. 2003). Boundary vertices get 0
/// (their defect is geodesic curvature of the boundary, not Gaussian curvature).
std::vector<double> gaussian_curvature(const TriangleMesh& mesh);

/// #V sum of incident triangle angles at each vertex, radians.
std::vector<double> vertex_angle_sums(const TriangleMesh& mesh);

/// #V mixed Voronoi vertex areas (Meyer et al. 2003): Voronoi region in non-obtuse triangles,
/// half / quarter of the area in obtuse ones; they sum to the surface area.
std::vector<double> mixed_voronoi_areas(const TriangleMesh& mesh);

/// #V barycentric vertex areas (a third of each incident triangle).
std::vector<double> vertex_areas(const TriangleMesh& mesh);

}  // namespace gridshell
