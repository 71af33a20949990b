// SPDX-License-Identifier: GPL-3.0-or-later
// Sheet drawings, their SVG form, the assembly sheet and the two tables (the DXF form is in
// sheet_dxf.cpp, the one file that sees dxflib).
#include "gridshell/fabrication/kit_export.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <numbers>
#include <string>

namespace gridshell {
namespace {

std::string format(const char* pattern, ...) {
  char text[512];
  va_list args;
  va_start(args, pattern);
  std::vsnprintf(text, sizeof text, pattern, args);
  va_end(args);
  return text;
}

std::string member_name(Family family, int index) {
  return (family == Family::G ? "g" : "h") + std::to_string(index);
}

/// Text length estimate (mm) for the laser's single-line fonts and SVG's sans-serif: a character
/// is at most 0.75 of the height wide.
double text_length(const std::string& text, double height) {
  return 0.75 * height * static_cast<double>(text.size());
}

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else
      out += c;
  }
  return out;
}

const char* layer_colour(SheetLayer layer) {
  return layer == SheetLayer::Cut ? "#ff0000" : "#0000ff";
}

}  // namespace

SheetDrawing sheet_drawing(const Kit& kit, int sheet) {
  const FabricationOptions& o = kit.options;
  SheetDrawing drawing;
  drawing.width = o.sheet_width;
  drawing.height = o.sheet_height;
  const double k = o.kerf, r = 0.5 * (o.hole_diameter - o.kerf);
  const double th = o.text_height, th_partner = 0.7 * o.text_height;
  for (int index : kit.sheets.at(sheet).parts) {
    const Part& part = kit.parts[index];
    const double angle = part.rotation * std::numbers::pi / 180;
    const double half = 0.5 * part.width;
    const auto at = [&](double x, double y) { return part.to_sheet(Vec2(x, y)); };
    // Outline: the nominal rectangle grown by half the kerf (mitred corners).
    SheetPolyline outline;
    outline.points = {at(-0.5 * k, -half - 0.5 * k), at(part.length + 0.5 * k, -half - 0.5 * k),
                      at(part.length + 0.5 * k, half + 0.5 * k), at(-0.5 * k, half + 0.5 * k)};
    outline.bulges = {0, 0, 0, 0};
    drawing.polylines.push_back(outline);
    // Holes and slots shrunk by half the kerf; obstacles for the labels along x.
    std::vector<std::pair<double, double>> taken;
    for (size_t i = 0; i < part.features.size(); ++i) {
      const PartFeature& f = part.features[i];
      if (f.kind == FeatureKind::Hole) {
        drawing.circles.push_back({SheetLayer::Cut, at(f.x0, 0), r});
      } else {
        SheetPolyline slot;
        slot.points = {at(f.x0, -r), at(f.x1, -r), at(f.x1, r), at(f.x0, r)};
        slot.bulges = {0, 1, 0, 1};  // half circles, counter-clockwise, around the slot's ends
        drawing.polylines.push_back(slot);
      }
      // The partner's name beside the hole or slot: after it where it fits before the next
      // feature (or the part's end), else before it where there is more room.
      const std::string& label = f.partner_name;
      const double length = text_length(label, th_partner), gap = 0.4 * th_partner;
      const double half_d = 0.5 * f.diameter;
      const double room_after =
          (i + 1 < part.features.size() ? part.features[i + 1].x0 - half_d : part.length) -
          (f.x1 + half_d);
      const double room_before = f.x0 - half_d - (i > 0 ? part.features[i - 1].x1 + half_d : 0);
      const bool before = room_after < length + 2 * gap && room_before > room_after;
      const double x =
          before ? f.x0 - 0.5 * f.diameter - gap - length : f.x1 + 0.5 * f.diameter + gap;
      drawing.texts.push_back(
          {SheetLayer::Engrave, at(x, -0.5 * th_partner), th_partner, angle, label});
      taken.push_back({f.x0 - 0.5 * f.diameter, f.x1 + 0.5 * f.diameter});
      taken.push_back({x, x + length});
    }
    // The part's name with the top-face triangle before it and the arc-length arrow after it,
    // in the middle of the longest free stretch.
    std::sort(taken.begin(), taken.end());
    double best_from = 0, best_to = 0, cursor = 0;
    for (const auto& [from, to] : taken) {
      if (from - cursor > best_to - best_from) {
        best_from = cursor;
        best_to = from;
      }
      cursor = std::max(cursor, to);
    }
    if (part.length - cursor > best_to - best_from) {
      best_from = cursor;
      best_to = part.length;
    }
    const double name_length = text_length(part.name, th);
    const double group = th + 0.4 * th + name_length + 0.4 * th + 2 * th;
    double x = 0.5 * (best_from + best_to) - 0.5 * group;
    // Top-face mark: a triangle pointing across the lamella.
    const double tri = 0.8 * th;
    SheetPolyline top;
    top.layer = SheetLayer::Engrave;
    top.points = {at(x, -0.5 * tri), at(x + tri, -0.5 * tri), at(x + 0.5 * tri, 0.5 * tri)};
    top.bulges = {0, 0, 0};
    drawing.polylines.push_back(top);
    x += th + 0.4 * th;
    drawing.texts.push_back({SheetLayer::Engrave, at(x, -0.5 * th), th, angle, part.name});
    x += name_length + 0.4 * th;
    // Arrow: shaft and head, pointing to increasing arc length (+x).
    SheetPolyline shaft;
    shaft.layer = SheetLayer::Engrave;
    shaft.closed = false;
    shaft.points = {at(x, 0), at(x + 2 * th, 0)};
    shaft.bulges = {0, 0};
    drawing.polylines.push_back(shaft);
    SheetPolyline head;
    head.layer = SheetLayer::Engrave;
    head.points = {at(x + 2 * th, 0), at(x + 1.4 * th, 0.3 * th), at(x + 1.4 * th, -0.3 * th)};
    head.bulges = {0, 0, 0};
    drawing.polylines.push_back(head);
  }
  return drawing;
}

