// SPDX-License-Identifier: GPL-3.0-or-later
// The design's human-readable views (gridshell/design/design_export.h), parsed back and checked
// against the design: planar_svg (one line per member between its planar endpoints, to scale,
// inside the viewBox; notch slots of length |s - s̄| along their member; a dot per crossing; a
// square per anchor), spatial_obj (the patch's vertices and faces, every member's polyline) and
// maps_svg (well-formed, both cladding curves with all their points, a dot per member).
//
// The SVGs are read with a small XML reader below (elements, attributes, text; no new
// dependency). maps_svg prints 6 significant digits ("%.6g"), so its numbers are compared to half
// a unit in the 6th digit of the printed value; planar_svg prints exact decimals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "gridshell/design/design.h"
#include "gridshell/design/design_export.h"
#include "gridshell/example_surfaces.h"
#include "support.h"

namespace gridshell {
namespace {

// ---------------------------------------------------------------------------------------------
// A small XML reader: enough for well-formedness and the elements' attributes and text.

struct Element {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::string text;
  int depth = 0;
  double number(const std::string& attribute) const {
    const auto it = attributes.find(attribute);
    if (it == attributes.end()) {
      ADD_FAILURE() << "<" << name << "> has no attribute " << attribute;
      return std::nan("");
    }
    return std::stod(it->second);
  }
  std::string operator[](const std::string& attribute) const {
    const auto it = attributes.find(attribute);
    return it == attributes.end() ? "" : it->second;
  }
};

/// Parses `xml` into its elements in document order. Returns an empty string if it is
/// well-formed (one root, every tag closed in order, attributes quoted), else the problem.
std::string parse_xml(const std::string& xml, std::vector<Element>& elements) {
  std::vector<std::size_t> open;  // indices of the open elements
  int roots = 0;
  std::size_t i = 0;
  const auto name_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == ':' ||
           c == '.';
  };
  const auto skip_space = [&] {
    while (i < xml.size() && std::isspace(static_cast<unsigned char>(xml[i]))) ++i;
  };
  while (i < xml.size()) {
    if (xml[i] != '<') {
      const std::size_t end = xml.find('<', i);
      const std::string text = xml.substr(i, end == std::string::npos ? end : end - i);
      if (open.empty()) {
        if (text.find_first_not_of(" \t\r\n") != std::string::npos)
          return "text outside the root: " + text;
      } else {
        elements[open.back()].text += text;
      }
      if (end == std::string::npos) break;
      i = end;
      continue;
    }
    if (xml.compare(i, 2, "<?") == 0 || xml.compare(i, 4, "<!--") == 0) {
      const std::string close = xml.compare(i, 2, "<?") == 0 ? "?>" : "-->";
      const std::size_t end = xml.find(close, i);
      if (end == std::string::npos) return "unterminated " + close;
      i = end + close.size();
      continue;
    }
    if (xml.compare(i, 2, "</") == 0) {
      i += 2;
      const std::size_t start = i;
      while (i < xml.size() && name_char(xml[i])) ++i;
      const std::string name = xml.substr(start, i - start);
      skip_space();
      if (i >= xml.size() || xml[i] != '>') return "bad closing tag </" + name;
      ++i;
      if (open.empty() || elements[open.back()].name != name)
        return "</" + name + "> closes " +
               (open.empty() ? std::string("nothing") : "<" + elements[open.back()].name + ">");
      open.pop_back();
      continue;
    }
    ++i;
    Element element;
    const std::size_t start = i;
    while (i < xml.size() && name_char(xml[i])) ++i;
    element.name = xml.substr(start, i - start);
    if (element.name.empty()) return "empty tag name";
    element.depth = static_cast<int>(open.size());
    bool self_closing = false;
    for (;;) {
      skip_space();
      if (i >= xml.size()) return "unterminated <" + element.name;
      if (xml[i] == '/') {
        if (i + 1 >= xml.size() || xml[i + 1] != '>') return "bad '/' in <" + element.name;
        i += 2;
        self_closing = true;
        break;
      }
      if (xml[i] == '>') {
        ++i;
        break;
      }
      const std::size_t a = i;
      while (i < xml.size() && name_char(xml[i])) ++i;
      const std::string attribute = xml.substr(a, i - a);
      if (attribute.empty() || i + 1 >= xml.size() || xml[i] != '=' ||
          (xml[i + 1] != '"' && xml[i + 1] != '\''))
        return "bad attribute in <" + element.name + ">";
      const char quote = xml[i + 1];
      const std::size_t end = xml.find(quote, i + 2);
      if (end == std::string::npos) return "unterminated attribute " + attribute;
      if (element.attributes.count(attribute)) return "repeated attribute " + attribute;
      element.attributes[attribute] = xml.substr(i + 2, end - i - 2);
      if (element.attributes[attribute].find('<') != std::string::npos)
        return "'<' in attribute " + attribute;
      i = end + 1;
    }
    if (open.empty()) ++roots;
    elements.push_back(element);
    if (!self_closing) open.push_back(elements.size() - 1);
  }
  if (!open.empty()) return "<" + elements[open.back()].name + "> never closed";
  if (roots != 1) return std::to_string(roots) + " root elements";
  return "";
}

std::vector<Element> parse_or_fail(const std::string& xml) {
  std::vector<Element> elements;
  const std::string problem = parse_xml(xml, elements);
  EXPECT_EQ(problem, "") << "not well-formed";
  return elements;
}

std::vector<const Element*> all_named(const std::vector<Element>& elements,
                                      const std::string& name) {
  std::vector<const Element*> out;
  for (const Element& e : elements)
    if (e.name == name) out.push_back(&e);
  return out;
}

std::vector<double> numbers(const std::string& text) {
  std::vector<double> out;
  std::string cleaned = text;
  std::replace(cleaned.begin(), cleaned.end(), ',', ' ');
  std::istringstream in(cleaned);
  double x;
  while (in >> x) out.push_back(x);
  return out;
}

/// Half a unit in the 6th significant digit of `printed` ("%.6g"), plus rounding.
double printed_precision(double printed) { return 5e-6 * std::abs(printed) + 1e-12; }

// ---------------------------------------------------------------------------------------------
// The design

const Design& double_vault() {
  static const std::unique_ptr<const Design> design = [] {
    const ExampleSurface example = make_example("double-vault");
    DesignOptions options;
    options.maps.resolution = 48;
    return std::make_unique<const Design>(
        make_design(example.mesh, CornerSpec::at_vertices(example.corners), options));
  }();
  return *design;
}

std::string member_name(const Member& m) {
  return (m.family == Family::G ? "g" : "h") + std::to_string(m.index);
}

// ---------------------------------------------------------------------------------------------
// planar_svg

/// The planar SVG parsed, with the translation (x, y) -> (x + dx, dy - y) it applies.
struct PlanarSvg {
  std::vector<Element> elements;
  double width = 0, height = 0;
  std::vector<const Element*> member_lines, notch_lines, labels, dots, squares;
  double dx = 0, dy = 0;
  /// Coordinates are good to half a unit in the 6th digit of the drawing's size (and the
  /// translation, read from printed numbers, to the same).
  double tolerance = 0;
  Vec2 to_svg(const Vec2& p) const { return Vec2(p.x() + dx, dy - p.y()); }
};

PlanarSvg read_planar(const Design& d) {
  PlanarSvg svg;
  svg.elements = parse_or_fail(planar_svg(d, d.lamella_width));
  const Element& root = svg.elements.at(0);
  EXPECT_EQ(root.name, "svg");
  EXPECT_EQ(root["xmlns"], "http://www.w3.org/2000/svg");
  const std::vector<double> box = numbers(root["viewBox"]);
  EXPECT_EQ(box.size(), 4u);
  if (box.size() == 4) {
    EXPECT_EQ(box[0], 0.0);
    EXPECT_EQ(box[1], 0.0);
    svg.width = box[2];
    svg.height = box[3];
  }
  // To scale: the physical size in mm is the viewBox size (1 unit = 1 mm).
  EXPECT_EQ(root["width"], root["viewBox"].substr(4, root["viewBox"].find(' ', 4) - 4) + "mm");
  for (const Element& e : svg.elements) {
    if (e.name == "line") {
      (e["stroke"] == "#d62728" ? svg.notch_lines : svg.member_lines).push_back(&e);
    } else if (e.name == "text") {
      svg.labels.push_back(&e);
    } else if (e.name == "circle") {
      svg.dots.push_back(&e);
    } else if (e.name == "rect" && e["width"] != "100%") {
      svg.squares.push_back(&e);
    }
  }
  svg.tolerance = 3 * printed_precision(std::max(svg.width, svg.height));
  // The translation, from the first member's start point.
  if (!svg.member_lines.empty()) {
    const Vec2& p = d.grid.g.front().planar[0];
    svg.dx = svg.member_lines[0]->number("x1") - p.x();
    svg.dy = svg.member_lines[0]->number("y1") + p.y();
  }
  return svg;
}

/// Largest coordinate error seen by expect_near_printed, for the report.
double worst_coordinate_error = 0;

void expect_near_printed(const PlanarSvg& svg, const Vec2& printed, const Vec2& expected,
                         const std::string& what) {
  EXPECT_NEAR(printed.x(), expected.x(), svg.tolerance) << what;
  EXPECT_NEAR(printed.y(), expected.y(), svg.tolerance) << what;
  worst_coordinate_error =
      std::max(worst_coordinate_error, (printed - expected).cwiseAbs().maxCoeff());
}

TEST(PlanarSvg, OneLinePerMemberBetweenItsPlanarEndpoints) {
  const Design& d = double_vault();
  const PlanarSvg svg = read_planar(d);
  std::vector<const Member*> members;
  for (const auto* family : {&d.grid.g, &d.grid.h})
    for (const Member& m : *family) members.push_back(&m);
  ASSERT_EQ(svg.member_lines.size(), members.size());
  ASSERT_EQ(svg.labels.size(), members.size());
  std::set<std::string> names;
  for (std::size_t k = 0; k < members.size(); ++k) {
    const Member& m = *members[k];
    const Element& line = *svg.member_lines[k];
    const std::string name = member_name(m);
    expect_near_printed(svg, Vec2(line.number("x1"), line.number("y1")), svg.to_svg(m.planar[0]),
                        name + " start");
    expect_near_printed(svg, Vec2(line.number("x2"), line.number("y2")), svg.to_svg(m.planar[1]),
                        name + " end");
    // Drawn at the lamella's width, coloured by family, labelled with its name.
    EXPECT_NEAR(line.number("stroke-width"), d.lamella_width, printed_precision(d.lamella_width));
    EXPECT_EQ(line["stroke"], m.family == Family::G ? "#c8813a" : "#3a7fc8");
    EXPECT_EQ(svg.labels[k]->text, name);
    names.insert(svg.labels[k]->text);
    // To scale: the drawn length is the member's length.
    const double drawn =
        std::hypot(line.number("x2") - line.number("x1"), line.number("y2") - line.number("y1"));
    EXPECT_NEAR(drawn, m.planar_length, 2 * svg.tolerance) << name;
  }
  EXPECT_EQ(names.size(), members.size());
  std::printf("  largest endpoint coordinate error %.2e (drawing %.4g x %.4g)\n",
              worst_coordinate_error, svg.width, svg.height);
}

TEST(PlanarSvg, ViewBoxEnclosesEveryMember) {
  const Design& d = double_vault();
  const PlanarSvg svg = read_planar(d);
  ASSERT_GT(svg.width, 0.0);
  ASSERT_GT(svg.height, 0.0);
  const double half = d.lamella_width / 2;
  for (const Element* line : svg.member_lines)
    for (const auto& [x, y] : {std::pair{"x1", "y1"}, std::pair{"x2", "y2"}}) {
      EXPECT_GE(line->number(x) - half, 0.0);
      EXPECT_LE(line->number(x) + half, svg.width);
      EXPECT_GE(line->number(y) - half, 0.0);
      EXPECT_LE(line->number(y) + half, svg.height);
    }
  for (const Element* text : svg.labels) {
    EXPECT_GE(text->number("x"), 0.0);
    EXPECT_LE(text->number("x"), svg.width);
    EXPECT_GE(text->number("y"), 0.0);
    EXPECT_LE(text->number("y"), svg.height);
  }
}

// A slot per non-zero notch, in crossing order (g's notch, then h's): from the crossing along
// its member, of length |s - s̄|, in the direction of the sign.
TEST(PlanarSvg, NotchSlotsHaveLengthSMinusSBarAlongTheirMember) {
  const Design& d = double_vault();
  const PlanarSvg svg = read_planar(d);
  struct Slot {
    const Member* member;
    const Crossing* crossing;
    double notch;
  };
  std::vector<Slot> slots;
  for (const Crossing& x : d.grid.crossings) {
    if (x.notch_g() != 0.0) slots.push_back({&d.grid.g[x.g], &x, x.notch_g()});
    if (x.notch_h() != 0.0) slots.push_back({&d.grid.h[x.h], &x, x.notch_h()});
  }
  ASSERT_GT(slots.size(), 0u);
  ASSERT_EQ(svg.notch_lines.size(), slots.size());
  const double precision = 2 * svg.tolerance;
  double shortest = 1e300;
  for (std::size_t k = 0; k < slots.size(); ++k) {
    const Slot& s = slots[k];
    const Element& line = *svg.notch_lines[k];
    const std::string what = member_name(*s.member) + " at crossing g" +
                             std::to_string(s.crossing->g) + " h" + std::to_string(s.crossing->h);
    const Vec2 a(line.number("x1"), line.number("y1")), b(line.number("x2"), line.number("y2"));
    expect_near_printed(svg, a, svg.to_svg(s.crossing->planar_point), what + " start");
    EXPECT_NEAR((b - a).norm(), std::abs(s.notch), precision) << what;
    // Along the member (y flipped in the SVG), in the direction of the sign.
    Vec2 direction = s.member->planar[1] - s.member->planar[0];
    direction = Vec2(direction.x(), -direction.y()).normalized();
    EXPECT_NEAR((b - a).dot(direction), s.notch, precision) << what;
    EXPECT_NEAR(std::abs(direction.x() * (b - a).y() - direction.y() * (b - a).x()), 0.0, precision)
        << what;
    shortest = std::min(shortest, std::abs(s.notch));
  }
  std::printf("  %zu notch slots, shortest %.3g (drawing %.4g x %.4g)\n", slots.size(), shortest,
              svg.width, svg.height);
}

TEST(PlanarSvg, ADotPerCrossingAndASquarePerAnchor) {
  const Design& d = double_vault();
  const PlanarSvg svg = read_planar(d);
  ASSERT_EQ(svg.dots.size(), d.grid.crossings.size());
  for (std::size_t k = 0; k < d.grid.crossings.size(); ++k) {
    const Crossing& x = d.grid.crossings[k];
    expect_near_printed(svg, Vec2(svg.dots[k]->number("cx"), svg.dots[k]->number("cy")),
                        svg.to_svg(x.planar_point), "crossing " + std::to_string(k));
  }
  ASSERT_EQ(svg.squares.size(), d.anchors.size());
  ASSERT_GE(d.anchors.size(), 4u);
  for (std::size_t k = 0; k < d.anchors.size(); ++k) {
    const Anchor& a = d.anchors[k];
    const Crossing& x = d.grid.crossings[a.g * d.grid.h.size() + a.h];
    const Element& square = *svg.squares[k];
    const double side = square.number("width");
    EXPECT_EQ(square.number("height"), side);
    EXPECT_NEAR(side, 1.2 * d.lamella_width, printed_precision(side));
    expect_near_printed(svg, Vec2(square.number("x") + side / 2, square.number("y") + side / 2),
                        svg.to_svg(x.planar_point), "anchor " + std::to_string(k));
  }
}

// planar_svg is a drawing to scale whose notch slots go down to a thousandth of the model:
// printed with 6 significant digits they were off by up to 7.6e-4 in length (2.7 % of a
// 2.4e-3 notch); it now prints the shortest round-trip decimal of every number.
TEST(PlanarSvg, EndpointsAndNotchSlotsAccurateTo1e6) {
  const Design& d = double_vault();
  const PlanarSvg svg = read_planar(d);
  // The translation, exactly: the code's lo = min(planar corners) - margin, hi = max + margin.
  Vec2 lo = d.planar.corners[0], hi = lo;
  for (const Vec2& c : d.planar.corners) lo = lo.cwiseMin(c), hi = hi.cwiseMax(c);
  const double margin = 0.05 * (hi - lo).maxCoeff() + 2 * d.lamella_width;
  const auto to_svg = [&](const Vec2& p) {
    return Vec2(p.x() - (lo.x() - margin), (hi.y() + margin) - p.y());
  };
  std::size_t k = 0;
  for (const auto* family : {&d.grid.g, &d.grid.h})
    for (const Member& m : *family) {
      const Element& line = *svg.member_lines.at(k++);
      EXPECT_LT((Vec2(line.number("x1"), line.number("y1")) - to_svg(m.planar[0])).norm(), 1e-6)
          << member_name(m);
      EXPECT_LT((Vec2(line.number("x2"), line.number("y2")) - to_svg(m.planar[1])).norm(), 1e-6)
          << member_name(m);
    }
  k = 0;
  for (const Crossing& x : d.grid.crossings)
    for (double notch : {x.notch_g(), x.notch_h()}) {
      if (notch == 0.0) continue;
      const Element& line = *svg.notch_lines.at(k++);
      const Vec2 a(line.number("x1"), line.number("y1")), b(line.number("x2"), line.number("y2"));
      EXPECT_NEAR((b - a).norm(), std::abs(notch), 1e-6) << "crossing g" << x.g << " h" << x.h;
    }
}

// ---------------------------------------------------------------------------------------------
// spatial_obj

struct ObjObject {
  std::string name;
  std::vector<Vec3> vertices;
  std::vector<std::vector<int>> faces, lines;  // 1-based global indices
};

std::vector<ObjObject> parse_obj(const std::string& text, std::vector<Vec3>& all_vertices) {
  std::vector<ObjObject> objects;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string kind;
    fields >> kind;
    if (kind == "o") {
      objects.emplace_back();
      fields >> objects.back().name;
      continue;
    }
    if (objects.empty()) {
      ADD_FAILURE() << "record before any object: " << line;
      continue;
    }
    if (kind == "v") {
      Vec3 p;
      fields >> p.x() >> p.y() >> p.z();
      EXPECT_FALSE(fields.fail()) << line;
      objects.back().vertices.push_back(p);
      all_vertices.push_back(p);
    } else if (kind == "f" || kind == "l") {
      std::vector<int> indices;
      int k;
      while (fields >> k) indices.push_back(k);
      (kind == "f" ? objects.back().faces : objects.back().lines).push_back(indices);
    } else {
      ADD_FAILURE() << "unexpected record: " << line;
    }
  }
  return objects;
}

