// SPDX-License-Identifier: GPL-3.0-or-later
// Views of a deployment (gridshell/simulation/deployment_export.h), parsed back: deployed_obj
// (a closed box per lamella with the lamella's cross-section, faces oriented outwards, 4
// vertices per centerline vertex and two caps) and deviation_ply (header counts, the
// `deviation` property equal to the run's deviations, colours monotone in the deviation, edges
// joining consecutive centerline vertices). Runs are built by hand (straight and curved
// lamellas with known frames), plus one from a small real simulation.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "gridshell/design/design.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/simulation/deployment_export.h"
#include "gridshell/simulation/simulation.h"
#include "support.h"

namespace gridshell {
namespace {

// ---------------------------------------------------------------------------------------------
// Hand-built runs

/// A lamella along `centerline` with material normal `normal(k)` at vertex k (made orthogonal to
/// the tangent) and width direction tangent x normal, the simulation's frame (t, m1, m2) with
/// m2 = t x m1.
SimulatedLamella lamella(Family family, int index, const std::vector<Vec3>& centerline,
                         const std::function<Vec3(int)>& normal) {
  SimulatedLamella l;
  l.family = family;
  l.index = index;
  l.centerline = centerline;
  const int n = static_cast<int>(centerline.size());
  for (int k = 0; k < n; ++k) {
    const Vec3 t =
        (centerline[std::min(k + 1, n - 1)] - centerline[std::max(k - 1, 0)]).normalized();
    Vec3 m = normal(k);
    m = (m - m.dot(t) * t).normalized();
    l.normals.push_back(m);
    l.widths.push_back(t.cross(m));
    l.deviation.push_back(0.01 * ((7 * k + 3 * index) % 11));
  }
  return l;
}

/// g0: straight along x, normal +z; h1: straight along y, normal tilted 30 degrees about the
/// tangent; g2: a quarter circle in the xy plane, normal +z; h3: a single vertex (no box; one
/// PLY vertex with no deviation recorded); h4: the quarter circle raised, its normal turning by
/// 90 degrees about the tangent (a twisted box).
DeploymentRun hand_built_run() {
  DeploymentRun run;
  run.notches = true;
  std::vector<Vec3> straight, across, arc, raised;
  for (int k = 0; k <= 5; ++k) straight.push_back(Vec3(2.0 * k, 0, 0));
  for (int k = 0; k <= 3; ++k) across.push_back(Vec3(4, -3 + 2.5 * k, 1));
  for (int k = 0; k <= 12; ++k) {
    const double a = M_PI / 2 * k / 12;
    arc.push_back(Vec3(5 * std::cos(a), 5 * std::sin(a), 2));
    raised.push_back(Vec3(5 * std::cos(a), 5 * std::sin(a), 6));
  }
  run.lamellas.push_back(lamella(Family::G, 0, straight, [](int) { return Vec3(0, 0, 1); }));
  run.lamellas.push_back(lamella(
      Family::H, 1, across, [](int) { return Vec3(std::sin(M_PI / 6), 0, std::cos(M_PI / 6)); }));
  run.lamellas.push_back(lamella(Family::G, 2, arc, [](int) { return Vec3(0, 0, 1); }));
  SimulatedLamella single;
  single.family = Family::H;
  single.index = 3;
  single.centerline = {Vec3(9, 9, 9)};
  single.normals = {Vec3(0, 0, 1)};
  single.widths = {Vec3(1, 0, 0)};
  run.lamellas.push_back(single);
  run.lamellas.push_back(lamella(Family::H, 4, raised, [&](int k) -> Vec3 {
    const double a = M_PI / 2 * k / 12;
    return Vec3(std::cos(a), std::sin(a), 0) * std::sin(a) + Vec3(0, 0, 1) * std::cos(a);
  }));
  for (const SimulatedLamella& l : run.lamellas)
    for (double d : l.deviation) run.max_deviation = std::max(run.max_deviation, d);
  return run;
}

// ---------------------------------------------------------------------------------------------
// OBJ

struct ObjBox {
  std::string name;
  std::vector<Vec3> vertices;           // this object's, in order
  std::vector<std::vector<int>> faces;  // 0-based global indices
};

struct Obj {
  std::string header;
  std::vector<Vec3> vertices;  // all, in order
  std::vector<ObjBox> boxes;
};

Obj parse_obj(const std::string& text) {
  Obj obj;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line[0] == '#') {
      obj.header += line;
      continue;
    }
    std::istringstream fields(line);
    std::string kind;
    fields >> kind;
    if (kind == "o") {
      obj.boxes.emplace_back();
      fields >> obj.boxes.back().name;
    } else if (kind == "v") {
      Vec3 p;
      fields >> p.x() >> p.y() >> p.z();
      EXPECT_FALSE(fields.fail()) << line;
      obj.vertices.push_back(p);
      if (!obj.boxes.empty()) obj.boxes.back().vertices.push_back(p);
    } else if (kind == "f") {
      std::vector<int> face;
      int k;
      while (fields >> k) face.push_back(k - 1);
      if (!obj.boxes.empty()) obj.boxes.back().faces.push_back(face);
    } else {
      ADD_FAILURE() << "unexpected record: " << line;
    }
  }
  return obj;
}

