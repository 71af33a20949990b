// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the whole patch stage: corners -> cut -> convexity check -> coverability ->
// smoothing (paper Sections 3.1-3.3). This is what `gridshell patch` and the daemon run.
#pragma once

#include <array>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gridshell/design/auto_corners.h"
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
  /// Smoothing never re-cuts a side (a layout's sides are shared with a neighbour): a patch
  /// whose sides are no longer shortest geodesics after smoothing is Infeasible instead.
  bool fixed_sides = false;
  AutoCornerOptions auto_corners;  // the search behind CornerSpec::Kind::Auto
};

struct TargetPatch {
  Patch patch;                                ///< trimmed (and smoothed) patch
  std::array<SurfacePoint, 4> input_corners;  ///< corners on the input mesh, in the user's order
  std::array<double, 4> corner_angles{};      ///< inner angles at patch.corners (after smoothing)
  std::array<double, 4> boundary_lengths{};   ///< lengths of patch.sides
  double area = 0;
  CoverabilityReport coverability;  ///< before smoothing
  SmoothingResult smoothing;
  /// Per side: relative excess of its length over the shortest geodesic between its corners on
  /// the final patch (<= kBoundaryGeodesicTolerance: the sides are exact shortest geodesics).
  std::array<double, 4> boundary_excess{};
  /// Conditions the user must see (eta above eta_max without smoothing, ...), one line each.
  std::vector<std::string> warnings;
  std::map<std::string, double> stage_seconds;  ///< "cut", "coverability", "smoothing"
  /// With automatic corners: the candidates tried and the choice.
  std::optional<AutoCornerReport> auto_corners;
  /// With automatic corners: the distance maps the search computed on this patch (with
  /// maps_options), so that the design need not compute them again; null otherwise.
  std::shared_ptr<const DistanceMaps> maps;
  DistanceMapOptions maps_options;
};

/// Resolves the corner spec on `mesh` (vertex indices refer to `mesh`), cuts the patch, checks
/// grid criterion (iv), analyses coverability and smooths. Throws InvalidInput (bad corners),
/// Infeasible (criterion (iv), smoothing cap) or Cancelled.
TargetPatch make_target_patch(const TriangleMesh& mesh, const CornerSpec& corners,
                              const TargetPatchOptions& options = {},
                              const Progress& progress = {});

/// The patch stage for corners already located on `mesh`.
TargetPatch target_patch_at(const TriangleMesh& mesh, const std::array<SurfacePoint, 4>& corners,
                            const TargetPatchOptions& options = {}, const Progress& progress = {});

/// The patch stage after the cut: convexity, coverability, smoothing with exact re-cut
/// boundaries, the boundary check and warnings.
TargetPatch target_patch_from_cut(Patch patch, const std::array<SurfacePoint, 4>& corners,
                                  const TargetPatchOptions& options = {},
                                  const Progress& progress = {});

/// The automatic corners' search (auto_corners.h): the largest acceptable candidate's patch,
/// with its report and distance maps. Throws Infeasible (field "corners") naming the best
/// candidates' reasons when none is acceptable.
TargetPatch search_auto_corners(const TriangleMesh& mesh, const TargetPatchOptions& options = {},
                                const Progress& progress = {});

}  // namespace gridshell
