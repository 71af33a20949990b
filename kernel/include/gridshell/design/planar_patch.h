// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the planar patch P̄(ᾱ) (paper Sections 3.2, 4.2): the planar quadrilateral with
// the same four side lengths as the surface patch, angle ᾱ at corner 0, in the convex
// configuration of the four-bar linkage; and its planar distance maps D̄_u, D̄_v(ᾱ).
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>

#include "gridshell/design/family.h"
#include "gridshell/mesh/mesh.h"

namespace gridshell {

struct PlanarPatch {
  double alpha_bar = 0;                  ///< inner angle at corner 0, radians
  std::array<double, 4> side_lengths{};  ///< L_i = |c_i c_{i+1}|
  /// c0 = (0,0), c1 = (L0, 0), c3 = L3 (cos ᾱ, sin ᾱ); c2 closes the quadrilateral; all four
  /// inner angles < pi (counter-clockwise order).
  std::array<Vec2, 4> corners{};
};

/// The convex planar quadrilateral for angle ᾱ, or nullopt if none exists (the four-bar linkage
/// cannot close, or the closed shape is not strictly convex).
std::optional<PlanarPatch> make_planar_patch(const std::array<double, 4>& side_lengths,
                                             double alpha_bar);

/// The open interval of ᾱ in (0, pi) for which a strictly convex configuration exists, found to
/// 1e-12 rad; {0,0} if none.
std::array<double, 2> convex_alpha_interval(const std::array<double, 4>& side_lengths);

/// Inner angles at c0..c3.
std::array<double, 4> planar_corner_angles(const PlanarPatch& planar);

/// The point at parameter t in [0,1] on a family's boundary in the plane (same conventions as
/// family_boundary in distance_map.h).
Vec2 planar_boundary_point(const PlanarPatch& planar, Family family, int end, double t);

/// D̄ of one family on the same R x R grid as the surface map.
Eigen::MatrixXd planar_distance_map(const PlanarPatch& planar, Family family, int resolution);

}  // namespace gridshell