/// Signed volume enclosed by the faces (fan-triangulated): positive iff oriented outwards.
double signed_volume(const std::vector<Vec3>& vertices,
                     const std::vector<std::vector<int>>& faces) {
  double volume = 0;
  for (const auto& f : faces)
    for (std::size_t k = 1; k + 1 < f.size(); ++k)
      volume += vertices[f[0]].dot(vertices[f[k]].cross(vertices[f[k + 1]])) / 6;
  return volume;
}

/// Every directed edge once and its reverse once: a closed, consistently oriented surface.
void expect_closed_and_oriented(const std::vector<std::vector<int>>& faces,
                                const std::string& what) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& f : faces)
    for (std::size_t k = 0; k < f.size(); ++k) ++directed[{f[k], f[(k + 1) % f.size()]}];
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << what << ": edge " << edge.first << "-" << edge.second;
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u)
        << what << ": edge " << edge.first << "-" << edge.second << " is on a hole";
  }
}

/// The checks of deployed_obj for any run; `tolerance` for the printed positions (%.9g).
void expect_boxes(const DeploymentRun& run, double width, double thickness, double tolerance) {
  const Obj obj = parse_obj(deployed_obj(run, width, thickness));
  EXPECT_NE(obj.header.find(run.notches ? "with notches" : "without notches"), std::string::npos)
      << obj.header;
  std::vector<const SimulatedLamella*> drawn;
  std::size_t centerline_vertices = 0;
  for (const SimulatedLamella& l : run.lamellas)
    if (l.centerline.size() >= 2) {
      drawn.push_back(&l);
      centerline_vertices += l.centerline.size();
    }
  ASSERT_EQ(obj.boxes.size(), drawn.size());
  EXPECT_EQ(obj.vertices.size(), 4 * centerline_vertices);
  for (std::size_t b = 0; b < drawn.size(); ++b) {
    const SimulatedLamella& l = *drawn[b];
    const ObjBox& box = obj.boxes[b];
    const std::string name = (l.family == Family::G ? "g" : "h") + std::to_string(l.index);
    SCOPED_TRACE(name);
    EXPECT_EQ(box.name, name);
    const std::size_t n = l.centerline.size();
    ASSERT_EQ(box.vertices.size(), 4 * n);
    // 4 side quads per centerline edge plus two end caps, all quads.
    ASSERT_EQ(box.faces.size(), 4 * (n - 1) + 2);
    for (const auto& f : box.faces) {
      ASSERT_EQ(f.size(), 4u);
      for (int v : f) ASSERT_TRUE(v >= 0 && v < static_cast<int>(obj.vertices.size()));
    }
    // Each cross-section: a w x t rectangle centred on the centerline vertex, its sides along
    // the width direction and the material normal.
    for (std::size_t k = 0; k < n; ++k) {
      const Vec3* c = &box.vertices[4 * k];
      for (int i = 0; i < 4; ++i) {
        const double expected = i % 2 == 0 ? width : thickness;
        EXPECT_NEAR((c[i] - c[(i + 1) % 4]).norm(), expected, tolerance) << "section " << k;
      }
      // Diagonals: |w W + t N| and |w W - t N| (a rectangle when W and N are orthogonal).
      const double skew = 2 * width * thickness * l.widths[k].dot(l.normals[k]);
      EXPECT_NEAR((c[0] - c[2]).norm(), std::sqrt(width * width + thickness * thickness + skew),
                  tolerance);
      EXPECT_NEAR((c[1] - c[3]).norm(), std::sqrt(width * width + thickness * thickness - skew),
                  tolerance);
      EXPECT_LT(((c[0] + c[1] + c[2] + c[3]) / 4 - l.centerline[k]).norm(), tolerance);
      EXPECT_LT(((c[0] - c[1]) / width - l.widths[k]).norm(), 10 * tolerance / width);
      EXPECT_LT(((c[0] - c[3]) / thickness - l.normals[k]).norm(), 10 * tolerance / thickness);
    }
    // Closed, consistently oriented, outwards: positive enclosed volume, and every side face's
    // normal points away from the centerline.
    expect_closed_and_oriented(box.faces, name);
    EXPECT_GT(signed_volume(obj.vertices, box.faces), 0.0);
    for (std::size_t f = 0; f < 4 * (n - 1); ++f) {
      const auto& q = box.faces[f];
      const Vec3 centre =
          (obj.vertices[q[0]] + obj.vertices[q[1]] + obj.vertices[q[2]] + obj.vertices[q[3]]) / 4;
      const Vec3 normal =
          (obj.vertices[q[1]] - obj.vertices[q[0]]).cross(obj.vertices[q[3]] - obj.vertices[q[0]]);
      const std::size_t k = f / 4;
      const Vec3 axis = (l.centerline[k] + l.centerline[k + 1]) / 2;
      EXPECT_GT(normal.dot(centre - axis), 0.0) << "side face " << f;
    }
  }
}

