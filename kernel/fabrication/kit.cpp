// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/fabrication/kit.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>

#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

std::string format_mm(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", v);
  return text;
}

void require(bool ok, const char* field, const std::string& message) {
  if (!ok) throw InvalidInput(std::string("options.") + field, message);
}

std::string member_name(Family family, int index) {
  return (family == Family::G ? "g" : "h") + std::to_string(index);
}

/// The crossing of two members, or null.
const Crossing* find_crossing(const Grid& grid, int g, int h) {
  for (const Crossing& c : grid.crossings)
    if (c.g == g && c.h == h) return &c;
  return nullptr;
}

/// Unit direction in which `polyline` leaves its end nearest to `corner`.
Vec3 leaving_direction(const std::vector<Vec3>& polyline, const Vec3& corner) {
  const bool from_start = (polyline.front() - corner).norm() <= (polyline.back() - corner).norm();
  const Vec3 start = from_start ? polyline.front() : polyline.back();
  // A point a few percent of the length along: the tangent of a discretised geodesic.
  double total = 0;
  for (size_t i = 1; i < polyline.size(); ++i) total += (polyline[i] - polyline[i - 1]).norm();
  const double reach = 0.02 * total;
  double walked = 0;
  for (size_t k = 1; k < polyline.size(); ++k) {
    const size_t i = from_start ? k : polyline.size() - 1 - k;
    const size_t j = from_start ? k - 1 : polyline.size() - k;
    walked += (polyline[i] - polyline[j]).norm();
    if (walked >= reach || k + 1 == polyline.size()) return (polyline[i] - start).normalized();
  }
  return Vec3::UnitX();
}

double angle_between(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace

Vec2 Part::to_sheet(const Vec2& p) const {
  if (rotation == 0) return p + translation;
  return Vec2(-p.y(), p.x()) + translation;  // 90 degrees counter-clockwise
}

FabricationOptions resolve_fabrication_options(FabricationOptions o, double lamella_width,
                                               double lamella_thickness) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  require(positive(o.millimetres_per_unit) && o.millimetres_per_unit < 1e9, "unit",
          "the design's length unit is needed (mm, cm, m, in, ft or millimetres per unit)");
  require(positive(o.sheet_width) && positive(o.sheet_height) && o.sheet_width < 1e6 &&
              o.sheet_height < 1e6,
          "sheet", "width and height must be positive numbers of mm (below 1 km)");
  require(std::isfinite(o.kerf) && o.kerf >= 0 && o.kerf < 10, "kerf",
          "must be between 0 and 10 mm");
  require(positive(o.hole_diameter) && o.hole_diameter < 1000, "hole_diameter",
          "must be a positive number of mm");
  require(o.hole_diameter > o.kerf, "hole_diameter",
          "must be larger than the kerf (" + format_mm(o.kerf) + " mm)");
  require(std::isfinite(o.end_allowance) && o.end_allowance >= 0, "end_allowance",
          "must be 0 (automatic) or a positive number of mm");
  require(std::isfinite(o.spacing) && o.spacing >= 0, "spacing", "must be at least 0 mm");
  require(std::isfinite(o.thickness) && o.thickness >= 0, "thickness",
          "must be 0 (the design's) or a positive number of mm");
  require(std::isfinite(o.min_slot) && o.min_slot >= 0, "min_slot", "must be at least 0 mm");
  require(std::isfinite(o.text_height) && o.text_height >= 0, "text_height",
          "must be 0 (automatic) or a positive number of mm");
  const double width = lamella_width * o.millimetres_per_unit;
  if (o.end_allowance == 0) o.end_allowance = std::max(width, o.hole_diameter);
  require(o.end_allowance >= 0.5 * o.hole_diameter, "end_allowance",
          "must leave the hole inside the lamella (at least half the hole diameter, " +
              format_mm(0.5 * o.hole_diameter) + " mm)");
  if (o.thickness == 0) o.thickness = lamella_thickness * o.millimetres_per_unit;
  if (o.text_height == 0) o.text_height = std::clamp(0.4 * width, 1.0, 8.0);
  return o;
}

