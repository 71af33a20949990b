// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — anchors (paper Section 4.6): connections pinned to the target surface so the
// elastic grid deploys into the target and not into one of its isometric deformations.
// By default anchors are only on the boundary, as in the paper: the four corners, plus the
// boundary crossings nearest to points of locally extreme curvature of the boundary geodesics
// (small extrema filtered out). Optionally (AnchorOptions::interior) also inner crossings at the
// most prominent bumps and dips of the target, for surfaces whose boundary does not decide the
// direction of their inner bumps (the limitation the paper names in its Section 7).
#pragma once

#include <vector>

#include "gridshell/design/grid.h"
#include "gridshell/design/patch.h"

namespace gridshell {

struct AnchorOptions {
  /// Curvature extrema smaller than this fraction of the largest boundary curvature are ignored.
  double min_relative_curvature = 0.25;
  /// A curvature maximum must stand out from its surroundings by this fraction of the largest
  /// boundary curvature (topographic prominence), so a broad crown gives one anchor, not three.
  double min_relative_prominence = 0.1;
  /// Ignore curvature that turns the side by less than this angle (radians) over one window:
  /// straight or nearly straight sides get no anchors from rounding noise.
  double min_turning = 0.02;
  /// Extrema closer than this fraction of the side length to a corner or another extremum are
  /// merged (the larger one wins).
  double min_separation = 0.1;
  /// Arc-length window, as a fraction of the side length, over which boundary curvature is
  /// measured (the sides are polylines with uneven vertices from the cut).
  double curvature_window = 0.04;
  /// Inner anchors: at most this many inner crossings, at strict local extrema (among the 8
  /// neighbouring crossings of the grid) of the height over the least-squares plane of the
  /// patch boundary, most prominent first. 0 = boundary anchors only (the paper's rule).
  int interior = 0;
  /// An inner extremum counts if its height differs from the mean of its 8 neighbours by at
  /// least this fraction of the patch's bounding-box diagonal.
  double min_interior_prominence = 0.002;
};

struct Anchor {
  int g = 0, h = 0;     ///< the crossing (member indices) it pins
  bool corner = false;  ///< one of the four patch corners
  int side = -1;  ///< boundary side 0..3 it lies on (for a corner: the side it starts); -1 inside
  Vec3 position = Vec3::Zero();
  Vec3 normal = Vec3::Zero();     ///< unit surface normal of the target at the anchor
  double boundary_curvature = 0;  ///< curvature of the boundary geodesic there (0 for corners)
};

/// Curvature (1/length) of a boundary polyline sampled at `samples` points uniformly in arc
/// length, measured over the window of AnchorOptions::curvature_window.
std::vector<double> boundary_curvature(const std::vector<Vec3>& polyline, int samples,
                                       double window_fraction);

/// Corners first (c0..c3), then curvature anchors by side and arc length, then inner anchors
/// by decreasing prominence. Deterministic.
std::vector<Anchor> place_anchors(const Patch& patch, const Grid& grid,
                                  const AnchorOptions& options = {});

}  // namespace gridshell