double polyline_length(const std::vector<Vec3>& polyline) {
  double length = 0;
  for (std::size_t k = 1; k < polyline.size(); ++k)
    length += (polyline[k] - polyline[k - 1]).norm();
  return length;
}

TEST(DeployedObj, HandBuiltRunGivesClosedOutwardBoxesOfTheCrossSection) {
  const DeploymentRun run = hand_built_run();
  expect_boxes(run, 0.8, 0.08, 1e-7);
  // Volumes: exactly w t L for the straight lamellas. The untwisted arc's inner sections lie in
  // radial planes (the vertex tangent is the chord through its neighbours), so each of its 12
  // segments is a wedge of t x (1/2) sin(7.5 deg) (r_out^2 - r_in^2) = t w R sin(7.5 deg); its
  // end sections, perpendicular to the end chords, change that by ~2e-4.
  const Obj obj = parse_obj(deployed_obj(run, 0.8, 0.08));
  ASSERT_EQ(obj.boxes.size(), 4u);
  EXPECT_EQ(obj.boxes[3].name, "h4");  // the single-vertex h3 has no box
  EXPECT_NEAR(signed_volume(obj.vertices, obj.boxes[0].faces), 0.8 * 0.08 * 10, 1e-7);
  EXPECT_NEAR(signed_volume(obj.vertices, obj.boxes[1].faces), 0.8 * 0.08 * 7.5, 1e-7);
  const double wedges = 12 * 0.08 * 0.8 * 5 * std::sin(M_PI / 24);
  EXPECT_NEAR(signed_volume(obj.vertices, obj.boxes[2].faces), wedges, 5e-4 * wedges);
  // Other cross-sections.
  expect_boxes(run, 2.0, 0.5, 1e-7);
  DeploymentRun fixed = run;
  fixed.notches = false;
  expect_boxes(fixed, 1.0, 0.1, 1e-7);
}

// ---------------------------------------------------------------------------------------------
// PLY

struct Ply {
  std::map<std::string, int> counts;                      // element -> count
  std::map<std::string, std::vector<std::string>> props;  // element -> property names
  std::vector<std::vector<double>> vertices;              // x y z r g b deviation
  std::vector<std::array<int, 2>> edges;
};