TEST(SpatialObj, PatchFacesAndMemberPolylinesReadBackExactly) {
  const Design& d = double_vault();
  const TriangleMesh& mesh = d.target.patch.mesh;
  std::vector<Vec3> all;
  const std::vector<ObjObject> objects = parse_obj(spatial_obj(d), all);
  ASSERT_EQ(objects.size(), 1 + d.grid.g.size() + d.grid.h.size());
  // The patch: the same vertex positions (17 digits: exact) and faces.
  const ObjObject& patch = objects[0];
  EXPECT_EQ(patch.name, "patch");
  ASSERT_EQ(patch.vertices.size(), mesh.vertices().size());
  for (int v = 0; v < mesh.vertex_count(); ++v)
    EXPECT_EQ(patch.vertices[v], mesh.vertices()[v]) << "vertex " << v;
  ASSERT_EQ(static_cast<int>(patch.faces.size()), mesh.face_count());
  for (int f = 0; f < mesh.face_count(); ++f) {
    ASSERT_EQ(patch.faces[f].size(), 3u);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(patch.faces[f][i] - 1, mesh.faces()[f][i]) << f;
  }
  EXPECT_TRUE(patch.lines.empty());
  // Rebuilt from the file, the patch has the same area.
  std::vector<Face> faces;
  for (const auto& f : patch.faces) faces.push_back({f[0] - 1, f[1] - 1, f[2] - 1});
  EXPECT_EQ(surface_area(TriangleMesh(patch.vertices, faces)), surface_area(mesh));
  // Every member: its object, its surface polyline as vertices, one line through them in order.
  std::size_t k = 1;
  for (const auto* family : {&d.grid.g, &d.grid.h})
    for (const Member& m : *family) {
      const ObjObject& o = objects[k++];
      EXPECT_EQ(o.name, member_name(m));
      ASSERT_EQ(o.vertices.size(), m.surface.size()) << o.name;
      for (std::size_t p = 0; p < m.surface.size(); ++p)
        EXPECT_EQ(o.vertices[p], m.surface[p]) << o.name << " point " << p;
      ASSERT_EQ(o.lines.size(), 1u) << o.name;
      ASSERT_EQ(o.lines[0].size(), m.surface.size()) << o.name;
      for (std::size_t p = 0; p < m.surface.size(); ++p) {
        const int index = o.lines[0][p];
        ASSERT_GE(index, 1);
        ASSERT_LE(index, static_cast<int>(all.size()));
        EXPECT_EQ(all[index - 1], m.surface[p]) << o.name << " point " << p;
      }
      EXPECT_TRUE(o.faces.empty());
    }
}