std::string sheet_svg(const SheetDrawing& d) {
  const auto X = [&](const Vec2& p) { return p.x(); };
  const auto Y = [&](const Vec2& p) { return d.height - p.y(); };
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.10gmm\" height=\"%.10gmm\" "
      "viewBox=\"0 0 %.10g %.10g\">\n",
      d.width, d.height, d.width, d.height);
  out +=
      "<!-- gridshell cut sheet, 1 unit = 1 mm; red hairlines: cut, blue: engrave "
      "(docs/fabrication.md) -->\n";
  out += format(
      "<rect id=\"sheet\" x=\"0\" y=\"0\" width=\"%.10g\" height=\"%.10g\" fill=\"none\" "
      "stroke=\"#999999\" stroke-width=\"0.01\" stroke-dasharray=\"5 5\"/>\n",
      d.width, d.height);
  for (SheetLayer layer : {SheetLayer::Engrave, SheetLayer::Cut}) {
    out += format("<g id=\"%s\" fill=\"none\" stroke=\"%s\" stroke-width=\"0.01\">\n",
                  layer == SheetLayer::Cut ? "CUT" : "ENGRAVE", layer_colour(layer));
    for (const SheetPolyline& p : d.polylines) {
      if (p.layer != layer) continue;
      out += format("<path d=\"M %.10g %.10g", X(p.points[0]), Y(p.points[0]));
      const size_t n = p.points.size(), segments = p.closed ? n : n - 1;
      for (size_t i = 0; i < segments; ++i) {
        const Vec2& b = p.points[(i + 1) % n];
        const double bulge = i < p.bulges.size() ? p.bulges[i] : 0;
        if (bulge == 0) {
          out += format(" L %.10g %.10g", X(b), Y(b));
        } else {
          const double theta = 4 * std::atan(bulge);
          const double chord = (b - p.points[i]).norm();
          const double radius = chord / (2 * std::sin(0.5 * std::abs(theta)));
          // The page flips y, so a counter-clockwise arc (y up, bulge > 0) runs in SVG's
          // negative angle direction (y down): sweep flag 0.
          out += format(" A %.10g %.10g 0 %d %d %.10g %.10g", radius, radius,
                        std::abs(theta) > std::numbers::pi ? 1 : 0, bulge > 0 ? 0 : 1, X(b), Y(b));
        }
      }
      out += p.closed ? " Z\"/>\n" : "\"/>\n";
    }
    for (const SheetCircle& c : d.circles)
      if (c.layer == layer)
        out += format("<circle cx=\"%.10g\" cy=\"%.10g\" r=\"%.10g\"/>\n", X(c.centre), Y(c.centre),
                      c.radius);
    for (const SheetText& t : d.texts)
      if (t.layer == layer)
        out += format(
                   "<text x=\"%.10g\" y=\"%.10g\" font-size=\"%.10g\" font-family=\"sans-serif\" "
                   "fill=\"%s\" stroke=\"none\" transform=\"rotate(%.10g %.10g %.10g)\">",
                   X(t.position), Y(t.position), t.height, layer_colour(layer),
                   -t.angle * 180 / std::numbers::pi, X(t.position), Y(t.position)) +
               escape(t.text) + "</text>\n";
    out += "</g>\n";
  }
  out += "</svg>\n";
  return out;
}

