// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — cladding functions and the feasible range of the planar angle ᾱ (paper 4.3).
//
// F_u is the zero set of D_u - D̄_u(ᾱ) in the (u1,u2) square, a curve from (0,0) to (1,1)
// (both are zeros by construction: the boundary members). A member pair (u1,u2) on it has the
// same length on the surface and in the plane (criterion i); bijectivity (criterion iii)
// requires the curve to be a monotone graph u2 = F(u1) with slopes in (k_min, k_max).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "gridshell/design/distance_map.h"
#include "gridshell/design/planar_patch.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/mesh/mesh.h"

namespace gridshell {

struct CladdingOptions {
  double k_min = 0.1;  // slope bounds of F (paper: empirical 0.1 and 10)
  double k_max = 10.0;
  double vertical_c = 1e3;  // slope of a vertical segment is taken as c * Δu2 (c >> k_max)
  /// Designer bound on the planar patch (paper 4.3: bounds on ᾱ express "designer constraints on
  /// the shape of P̄"): feasible_alpha_range only considers ᾱ for which every inner angle of
  /// P̄(ᾱ) lies in [min_planar_angle, pi - min_planar_angle]. Near the ends of the convex interval
  /// P̄ is a collapsed linkage whose members meet the boundaries at ~0 degrees, where no lamella
  /// of finite width fits, yet the cladding criteria alone often accept it (ᾱ_min would be ~0
  /// for most of the paper's examples). Radians; 0 = the paper's bare convexity bound.
  double min_planar_angle = 0.5235987755982988;  // 30 degrees
};

/// The piecewise-linear cladding function of one family at one ᾱ.
struct CladdingFunction {
  Family family = Family::G;
  double alpha_bar = 0;
  /// Points (u1,u2) of the zero set, ordered from (0,0) to (1,1); empty if the zero set does not
  /// connect the two corners.
  std::vector<Vec2> points;
  /// True iff the curve connects (0,0) to (1,1) and every segment slope is in (k_min, k_max).
  bool valid = false;
  /// Why not valid, naming the constraint and where (u1,u2) it fails; empty if valid.
  std::string problem;
};

/// Extracts F for a family from the surface map D and the planar map D̄ (same resolution).
CladdingFunction cladding_function(const Eigen::MatrixXd& surface_map,
                                   const Eigen::MatrixXd& planar_map, Family family,
                                   double alpha_bar, const CladdingOptions& options = {});

/// The diagonal condition (e - ē)(f - f̄) < 0 (eq. 2): e = D_u(0,1) = d(c0,c2),
/// f = D_u(1,0) = d(c1,c3) on the surface, ē, f̄ in the plane.
bool diagonal_condition(const DistanceMaps& maps, const PlanarPatch& planar);

struct AlphaRange {
  double min = 0;  ///< ᾱ_min: smallest feasible ᾱ (compact layout, the paper's default)
  double max = 0;  ///< ᾱ_max
};

/// Feasible range of ᾱ where both cladding functions are valid and the diagonal condition
/// holds (problem 3 of the paper), searched where every planar angle is within
/// options.min_planar_angle of (0, pi). If the feasible set has several windows (typically one
/// below and one above the surface angle α), the one with the smallest ᾱ among those at least
/// half as long as the longest. Both ends are feasible (to 1e-6 rad). Throws Infeasible naming
/// the constraint that fails where, if no ᾱ is feasible; reports progress, throws Cancelled.
AlphaRange feasible_alpha_range(const DistanceMaps& maps, const std::array<double, 4>& side_lengths,
                                const CladdingOptions& options = {}, const Progress& progress = {});

}  // namespace gridshell