Kit make_kit(const Design& design, const FabricationOptions& requested, const Progress& progress) {
  progress.report("fabricate: parts", 0);
  const double mm = requested.millimetres_per_unit;
  if (!(design.lamella_width > 0) || !std::isfinite(design.lamella_width))
    throw InvalidInput("design.options.lamella_width", "must be a positive number");
  if (!(design.lamella_thickness > 0) || !std::isfinite(design.lamella_thickness))
    throw InvalidInput("design.options.lamella_thickness", "must be a positive number");
  Kit kit;
  kit.options =
      resolve_fabrication_options(requested, design.lamella_width, design.lamella_thickness);
  const FabricationOptions& o = kit.options;
  const double width = design.lamella_width * mm;
  require(o.hole_diameter < width, "hole_diameter",
          format_mm(o.hole_diameter) + " mm does not fit in the lamella width (" +
              format_mm(width) + " mm)");

  // Parts: every member of both families, with a hole or a slot at each of its crossings.
  const Grid& grid = design.grid;
  for (int f = 0; f < 2; ++f) {
    const Family family = f == 0 ? Family::G : Family::H;
    for (const Member& m : f == 0 ? grid.g : grid.h) {
      Part part;
      part.family = family;
      part.index = m.index;
      part.boundary = m.boundary;
      part.name = member_name(family, m.index);
      part.width = width;
      kit.parts.push_back(std::move(part));
    }
  }
  const int ng = static_cast<int>(grid.g.size());
  for (size_t i = 0; i < grid.crossings.size(); ++i) {
    const Crossing& c = grid.crossings[i];
    for (int f = 0; f < 2; ++f) {
      PartFeature feature;
      feature.crossing = static_cast<int>(i);
      feature.partner_family = f == 0 ? Family::H : Family::G;
      feature.partner = f == 0 ? c.h : c.g;
      feature.partner_name = member_name(feature.partner_family, feature.partner);
      feature.s_bar = f == 0 ? c.s_bar_g : c.s_bar_h;
      const double notch = f == 0 ? c.notch_g() : c.notch_h();
      feature.s = feature.s_bar + notch;
      feature.diameter = o.hole_diameter;
      const bool slot = std::abs(notch) * mm >= o.min_slot && notch != 0;
      feature.kind = slot ? FeatureKind::Slot : FeatureKind::Hole;
      // Member arc length in mm for now; shifted to the part's frame below.
      feature.x0 = std::min(feature.s_bar, slot ? feature.s : feature.s_bar) * mm;
      feature.x1 = std::max(feature.s_bar, slot ? feature.s : feature.s_bar) * mm;
      const int member = f == 0 ? c.g : c.h;
      const int owner = f == 0 ? member : ng + member;
      if (member < 0 || owner >= static_cast<int>(kit.parts.size()))
        throw InvalidInput("design.crossings[" + std::to_string(i) + "]", "no such member");
      kit.parts[owner].features.push_back(feature);
      (slot ? kit.slots : kit.holes) += 1;
    }
  }
  for (Part& part : kit.parts) {
    if (part.features.empty())
      throw InvalidInput("design.members", "lamella " + part.name + " has no crossing");
    std::sort(part.features.begin(), part.features.end(),
              [](const PartFeature& a, const PartFeature& b) {
                return a.x0 != b.x0 ? a.x0 < b.x0 : a.crossing < b.crossing;
              });
    double lo = part.features.front().x0, hi = lo;
    for (const PartFeature& feature : part.features) {
      lo = std::min(lo, feature.x0);
      hi = std::max(hi, feature.x1);
    }
    part.start = lo - o.end_allowance;
    part.length = hi + o.end_allowance - part.start;
    for (PartFeature& feature : part.features) {
      feature.x0 -= part.start;
      feature.x1 -= part.start;
    }
  }

  progress.report("fabricate: nesting", 0.3);
  nest_kit(kit);

  // Which family lies on top in the flat grid as drawn (seen from +z of the plane): h lies on
  // the side of the surface normal (the simulation's convention), so it is on top where the
  // planar grid keeps the patch's orientation, i.e. where a planar grid cell and its surface
  // cell turn the same way about the target's normal (measured at the anchors, which carry it).
  double votes = 0;
  for (const Anchor& a : design.anchors) {
    const int g1 = a.g + 1 < ng ? a.g + 1 : a.g - 1;
    const int h1 = a.h + 1 < static_cast<int>(grid.h.size()) ? a.h + 1 : a.h - 1;
    const Crossing* c00 = find_crossing(grid, a.g, a.h);
    const Crossing* c10 = find_crossing(grid, g1, a.h);
    const Crossing* c01 = find_crossing(grid, a.g, h1);
    if (!c00 || !c10 || !c01) continue;
    const Vec2 p1 = c10->planar_point - c00->planar_point,
               p2 = c01->planar_point - c00->planar_point;
    const double planar_turn = p1.x() * p2.y() - p1.y() * p2.x();
    const double surface_turn = (c10->surface_point - c00->surface_point)
                                    .cross(c01->surface_point - c00->surface_point)
                                    .dot(a.normal);
    votes += (planar_turn > 0) == (surface_turn > 0) ? 1 : -1;
  }
  kit.top_family = votes >= 0 ? Family::H : Family::G;
  progress.report("fabricate: nesting", 1);
  return kit;
}

