// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the whole grid design (paper Section 4): patch -> distance maps -> feasible ᾱ ->
// cladding functions -> members -> grid with crossings and notches -> anchors.
#pragma once

#include <map>
#include <memory>
#include <string>

#include "gridshell/design/anchors.h"
#include "gridshell/design/cladding.h"
#include "gridshell/design/distance_map.h"
#include "gridshell/design/grid.h"
#include "gridshell/design/members.h"
#include "gridshell/design/planar_patch.h"
#include "gridshell/design/target_patch.h"

namespace gridshell {

struct DesignOptions {
  TargetPatchOptions patch;  // corners -> patch; its geodesic engine serves every stage
  DistanceMapOptions maps;
  CladdingOptions cladding;
  /// Member placement (lamella width and thickness 0 = automatic, see MemberPlacementOptions);
  /// count is overridden by members_g / members_h when > 0.
  MemberPlacementOptions members;
  int members_g = 0;  // explicit inner g-member count (CLI --members-u), 0 = auto
  int members_h = 0;  // explicit inner h-member count (CLI --members-v), 0 = auto
  enum class Alpha { Min, Max, Value } alpha = Alpha::Min;  // paper default: ᾱ_min (compact)
  double alpha_value = 0;  // radians, with Alpha::Value; must lie in the feasible range
  GridOptions grid;
  AnchorOptions anchors;
};

struct Design {
  TargetPatch target;
  DistanceMaps maps;
  AlphaRange alpha_range;
  double alpha = 0;              ///< spatial inner angle at corner c0
  double alpha_bar = 0;          ///< chosen planar angle at c0
  double lamella_width = 0;      ///< effective (after resolving 0 = automatic)
  double lamella_thickness = 0;  ///< effective
  PlanarPatch planar;
  CladdingFunction cladding_g, cladding_h;
  Grid grid;
  std::vector<Anchor> anchors;
  /// Maps computed on a simplified copy (maps.copy): the largest relative difference, over the
  /// inner members, between the copy's distance between a member's two ends and its exact
  /// length on the patch (map_copy_error), i.e. how far off the maps are where the design reads
  /// them. 0 for exact maps.
  double map_error = 0;
  /// The largest |u2 - u2 of the cladding function| of an inner member's end, by which its
  /// refinement on exact distances (criterion i) moved it: the maps' sampling and, on a copy,
  /// its error, seen in the design's own parameters.
  double member_end_shift = 0;
  std::map<std::string, double> stage_seconds;  ///< timings; not part of the design's value
};

/// What every design on one target patch shares, whatever ᾱ, the member counts, the lamella
/// size and the anchors are: the patch itself and its distance maps (the bulk of a design's
/// time). A daemon keeps one per patch so that changing ᾱ or the counts redesigns quickly.
struct PatchWork {
  TargetPatch target;
  DistanceMaps maps;
  double maps_seconds = 0;  ///< time the maps took
  /// Inner members built on this patch so far, reused by later designs on it (null = none; the
  /// daemon's cache sets one). The designs are the same with or without.
  std::shared_ptr<MemberMemo> members;
};

/// The distance maps of `target` (options.maps, with options.patch.geodesic).
PatchWork prepare_patch_work(TargetPatch target, const DesignOptions& options = {},
                             const Progress& progress = {});

/// The grid design on prepared patch work: feasible ᾱ, cladding functions, members, grid,
/// anchors. Gives the same design as design_grid on the same patch and options.
/// stage_seconds holds "cladding", "members" and "grid" (the caller adds the rest).
Design design_on_patch(const PatchWork& work, const DesignOptions& options = {},
                       const Progress& progress = {});

/// The grid design on an already computed target patch: prepare_patch_work + design_on_patch.
Design design_grid(TargetPatch target, const DesignOptions& options = {},
                   const Progress& progress = {});

/// The patch stage's options of a design: options.patch, with the automatic corners' search
/// checking the planar angle on the design's maps and slope bounds.
TargetPatchOptions patch_options(const DesignOptions& options);

/// Patch stage then grid design.
Design make_design(const TriangleMesh& mesh, const CornerSpec& corners,
                   const DesignOptions& options = {}, const Progress& progress = {});

}  // namespace gridshell
