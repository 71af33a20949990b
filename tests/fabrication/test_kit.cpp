// SPDX-License-Identifier: GPL-3.0-or-later
// The fabrication kit on small hand-made grids: parts and features from the crossings, the
// hole/slot rule, nesting invariants (no overlap with kerf and spacing, inside the sheet, never
// worse than one lamella per row), rotation onto tall sheets, errors; the lamella boxes and the
// point-cloud checks of the scan comparison.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

#include "gridshell/fabrication/compare.h"
#include "gridshell/fabrication/kit.h"
#include "gridshell/fabrication/kit_export.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/surface_point.h"
#include "support.h"

namespace gridshell {
namespace {

/// A flat grid: g members along y at x = 0, dx, ..., h members along x; lengths in design units.
/// Inner crossings get notch `notch` along g (s = s̄ + notch) and none along h.
Design flat_grid(int ng, int nh, double dx, double dy, double notch) {
  Design d;
  d.lamella_width = 1;
  d.lamella_thickness = 0.1;
  const double lx = (ng - 1) * dx, ly = (nh - 1) * dy;
  for (int i = 0; i < ng; ++i) {
    Member m;
    m.family = Family::G;
    m.index = i;
    m.boundary = i == 0 || i == ng - 1;
    m.planar = {Vec2(i * dx, 0), Vec2(i * dx, ly)};
    m.surface = {Vec3(i * dx, 0, 0), Vec3(i * dx, ly, 0)};
    m.length = m.planar_length = ly;
    d.grid.g.push_back(m);
  }
  for (int j = 0; j < nh; ++j) {
    Member m;
    m.family = Family::H;
    m.index = j;
    m.boundary = j == 0 || j == nh - 1;
    m.planar = {Vec2(0, j * dy), Vec2(lx, j * dy)};
    m.surface = {Vec3(0, j * dy, 0), Vec3(lx, j * dy, 0)};
    m.length = m.planar_length = lx;
    d.grid.h.push_back(m);
  }
  for (int i = 0; i < ng; ++i)
    for (int j = 0; j < nh; ++j) {
      Crossing c;
      c.g = i;
      c.h = j;
      c.planar_point = Vec2(i * dx, j * dy);
      c.surface_point = Vec3(i * dx, j * dy, 0);
      c.on_boundary = d.grid.g[i].boundary || d.grid.h[j].boundary;
      c.s_bar_g = j * dy;
      c.s_g = c.s_bar_g + (c.on_boundary ? 0 : notch);
      c.s_bar_h = c.s_h = i * dx;
      d.grid.crossings.push_back(c);
    }
  for (int k = 0; k < 4; ++k) {
    Anchor a;
    a.g = k == 0 || k == 3 ? 0 : ng - 1;
    a.h = k < 2 ? 0 : nh - 1;
    a.corner = true;
    a.side = k;
    a.position = d.grid.crossings[a.g * nh + a.h].surface_point;
    a.normal = Vec3::UnitZ();
    d.anchors.push_back(a);
  }
  return d;
}

struct Box {
  double x0, y0, x1, y1;
};
Box footprint(const Part& p, double kerf) {
  const Vec2 a = p.to_sheet(Vec2(-0.5 * kerf, -0.5 * p.width - 0.5 * kerf));
  const Vec2 b = p.to_sheet(Vec2(p.length + 0.5 * kerf, 0.5 * p.width + 0.5 * kerf));
  return {std::min(a.x(), b.x()), std::min(a.y(), b.y()), std::max(a.x(), b.x()),
          std::max(a.y(), b.y())};
}

void expect_nested(const Kit& kit) {
  const FabricationOptions& o = kit.options;
  for (size_t a = 0; a < kit.parts.size(); ++a) {
    const Box A = footprint(kit.parts[a], o.kerf);
    EXPECT_GE(A.x0, o.spacing - 1e-9);
    EXPECT_GE(A.y0, o.spacing - 1e-9);
    EXPECT_LE(A.x1, o.sheet_width - o.spacing + 1e-9);
    EXPECT_LE(A.y1, o.sheet_height - o.spacing + 1e-9);
    for (size_t b = a + 1; b < kit.parts.size(); ++b) {
      if (kit.parts[a].sheet != kit.parts[b].sheet) continue;
      const Box B = footprint(kit.parts[b], o.kerf);
      const double gap = std::max({B.x0 - A.x1, A.x0 - B.x1, B.y0 - A.y1, A.y0 - B.y1});
      EXPECT_GE(gap, o.spacing - 1e-9) << kit.parts[a].name << " " << kit.parts[b].name;
    }
  }
  EXPECT_LE(static_cast<int>(kit.sheets.size()), kit.baseline_sheets);
  EXPECT_GE(kit.utilisation, kit.baseline_utilisation - 1e-12);
}

TEST(Kit, PartsHoldEveryCrossingAsHoleOrSlot) {
  const Design d = flat_grid(5, 4, 10, 20, 0.5);  // cm: g 600 mm, h 400 mm
  FabricationOptions o;
  o.millimetres_per_unit = 10;
  const Kit kit = make_kit(d, o);
  ASSERT_EQ(kit.parts.size(), 9u);
  EXPECT_EQ(kit.holes + kit.slots, 2 * 20);
  EXPECT_EQ(kit.slots, 3 * 2);  // inner crossings along g only
  const Part& g2 = kit.parts[2];
  EXPECT_EQ(g2.name, "g2");
  EXPECT_DOUBLE_EQ(g2.length, 600 + 2 * 10);  // end allowance = width = 10 mm
  ASSERT_EQ(g2.features.size(), 4u);
  EXPECT_EQ(g2.features[0].kind, FeatureKind::Hole);
  EXPECT_NEAR(g2.features[0].x0, 10, 1e-12);
  EXPECT_EQ(g2.features[1].kind, FeatureKind::Slot);
  EXPECT_NEAR(g2.features[1].x0, 10 + 200, 1e-9);
  EXPECT_NEAR(g2.features[1].x1, 10 + 205, 1e-9);
  EXPECT_NEAR(g2.features[1].length(), 5 + 3.2, 1e-9);
  EXPECT_EQ(g2.features[1].partner_family, Family::H);
  EXPECT_EQ(g2.features[1].partner, 1);
  EXPECT_EQ(kit.top_family, Family::H);  // planar and surface turn the same way about +z
  expect_nested(kit);
}

TEST(Kit, ShortSlidingRangesBecomeHoles) {
  const Design d = flat_grid(4, 4, 10, 10, 0.005);  // 0.05 mm at cm
  FabricationOptions o;
  o.millimetres_per_unit = 10;
  EXPECT_EQ(make_kit(d, o).slots, 0);
  o.min_slot = 0.01;
  EXPECT_EQ(make_kit(d, o).slots, 4);
}

TEST(Kit, NestingFillsRowsFirstFitDecreasing) {
  // 12 g lamellas of 500 mm + 2 x 10 allowance: two per 1200 mm row; 3 h of 1100 + 20.
  const Design d = flat_grid(12, 3, 10, 25, 0);
  FabricationOptions o;
  o.millimetres_per_unit = 10;
  const Kit kit = make_kit(d, o);
  EXPECT_EQ(kit.rows, 3 + 6);
  EXPECT_EQ(kit.sheets.size(), 1u);
  expect_nested(kit);
  // A tall sheet: the same rows, turned by 90 degrees.
  o.sheet_width = 600;
  o.sheet_height = 1200;
  const Kit tall = make_kit(d, o);
  EXPECT_EQ(tall.rows, kit.rows);
  for (const Part& p : tall.parts) EXPECT_EQ(p.rotation, 90);
  expect_nested(tall);
  // Small sheets: several of them, never more than one lamella per row would need.
  o.sheet_width = 1200;
  o.sheet_height = 60;
  const Kit small = make_kit(d, o);
  EXPECT_GT(small.sheets.size(), 1u);
  expect_nested(small);
  // Drawings: one outline per part, every feature cut.
  int outlines = 0, circles = 0;
  for (size_t s = 0; s < small.sheets.size(); ++s) {
    const SheetDrawing drawing = sheet_drawing(small, static_cast<int>(s));
    for (const SheetPolyline& p : drawing.polylines)
      outlines += p.layer == SheetLayer::Cut && p.bulges == std::vector<double>(4, 0.0);
    circles += static_cast<int>(drawing.circles.size());
  }
  EXPECT_EQ(outlines, 15);
  EXPECT_EQ(circles, 2 * 36);
}

TEST(Kit, ErrorsNameTheOption) {
  const Design d = flat_grid(3, 3, 70, 10, 0);  // h: 1400 mm at cm
  FabricationOptions o;
  o.millimetres_per_unit = 10;
  try {
    make_kit(d, o);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), "options.sheet");
    EXPECT_NE(std::string(e.what()).find("lamella h0 is 1420.0 mm long"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("1200.0 x 600.0 mm"), std::string::npos);
  }
  o.millimetres_per_unit = 0;
  EXPECT_THROW(make_kit(d, o), InvalidInput);
  o.millimetres_per_unit = 1;
  o.hole_diameter = 2;  // the lamella is 1 mm wide at mm
  try {
    make_kit(d, o);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), "options.hole_diameter");
  }
}