void nest_kit(Kit& kit) {
  const FabricationOptions& o = kit.options;
  double width = 0;
  for (const Part& part : kit.parts) width = std::max(width, part.width);
  // Nesting: rows of lamellas along the sheet's long side, first-fit decreasing (a part goes
  // into the first row, on any sheet, where it fits; a new row otherwise). Every footprint is
  // the kerf-compensated outline; footprints keep `spacing` from each other and the edges.
  const double long_side = std::max(o.sheet_width, o.sheet_height);
  const double short_side = std::min(o.sheet_width, o.sheet_height);
  const double row_length = long_side - 2 * o.spacing;
  const double footprint_width = width + o.kerf;
  const std::string sheet_size = format_mm(o.sheet_width) + " x " + format_mm(o.sheet_height);
  kit.rows_per_sheet = static_cast<int>(
      std::floor((short_side - 2 * o.spacing + o.spacing) / (footprint_width + o.spacing)));
  if (kit.rows_per_sheet < 1)
    throw InvalidInput("options.sheet", "the lamellas are " + format_mm(width) + " mm wide (" +
                                            format_mm(footprint_width + 2 * o.spacing) +
                                            " mm with kerf and spacing): wider than the sheet " +
                                            sheet_size + " mm");
  std::vector<int> order(kit.parts.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return kit.parts[a].length > kit.parts[b].length; });
  struct Row {
    int sheet = 0, row = 0;
    double used = 0;  // length taken, including the spacing after each part
  };
  std::vector<Row> rows;
  for (int index : order) {
    Part& part = kit.parts[index];
    const double footprint = part.length + o.kerf;
    if (footprint > row_length)
      throw InvalidInput("options.sheet", "lamella " + part.name + " is " + format_mm(part.length) +
                                              " mm long (" + format_mm(footprint + 2 * o.spacing) +
                                              " mm with kerf and spacing): longer than the sheet " +
                                              sheet_size + " mm");
    Row* row = nullptr;
    for (Row& r : rows)
      if (r.used + footprint <= row_length + 1e-9) {
        row = &r;
        break;
      }
    if (!row) {
      Row r;
      if (!rows.empty()) {
        r.sheet = rows.back().sheet;
        r.row = rows.back().row + 1;
        if (r.row >= kit.rows_per_sheet) {
          r.sheet += 1;
          r.row = 0;
        }
      }
      rows.push_back(r);
      row = &rows.back();
    }
    // Position in (along, across) sheet coordinates of the footprint's lower left corner.
    const double along = o.spacing + row->used;
    const double across = o.spacing + row->row * (footprint_width + o.spacing);
    row->used += footprint + o.spacing;
    part.sheet = row->sheet;
    part.row = row->row;
    // The part frame's origin is the nominal outline's left end on the centerline.
    const Vec2 origin(along + 0.5 * o.kerf, across + 0.5 * footprint_width);
    if (o.sheet_width >= o.sheet_height) {
      part.rotation = 0;
      part.translation = origin;
    } else {  // rows run up the sheet: part x -> sheet y
      part.rotation = 90;
      part.translation = Vec2(o.sheet_width - origin.y(), origin.x());
    }
  }
  const int sheets = rows.empty() ? 0 : rows.back().sheet + 1;
  kit.sheets.resize(sheets);
  kit.rows = static_cast<int>(rows.size());
  double part_area = 0;
  for (size_t i = 0; i < kit.parts.size(); ++i) {
    const Part& part = kit.parts[i];
    Sheet& sheet = kit.sheets[part.sheet];
    sheet.parts.push_back(static_cast<int>(i));
    sheet.utilisation += part.length * part.width / (o.sheet_width * o.sheet_height);
    part_area += part.length * part.width;
  }
  for (const Row& r : rows)
    kit.sheets[r.sheet].rows = std::max(kit.sheets[r.sheet].rows, r.row + 1);
  const double sheet_area = o.sheet_width * o.sheet_height;
  kit.utilisation = sheets ? part_area / (sheets * sheet_area) : 0;
  const int n = static_cast<int>(kit.parts.size());
  kit.baseline_sheets = (n + kit.rows_per_sheet - 1) / kit.rows_per_sheet;
  kit.baseline_utilisation =
      kit.baseline_sheets ? part_area / (kit.baseline_sheets * sheet_area) : 0;
}

CornerAngles corner_angles(const Design& design) {
  CornerAngles out;
  const Grid& grid = design.grid;
  if (grid.g.size() < 2 || grid.h.size() < 2) return out;
  const int gl = static_cast<int>(grid.g.size()) - 1, hl = static_cast<int>(grid.h.size()) - 1;
  // c0 = g0 x h0, c1 = g_last x h0, c2 = g_last x h_last, c3 = g0 x h_last (family.h).
  const std::array<std::array<int, 2>, 4> corner = {{{0, 0}, {gl, 0}, {gl, hl}, {0, hl}}};
  for (int k = 0; k < 4; ++k) {
    const Crossing* c = find_crossing(grid, corner[k][0], corner[k][1]);
    const Crossing* prev = find_crossing(grid, corner[(k + 3) % 4][0], corner[(k + 3) % 4][1]);
    const Crossing* next = find_crossing(grid, corner[(k + 1) % 4][0], corner[(k + 1) % 4][1]);
    if (!c || !prev || !next) continue;
    const Vec2 a = next->planar_point - c->planar_point, b = prev->planar_point - c->planar_point;
    out.planar[k] = std::atan2(std::abs(a.x() * b.y() - a.y() * b.x()), a.dot(b));
    const Member& g = grid.g[corner[k][0]];
    const Member& h = grid.h[corner[k][1]];
    out.target[k] = angle_between(leaving_direction(g.surface, c->surface_point),
                                  leaving_direction(h.surface, c->surface_point));
  }
  return out;
}

}  // namespace gridshell