std::string assembly_svg(const Design& design, const Kit& kit, const std::string& unit,
                         const std::string& patch) {
  // A layout's patch names its lamellas as its kit does: "P2-g3".
  const std::string prefix = patch.empty() ? "" : patch + "-";
  const auto lamella_name = [&](Family family, int index) {
    return prefix + member_name(family, index);
  };
  const double mm = kit.options.millimetres_per_unit;
  const Grid& grid = design.grid;
  const double w = design.lamella_width * mm;
  // Extent of the flat grid (mm).
  Vec2 lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const auto* family : {&grid.g, &grid.h})
    for (const Member& m : *family)
      for (const Vec2& p : m.planar) {
        lo = lo.cwiseMin(p * mm);
        hi = hi.cwiseMax(p * mm);
      }
  const double size = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  const double margin = 0.08 * size + 4 * w;
  const double font = std::max(0.012 * size, 1.5 * kit.options.text_height);
  const double page1 = hi.y() - lo.y() + 2 * margin + 3 * font;
  const double page2 = 0.7 * size + 14 * font;
  const double width = hi.x() - lo.x() + 2 * margin;
  const double height = page1 + page2;
  // Plane (mm, y up) -> page (y down).
  const auto X = [&](const Vec2& p) { return p.x() * mm - lo.x() + margin; };
  const auto Y = [&](const Vec2& p) { return hi.y() - p.y() * mm + margin + 2 * font; };
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.6gmm\" height=\"%.6gmm\" "
      "viewBox=\"0 0 %.6g %.6g\" font-family=\"sans-serif\">\n",
      width, height, width, height);
  out += format("<rect width=\"%.6g\" height=\"%.6g\" fill=\"white\"/>\n", width, height);
  const Family top = kit.top_family, bottom = top == Family::H ? Family::G : Family::H;
  out += format(
      "<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.6g\">%sAssembly, 1:1 in mm (%zu lamellas, %zu "
      "crossings). %s lamellas lie on top of %s lamellas at every crossing; engraved faces "
      "up.</text>\n",
      margin, 1.5 * font, font, patch.empty() ? "" : ("Patch " + patch + ". ").c_str(),
      grid.g.size() + grid.h.size(), grid.crossings.size(), top == Family::H ? "h" : "g",
      bottom == Family::H ? "h" : "g");
  // Lamellas: the bottom family first, the top family over it.
  for (Family family : {bottom, top}) {
    const bool is_top = family == top;
    out += format("<g id=\"%s\" fill=\"%s\" stroke=\"#333333\" stroke-width=\"%.4g\">\n",
                  is_top ? "top" : "bottom", is_top ? "#f2d29b" : "#c9a66b", 0.08 * w);
    for (const Member& m : family == Family::G ? grid.g : grid.h) {
      const Vec2 a = m.planar[0], b = m.planar[1];
      const Vec2 t = (b - a).normalized(), n(-t.y(), t.x());
      const double half = 0.5 * design.lamella_width;
      const Vec2 p[4] = {a - n * half, b - n * half, b + n * half, a + n * half};
      out += format(
          "<polygon data-lamella=\"%s\" points=\"%.6g,%.6g %.6g,%.6g %.6g,%.6g %.6g,%.6g\"/>\n",
          lamella_name(family, m.index).c_str(), X(p[0]), Y(p[0]), X(p[1]), Y(p[1]), X(p[2]),
          Y(p[2]), X(p[3]), Y(p[3]));
    }
    out += "</g>\n";
  }
  // Names at the start of each lamella (where its arc length is 0, the arrow's tail).
  for (Family family : {Family::G, Family::H})
    for (const Member& m : family == Family::G ? grid.g : grid.h) {
      const Vec2 t = (m.planar[1] - m.planar[0]).normalized();
      const Vec2 at = m.planar[0] - t * (2.5 * w / mm);
      out += format(
          "<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.6g\" text-anchor=\"middle\" "
          "fill=\"%s\">%s</text>\n",
          X(at), Y(at) + 0.35 * font, font, family == Family::G ? "#003399" : "#993300",
          lamella_name(family, m.index).c_str());
    }
  // Crossings: the bolt (a dot) and both names, as engraved on the parts.
  const double small = std::max(0.35 * font, 0.9 * w);
  out += "<g id=\"crossings\">\n";
  for (const Crossing& c : grid.crossings) {
    const Vec2 p = c.planar_point;
    const bool slides = c.notch_g() != 0 || c.notch_h() != 0;
    out += format("<circle cx=\"%.6g\" cy=\"%.6g\" r=\"%.4g\" fill=\"%s\"/>\n", X(p), Y(p),
                  0.5 * kit.options.hole_diameter, slides ? "#cc0000" : "#000000");
    out +=
        format("<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.4g\" fill=\"#222222\">%sg%d·h%d</text>\n",
               X(p) + 0.6 * w, Y(p) - 0.6 * w, small, prefix.c_str(), c.g, c.h);
  }
  out += "</g>\n";
  // Anchors, numbered as in supports.csv.
  out += "<g id=\"anchors\" fill=\"none\" stroke=\"#008800\">\n";
  for (size_t i = 0; i < design.anchors.size(); ++i) {
    const Anchor& a = design.anchors[i];
    for (const Crossing& c : grid.crossings)
      if (c.g == a.g && c.h == a.h) {
        const Vec2 p = c.planar_point;
        out += format(
            "<rect x=\"%.6g\" y=\"%.6g\" width=\"%.6g\" height=\"%.6g\" stroke-width=\"%.4g\"/>"
            "<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.6g\" fill=\"#008800\" "
            "stroke=\"none\">A%zu</text>\n",
            X(p) - 1.5 * w, Y(p) - 1.5 * w, 3 * w, 3 * w, 0.2 * w, X(p) + 1.8 * w, Y(p) + 2.2 * w,
            font, i + 1);
      }
  }
  out += "</g>\n";
  out += format(
      "<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.6g\">black dot: bolt through two holes; red "
      "dot: bolt in a slot (the crossing slides during deployment); green squares: anchors "
      "A1..A%zu (supports.csv)</text>\n",
      margin, page1 - 0.5 * font, 0.8 * font, design.anchors.size());

  // Page 2: the deployment.
  const double top2 = page1 + 2 * font;
  out += format(
      "<line x1=\"0\" y1=\"%.6g\" x2=\"%.6g\" y2=\"%.6g\" stroke=\"#999999\" "
      "stroke-dasharray=\"%.4g\"/>\n",
      page1, width, page1, font);
  out += format("<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.6g\">Deployment</text>\n", margin, top2,
                1.3 * font);
  const CornerAngles angles = corner_angles(design);
  const int gl = static_cast<int>(grid.g.size()) - 1, hl = static_cast<int>(grid.h.size()) - 1;
  const std::array<std::array<int, 2>, 4> corner = {{{0, 0}, {gl, 0}, {gl, hl}, {0, hl}}};
  std::array<const Crossing*, 4> corners{};
  for (int k = 0; k < 4; ++k)
    for (const Crossing& c : grid.crossings)
      if (c.g == corner[k][0] && c.h == corner[k][1]) corners[k] = &c;
  const double deg = 180 / std::numbers::pi;
  double y = top2 + 2 * font;
  const auto line = [&](const std::string& text) {
    out += format("<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.6g\">", margin, y, font) +
           escape(text) + "</text>\n";
    y += 1.5 * font;
  };
  line(
      format("Corner angle at c0: flat %.2f°, target %.2f°. Hold c0 and the side c0-c1 "
             "(lamella h0); turn the side c0-c3",
             angles.planar[0] * deg, angles.target[0] * deg));
  line(
      "(lamella g0) about c0 until the angle is reached: corners c2 and c3 move, and every "
      "crossing turns with them (the grid is a linkage).");
  line(
      "Then set each anchor on its support (supports.csv) and tighten the bolts that are in "
      "holes; leave the bolts in slots free to slide.");
  for (int k = 0; k < 4; ++k)
    line(format("c%d (g%d·h%d): flat %.2f°, target %.2f°%s", k, corner[k][0], corner[k][1],
                angles.planar[k] * deg, angles.target[k] * deg,
                k == 0 || k == 1 ? "  (stays)" : "  (moves)"));
  if (corners[0] && corners[1] && corners[2] && corners[3]) {
    const auto planar = [&](int a, int b) {
      return (corners[a]->planar_point - corners[b]->planar_point).norm() * mm;
    };
    const auto spatial = [&](int a, int b) {
      return (corners[a]->surface_point - corners[b]->surface_point).norm() * mm;
    };
    line(
        format("Diagonals (mm): c0-c2 flat %.1f, target %.1f;  c1-c3 flat %.1f, target %.1f "
               "(straight distances between the corner bolts)",
               planar(0, 2), spatial(0, 2), planar(1, 3), spatial(1, 3)));
    // A small drawing of the flat quadrilateral with its corners named.
    const double s = 0.5 * size / std::max(1e-9, (hi - lo).maxCoeff());
    const double ox = margin, oy = y + 0.55 * size;
    std::string points, labels;
    for (int k = 0; k < 4; ++k) {
      const Vec2 p = (corners[k]->planar_point * mm - lo) * s;
      points += format("%.6g,%.6g ", ox + p.x(), oy - p.y());
      labels += format("<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.6g\">c%d</text>\n", ox + p.x(),
                       oy - p.y() + (k < 2 ? 1.2 : -0.4) * font, font, k);
    }
    out += "<polygon points=\"" + points +
           format("\" fill=\"#f2d29b\" stroke=\"#333333\" stroke-width=\"%.4g\"/>\n", 0.1 * font) +
           labels;
  }
  (void)unit;
  out += "</svg>\n";
  return out;
}