TEST(Kit, CornerAnglesOfARectangleAreRight) {
  const CornerAngles a = corner_angles(flat_grid(3, 3, 10, 10, 0));
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(a.planar[k], M_PI / 2, 1e-12);
    EXPECT_NEAR(a.target[k], M_PI / 2, 1e-12);
  }
}

TEST(Compare, LamellaBoxesAreClosedAndSized) {
  SimulatedLamella l;
  for (int i = 0; i <= 10; ++i) {
    l.centerline.push_back(Vec3(i, 0, 0));
    l.normals.push_back(Vec3::UnitZ());
  }
  const auto triangles = lamella_surface({l}, 1.0, 0.1);
  double area = 0;
  Vec3 moment = Vec3::Zero();
  for (const auto& t : triangles) {
    const Vec3 n = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]);
    area += n.norm();
    moment += n;  // a closed surface's vector area is zero
  }
  EXPECT_NEAR(area, 2 * (1.0 + 0.1) * 10 + 2 * 0.1, 1e-12);
  EXPECT_LT(moment.norm(), 1e-12);
}

TEST(Compare, PointCloudChecks) {
  std::vector<Vec3> line;
  for (int i = 0; i < 200; ++i) line.push_back(Vec3(i, 2 * i, 0));
  EXPECT_THROW(check_point_cloud(line, "scan"), InvalidInput);
  line.resize(50);
  EXPECT_THROW(check_point_cloud(line, "scan"), InvalidInput);
  std::vector<Vec3> plane;
  for (int i = 0; i < 200; ++i) plane.push_back(Vec3(i % 20, i / 20, 0));
  EXPECT_NO_THROW(check_point_cloud(plane, "scan"));
  plane[7].x() = std::nan("");
  EXPECT_THROW(check_point_cloud(plane, "scan"), InvalidInput);
}

