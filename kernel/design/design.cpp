// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/design/design.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <sstream>

#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {
double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

namespace {

// Lamella dimensions against the patch, before the expensive maps: a section wider than half
// the patch, or a millionth of it, is no gridshell (and its simulation has no meaning).
void check_lamella_size(const Patch& patch, const DesignOptions& options) {
  const std::array<double, 4> sides = side_lengths(patch);
  const double longest = *std::max_element(sides.begin(), sides.end());
  for (const auto& [value, field] :
       {std::pair{options.members.lamella_width, "options.lamella_width"},
        std::pair{options.members.lamella_thickness, "options.lamella_thickness"}})
    if (value != 0 && !(value >= 1e-6 * longest && value <= 0.5 * longest)) {
      std::ostringstream msg;
      msg << value << " is outside [1e-6, 0.5] x the longest patch side (" << longest << ")";
      throw InvalidInput(field, msg.str());
    }
}

}  // namespace

PatchWork prepare_patch_work(TargetPatch target, const DesignOptions& options,
                             const Progress& progress) {
  check_lamella_size(target.patch, options);
  PatchWork work;
  work.target = std::move(target);
  const auto start = std::chrono::steady_clock::now();
  // The automatic corners' search computed these maps already (same patch, same options).
  // Otherwise the coverability's simplified copy serves the maps too if smoothing left the patch
  // as it was (compute_distance_maps checks that it fits); the work keeps it only through the maps.
  std::shared_ptr<const MapCopy> copy = std::move(work.target.coverability.map_copy);
  if (work.target.smoothing.iterations > 0) copy.reset();
  if (work.target.maps && work.target.maps_options.resolution == options.maps.resolution) {
    work.maps = *work.target.maps;
  } else {
    const GeodesicSolver solver(work.target.patch.mesh, options.patch.geodesic);
    work.maps = compute_distance_maps(work.target.patch, solver, options.maps, progress, copy);
  }
  work.target.maps.reset();
  work.maps_seconds = seconds_since(start);
  return work;
}

Design design_on_patch(const PatchWork& work, const DesignOptions& options,
                       const Progress& progress) {
  check_lamella_size(work.target.patch, options);
  Design design;
  design.target = work.target;
  design.maps = work.maps;
  const Patch& patch = design.target.patch;
  // The grid's member solves need a solver on the patch; building one is O(F), milliseconds.
  const GeodesicSolver solver(patch.mesh, options.patch.geodesic);
  auto start = std::chrono::steady_clock::now();
  const std::array<double, 4> lengths = side_lengths(patch);
  design.alpha_range = feasible_alpha_range(design.maps, lengths, options.cladding, progress);
  switch (options.alpha) {
    case DesignOptions::Alpha::Min:
      design.alpha_bar = design.alpha_range.min;
      break;
    case DesignOptions::Alpha::Max:
      design.alpha_bar = design.alpha_range.max;
      break;
    case DesignOptions::Alpha::Value:
      if (options.alpha_value < design.alpha_range.min ||
          options.alpha_value > design.alpha_range.max) {
        std::ostringstream msg;
        msg << options.alpha_value << " rad is outside the feasible range ["
            << design.alpha_range.min << ", " << design.alpha_range.max << "] rad";
        throw Infeasible("options.alpha", msg.str());
      }
      design.alpha_bar = options.alpha_value;
      break;
  }
  const auto planar = make_planar_patch(lengths, design.alpha_bar);
  if (!planar) throw Infeasible("options.alpha", "no convex planar patch at this planar angle");
  design.planar = *planar;
  design.alpha = corner_angles(patch)[0];
  const int R = design.maps.g.resolution();
  design.cladding_g =
      cladding_function(design.maps.g.distances, planar_distance_map(design.planar, Family::G, R),
                        Family::G, design.alpha_bar, options.cladding);
  design.cladding_h =
      cladding_function(design.maps.h.distances, planar_distance_map(design.planar, Family::H, R),
                        Family::H, design.alpha_bar, options.cladding);
  for (const CladdingFunction* f : {&design.cladding_g, &design.cladding_h})
    if (!f->valid)
      throw Infeasible("options.alpha", "cladding function invalid at this angle: " + f->problem);
  design.stage_seconds["cladding"] = seconds_since(start);

  start = std::chrono::steady_clock::now();
  MemberPlacementOptions g_options = options.members, h_options = options.members;
  const LamellaSize size = lamella_size(patch, options.members);
  design.lamella_width = size.width;
  design.lamella_thickness = size.thickness;
  g_options.lamella_width = h_options.lamella_width = design.lamella_width;
  g_options.lamella_thickness = h_options.lamella_thickness = design.lamella_thickness;
  if (options.members_g > 0) g_options.count = options.members_g;
  if (options.members_h > 0) h_options.count = options.members_h;
  const auto g_members =
      place_members(design.cladding_g, design.maps.g, patch, design.planar, g_options);
  const auto h_members =
      place_members(design.cladding_h, design.maps.h, patch, design.planar, h_options);
  design.stage_seconds["members"] = seconds_since(start);

  start = std::chrono::steady_clock::now();
  design.grid = build_grid(patch, solver, design.planar, g_members, h_members, options.grid,
                           progress, work.members.get());
  design.anchors = place_anchors(patch, design.grid, options.anchors);
  design.stage_seconds["grid"] = seconds_since(start);

  // How far the maps put the members' ends from where exact distances put them, and (on a
  // copy) how far the copy's distances are off there.
  std::vector<BoundaryDistance> checks;
  for (const auto& [members, positions] :
       {std::pair{&design.grid.g, &g_members}, std::pair{&design.grid.h, &h_members}})
    for (std::size_t k = 0; k < positions->size(); ++k) {
      const Member& m = (*members)[k + 1];
      design.member_end_shift =
          std::max(design.member_end_shift, std::abs(m.u_end - (*positions)[k].u2));
      checks.push_back({m.family, m.u_start, m.u_end, m.length});
    }
  if (design.maps.copy) {
    start = std::chrono::steady_clock::now();
    design.map_error =
        map_copy_error(*design.maps.copy, patch, checks, options.grid.threads, progress.checker());
    design.stage_seconds["map_check"] = seconds_since(start);
  }
  return design;
}

Design design_grid(TargetPatch target, const DesignOptions& options, const Progress& progress) {
  const PatchWork work = prepare_patch_work(std::move(target), options, progress);
  Design design = design_on_patch(work, options, progress);
  design.stage_seconds["distance_maps"] = work.maps_seconds;
  return design;
}

TargetPatchOptions patch_options(const DesignOptions& options) {
  TargetPatchOptions patch = options.patch;
  patch.auto_corners.maps = options.maps;
  patch.auto_corners.cladding = options.cladding;
  return patch;
}

Design make_design(const TriangleMesh& mesh, const CornerSpec& corners,
                   const DesignOptions& options, const Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  TargetPatch target = make_target_patch(mesh, corners, patch_options(options), progress);
  const double patch_seconds = seconds_since(start);
  Design design = design_grid(std::move(target), options, progress);
  design.stage_seconds["patch"] = patch_seconds;
  return design;
}

}  // namespace gridshell
