// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — patch layouts (issue 35, docs/multi-patch.md): a surface covered by several
// four-sided patches that share corners. A side that two patches share is a seam; both patches
// are cut along the same exact shortest geodesic there, which the result checks (seam mismatch).
//
// A layout (given, or computed for a disk by auto_layout) is cut, each patch is checked and
// smoothed as a single patch is (corners, convexity, coverability), but smoothing keeps the
// shared sides; the coverage of the input is reported, with the reason of every patch that fails.
// Designed patches meet at seam joints (seam_joints).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "gridshell/design/anchors.h"
#include "gridshell/design/family.h"
#include "gridshell/design/grid.h"
#include "gridshell/design/target_patch.h"

namespace gridshell {

/// A corner of a layout: a vertex of the input mesh, or a point snapped to the surface.
struct LayoutCorner {
  int vertex = -1;  ///< >= 0: this vertex; else `point`
  Vec3 point = Vec3::Zero();
};

struct PatchLayout {
  std::vector<LayoutCorner> corners;
  struct Quad {
    std::string name;              ///< "" = "P<k>" (1-based)
    std::array<int, 4> corners{};  ///< indices into `corners`, in order around the patch
  };
  std::vector<Quad> patches;
};

/// One side of one or two patches: the corners it joins and which patch sides run along it.
struct LayoutSeam {
  std::array<int, 2> corners{};  ///< layout corner indices, the smaller first
  /// (patch, side) of each patch that has this side; side k joins the patch's corners k, k+1.
  std::vector<std::pair<int, int>> uses;
  double length = 0;  ///< of the first cut patch's side along it
  /// Largest distance between the two patches' boundary polylines along a shared seam (both cut
  /// patches), 0 for an outer edge or when a patch could not be cut.
  double mismatch = 0;
  std::vector<Vec3> points;  ///< the side as cut (the first cut patch's), first corner first
  bool shared() const { return uses.size() == 2; }
};

/// A layout patch as cut and checked, or why it could not be.
struct LayoutPatch {
  std::string name;
  std::optional<TargetPatch> target;  ///< the cut (and smoothed) patch, when it could be cut
  /// Its first problem: an error from the patch stage (the field within the patch: "corners[1]")
  /// or eta above eta_max, or no feasible planar angle. Empty when the patch meets the checks.
  std::optional<Error> problem;
  /// The feasible planar angle range (radians) on the patch's distance maps, which stay in
  /// `target` for its design (full checks of a patch that passes the others).
  std::optional<std::array<double, 2>> alpha_range;
};

struct LayoutResult {
  PatchLayout layout;                ///< with names filled in
  std::vector<LayoutPatch> patches;  ///< in layout order
  std::vector<LayoutSeam> seams;     ///< every side, shared or not, ordered by corners
  std::vector<Vec3> corners;         ///< where each layout corner is on the surface
  double input_area = 0;
  double covered_area = 0;  ///< sum of the areas of the patches that meet the checks
  double coverage() const { return input_area > 0 ? covered_area / input_area : 0; }
};

/// Cuts every patch of `layout` from `mesh` (as make_target_patch does, but smoothing keeps the
/// sides, which neighbours share: TargetPatchOptions::fixed_sides) and
/// checks the layout as a whole. Throws InvalidInput for a malformed layout (field
/// "layout.corners[i]", "layout.patches[j].corners[k]", ...: indices out of range, a patch with
/// a corner twice, a name taken twice, a side used by three patches) and Infeasible
/// ("layout.patches[j]") when two patches lie on the same side of a seam (they overlap). A patch
/// that cannot be cut or misses a criterion is reported in its LayoutPatch, not thrown. The
/// criteria: corners, coverability after smoothing, sides that stay shortest geodesics, and a
/// feasible planar angle ᾱ on the patch's distance maps (options.auto_corners.maps and
/// .cladding: patch_options() sets the design's), which are kept for its design.
/// `checks` CutOnly: each patch is cut and its corners checked for convexity only (no
/// coverability, smoothing, side or ᾱ check): its coverage is an upper bound of the full checks'.
enum class LayoutChecks { Full, CutOnly };
LayoutResult cut_layout(const TriangleMesh& mesh, const PatchLayout& layout,
                        const TargetPatchOptions& options = {}, const Progress& progress = {},
                        LayoutChecks checks = LayoutChecks::Full);

/// layout.svg: a plan of the layout on the plane of the input's two largest principal
/// directions. Each cut patch is filled in its colour with its name, shared seams are drawn
/// thick, corners are dots with their layout index, and the input's boundary loops are dashed
/// (what no patch covers shows as white inside them). One unit = one mesh unit.
std::string layout_svg(const TriangleMesh& mesh, const LayoutResult& layout);

// Seam joints (docs/multi-patch.md, "Members at seams") -------------------------------------------

struct Design;

/// A patch's boundary lamella along a seam.
struct SeamLamella {
  int patch = 0;              ///< index into LayoutResult::patches
  Family family = Family::G;  ///< the boundary member's family ...
  int member = 0;             ///< ... and index in it (0 or n+1)
  bool forward = true;        ///< runs from the seam's first corner to its second
  double length = 0;          ///< its surface length
};

/// One bolt through the two boundary lamellas of a seam: where a member of either patch ends on
/// the seam (both lamellas are the same curve, so arc length s from the seam's first corner is
/// the same point on both).
struct SeamJoint {
  double s = 0;               ///< arc length along the seam from its first corner
  Vec3 point = Vec3::Zero();  ///< on the seam
  /// The members that end here: (patch, family, member index), a corner's boundary members too.
  std::vector<std::tuple<int, Family, int>> ends;
};

struct SeamJoints {
  int seam = 0;                         ///< index into LayoutResult::seams
  std::array<SeamLamella, 2> lamellas;  ///< the two patches' boundary lamellas along it
  std::vector<SeamJoint> joints;        ///< by s, first corner first
  /// |length of one lamella - length of the other|: both are the seam (0 up to rounding).
  double length_difference = 0;
};

/// The joints of every shared seam whose two patches both have a design (`designs[j]` null for
/// a patch without one). Joints closer than 1e-6 of the seam's length are one bolt: members of
/// both patches that end there (at least the corners) share it. Throws Infeasible naming
/// "layout.patches[j]" if a design's boundary does not run along its seam (a design not made on
/// this layout's cut patch).
std::vector<SeamJoints> seam_joints(const LayoutResult& layout,
                                    const std::vector<const Design*>& designs);

/// A patch's boundary lamella that runs along a shared seam: (patch, family, member index).
struct SeamMember {
  int patch = 0;
  Family family = Family::G;
  int member = 0;
};

/// The boundary lamellas of every seam in `joints`.
std::vector<SeamMember> seam_members(const std::vector<SeamJoints>& joints);

/// The anchors that hold the whole of a layout joined at its seams (docs/multi-patch.md,
/// "Simulation of the whole"), per patch.
struct WholeAnchors {
  std::vector<std::vector<Anchor>> patches;  ///< per patch, in layout order
  int held_by = -1;  ///< the patch a closed whole stands on; -1 when outer sides hold it
};

/// A seam lies inside the whole, so an anchor whose boundary members all run along seams
/// (`seams`) is dropped; anchors on an outer side (a corner: on either of its sides) and inner
/// anchors stay. A closed surface has no outer side, so none would stay: the whole then stands
/// on its lowest patch (the smallest mean anchor height, z up as the kit's ground plane), held
/// at all of that patch's anchors. `anchors[j]` and `grids[j]` are patch j's (null: no design,
/// no anchors). The simulation of the whole and the kit's supports both use this.
WholeAnchors whole_anchors(const std::vector<const std::vector<Anchor>*>& anchors,
                           const std::vector<const Grid*>& grids,
                           const std::vector<SeamMember>& seams);

// Automatic layouts (docs/multi-patch.md, "Automatic layouts")
// -------------------------------------

struct AutoLayoutOptions {
  /// Patches at most (columns x rows of the layout grid).
  int max_patches = 36;
  /// Stop at the first layout (fewest patches first) whose checked patches cover this fraction
  /// of the input's area.
  double coverage_goal = 0.95;
};

/// One layout tried: a columns x rows grid of patches.
struct AutoLayoutTrial {
  int columns = 0, rows = 0;
  int patches = 0;  ///< columns x rows, 6 x columns x rows on a closed surface
  /// Of the patches cut alone (LayoutChecks::CutOnly): an upper bound of `coverage`.
  double cut_coverage = 0;
  bool checked = false;  ///< its patches were checked in full (coverage below is theirs)
  double coverage = 0;
  int failing = 0;            ///< patches that could not be cut or missed a check
  std::string first_problem;  ///< the first failing patch's name and problem, "" if none
  double seconds = 0;
};

struct AutoLayout {
  LayoutResult result;  ///< the layout chosen, cut and checked (result.layout is the layout)
  /// "disk", "ring" (two boundary loops: a ring, a tube, a half-tunnel with a hole) or
  /// "closed" (without handles).
  std::string surface;
  int columns = 0, rows = 0;
  int patches = 0;  ///< of the layout chosen
  /// The input's vertices at the four corners of the parameter square, in order (a ring: the
  /// cut's ends, each twice; none on a closed surface).
  std::vector<int> boundary_corners;
  /// Where the surface was cut open or split to be mapped (plain text), "" for a disk.
  std::string cut;
  std::vector<Vec3> cut_path;           ///< a ring's cut, from its longer loop to the other
  std::vector<AutoLayoutTrial> trials;  ///< in the order tried
};

/// A layout of columns x rows patches computed for a surface with one boundary loop and no
/// holes (a disk). Four boundary vertices become the corners of a square. Where the boundary
/// turns is measured in plan (on the plane of the surface's two largest principal directions,
/// where a roof's or a facade's corners are), summed over a 32nd of the perimeter either side of
/// each vertex so that rounded corners count: the corners are the most turning vertex, then
/// the most turning one (above 30 degrees) within an eighth of the perimeter of each quarter
/// point along the boundary from it, else the quarter point; each then moves to the vertex
/// whose own turn is largest within its 32nd of the perimeter (a sharp corner). The surface is
/// mapped onto the square (CGAL's mean value coordinates, the boundary by arc length between the
/// corners), and the layout's corners are the surface's points at a columns x rows grid of the
/// square: the outer ones on the boundary. Grids of 1, 2, ... patches, each patch at most twice as
/// long as wide by the boundary's side lengths, are cut in that order (LayoutChecks::CutOnly: an
/// upper bound of their coverage), and one whose bound reaches options.coverage_goal is checked
/// in full; the first that covers the goal is chosen. If none does, those with the largest bounds
/// are checked until no bound left is above the best coverage found, which is chosen (the fewer
/// patches on a tie).
///
/// A ring (two boundary loops, Euler characteristic 0: an annulus, a tube, a vault with an
/// opening) is cut open along the shortest edge path between its loops into a disk, mapped onto
/// the square with the cut's two sides at u = 0 and u = 1 (the same points, by arc length), and
/// laid out in at least 3 columns round it and rows across it, the last column joining the first.
/// A closed surface without handles is split along a cube about its area centroid (axes the
/// principal directions, stretched to the extents): 6 k x k patches whose corners are where the
/// rays from the centroid through the cube faces' grid points (at equal angles) meet the
/// surface; it must be star-shaped about its centroid (every face facing away from it).
/// Throws Infeasible (field "layout") for any other surface (more holes, handles, several
/// pieces), and for a closed surface that is not star-shaped, saying why; InvalidInput
/// ("max_patches") when it allows fewer patches than a ring's 3 columns or a cube's 6 faces.
AutoLayout auto_layout(const TriangleMesh& mesh, const TargetPatchOptions& patch_options = {},
                       const AutoLayoutOptions& options = {}, const Progress& progress = {});

}  // namespace gridshell