Ply parse_ply(const std::string& text) {
  Ply ply;
  std::istringstream in(text);
  std::string line, element;
  std::getline(in, line);
  EXPECT_EQ(line, "ply");
  std::getline(in, line);
  EXPECT_EQ(line, "format ascii 1.0");
  std::vector<std::string> order;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream fields(line);
    std::string kind;
    fields >> kind;
    if (kind == "comment") continue;
    if (kind == "element") {
      int count = -1;
      fields >> element >> count;
      ply.counts[element] = count;
      order.push_back(element);
    } else if (kind == "property") {
      std::string type, name;
      fields >> type >> name;
      ply.props[element].push_back(name);
    } else {
      ADD_FAILURE() << "unexpected header line: " << line;
    }
  }
  EXPECT_EQ(line, "end_header");
  EXPECT_EQ(order, (std::vector<std::string>{"vertex", "edge"}));
  for (int k = 0; k < ply.counts["vertex"]; ++k) {
    std::getline(in, line);
    std::istringstream fields(line);
    std::vector<double> values;
    double x;
    while (fields >> x) values.push_back(x);
    EXPECT_EQ(values.size(), 7u) << line;
    ply.vertices.push_back(values);
  }
  for (int k = 0; k < ply.counts["edge"]; ++k) {
    std::getline(in, line);
    std::istringstream fields(line);
    std::array<int, 2> e{-1, -1};
    fields >> e[0] >> e[1];
    EXPECT_FALSE(fields.fail()) << line;
    ply.edges.push_back(e);
  }
  std::string rest;
  while (std::getline(in, rest)) EXPECT_TRUE(rest.empty()) << "trailing data: " << rest;
  return ply;
}

void expect_ply(const DeploymentRun& run, double max_deviation) {
  const Ply ply = parse_ply(deviation_ply(run, max_deviation));
  std::size_t vertices = 0, edges = 0;
  for (const SimulatedLamella& l : run.lamellas) {
    vertices += l.centerline.size();
    edges += l.centerline.size() > 0 ? l.centerline.size() - 1 : 0;
  }
  EXPECT_EQ(ply.counts.at("vertex"), static_cast<int>(vertices));
  EXPECT_EQ(ply.counts.at("edge"), static_cast<int>(edges));
  EXPECT_EQ(ply.props.at("vertex"),
            (std::vector<std::string>{"x", "y", "z", "red", "green", "blue", "deviation"}));
  EXPECT_EQ(ply.props.at("edge"), (std::vector<std::string>{"vertex1", "vertex2"}));
  ASSERT_EQ(ply.vertices.size(), vertices);
  // Positions and deviations, vertex by vertex in lamella order; edges between consecutive
  // centerline vertices of one lamella.
  const double top = max_deviation > 0 ? max_deviation : run.max_deviation;
  std::size_t v = 0, e = 0;
  for (const SimulatedLamella& l : run.lamellas) {
    for (std::size_t k = 0; k < l.centerline.size(); ++k, ++v) {
      const std::vector<double>& row = ply.vertices[v];
      for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(row[i], l.centerline[k][i], 1e-8 * std::max(1.0, std::abs(l.centerline[k][i])));
      const double d = k < l.deviation.size() ? l.deviation[k] : 0.0;
      EXPECT_NEAR(row[6], d, 1e-8 * std::max(d, 1e-30)) << "vertex " << v;
      // Colour: blue at 0, green at half the top, red at (and beyond) the top.
      const double f = std::clamp(d / top, 0.0, 1.0);
      EXPECT_NEAR(row[3], 255 * std::clamp(2 * f - 1, 0.0, 1.0), 0.5 + 1e-9) << "red " << v;
      EXPECT_NEAR(row[5], 255 * std::clamp(1 - 2 * f, 0.0, 1.0), 0.5 + 1e-9) << "blue " << v;
      for (int i = 3; i < 6; ++i) {
        EXPECT_EQ(row[i], std::round(row[i]));
        EXPECT_GE(row[i], 0);
        EXPECT_LE(row[i], 255);
      }
    }
    for (std::size_t k = 0; k + 1 < l.centerline.size(); ++k, ++e) {
      ASSERT_LT(e, ply.edges.size());
      EXPECT_EQ(ply.edges[e][0], static_cast<int>(v - l.centerline.size() + k));
      EXPECT_EQ(ply.edges[e][1], static_cast<int>(v - l.centerline.size() + k + 1));
    }
  }
  EXPECT_EQ(e, ply.edges.size());
  // Monotone colours: sorted by deviation, red never falls and blue never rises.
  std::vector<std::vector<double>> sorted = ply.vertices;
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a[6] < b[6]; });
  for (std::size_t k = 1; k < sorted.size(); ++k) {
    EXPECT_GE(sorted[k][3], sorted[k - 1][3]) << "red falls";
    EXPECT_LE(sorted[k][5], sorted[k - 1][5]) << "blue rises";
  }
}