double ground_height(const Design& design) {
  double ground = 1e300;
  for (const auto* family : {&design.grid.g, &design.grid.h})
    for (const Member& m : *family)
      if (m.boundary)
        for (const Vec3& p : m.surface) ground = std::min(ground, p.z());
  return ground == 1e300 ? 0 : ground;
}

std::string supports_header(const std::string& u) {
  return "id,kind,g,h,side,x_" + u + ",y_" + u + ",z_" + u + ",nx,ny,nz,tilt_deg,height_" + u +
         "\n";
}

std::string support_row(const std::string& id, const Anchor& a, double ground, double scale) {
  const char* kind = a.corner ? "corner" : a.side >= 0 ? "boundary" : "inner";
  const Vec3 n = a.normal.normalized();
  const double tilt = std::acos(std::clamp(n.z(), -1.0, 1.0)) * 180 / std::numbers::pi;
  return format("%s,%s,%d,%d,%d,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.3f,%.6f\n", id.c_str(), kind, a.g,
                a.h, a.side, a.position.x() * scale, a.position.y() * scale, a.position.z() * scale,
                n.x(), n.y(), n.z(), tilt, (a.position.z() - ground) * scale);
}

std::string supports_csv(const Design& design, double scale, const std::string& unit) {
  // Ground plane: the lowest point of the boundary members (z up).
  const double ground = ground_height(design);
  std::string out = supports_header(unit);
  for (size_t i = 0; i < design.anchors.size(); ++i)
    out += support_row("A" + std::to_string(i + 1), design.anchors[i], ground, scale);
  return out;
}