TEST(Compare, ReadsPlyXyzObjAndOff) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("gridshell-kit-" + std::to_string(::getpid())))
          .string();
  std::filesystem::create_directories(dir);
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir + "/" + name, std::ios::binary) << text;
    return dir + "/" + name;
  };
  const std::string ply_ascii =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty "
      "float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n1 2 3 0 0 1\n"
      "4 5 6 0 1 0\n";
  float binary[6] = {1, 2, 3, 4, 5, 6};
  const std::string ply_binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float "
      "y\nproperty float z\nend_header\n" +
      std::string(reinterpret_cast<const char*>(binary), sizeof binary);
  for (const std::string& file : {write("a.ply", ply_ascii), write("b.ply", ply_binary),
                                  write("c.xyz", "# x y z intensity\n1 2 3 7\n\n4,5,6\n"),
                                  write("d.obj", "v 1 2 3\nvn 0 0 1\nv 4 5 6\n"),
                                  write("e.off", "OFF\n2 0 0\n1 2 3\n4 5 6\n")}) {
    const std::vector<Vec3> points = read_point_cloud(file);
    ASSERT_EQ(points.size(), 2u) << file;
    EXPECT_EQ(points[0], Vec3(1, 2, 3)) << file;
    EXPECT_EQ(points[1], Vec3(4, 5, 6)) << file;
  }
  EXPECT_THROW(read_point_cloud(write("f.xyz", "1 2\n")), InvalidInput);
  EXPECT_THROW(read_point_cloud(write("g.xyz", "1 2 inf\n")), InvalidInput);
  std::filesystem::remove_all(dir);
}

