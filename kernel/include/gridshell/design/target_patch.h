// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the whole patch stage: corners -> cut -> convexity check -> coverability ->
// smoothing (paper Sections 3.1-3.3). This is what `gridshell patch` and the daemon run.
#pragma once

#include <array>
#include <map>
#include <string>

#include "gridshell/design/coverability.h"
#include "gridshell/design/patch.h"

namespace gridshell {

struct TargetPatchOptions {
  /// The geodesic engine of every stage (boundary geodesics, coverability, distance maps and
  /// members): chosen here once and passed down. Default: the fast exact engine.
  GeodesicOptions geodesic;
  PatchCutOptions cut;               // boundary geodesics and cutting
  CoverabilityOptions coverability;  // eta_max, smoothing cap and step
  bool smooth = true;                // run smoothing when eta > eta_max
};

struct TargetPatch {
  Patch patch;                                ///< trimmed (and smoothed) patch
  std::array<SurfacePoint, 4> input_corners;  ///< corners on the input mesh, in the user's order
  std::array<double, 4> corner_angles{};      ///< inner angles at patch.corners (after smoothing)
  std::array<double, 4> boundary_lengths{};   ///< lengths of patch.sides
  double area = 0;
  CoverabilityReport coverability;  ///< before smoothing
  SmoothingResult smoothing;
  std::map<std::string, double> stage_seconds;  ///< "cut", "coverability", "smoothing"
};

/// Resolves the corner spec on `mesh` (vertex indices refer to `mesh`), cuts the patch, checks
/// grid criterion (iv), analyses coverability and smooths. Throws InvalidInput (bad corners),
/// Infeasible (criterion (iv), smoothing cap) or Cancelled.
TargetPatch make_target_patch(const TriangleMesh& mesh, const CornerSpec& corners,
                              const TargetPatchOptions& options = {},
                              const Progress& progress = {});

}  // namespace gridshell
