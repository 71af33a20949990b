// SPDX-License-Identifier: GPL-3.0-or-later
// The grid (gridshell/design/grid.h, paper 4.1, 4.4, 4.5): build_grid's members and crossings
// checked independently of how build_grid finds them: every g crosses every h exactly once on
// both patches (by brute-force segment distances on the surface, segment intersection in the
// plane), members as long on the surface as in the plane, crossings' arc lengths locating the
// crossing on both members, notches s - s̄ and zero on the boundary.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <set>
#include <vector>

#include "gridshell/design/design.h"
#include "gridshell/design/grid.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "support.h"

namespace gridshell {
namespace {

/// A design of the double vault (maps at resolution 48), shared by the tests of this file.
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

/// The inner members' positions of a family, as build_grid takes them.
std::vector<MemberPosition> positions(const std::vector<Member>& family) {
  std::vector<MemberPosition> out;
  for (const Member& m : family)
    if (!m.boundary) {
      MemberPosition p;
      p.u1 = m.u_start;
      p.u2 = m.u_end;
      out.push_back(p);
    }
  return out;
}

/// The grid rebuilt by build_grid itself from the design's member positions.
const Grid& rebuilt_grid() {
  static const std::unique_ptr<const Grid> grid = [] {
    const Design& d = double_vault();
    const GeodesicSolver solver(d.target.patch.mesh);
    GridOptions options;
    options.threads = 2;
    return std::make_unique<const Grid>(build_grid(
        d.target.patch, solver, d.planar, positions(d.grid.g), positions(d.grid.h), options));
  }();
  return *grid;
}

double polyline_length(const std::vector<Vec3>& polyline) {
  double length = 0;
  for (std::size_t k = 1; k < polyline.size(); ++k)
    length += (polyline[k] - polyline[k - 1]).norm();
  return length;
}

/// The point at arc length s along a polyline.
Vec3 at_arc_length(const std::vector<Vec3>& polyline, double s) {
  double acc = 0;
  for (std::size_t k = 1; k < polyline.size(); ++k) {
    const double l = (polyline[k] - polyline[k - 1]).norm();
    if (acc + l >= s)
      return polyline[k - 1] + (l > 0 ? (s - acc) / l : 0.0) * (polyline[k] - polyline[k - 1]);
    acc += l;
  }
  return polyline.back();
}

/// Closest points of segments pq and rs (clamped), for their distance.
double segment_segment_distance(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s,
                                Vec3& at) {
  const Vec3 d1 = q - p, d2 = s - r, w = p - r;
  const double a = d1.dot(d1), e = d2.dot(d2), b = d1.dot(d2), c = d1.dot(w), f = d2.dot(w);
  const double denom = a * e - b * b;
  double t = denom > 1e-30 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  double u = e > 0 ? std::clamp((b * t + f) / e, 0.0, 1.0) : 0.0;
  t = a > 0 ? std::clamp((b * u - c) / a, 0.0, 1.0) : 0.0;
  at = p + t * d1;
  return (p + t * d1 - (r + u * d2)).norm();
}

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

const Crossing& crossing_of(const Grid& grid, int g, int h) {
  return grid.crossings.at(static_cast<std::size_t>(g) * grid.h.size() + h);
}

double size_of(const Design& d) { return bounding_box_size(d.target.patch.mesh).norm(); }

void expect_grid_invariants(const Grid& grid, const Design& d) {
  const int ng = static_cast<int>(grid.g.size()), nh = static_cast<int>(grid.h.size());
  ASSERT_GE(ng, 3);
  ASSERT_GE(nh, 3);
  // Crossings: every (g, h) once, sorted by (g, h).
  ASSERT_EQ(grid.crossings.size(), static_cast<std::size_t>(ng * nh));
  for (int i = 0; i < ng; ++i)
    for (int j = 0; j < nh; ++j) {
      const Crossing& x = crossing_of(grid, i, j);
      EXPECT_EQ(x.g, i);
      EXPECT_EQ(x.h, j);
      EXPECT_EQ(x.on_boundary, i == 0 || i == ng - 1 || j == 0 || j == nh - 1);
    }
  // Members: index, family, boundary flags; surface = positions of the path; lengths.
  for (const auto* family : {&grid.g, &grid.h})
    for (std::size_t k = 0; k < family->size(); ++k) {
      const Member& m = (*family)[k];
      SCOPED_TRACE((m.family == Family::G ? "g" : "h") + std::to_string(m.index));
      EXPECT_EQ(m.index, static_cast<int>(k));
      EXPECT_EQ(m.family, family == &grid.g ? Family::G : Family::H);
      EXPECT_EQ(m.boundary, k == 0 || k + 1 == family->size());
      ASSERT_EQ(m.surface.size(), m.surface_path.size());
      for (std::size_t p = 0; p < m.surface.size(); ++p)
        EXPECT_LT((m.surface[p] - m.surface_path[p].position(d.target.patch.mesh)).norm(),
                  1e-12 * size_of(d));
      EXPECT_NEAR(m.length, polyline_length(m.surface), 1e-12 * m.length);
      EXPECT_NEAR(m.planar_length, (m.planar[1] - m.planar[0]).norm(), 1e-12 * m.length);
      // Criterion (i): as long in the plane as on the surface.
      EXPECT_NEAR(m.planar_length, m.length, 1e-9 * m.length);
    }
}

TEST(BuildGrid, MembersAndCrossingsAreConsistent) {
  expect_grid_invariants(double_vault().grid, double_vault());
  expect_grid_invariants(rebuilt_grid(), double_vault());
}

// Every g crosses every h exactly once on the surface: the segment pairs of the two polylines
// that touch (distance below 1e-9 of the model) all lie at the crossing's surface point.
TEST(BuildGrid, EveryGCrossesEveryHExactlyOnceOnTheSurface) {
  const Design& d = double_vault();
  const Grid& grid = d.grid;
  const double size = size_of(d);
  for (const Member& g : grid.g)
    for (const Member& h : grid.h) {
      const Crossing& x = crossing_of(grid, g.index, h.index);
      int touching = 0;
      for (std::size_t a = 0; a + 1 < g.surface.size(); ++a)
        for (std::size_t b = 0; b + 1 < h.surface.size(); ++b) {
          Vec3 at;
          if (segment_segment_distance(g.surface[a], g.surface[a + 1], h.surface[b],
                                       h.surface[b + 1], at) > 1e-9 * size)
            continue;
          ++touching;
          EXPECT_LT((at - x.surface_point).norm(), 1e-6 * size)
              << "g" << g.index << " and h" << h.index << " also meet at " << at.transpose()
              << ", away from the crossing " << x.surface_point.transpose();
        }
      EXPECT_GE(touching, 1) << "g" << g.index << " and h" << h.index << " do not meet";
    }
}

// In the plane: the straight members g and h intersect (within both segments) at the crossing's
// planar point; two members of one family never intersect (except at shared corners).
TEST(BuildGrid, EveryGCrossesEveryHOnceInThePlaneAndFamiliesDoNotCross) {
  const Design& d = double_vault();
  const Grid& grid = d.grid;
  const double size = size_of(d);
  for (const Member& g : grid.g)
    for (const Member& h : grid.h) {
      const Crossing& x = crossing_of(grid, g.index, h.index);
      const Vec2 r = g.planar[1] - g.planar[0], q = h.planar[1] - h.planar[0];
      const double denom = cross2(r, q);
      ASSERT_GT(std::abs(denom), 1e-9 * r.norm() * q.norm());  // not parallel
      const double t = cross2(h.planar[0] - g.planar[0], q) / denom;
      const double u = cross2(h.planar[0] - g.planar[0], r) / denom;
      EXPECT_GE(t, -1e-9);
      EXPECT_LE(t, 1 + 1e-9);
      EXPECT_GE(u, -1e-9);
      EXPECT_LE(u, 1 + 1e-9);
      EXPECT_LT((g.planar[0] + t * r - x.planar_point).norm(), 1e-9 * size)
          << "g" << g.index << " h" << h.index;
    }
  for (const auto* family : {&grid.g, &grid.h})
    for (std::size_t a = 0; a < family->size(); ++a)
      for (std::size_t b = a + 1; b < family->size(); ++b) {
        const Member& m = (*family)[a];
        const Member& n = (*family)[b];
        const Vec2 r = m.planar[1] - m.planar[0], q = n.planar[1] - n.planar[0];
        const double denom = cross2(r, q);
        if (std::abs(denom) < 1e-12 * r.norm() * q.norm()) continue;  // parallel: never meet
        const double t = cross2(n.planar[0] - m.planar[0], q) / denom;
        const double u = cross2(n.planar[0] - m.planar[0], r) / denom;
        EXPECT_FALSE(t > 1e-9 && t < 1 - 1e-9 && u > 1e-9 && u < 1 - 1e-9)
            << "members " << a << " and " << b << " cross in the plane";
      }
}

// The crossing's arc lengths locate it: s_g along g's surface polyline and s_h along h's both
// reach the surface point; s̄_g and s̄_h along the straight members reach the planar point.
TEST(BuildGrid, CrossingArcLengthsLocateTheCrossingOnBothMembers) {
  const Design& d = double_vault();
  const Grid& grid = d.grid;
  const double size = size_of(d);
  for (const Crossing& x : grid.crossings) {
    SCOPED_TRACE("g" + std::to_string(x.g) + " h" + std::to_string(x.h));
    const Member& g = grid.g[x.g];
    const Member& h = grid.h[x.h];
    EXPECT_GE(x.s_g, -1e-12);
    EXPECT_LE(x.s_g, g.length * (1 + 1e-12));
    EXPECT_GE(x.s_h, -1e-12);
    EXPECT_LE(x.s_h, h.length * (1 + 1e-12));
    EXPECT_LT((at_arc_length(g.surface, x.s_g) - x.surface_point).norm(), 1e-8 * size);
    EXPECT_LT((at_arc_length(h.surface, x.s_h) - x.surface_point).norm(), 1e-8 * size);
    const Vec2 on_g = g.planar[0] + x.s_bar_g * (g.planar[1] - g.planar[0]).normalized();
    const Vec2 on_h = h.planar[0] + x.s_bar_h * (h.planar[1] - h.planar[0]).normalized();
    EXPECT_LT((on_g - x.planar_point).norm(), 1e-9 * size);
    EXPECT_LT((on_h - x.planar_point).norm(), 1e-9 * size);
    // Along each member the crossings come in the other family's order.
    if (x.h > 0) {
      EXPECT_GT(x.s_g, crossing_of(grid, x.g, x.h - 1).s_g);
      EXPECT_GT(x.s_bar_g, crossing_of(grid, x.g, x.h - 1).s_bar_g);
    }
  }
}

TEST(BuildGrid, NotchesAreSMinusSBarAndZeroOnTheBoundary) {
  const Grid& grid = double_vault().grid;
  int inner = 0, nonzero = 0;
  for (const Crossing& x : grid.crossings) {
    if (x.on_boundary) {
      EXPECT_EQ(x.notch_g(), 0.0);
      EXPECT_EQ(x.notch_h(), 0.0);
      // Boundary crossings: s = s̄ by boundary correspondence (criterion ii).
      EXPECT_NEAR(x.s_g, x.s_bar_g, 1e-9 * grid.g[x.g].length + 1e-12);
      EXPECT_NEAR(x.s_h, x.s_bar_h, 1e-9 * grid.h[x.h].length + 1e-12);
    } else {
      ++inner;
      EXPECT_EQ(x.notch_g(), x.s_g - x.s_bar_g);
      EXPECT_EQ(x.notch_h(), x.s_h - x.s_bar_h);
      nonzero += x.notch_g() != 0.0;
      // A notch is shorter than its member.
      EXPECT_LT(std::abs(x.notch_g()), grid.g[x.g].length);
      EXPECT_LT(std::abs(x.notch_h()), grid.h[x.h].length);
    }
  }
  EXPECT_GT(inner, 0);
  EXPECT_GT(nonzero, 0);  // a doubly curved surface needs sliding connections
}

// The boundary members are the patch sides: g0 = c0 -> c3, g_last = c1 -> c2, h0 = c1 -> c0,
// h_last = c2 -> c3, on the surface and between the planar corners.
TEST(BuildGrid, BoundaryMembersAreThePatchSides) {
  const Design& d = double_vault();
  const Grid& grid = d.grid;
  const Patch& patch = d.target.patch;
  const auto& c = d.planar.corners;
  const auto vertex = [&](int corner) { return patch.mesh.vertices()[patch.corners[corner]]; };
  struct Expected {
    const Member* member;
    int from, to;
  };
  for (const Expected& e : {Expected{&grid.g.front(), 0, 3}, Expected{&grid.g.back(), 1, 2},
                            Expected{&grid.h.front(), 1, 0}, Expected{&grid.h.back(), 2, 3}}) {
    EXPECT_TRUE(e.member->boundary);
    EXPECT_EQ(e.member->surface.front(), vertex(e.from));
    EXPECT_EQ(e.member->surface.back(), vertex(e.to));
    EXPECT_EQ(e.member->planar[0], c[e.from]);
    EXPECT_EQ(e.member->planar[1], c[e.to]);
  }
}

TEST(BuildGrid, RebuildingFromTheDesignsPositionsGivesTheSameGrid) {
  const Grid& a = double_vault().grid;
  const Grid& b = rebuilt_grid();
  ASSERT_EQ(a.g.size(), b.g.size());
  ASSERT_EQ(a.h.size(), b.h.size());
  for (const auto& [fa, fb] : {std::pair{&a.g, &b.g}, std::pair{&a.h, &b.h}})
    for (std::size_t k = 0; k < fa->size(); ++k) {
      EXPECT_EQ((*fa)[k].u_start, (*fb)[k].u_start);
      EXPECT_EQ((*fa)[k].u_end, (*fb)[k].u_end);  // already refined: kept
      EXPECT_EQ((*fa)[k].length, (*fb)[k].length);
    }
  ASSERT_EQ(a.crossings.size(), b.crossings.size());
  for (std::size_t k = 0; k < a.crossings.size(); ++k) {
    EXPECT_EQ(a.crossings[k].s_g, b.crossings[k].s_g);
    EXPECT_EQ(a.crossings[k].s_h, b.crossings[k].s_h);
    EXPECT_EQ(a.crossings[k].planar_point, b.crossings[k].planar_point);
  }
}

TEST(BuildGrid, GoalPrunedMemberSolvesGiveTheMembersOfCompleteSolves) {
  // Each member's first solve is exact only near its expected end; where the end lies outside
  // that piece of the opposite boundary, a complete solve follows. Both ways must give the
  // members complete solves give: start positions moved a little (the root stays inside the
  // searched piece) and moved far (it does not: the complete solve runs).
  const Design& d = double_vault();
  const GeodesicSolver solver(d.target.patch.mesh);
  for (const double shift : {0.003, -0.004, 0.03}) {
    std::vector<MemberPosition> g = positions(d.grid.g), h = positions(d.grid.h);
    for (std::vector<MemberPosition>* family : {&g, &h})
      for (MemberPosition& p : *family) p.u2 = std::clamp(p.u2 + shift, 1e-6, 1 - 1e-6);
    GridOptions pruned, complete;
    pruned.threads = complete.threads = 2;
    complete.goal_pruning = false;
    const Grid a = build_grid(d.target.patch, solver, d.planar, g, h, pruned);
    const Grid b = build_grid(d.target.patch, solver, d.planar, g, h, complete);
    EXPECT_EQ(b.complete_member_solves, 0);
    if (shift > 0.02)
      EXPECT_GT(a.complete_member_solves, 0) << "the far start must need complete solves";
    else
      EXPECT_EQ(a.complete_member_solves, 0) << shift;
    for (const auto& [fa, fb] : {std::pair{&a.g, &b.g}, std::pair{&a.h, &b.h}}) {
      ASSERT_EQ(fa->size(), fb->size());
      for (std::size_t k = 0; k < fa->size(); ++k) {
        const Member& ma = (*fa)[k];
        const Member& mb = (*fb)[k];
        EXPECT_NEAR(ma.u_end, mb.u_end, 1e-9) << shift << " member " << k;
        EXPECT_NEAR(ma.length, mb.length, 1e-9 * mb.length) << shift << " member " << k;
        EXPECT_NEAR(ma.length, ma.planar_length, 1e-9 * ma.planar_length);
        ASSERT_FALSE(ma.surface.empty());
        EXPECT_LE((ma.surface.back() - mb.surface.back()).norm(), 1e-8 * mb.length);
      }
    }
    ASSERT_EQ(a.crossings.size(), b.crossings.size());
    for (std::size_t k = 0; k < a.crossings.size(); ++k) {
      EXPECT_NEAR(a.crossings[k].s_g, b.crossings[k].s_g, 1e-8 * d.grid.g.front().length);
      EXPECT_NEAR(a.crossings[k].s_h, b.crossings[k].s_h, 1e-8 * d.grid.h.front().length);
    }
  }
}

TEST(BuildGrid, TheMemoryGateChangesNothingButHowManySolvesRunAtOnce) {
  // GridOptions::member_memory: 1 byte lets one member solve run at a time, 0 any number; the
  // members must be the same to the bit (each is a function of its own inputs).
  const Design& d = double_vault();
  const GeodesicSolver solver(d.target.patch.mesh);
  const std::vector<MemberPosition> g = positions(d.grid.g), h = positions(d.grid.h);
  GridOptions one_at_a_time, unlimited;
  one_at_a_time.threads = unlimited.threads = 4;
  one_at_a_time.member_memory = 1;
  unlimited.member_memory = 0;
  const Grid a = build_grid(d.target.patch, solver, d.planar, g, h, one_at_a_time);
  const Grid b = build_grid(d.target.patch, solver, d.planar, g, h, unlimited);
  for (const auto& [fa, fb] : {std::pair{&a.g, &b.g}, std::pair{&a.h, &b.h}}) {
    ASSERT_EQ(fa->size(), fb->size());
    for (std::size_t k = 0; k < fa->size(); ++k) {
      EXPECT_EQ((*fa)[k].u_end, (*fb)[k].u_end) << k;
      EXPECT_EQ((*fa)[k].surface, (*fb)[k].surface) << k;
    }
  }
}

TEST(GeodesicField, MemoryBytesCountsTheKeptWindows) {
  const Design& d = double_vault();
  const GeodesicSolver solver(d.target.patch.mesh);
  const SurfacePoint source =
      SurfacePoint::at_vertex(d.target.patch.mesh, d.target.patch.corners[0]);
  SolveOptions keep, drop;
  drop.keep_windows = false;
  const std::size_t kept = solver.solve(source, keep).memory_bytes();
  // At least one window per vertex (a complete field), at most 400 per vertex of 56 bytes.
  EXPECT_GT(kept, 56u * d.target.patch.mesh.vertex_count());
  EXPECT_LT(kept, 56u * 400u * d.target.patch.mesh.vertex_count());
  EXPECT_LT(solver.solve(source, drop).memory_bytes(), kept / 10);
}

TEST(BuildGrid, RejectsPositionsOutsideTheOpenIntervalOrNotIncreasing) {
  const Design& d = double_vault();
  const GeodesicSolver solver(d.target.patch.mesh);
  const std::vector<MemberPosition> g = positions(d.grid.g), h = positions(d.grid.h);
  auto field = [&](const std::vector<MemberPosition>& gg, const std::vector<MemberPosition>& hh) {
    try {
      build_grid(d.target.patch, solver, d.planar, gg, hh);
    } catch (const InvalidInput& e) {
      return e.field();
    }
    return std::string("no InvalidInput");
  };
  std::vector<MemberPosition> bad = g;
  bad[0].u1 = 0.0;
  EXPECT_EQ(field(bad, h), "g_members");
  bad = g;
  std::swap(bad[0], bad[1]);
  EXPECT_EQ(field(bad, h), "g_members");
  bad = h;
  bad.back().u2 = 1.0;
  EXPECT_EQ(field(g, bad), "h_members");
}

}  // namespace
}  // namespace gridshell