TEST(DeviationPly, HandBuiltRunReadsBack) {
  const DeploymentRun run = hand_built_run();
  expect_ply(run, 0);
  expect_ply(run, 2 * run.max_deviation);  // an explicit scale: nothing reaches red
  const Ply scaled = parse_ply(deviation_ply(run, 2 * run.max_deviation));
  for (const auto& row : scaled.vertices) EXPECT_EQ(row[3], 0.0);
  // The run's extremes get pure blue and pure red.
  const Ply own = parse_ply(deviation_ply(run));
  bool blue = false, red = false;
  for (const auto& row : own.vertices) {
    blue |= row[6] == 0.0 && row[3] == 0 && row[4] == 0 && row[5] == 255;
    red |= row[6] == run.max_deviation && row[3] == 255 && row[4] == 0 && row[5] == 0;
  }
  EXPECT_TRUE(blue);
  EXPECT_TRUE(red);
}

// ---------------------------------------------------------------------------------------------
// A real (small) simulation

struct Simulated {
  Design design;
  DeploymentRun run;
};

const Simulated& small_simulation() {
  static const std::unique_ptr<const Simulated> simulated = [] {
    const ExampleSurface example = make_example("sphere", 0.5);
    DesignOptions options;
    options.maps.resolution = 32;
    options.members_g = options.members_h = 3;
    auto out = std::make_unique<Simulated>();
    out->design = make_design(example.mesh, CornerSpec::at_vertices(example.corners), options);
    SimulationOptions simulation;
    simulation.edges_per_interval = 2;
    const auto start = std::chrono::steady_clock::now();
    out->run =
        simulate_deployment(out->design.grid, out->design.anchors, out->design.target.patch.mesh,
                            out->design.lamella_width, out->design.lamella_thickness, simulation);
    std::printf("  simulation: %zu lamellas, %d rod vertices, %.2f s, %s\n",
                out->run.lamellas.size(), out->run.grid_vertices,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                out->run.converged ? "converged" : "not converged");
    return out;
  }();
  return *simulated;
}

TEST(DeploymentExport, RealSimulationBoxesAndDeviations) {
  const Simulated& s = small_simulation();
  const DeploymentRun& run = s.run;
  ASSERT_EQ(run.lamellas.size(), s.design.grid.g.size() + s.design.grid.h.size());
  const double size = bounding_box_size(s.design.target.patch.mesh).norm();
  // The simulation's frames are orthonormal with widths = tangent x normal (what deployed_obj
  // orients its faces by).
  for (const SimulatedLamella& l : run.lamellas)
    for (std::size_t k = 0; k + 1 < l.centerline.size(); ++k) {
      const Vec3 t = (l.centerline[k + 1] - l.centerline[k]).normalized();
      EXPECT_NEAR(l.normals[k].norm(), 1.0, 1e-9);
      EXPECT_NEAR(l.widths[k].norm(), 1.0, 1e-9);
      // Vertex frames are the two edges' frames averaged and made orthonormal again.
      EXPECT_NEAR(l.normals[k].dot(l.widths[k]), 0.0, 1e-12);
      EXPECT_GT(t.cross(l.normals[k]).dot(l.widths[k]), 0.9);
    }
  expect_boxes(run, s.design.lamella_width, s.design.lamella_thickness, 1e-8 * size);
  // Slowly turning frames: each box encloses about w t L.
  const Obj obj = parse_obj(deployed_obj(run, s.design.lamella_width, s.design.lamella_thickness));
  ASSERT_EQ(obj.boxes.size(), run.lamellas.size());
  for (std::size_t b = 0; b < run.lamellas.size(); ++b) {
    const double expected = s.design.lamella_width * s.design.lamella_thickness *
                            polyline_length(run.lamellas[b].centerline);
    EXPECT_NEAR(signed_volume(obj.vertices, obj.boxes[b].faces), expected, 0.02 * expected)
        << obj.boxes[b].name;
  }
  expect_ply(run, 0);
}

}  // namespace
}  // namespace gridshell
