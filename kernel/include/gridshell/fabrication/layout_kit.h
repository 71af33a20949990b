// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — one fabrication kit for every patch of a layout (issue 35, docs/multi-patch.md):
// the parts of all patches named by patch ("P2-g7"), nested on one set of sheets, with a hole for
// each seam bolt in both boundary lamellas of its seam, and the bolts counted by how many
// lamellas each holds.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gridshell/fabrication/kit.h"

namespace gridshell {

/// A designed patch of a layout.
/// A layout's part name: the patch's name, its family and the member's index ("P2-g7").
std::string layout_part_name(const std::string& patch, Family family, int index);
/// The family and member index of `patch`'s part `name` (none if it is not one of its parts).
std::optional<std::pair<Family, int>> parse_layout_part_name(const std::string& name,
                                                             const std::string& patch);

struct LayoutKitPatch {
  std::string name;  ///< "P1"
  const Design* design = nullptr;
  /// Its anchors that hold the whole (whole_anchors: none on a seam; a closed whole's lowest
  /// patch all of its own), the supports to build.
  std::vector<Anchor> supports;
};

/// A bolt through the two boundary lamellas of a seam (see SeamJoint).
struct SeamBolt {
  std::array<std::string, 2> lamellas;  ///< part names: "P1-g5", "P2-g0"
  std::array<double, 2> along{};        ///< arc length along each lamella (design units)
  std::vector<std::string> members;     ///< part names of the members that end here
  Vec3 point = Vec3::Zero();
};

/// A seam of two designed patches and its bolts, in order along it.
struct KitSeam {
  std::array<std::string, 2> patches;
  std::array<int, 2> corners{};  ///< layout corner indices
  std::vector<SeamBolt> bolts;
};

struct LayoutKit {
  Kit kit;  ///< every part of every patch, nested together; holes and slots of all of them
  /// Each patch's own kit (its parts named by patch, nested alone), for its assembly sheet.
  std::vector<Kit> patch_kits;
  int seam_bolts = 0;  ///< bolt positions on seams (a corner where seams meet counts once)
  int seam_holes = 0;  ///< holes added to boundary lamellas for seam bolts
  /// Bolts by the number of lamellas they hold: 2 at a crossing inside a patch, more where a
  /// seam bolt meets a crossing or patches meet at a corner.
  std::map<int, int> bolts_by_grip;
};

/// The kit of a layout's designed patches. Every seam bolt becomes a hole in each of its two
/// lamellas at its arc length, unless that lamella has a hole within half a hole's diameter of
/// it (a member of its own patch ends there; the bolt goes through that hole). Bolt positions
/// within half a hole of each other are one bolt. Throws InvalidInput ("seams") for a seam
/// bolt on a lamella no patch has, or outside it; errors of make_kit and nest_kit otherwise, naming
/// the patch.
LayoutKit make_layout_kit(const std::vector<LayoutKitPatch>& patches,
                          const std::vector<KitSeam>& seams, const FabricationOptions& options,
                          const Progress& progress = {});

/// The order of work: patches in the order they are deployed (each, after the first, joined to
/// one already standing), and the seams in the order they are bolted. Breadth first from the
/// first patch over the seams; a patch no seam reaches starts again on its own.
struct JoiningStep {
  std::string patch;       ///< deployed in this step
  std::vector<int> seams;  ///< indices into the seams bolted right after it
};
std::vector<JoiningStep> joining_order(const std::vector<LayoutKitPatch>& patches,
                                       const std::vector<KitSeam>& seams);

/// joining.svg: the seams in plan (the plane of their bolts' two largest principal directions),
/// each a line through its bolts named by its two patches and bolt count, each patch's name at
/// the middle of its seams, and the order of work as numbered steps.
std::string joining_svg(const std::vector<LayoutKitPatch>& patches,
                        const std::vector<KitSeam>& seams);

/// supports.csv of a layout's kit: each patch's supports named by patch and by their number on
/// its assembly sheet ("P2-A3"), heights above the whole's ground plane (the lowest boundary
/// point of all patches).
std::string layout_supports_csv(const std::vector<LayoutKitPatch>& patches, double scale,
                                const std::string& unit);

/// bom.csv of a layout's kit: lamellas per family over all patches, sheets, bolts by grip, nuts,
/// washers, holes, slots and supports.
std::string layout_bom_csv(const std::vector<LayoutKitPatch>& patches, const LayoutKit& kit,
                           const std::string& material);

}  // namespace gridshell
