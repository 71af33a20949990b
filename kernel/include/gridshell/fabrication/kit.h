// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the fabrication kit of a design (paper Section 6.1: lamellas laser-cut from thin
// plates, bolts at the crossings, slots where a connection slides): every lamella as a flat part
// with its holes and slots, nested on sheets, plus what assembly needs (which family lies on
// top, the corner angles of the deployment, the anchors).
//
// Units. Parts, sheets and every option here are in millimetres; the design's lengths are
// converted with `FabricationOptions::millimetres_per_unit`. A part's own frame: x along the
// lamella from the left end of its (uncompensated) outline, y across it, the centerline at y = 0;
// the design's arc length s maps to x = s * millimetres_per_unit - start.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "gridshell/design/design.h"
#include "gridshell/foundation/progress.h"

namespace gridshell {

struct FabricationOptions {
  double millimetres_per_unit = 0;  ///< required: the design's length unit in mm (> 0)
  double sheet_width = 1200;        ///< mm
  double sheet_height = 600;        ///< mm
  double kerf = 0.15;               ///< mm: width of the cut; outlines grow, holes shrink by half
  double hole_diameter = 3.2;       ///< mm: bolt holes and slot widths (M3 clearance)
  double end_allowance = 0;         ///< mm beyond the outermost crossing; 0 = the lamella width
  double spacing = 3;               ///< mm between parts (after kerf) and from the sheet's edges
  double thickness = 0;             ///< mm; 0 = the design's lamella thickness
  /// mm: a crossing whose sliding range along a lamella is shorter than this gets a round hole
  /// there (a bolt in its clearance hole moves that much anyway).
  double min_slot = 0.1;
  double text_height = 0;  ///< mm, labels; 0 = 0.4 x the lamella width, within [1, 8]
};

/// Checks the options (InvalidInput naming "options.<field>") and fills the automatic values
/// (end allowance, thickness, text height) for a design with the given lamella size (design
/// units).
FabricationOptions resolve_fabrication_options(FabricationOptions options, double lamella_width,
                                               double lamella_thickness);

enum class FeatureKind { Hole, Slot };

/// A hole or slot of one part at one crossing.
struct PartFeature {
  FeatureKind kind = FeatureKind::Hole;
  int crossing = 0;  ///< index into Design::grid.crossings
  Family partner_family = Family::H;
  int partner = 0;           ///< the other lamella's index in its family
  std::string partner_name;  ///< as engraved beside it: "h3", or "P2-h3" in a layout's kit
  double s_bar = 0;          ///< arc length of the crossing in the plane (design units)
  double s = 0;              ///< ... on the surface; the slot spans [s̄, s]; a hole sits at s̄
  double x0 = 0, x1 = 0;     ///< centres along the part (mm): hole x0 = x1, slot x0 < x1
  /// Nominal size (mm) before kerf compensation: diameter d; a slot is |s - s̄| + d long.
  double diameter = 0;
  double length() const { return x1 - x0 + diameter; }
};

/// One lamella as a flat part, and where it lies on its sheet.
struct Part {
  Family family = Family::G;
  int index = 0;
  bool boundary = false;
  std::string name;                   ///< "g3", "h0": family + index, as everywhere in gridshell
  double length = 0;                  ///< mm, nominal outline (kerf not included)
  double width = 0;                   ///< mm
  double start = 0;                   ///< member arc length (mm) at x = 0: minus the end allowance
  std::vector<PartFeature> features;  ///< by x
  int sheet = 0;                      ///< 0-based
  int row = 0;                        ///< row on its sheet, 0-based
  double rotation = 0;                ///< degrees, 0 or 90: sheet = R * part + translation
  Vec2 translation = Vec2::Zero();    ///< mm
  /// Part frame -> sheet (mm).
  Vec2 to_sheet(const Vec2& p) const;
};

struct Sheet {
  std::vector<int> parts;  ///< indices into Kit::parts
  int rows = 0;
  double utilisation = 0;  ///< nominal part area / sheet area
};

struct Kit {
  FabricationOptions options;  ///< resolved
  std::vector<Part> parts;     ///< g members by index, then h members
  std::vector<Sheet> sheets;
  int rows = 0;  ///< rows used on all sheets
  int rows_per_sheet = 0;
  double utilisation = 0;  ///< nominal part area / area of all sheets
  /// One lamella per row (the simplest layout), for comparison.
  int baseline_sheets = 0;
  double baseline_utilisation = 0;
  int holes = 0, slots = 0;
  /// The family whose lamellas lie on top, seen from above the flat grid as planar_svg and the
  /// assembly sheet draw it (the simulation puts h on the side of the surface normal).
  Family top_family = Family::H;
};

/// Parts, features and nesting (first-fit decreasing into rows along the sheet's long side).
/// Throws InvalidInput naming "options.sheet" for a lamella longer (or wider) than the sheet,
/// naming the lamella, its length and the sheet size.
Kit make_kit(const Design& design, const FabricationOptions& options,
             const Progress& progress = {});

/// The nesting step of make_kit on kit.parts (rows as wide as the widest part): sets each part's
/// sheet, row and placement, the sheets and the utilisation figures. Errors as make_kit's.
void nest_kit(Kit& kit);

/// Corner angles of the flat grid (planar corners) and of the target (between the boundary
/// geodesics), c0..c3, radians.
struct CornerAngles {
  std::array<double, 4> planar{};
  std::array<double, 4> target{};
};
CornerAngles corner_angles(const Design& design);

}  // namespace gridshell