TEST(Compare, RegistersASmallScanUnderAnyMotion) {
  // Three bent lamellas in an asymmetric layout; a scan of 4000 points with noise, moved.
  std::vector<SimulatedLamella> lamellas(3);
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i <= 20; ++i) {
      const double t = i / 20.0;
      const Vec3 p = k == 0   ? Vec3(10 * t, 0, 2 * t * t)
                     : k == 1 ? Vec3(3, 8 * t, 1 - t)
                              : Vec3(7 + t, 5 * t, 3 * t * (1 - t));
      lamellas[k].centerline.push_back(p);
      lamellas[k].normals.push_back(Vec3(0.1 * k, -0.2 * t, 1).normalized());
    }
  const auto triangles = lamella_surface(lamellas, 0.5, 0.1);
  std::mt19937_64 random(3);
  std::normal_distribution<double> gauss(0, 0.005);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(2.2, Vec3(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  const Vec3 shift(40, -12, 7);
  std::vector<Vec3> scan = testing::sample_triangles(triangles, 4000, random);
  for (Vec3& p : scan) p = R * (p + Vec3(gauss(random), gauss(random), gauss(random))) + shift;
  // The target patch: a plane under the lamellas (only its distances are reported).
  const TriangleMesh target({Vec3(-1, -1, 0), Vec3(12, -1, 0), Vec3(12, 10, 0), Vec3(-1, 10, 0)},
                            {{0, 1, 2}, {0, 2, 3}});
  CompareOptions options;
  options.reference_samples = 20000;
  options.icp_points = 2000;
  const ScanComparison c = compare_scan(scan, triangles, target, options);
  double worst = 0;
  for (const auto& l : lamellas)
    for (const Vec3& p : l.centerline)
      worst = std::max(worst, (c.rotation * (R * p + shift) + c.translation - p).norm());
  EXPECT_LT(worst, 0.01) << c.coarse;  // the model is about 12 long
  // Nothing else fits: the best other pose is much farther from the lamellas than the noise.
  EXPECT_LT(c.residual, 0.01);
  EXPECT_TRUE(!c.has_runner_up || c.runner_up > 2 * c.residual) << c.runner_up;
  EXPECT_NEAR(c.deployment.rms, 0.005, 0.001);
  EXPECT_EQ(c.used + c.rejected, 4000);
  EXPECT_EQ(c.deployment.histogram_counts.size(), 20u);
  // The distances are exact whatever hint the AABB tree was given (the previous point's closest
  // point in Morton order, or the nearest sample): every one against brute force over all
  // triangles with closest_point_on_triangle (an independent oracle, not CGAL).
  const auto brute = [](const Vec3& q, const std::vector<Triangle3>& surface) {
    double best = 1e300;
    for (const Triangle3& t : surface) {
      const Vec3 w = closest_point_on_triangle(q, t[0], t[1], t[2]);  // barycentric weights
      best = std::min(best, (q - (w[0] * t[0] + w[1] * t[1] + w[2] * t[2])).norm());
    }
    return best;
  };
  const std::vector<Triangle3> plane = {
      {target.vertices()[0], target.vertices()[1], target.vertices()[2]},
      {target.vertices()[0], target.vertices()[2], target.vertices()[3]}};
  double worst_deployment = 0, worst_target = 0;
  for (size_t i = 0; i < scan.size(); ++i) {
    const Vec3 q = c.rotation * scan[i] + c.translation;
    worst_deployment =
        std::max(worst_deployment, std::abs(c.deployment_distance[i] - brute(q, triangles)));
    worst_target = std::max(worst_target, std::abs(c.target_distance[i] - brute(q, plane)));
  }
  EXPECT_LT(worst_deployment, 1e-9);
  EXPECT_LT(worst_target, 1e-9);
}

TEST(Compare, ASymmetricGridRegistersToOneOfItsPosesAndSaysItIsAmbiguous) {
  // A 5 x 5 grid of lamellas on the saddle z = 0.04 (x^2 - y^2): half a turn about z maps it onto
  // itself, and so does a half turn about a diagonal. An exact scan (no noise), moved: the
  // residual is at the level of double rounding, the pose found puts the model onto itself (the
  // true one or a symmetric one), and another pose fits as well, which the registration says.
  const auto z = [](double x, double y) { return 0.04 * (x * x - y * y); };
  std::vector<SimulatedLamella> lamellas;
  for (int family = 0; family < 2; ++family)
    for (int k = -2; k <= 2; ++k) {
      SimulatedLamella l;
      for (int i = 0; i <= 24; ++i) {
        const double t = -6 + 0.5 * i, c = 2.5 * k;
        const double x = family ? c : t, y = family ? t : c;
        l.centerline.push_back(Vec3(x, y, z(x, y)));
        l.normals.push_back(Vec3(-0.08 * x, 0.08 * y, 1).normalized());
      }
      lamellas.push_back(l);
    }
  const auto triangles = lamella_surface(lamellas, 0.5, 0.1);
  std::vector<Vec3> grid;
  std::vector<Face> faces;
  for (int i = 0; i <= 14; ++i)
    for (int j = 0; j <= 14; ++j) {
      const double x = -7 + i, y = -7 + j;
      grid.push_back(Vec3(x, y, z(x, y)));
      if (i < 14 && j < 14) {
        const int a = 15 * i + j;
        faces.push_back({a, a + 15, a + 16});
        faces.push_back({a, a + 16, a + 1});
      }
    }
  const TriangleMesh target(grid, faces);
  std::mt19937_64 random(7);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(1.3, Vec3(-0.4, 0.7, 0.2).normalized()).toRotationMatrix();
  const Vec3 shift(-20, 31, 5);
  std::vector<Vec3> scan = testing::sample_triangles(triangles, 4000, random);
  for (Vec3& p : scan) p = R * p + shift;
  CompareOptions options;
  options.reference_samples = 20000;
  options.icp_points = 2000;
  const ScanComparison c = compare_scan(scan, triangles, target, options);
  const double size = 17;  // the model's diagonal, about
  EXPECT_LT(c.residual, 1e-9 * size) << c.coarse;
  EXPECT_LT(c.deployment.rms, 1e-9 * size);
  EXPECT_EQ(c.rejected, 0);
  // Both poses put every lamella's centre line where the true motion puts it: inside the
  // lamellas, its farthest point as far from their faces as there (brute force over all
  // triangles).
  const auto on_lamellas = [&](const Eigen::Matrix3d& Q, const Vec3& q) {
    double worst = 0;
    for (const auto& l : lamellas)
      for (const Vec3& p : l.centerline) {
        const Vec3 moved = Q * (R * p + shift) + q;
        double best = 1e300;
        for (const Triangle3& t : triangles) {
          const Vec3 w = closest_point_on_triangle(moved, t[0], t[1], t[2]);
          best = std::min(best, (moved - (w[0] * t[0] + w[1] * t[1] + w[2] * t[2])).norm());
        }
        worst = std::max(worst, best);
      }
    return worst;
  };
  const double exact = on_lamellas(R.transpose(), -(R.transpose() * shift));  // about 0.05
  EXPECT_NEAR(on_lamellas(c.rotation, c.translation), exact, 1e-9);
  ASSERT_TRUE(c.has_runner_up);
  EXPECT_LT(c.runner_up, 1e-9 * size);
  EXPECT_NEAR(on_lamellas(c.runner_up_rotation, c.runner_up_translation), exact, 1e-9);
  // The two are different poses: a half turn apart.
  EXPECT_NEAR(Eigen::AngleAxisd(c.rotation * c.runner_up_rotation.transpose()).angle(),
              std::numbers::pi, 1e-6);
}

}  // namespace
}  // namespace gridshell
