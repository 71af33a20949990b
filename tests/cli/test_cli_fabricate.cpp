// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell fabricate` end to end: the cut sheets read back by an independent DXF reader
// (Debian's python3-ezdxf, tests/fabrication/read_sheets.py) and checked against design.json:
// every hole and slot at its arc length, slot lengths, kerf offsets, no overlaps, inside the
// sheet, SVG = DXF; kit.json, supports.csv, bom.csv; bad designs and options.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "support.h"

namespace gridshell {
namespace {

using nlohmann::json;
using testing::read_text;
using testing::run_cli;
using testing::temp_dir;

constexpr double kMmPerUnit = 10;  // --unit cm
constexpr double kKerf = 0.15, kHole = 3.2, kSpacing = 3, kMinSlot = 0.1;

/// design.json of double-vault, made once.
const std::string& run_dir() {
  static const std::string dir = [] {
    const std::string out = temp_dir() + "/dv";
    const auto r = run_cli("design example:double-vault --quiet --out '" + out + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return out;
  }();
  return dir;
}

json read_json(const std::string& path) { return json::parse(read_text(path)); }

/// The kit of double-vault with the default options, and its sheets as read_sheets.py reads them.
struct KitFiles {
  std::string dir;
  json kit, sheets;
};
const KitFiles& kit_files() {
  static const KitFiles files = [] {
    KitFiles f;
    f.dir = temp_dir() + "/kit";
    const auto r = run_cli("fabricate '" + run_dir() + "/design.json' --unit cm --quiet --out '" +
                           f.dir + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    f.kit = read_json(f.dir + "/kit.json");
    const std::string listing = f.dir + "/sheets.json";
    const std::string command = "/usr/bin/python3 '" GRIDSHELL_SOURCE_DIR
                                "/tests/fabrication/read_sheets.py' '" +
                                f.dir + "' > '" + listing + "'";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    f.sheets = read_json(listing);
    return f;
  }();
  return files;
}

struct P {
  double x = 0, y = 0;
};
P operator-(P a, P b) { return {a.x - b.x, a.y - b.y}; }
double dot(P a, P b) { return a.x * b.x + a.y * b.y; }
double norm(P a) { return std::hypot(a.x, a.y); }
P point(const json& p) { return {p[0].get<double>(), p[1].get<double>()}; }

/// A part outline read from a DXF: its corners and frame.
struct Outline {
  std::vector<P> corners;
  P origin, axis, across;  // origin: a corner at one end; axis: along the long side
  double length = 0, width = 0;
  bool contains(P p) const {
    const double a = dot(p - origin, axis), b = dot(p - origin, across);
    return a >= -1e-9 && a <= length + 1e-9 && b >= -1e-9 && b <= width + 1e-9;
  }
};

Outline outline_of(const json& polyline) {
  Outline o;
  for (const json& p : polyline["points"]) o.corners.push_back(point(p));
  const P e1 = o.corners[1] - o.corners[0], e3 = o.corners[3] - o.corners[0];
  const bool first_long = norm(e1) >= norm(e3);
  const P along = first_long ? e1 : e3, side = first_long ? e3 : e1;
  o.origin = o.corners[0];
  o.length = norm(along);
  o.width = norm(side);
  o.axis = {along.x / o.length, along.y / o.length};
  o.across = {side.x / o.width, side.y / o.width};
  return o;
}

struct Expected {
  std::string kind;
  double x0 = 0, x1 = 0;  // centres along the part from its nominal left end, mm
};

/// What design.json says the part of lamella `name` must have (kit rule: a slot where the
/// sliding range is at least --min-slot), positions from the nominal left end.
std::vector<Expected> expected_features(const json& design, const std::string& name,
                                        double allowance) {
  const std::string family = name.substr(0, 1);
  const int index = std::stoi(name.substr(1));
  std::vector<Expected> out;
  double lo = 1e300;
  for (const json& c : design["crossings"]) {
    if (c[family].get<int>() != index) continue;
    const double s_bar = c["s_bar_" + family].get<double>() * kMmPerUnit;
    const double notch = c["notch_" + family].get<double>() * kMmPerUnit;
    Expected e;
    e.kind = std::abs(notch) >= kMinSlot ? "slot" : "hole";
    e.x0 = e.kind == "slot" ? std::min(s_bar, s_bar + notch) : s_bar;
    e.x1 = e.kind == "slot" ? std::max(s_bar, s_bar + notch) : s_bar;
    lo = std::min(lo, e.x0);
    out.push_back(e);
  }
  for (Expected& e : out) {
    e.x0 += allowance - lo;
    e.x1 += allowance - lo;
  }
  std::sort(out.begin(), out.end(),
            [](const Expected& a, const Expected& b) { return a.x0 < b.x0; });
  return out;
}

TEST(Fabricate, SheetsReadBackByEzdxfHoldEveryCrossingAtItsArcLength) {
  const KitFiles& f = kit_files();
  const json design = read_json(run_dir() + "/design.json");
  const double width = design["options"]["lamella_width"].get<double>() * kMmPerUnit;
  const double allowance = width;  // default: the lamella width
  const double text_height = std::clamp(0.4 * width, 1.0, 8.0);
  std::map<std::string, double> planar_length;
  for (const json& m : design["members"])
    planar_length[m["family"].get<std::string>() + std::to_string(m["index"].get<int>())] =
        m["planar_length"].get<double>() * kMmPerUnit;

  int holes = 0, slots = 0, parts = 0;
  double worst_position = 0, worst_slot = 0;
  std::map<std::string, int> seen;
  for (const json& sheet : f.sheets["sheets"]) {
    const json& dxf = sheet["dxf"];
    EXPECT_EQ(dxf["units"].get<int>(), 4) << "$INSUNITS = mm";
    EXPECT_GE(dxf["version"].get<std::string>(), std::string("AC1009"));
    EXPECT_TRUE(dxf["other"].empty()) << dxf["other"].dump();
    const auto& layers = dxf["layers"];
    EXPECT_NE(std::find(layers.begin(), layers.end(), "CUT"), layers.end());
    EXPECT_NE(std::find(layers.begin(), layers.end(), "ENGRAVE"), layers.end());
    std::vector<Outline> outlines;
    std::vector<json> slot_lines;
    for (const json& p : dxf["polylines"]) {
      if (p["layer"] != "CUT") continue;
      ASSERT_TRUE(p["closed"].get<bool>()) << "every cut is a closed path";
      bool bulged = false;
      for (const json& q : p["points"]) bulged = bulged || q[2].get<double>() != 0;
      if (bulged)
        slot_lines.push_back(p);
      else
        outlines.push_back(outline_of(p));
    }
    for (const json& c : dxf["circles"]) EXPECT_EQ(c["layer"], "CUT");
    const double W = f.kit["options"]["sheet_width"].get<double>();
    const double H = f.kit["options"]["sheet_height"].get<double>();
    for (size_t a = 0; a < outlines.size(); ++a) {
      const Outline& o = outlines[a];
      // Inside the sheet, and apart from every other part by the spacing.
      double minx = 1e300, maxx = -1e300, miny = 1e300, maxy = -1e300;
      for (const P& c : o.corners) {
        minx = std::min(minx, c.x), maxx = std::max(maxx, c.x);
        miny = std::min(miny, c.y), maxy = std::max(maxy, c.y);
      }
      EXPECT_GE(minx, kSpacing - 1e-6);
      EXPECT_GE(miny, kSpacing - 1e-6);
      EXPECT_LE(maxx, W - kSpacing + 1e-6);
      EXPECT_LE(maxy, H - kSpacing + 1e-6);
      for (size_t b = a + 1; b < outlines.size(); ++b) {
        double bx0 = 1e300, bx1 = -1e300, by0 = 1e300, by1 = -1e300;
        for (const P& c : outlines[b].corners) {
          bx0 = std::min(bx0, c.x), bx1 = std::max(bx1, c.x);
          by0 = std::min(by0, c.y), by1 = std::max(by1, c.y);
        }
        const double gap = std::max({bx0 - maxx, minx - bx1, by0 - maxy, miny - by1});
        EXPECT_GE(gap, kSpacing - 1e-6) << "parts " << a << " and " << b << " of " << sheet["name"];
      }
      // Kerf: the outline is the nominal rectangle grown by half the kerf on every side.
      EXPECT_NEAR(o.width, width + kKerf, 1e-6);
      // The part's name: the tallest engraved text inside it.
      std::string name;
      for (const json& t : dxf["texts"])
        if (std::abs(t["height"].get<double>() - text_height) < 1e-9 &&
            o.contains({t["x"].get<double>(), t["y"].get<double>()}))
          name = t["text"];
      ASSERT_FALSE(name.empty()) << "no name inside an outline of " << sheet["name"];
      ++seen[name];
      ++parts;
      EXPECT_NEAR(o.length, planar_length[name] + 2 * allowance + kKerf, 0.01) << name;
      // Features inside the outline, as (kind, centre positions from the nominal end).
      struct Measured {
        std::string kind;
        P c0, c1;
        double radius;
      };
      std::vector<Measured> measured;
      for (const json& c : dxf["circles"]) {
        const P centre{c["x"].get<double>(), c["y"].get<double>()};
        if (!o.contains(centre)) continue;
        measured.push_back({"hole", centre, centre, c["r"].get<double>()});
        EXPECT_NEAR(c["r"].get<double>(), 0.5 * (kHole - kKerf), 1e-9) << "hole shrunk by kerf/2";
      }
      for (const json& s : slot_lines) {
        const P p0 = point(s["points"][0]), p1 = point(s["points"][1]), p2 = point(s["points"][2]),
                p3 = point(s["points"][3]);
        if (!o.contains(p0)) continue;
        ASSERT_EQ(s["points"].size(), 4u);
        // Arcs (bulge 1: half circles) from p1 to p2 and from p3 to p0: their centres.
        EXPECT_NEAR(s["points"][1][2].get<double>(), 1, 1e-12);
        EXPECT_NEAR(s["points"][3][2].get<double>(), 1, 1e-12);
        const P c1{0.5 * (p1.x + p2.x), 0.5 * (p1.y + p2.y)};
        const P c0{0.5 * (p3.x + p0.x), 0.5 * (p3.y + p0.y)};
        const double radius = 0.5 * norm(p2 - p1);
        EXPECT_NEAR(radius, 0.5 * (kHole - kKerf), 1e-9) << "slot shrunk by kerf/2";
        measured.push_back({"slot", c0, c1, radius});
      }
      // Positions along the part from either end; the design decides which end is arc length 0.
      const std::vector<Expected> expected = expected_features(design, name, allowance);
      ASSERT_EQ(measured.size(), expected.size()) << name;
      double best = 1e300;
      std::vector<std::pair<double, double>> best_positions;
      for (int end = 0; end < 2; ++end) {
        std::vector<std::pair<double, double>> positions;
        for (const Measured& m : measured) {
          double a = dot(m.c0 - o.origin, o.axis) - 0.5 * kKerf;
          double b = dot(m.c1 - o.origin, o.axis) - 0.5 * kKerf;
          if (end == 1) {
            a = o.length - kKerf - a;
            b = o.length - kKerf - b;
          }
          positions.push_back({std::min(a, b), std::max(a, b)});
        }
        std::vector<size_t> order(measured.size());
        std::iota(order.begin(), order.end(), 0);
        std::sort(order.begin(), order.end(),
                  [&](size_t i, size_t j) { return positions[i].first < positions[j].first; });
        double error = 0;
        std::vector<std::pair<double, double>> sorted;
        for (size_t k = 0; k < order.size(); ++k) {
          sorted.push_back(positions[order[k]]);
          if (measured[order[k]].kind != expected[k].kind) error += 1e6;
          error = std::max(error, std::abs(sorted[k].first - expected[k].x0));
          error = std::max(error, std::abs(sorted[k].second - expected[k].x1));
        }
        if (error < best) {
          best = error;
          best_positions = sorted;
        }
      }
      EXPECT_LE(best, 0.01) << name << ": a hole or slot is off its arc length (mm)";
      worst_position = std::max(worst_position, best);
      for (size_t k = 0; k < expected.size(); ++k) {
        if (expected[k].kind == "slot") {
          ++slots;
          // Cut slot length (centre distance + cut diameter) + kerf = sliding range + hole.
          const double cut = best_positions[k].second - best_positions[k].first + (kHole - kKerf);
          const double range = expected[k].x1 - expected[k].x0;
          EXPECT_NEAR(cut + kKerf, range + kHole, 0.01) << name;
          worst_slot = std::max(worst_slot, std::abs(cut + kKerf - range - kHole));
        } else {
          ++holes;
        }
      }
    }
  }
  EXPECT_EQ(parts, static_cast<int>(design["members"].size()));
  for (const auto& [name, count] : seen) EXPECT_EQ(count, 1) << name;
  EXPECT_EQ(holes + slots, 2 * static_cast<int>(design["crossings"].size()));
  EXPECT_EQ(holes, f.kit["holes"].get<int>());
  EXPECT_EQ(slots, f.kit["slots"].get<int>());
  EXPECT_GT(slots, 0);
  std::printf("worst hole/slot position error %.2e mm, worst slot length error %.2e mm\n",
              worst_position, worst_slot);
}

TEST(Fabricate, SvgAndDxfDescribeTheSameGeometry) {
  const KitFiles& f = kit_files();
  for (const json& sheet : f.sheets["sheets"]) {
    const json &dxf = sheet["dxf"], &svg = sheet["svg"];
    EXPECT_EQ(svg["units"], "mm");
    EXPECT_EQ(svg["width"].get<double>(), f.kit["options"]["sheet_width"].get<double>());
    EXPECT_EQ(svg["height"].get<double>(), f.kit["options"]["sheet_height"].get<double>());
    // SVG groups by layer (engrave first, then cut); compare layer by layer in order.
    for (const char* layer : {"CUT", "ENGRAVE"}) {
      const char* colour = std::string(layer) == "CUT" ? "#ff0000" : "#0000ff";
      std::vector<json> a, b;
      for (const json& p : dxf["polylines"])
        if (p["layer"] == layer) a.push_back(p);
      for (const json& p : svg["polylines"])
        if (p["layer"] == layer) b.push_back(p);
      ASSERT_EQ(a.size(), b.size()) << layer;
      for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(b[i]["colour"], colour);
        EXPECT_EQ(a[i]["closed"], b[i]["closed"]);
        ASSERT_EQ(a[i]["points"].size(), b[i]["points"].size());
        for (size_t k = 0; k < a[i]["points"].size(); ++k)
          for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(a[i]["points"][k][c].get<double>(), b[i]["points"][k][c].get<double>(),
                        1e-6);
      }
      std::vector<json> ca, cb;
      for (const json& c : dxf["circles"])
        if (c["layer"] == layer) ca.push_back(c);
      for (const json& c : svg["circles"])
        if (c["layer"] == layer) cb.push_back(c);
      ASSERT_EQ(ca.size(), cb.size());
      for (size_t i = 0; i < ca.size(); ++i)
        for (const char* k : {"x", "y", "r"})
          EXPECT_NEAR(ca[i][k].get<double>(), cb[i][k].get<double>(), 1e-6);
      std::vector<json> ta, tb;
      for (const json& t : dxf["texts"])
        if (t["layer"] == layer) ta.push_back(t);
      for (const json& t : svg["texts"])
        if (t["layer"] == layer) tb.push_back(t);
      ASSERT_EQ(ta.size(), tb.size());
      for (size_t i = 0; i < ta.size(); ++i) {
        EXPECT_EQ(ta[i]["text"], tb[i]["text"]);
        for (const char* k : {"x", "y", "height"})
          EXPECT_NEAR(ta[i][k].get<double>(), tb[i][k].get<double>(), 1e-6);
      }
    }
  }
}

TEST(Fabricate, KitSupportsAndBillOfMaterials) {
  const KitFiles& f = kit_files();
  const json design = read_json(run_dir() + "/design.json");
  const json& kit = f.kit;
  // Nesting: at least as good as one lamella per row.
  EXPECT_GE(kit["utilisation"].get<double>(), kit["baseline_utilisation"].get<double>());
  EXPECT_LE(kit["sheets"].size(), kit["baseline_sheets"].get<size_t>());
  EXPECT_LT(kit["rows"].get<int>(), static_cast<int>(kit["parts"].size()));
  // kit.json is enough to rebuild the holes: part placement + feature x = the DXF (checked
  // above through the design); here its arc lengths against design.json.
  for (const json& part : kit["parts"]) {
    const std::string family = part["family"];
    for (const json& feature : part["features"]) {
      const json& c = design["crossings"][feature["crossing"].get<int>()];
      EXPECT_EQ(c[family].get<int>(), part["index"].get<int>());
      EXPECT_DOUBLE_EQ(feature["s_bar"].get<double>(), c["s_bar_" + family].get<double>());
      const double x = feature["x"][0].get<double>();
      const double s = feature["kind"] == "slot"
                           ? std::min(feature["s"].get<double>(), feature["s_bar"].get<double>())
                           : feature["s_bar"].get<double>();
      EXPECT_NEAR(x, s * kMmPerUnit - part["start"].get<double>(), 1e-9);
    }
  }
  // supports.csv: every anchor, heights above the lowest boundary point, in cm.
  std::istringstream csv(read_text(f.dir + "/supports.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "id,kind,g,h,side,x_cm,y_cm,z_cm,nx,ny,nz,tilt_deg,height_cm");
  double ground = 1e300;
  for (const json& m : design["members"])
    if (m["boundary"].get<bool>())
      for (const json& p : m["surface"]) ground = std::min(ground, p[2].get<double>());
  size_t rows = 0;
  while (std::getline(csv, line)) {
    const json& anchor = design["anchors"][rows];
    std::vector<std::string> cells;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    ASSERT_EQ(cells.size(), 13u) << line;
    EXPECT_EQ(cells[0], "A" + std::to_string(rows + 1));
    EXPECT_EQ(std::stoi(cells[2]), anchor["g"].get<int>());
    EXPECT_NEAR(std::stod(cells[7]), anchor["position"][2].get<double>(), 1e-5);
    EXPECT_NEAR(std::stod(cells[12]), anchor["position"][2].get<double>() - ground, 1e-5);
    EXPECT_GE(std::stod(cells[12]), -1e-9);
    ++rows;
  }
  EXPECT_EQ(rows, design["anchors"].size());
  const std::string bom = read_text(f.dir + "/bom.csv");
  EXPECT_NE(bom.find("bolts," + std::to_string(design["crossings"].size()) + ",pcs"),
            std::string::npos)
      << bom;
  EXPECT_NE(bom.find("sheets," + std::to_string(kit["sheets"].size()) + ",pcs"), std::string::npos);
  const std::string assembly = read_text(f.dir + "/assembly.svg");
  EXPECT_NE(assembly.find("data-lamella=\"g0\""), std::string::npos);
  EXPECT_NE(assembly.find("Deployment"), std::string::npos);
  EXPECT_NE(assembly.find(">A" + std::to_string(design["anchors"].size()) + "<"),
            std::string::npos);
}

TEST(Fabricate, KerfAndOptionsChangeTheCutAsAsked) {
  const std::string dir = temp_dir() + "/kerf";
  const auto r = run_cli("fabricate '" + run_dir() +
                         "/design.json' --unit cm --kerf 0.4 --hole-diameter 4 --sheet "
                         "600x1300 --quiet --out '" +
                         dir + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json kit = read_json(dir + "/kit.json");
  EXPECT_DOUBLE_EQ(kit["options"]["kerf"].get<double>(), 0.4);
  for (const json& part : kit["parts"]) EXPECT_EQ(part["rotation"].get<double>(), 90);
  // A circle of the first sheet: radius (4 - 0.4) / 2.
  const std::string dxf = read_text(dir + "/sheets/sheet-01.dxf");
  EXPECT_NE(dxf.find("CIRCLE"), std::string::npos);
  EXPECT_NE(dxf.find("\n 40\n1.8\n"), std::string::npos);
}

TEST(Fabricate, BadDesignsAndOptionsNameTheField) {
  const json design = read_json(run_dir() + "/design.json");
  const std::string dir = temp_dir();
  const auto write = [&](const std::string& name, const json& j) {
    return testing::write_text(dir, name, j.dump());
  };
  json no_members = design;
  no_members.erase("members");
  json bad_notch = design;
  for (json& c : bad_notch["crossings"])
    if (!c["on_boundary"].get<bool>()) {
      c["notch_g"] = -std::abs(c["notch_g"].get<double>()) - 1;
      break;
    }
  json zero_width = design;
  zero_width["options"]["lamella_width"] = 0;
  json missing_crossing = design;
  missing_crossing["crossings"].erase(missing_crossing["crossings"].begin() + 7);
  const std::string good = run_dir() + "/design.json";
  struct Case {
    std::string arguments, expect;
  } cases[] = {
      {"'" + write("a.json", no_members) + "' --unit cm", "(members)"},
      {"'" + write("b.json", bad_notch) + "' --unit cm", ".notch_g): notch length"},
      {"'" + write("c.json", zero_width) + "' --unit cm", "(options.lamella_width)"},
      {"'" + write("d.json", missing_crossing) + "' --unit cm", "(crossings): expected one"},
      {"'" + good + "'", "--unit: the design's length unit is needed"},
      {"'" + good + "' --unit parsec", "--unit: expected mm, cm"},
      {"'" + good + "' --unit cm --sheet 1000x600", "--sheet: lamella h7 is 1061.0 mm long"},
      {"'" + good + "' --unit cm --sheet 12x", "--sheet: expected WIDTHxHEIGHT"},
      {"'" + good + "' --unit cm --kerf -1", "--kerf: must be in [0, 10) mm, got -1"},
      {"'" + good + "' --unit cm --hole-diameter 12", "--hole-diameter: 12.0 mm does not fit"},
      {"'" + dir + "/none.json' --unit cm", "cannot open the design file"},
  };
  for (const Case& c : cases) {
    const auto r = run_cli("fabricate " + c.arguments + " --quiet --out '" + dir + "/out'");
    EXPECT_EQ(r.exit_code, 2) << c.arguments << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.arguments << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/kit.json"));
}

}  // namespace
}  // namespace gridshell