// ---------------------------------------------------------------------------------------------
// maps_svg

TEST(MapsSvg, WellFormedWithBothCladdingCurvesAndAllMembers) {
  const Design& d = double_vault();
  const std::string text = maps_svg(d);
  const std::vector<Element> elements = parse_or_fail(text);
  ASSERT_FALSE(elements.empty());
  EXPECT_EQ(elements[0].name, "svg");
  // Layout: two square panels of side n x 4 units, n = min(R, 64), 20 units apart.
  const int R = d.maps.g.resolution(), n = std::min(R, 64);
  const double side = 4.0 * n;
  EXPECT_EQ(elements[0].number("width"), 2 * side + 60);
  EXPECT_EQ(elements[0].number("height"), side + 60);
  const std::vector<const Element*> groups = all_named(elements, "g");
  ASSERT_EQ(groups.size(), 2u);
  const std::vector<const Element*> polylines = all_named(elements, "polyline");
  ASSERT_EQ(polylines.size(), 2u);
  const std::array<const CladdingFunction*, 2> cladding{&d.cladding_g, &d.cladding_h};
  const std::array<const std::vector<Member>*, 2> members{&d.grid.g, &d.grid.h};
  const std::vector<const Element*> circles = all_named(elements, "circle");
  ASSERT_EQ(circles.size(), d.grid.g.size() + d.grid.h.size());
  std::size_t circle = 0;
  for (int f = 0; f < 2; ++f) {
    SCOPED_TRACE(f == 0 ? "family G" : "family H");
    const double ox = 20 + f * (side + 20), oy = 20;
    const std::vector<double> xy = numbers((*polylines[f])["points"]);
    ASSERT_EQ(xy.size(), 2 * cladding[f]->points.size());
    ASSERT_GE(cladding[f]->points.size(), 2u);
    for (std::size_t p = 0; p < cladding[f]->points.size(); ++p) {
      const Vec2& expected = cladding[f]->points[p];
      EXPECT_NEAR((xy[2 * p] - ox) / side, expected.x(), 2 * printed_precision(xy[2 * p]) / side);
      EXPECT_NEAR(1 - (xy[2 * p + 1] - oy) / side, expected.y(),
                  2 * printed_precision(xy[2 * p + 1]) / side);
    }
    // From (0,0) to (1,1) of the panel.
    EXPECT_NEAR(xy[0], ox, 1e-9);
    EXPECT_NEAR(xy[1], oy + side, 1e-9);
    EXPECT_NEAR(xy[xy.size() - 2], ox + side, 1e-9);
    EXPECT_NEAR(xy.back(), oy, 1e-9);
    // A dot per member at (u_start, u_end), grey for the boundary members.
    for (const Member& m : *members[f]) {
      const Element& dot = *circles[circle++];
      EXPECT_NEAR(dot.number("cx"), ox + m.u_start * side, 2 * printed_precision(ox + side));
      EXPECT_NEAR(dot.number("cy"), oy + (1 - m.u_end) * side, 2 * printed_precision(oy + side));
      EXPECT_EQ(dot["fill"], m.boundary ? "gray" : "black");
    }
  }
  // The colour cells: n x n per panel, plus the background.
  EXPECT_EQ(all_named(elements, "rect").size(), static_cast<std::size_t>(2 * n * n + 1));
}

TEST(XmlReader, RejectsMalformedDocuments) {
  std::vector<Element> e;
  EXPECT_EQ(parse_xml("<a><b x=\"1\"/></a>", e), "");
  EXPECT_NE(parse_xml("<a><b></a></b>", e), "");
  EXPECT_NE(parse_xml("<a><b>", e), "");
  EXPECT_NE(parse_xml("<a x=1/>", e), "");
  EXPECT_NE(parse_xml("<a/><b/>", e), "");
  EXPECT_NE(parse_xml("<a x=\"1\" x=\"2\"/>", e), "");
  EXPECT_NE(parse_xml("text<a/>", e), "");
}

}  // namespace
}  // namespace gridshell
