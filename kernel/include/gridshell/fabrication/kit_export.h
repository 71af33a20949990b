// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the files of a fabrication kit: cut sheets as DXF and SVG (one drawing, two
// formats), the assembly sheet, the support table and the bill of materials.
#pragma once

#include <string>
#include <vector>

#include "gridshell/design/design.h"
#include "gridshell/fabrication/kit.h"

namespace gridshell {

/// What a laser does with a path: cut through (DXF layer CUT, SVG red hairline) or engrave
/// (layer ENGRAVE, blue).
enum class SheetLayer { Cut, Engrave };

/// A closed or open polyline; bulges[i] = tan(θ/4) of the arc from point i to point i+1
/// (DXF's convention: positive = counter-clockwise).
struct SheetPolyline {
  SheetLayer layer = SheetLayer::Cut;
  std::vector<Vec2> points;
  std::vector<double> bulges;
  bool closed = true;
};
struct SheetCircle {
  SheetLayer layer = SheetLayer::Cut;
  Vec2 centre = Vec2::Zero();
  double radius = 0;
};
/// Text with its baseline's left end at `position`, rotated by `angle` (radians).
struct SheetText {
  SheetLayer layer = SheetLayer::Engrave;
  Vec2 position = Vec2::Zero();
  double height = 0;
  double angle = 0;
  std::string text;
};

/// One sheet in mm, y up, origin at the sheet's lower left corner.
struct SheetDrawing {
  double width = 0, height = 0;
  std::vector<SheetPolyline> polylines;
  std::vector<SheetCircle> circles;
  std::vector<SheetText> texts;
};

/// The drawing of sheet `sheet` (0-based): per part its kerf-compensated outline (offset
/// outwards by half the kerf), holes as circles and slots as stadiums (offset inwards by half
/// the kerf), and on the engrave layer the part's name, an arrow in the direction of increasing
/// arc length, a triangle marking the top face, and the partner's name beside each hole or slot.
SheetDrawing sheet_drawing(const Kit& kit, int sheet);

/// ASCII DXF (AutoCAD 2000, written with dxflib): $INSUNITS = 4 (mm), layers CUT (red) and
/// ENGRAVE (blue), closed LWPOLYLINEs (slot ends as bulges), CIRCLEs, TEXT.
std::string sheet_dxf(const SheetDrawing& drawing);

/// SVG in mm (width/height in mm, viewBox in mm, y down): cut paths red hairlines, engraving
/// blue, texts as <text>.
std::string sheet_svg(const SheetDrawing& drawing);

/// The assembly sheet: the flat grid to scale with every lamella and crossing labelled as on the
/// parts, the lamella on top drawn over the other, anchors numbered as in supports.csv; below,
/// the deployment: the corners, their planar and target angles, which corners move and the
/// target diagonals. `patch`: a layout's patch, whose name prefixes its lamellas' ("P2-g3").
std::string assembly_svg(const Design& design, const Kit& kit, const std::string& unit,
                         const std::string& patch = "");

/// One row per anchor (corners included): id, kind, crossing, target position, normal, tilt of
/// the normal from vertical and height above the lowest boundary point (the ground plane, z up),
/// in the design's unit scaled by `scale` (1 = the design's own unit), named `unit`.
std::string supports_csv(const Design& design, double scale, const std::string& unit);

/// The ground plane of a design: the height (z) of the lowest point of its boundary members.
double ground_height(const Design& design);

/// supports.csv's header and one row: anchor `a` named `id`, its height above `ground` (z).
std::string supports_header(const std::string& unit);
std::string support_row(const std::string& id, const Anchor& a, double ground, double scale);

/// Bill of materials: lamellas per family (count, total length), sheets, bolts, nuts, washers,
/// material.
std::string bom_csv(const Design& design, const Kit& kit, const std::string& material);

}  // namespace gridshell