std::string bom_csv(const Design& design, const Kit& kit, const std::string& material) {
  const FabricationOptions& o = kit.options;
  std::string out = "item,quantity,unit,description\n";
  for (Family family : {Family::G, Family::H}) {
    int count = 0;
    double total = 0, longest = 0;
    for (const Part& p : kit.parts)
      if (p.family == family) {
        ++count;
        total += p.length;
        longest = std::max(longest, p.length);
      }
    out += format("lamellas %s,%d,pcs,\"%.1f mm in all, longest %.1f mm, %.2f x %.2f mm\"\n",
                  family == Family::G ? "g" : "h", count, total, longest, o.thickness,
                  kit.parts.empty() ? 0.0 : kit.parts[0].width);
  }
  out +=
      format("sheets,%zu,pcs,\"%.1f x %.1f x %.2f mm %s, %.1f %% used\"\n", kit.sheets.size(),
             o.sheet_width, o.sheet_height, o.thickness, material.c_str(), 100 * kit.utilisation);
  const size_t bolts = design.grid.crossings.size();
  out += format("bolts,%zu,pcs,\"for %.2f mm holes, grip at least %.2f mm (two lamellas)\"\n",
                bolts, o.hole_diameter, 2 * o.thickness);
  out += format(
      "nuts,%zu,pcs,\"to match the bolts; lock nuts where a crossing does not "
      "slide\"\n",
      bolts);
  out += format("washers,%zu,pcs,\"under the nuts on slots (%d slots)\"\n", 2 * bolts, kit.slots);
  out += format("holes,%d,pcs,\"round holes, %.2f mm (cut %.2f mm)\"\n", kit.holes, o.hole_diameter,
                o.hole_diameter - o.kerf);
  out += format("slots,%d,pcs,\"%.2f mm wide (cut %.2f mm)\"\n", kit.slots, o.hole_diameter,
                o.hole_diameter - o.kerf);
  out += format("supports,%zu,pcs,\"one per anchor (supports.csv)\"\n", design.anchors.size());
  return out;
}

}  // namespace gridshell
