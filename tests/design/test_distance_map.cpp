// SPDX-License-Identifier: GPL-3.0-or-later
// Distance maps D_u, D_v (paper Section 4.2): boundary chains, points on chains, the surface maps
// against Euclidean distances on flat patches and against the planar maps D̄ on developable
// examples, symmetry, thread independence, cancellation and error propagation.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>

#include "gridshell/design/distance_map.h"
#include "gridshell/design/distance_map_copy.h"
#include "gridshell/design/patch.h"
#include "gridshell/design/planar_patch.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/geodesic/geodesic.h"
#include "gridshell/mesh/surface_distance.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::bump;
using testing::flat_square;
using testing::grid_mesh;

// A general convex quadrilateral patch on the flat square.
const Patch& flat_patch() {
  static const Patch patch = [] {
    const TriangleMesh mesh = flat_square(20);
    const std::array<Vec3, 4> q{Vec3(2, 1, 0), Vec3(8.3, 2.2, 0), Vec3(9, 9, 0), Vec3(1.1, 7.3, 0)};
    std::array<SurfacePoint, 4> corners;
    for (int i = 0; i < 4; ++i) corners[i] = closest_surface_point(mesh, q[i]);
    return cut_patch(mesh, corners);
  }();
  return patch;
}

const Patch& bump_patch() {
  static const Patch patch = [] {
    const TriangleMesh mesh = bump(20);
    std::array<SurfacePoint, 4> corners;
    const std::array<Vec2, 4> q{Vec2(1.3, 0.8), Vec2(9.1, 1.7), Vec2(8.6, 9.2), Vec2(0.7, 8.4)};
    for (int i = 0; i < 4; ++i) {
      const double x = q[i].x(), y = q[i].y();
      corners[i] = closest_surface_point(
          mesh, Vec3(x, y, 2.5 * std::exp(-((x - 5) * (x - 5) + (y - 5) * (y - 5)) / 8)));
    }
    return cut_patch(mesh, corners);
  }();
  return patch;
}

Vec3 corner(const Patch& patch, int i) { return patch.mesh.vertices()[patch.corners[i]]; }

double relative_error(double value, double expected) {
  return std::abs(value - expected) / std::max(1.0, std::abs(expected));
}

TEST(FamilyBoundary, FollowsTheConventions) {
  const Patch& patch = flat_patch();
  const auto& c = patch.corners;
  const std::map<std::pair<Family, int>, std::pair<int, int>> ends{{{Family::G, 0}, {c[0], c[1]}},
                                                                   {{Family::G, 1}, {c[3], c[2]}},
                                                                   {{Family::H, 0}, {c[1], c[2]}},
                                                                   {{Family::H, 1}, {c[0], c[3]}}};
  for (const auto& [key, expected] : ends) {
    const auto chain = family_boundary(patch, key.first, key.second);
    ASSERT_GE(chain.size(), 2u);
    EXPECT_EQ(chain.front(), expected.first);
    EXPECT_EQ(chain.back(), expected.second);
  }
  EXPECT_EQ(family_boundary(patch, Family::G, 1).size(), patch.sides[2].size());
  EXPECT_THROW(family_boundary(patch, Family::G, 2), InvalidInput);
}

TEST(PointOnChain, ArcLengthParameterAndExactEdgePoints) {
  const Patch& patch = bump_patch();
  const TriangleMesh& mesh = patch.mesh;
  for (int side = 0; side < 4; ++side) {
    const auto& chain = patch.sides[side];
    const double length = chain_length(mesh, chain);
    EXPECT_GT(length, 0);
    EXPECT_EQ(point_on_chain(mesh, chain, 0.0).vertex(mesh), chain.front());
    EXPECT_EQ(point_on_chain(mesh, chain, 1.0).vertex(mesh), chain.back());
    for (double t : {0.01, 0.1, 0.25, 0.5, 0.61803, 0.9, 0.999}) {
      const SurfacePoint p = point_on_chain(mesh, chain, t);
      // Walk the chain to arc length t * L.
      double remaining = t * length;
      Vec3 expected = mesh.vertices()[chain.back()];
      int a = -1, b = -1;
      for (size_t k = 0; k + 1 < chain.size(); ++k) {
        const Vec3 &p0 = mesh.vertices()[chain[k]], &p1 = mesh.vertices()[chain[k + 1]];
        const double segment = (p1 - p0).norm();
        if (remaining <= segment) {
          expected = p0 + (remaining / segment) * (p1 - p0);
          a = chain[k];
          b = chain[k + 1];
          break;
        }
        remaining -= segment;
      }
      EXPECT_LT((p.position(mesh) - expected).norm(), 1e-12 * length) << "side " << side;
      // On an edge of its face: the opposite vertex has weight exactly 0, the edge is ab.
      if (p.vertex(mesh) < 0) {
        const Face& f = mesh.faces()[p.face];
        int zeros = 0;
        for (int k = 0; k < 3; ++k) {
          if (p.barycentric[k] == 0.0) {
            ++zeros;
            EXPECT_NE(f[k], a);
            EXPECT_NE(f[k], b);
          } else {
            EXPECT_TRUE(f[k] == a || f[k] == b);
          }
        }
        EXPECT_EQ(zeros, 1);
      }
    }
  }
  EXPECT_THROW(point_on_chain(mesh, patch.sides[0], -0.1), InvalidInput);
  EXPECT_THROW(point_on_chain(mesh, patch.sides[0], 1.5), InvalidInput);
  EXPECT_THROW(point_on_chain(mesh, patch.sides[0], std::nan("")), InvalidInput);
}

TEST(DistanceMapResolution, FixedOrAdaptive) {
  const Patch& patch = flat_patch();
  EXPECT_EQ(distance_map_resolution(patch, {}), 100);
  EXPECT_EQ(distance_map_resolution(patch, {.resolution = 17}), 17);
  size_t edges = 0;
  for (const auto& side : patch.sides) edges = std::max(edges, side.size() - 1);
  EXPECT_EQ(distance_map_resolution(patch, {.resolution = 0}),
            std::clamp<int>(static_cast<int>(edges), 32, 200));
  const GeodesicSolver solver(patch.mesh);
  const DistanceMaps adaptive = compute_distance_maps(patch, solver, {.resolution = 0});
  EXPECT_EQ(adaptive.g.resolution(), distance_map_resolution(patch, {.resolution = 0}));
  EXPECT_EQ(adaptive.h.resolution(), adaptive.g.resolution());
  EXPECT_THROW(distance_map_resolution(patch, {.resolution = 1}), InvalidInput);
  EXPECT_THROW(compute_distance_maps(patch, solver, {.resolution = 1}), InvalidInput);
  EXPECT_THROW(distance_map_resolution(patch, {.resolution = -3}), InvalidInput);
}

TEST(DistanceMaps, FlatPatchMapsAreEuclideanDistances) {
  const Patch& patch = flat_patch();
  const GeodesicSolver solver(patch.mesh);
  const int R = 21;
  const DistanceMaps maps = compute_distance_maps(patch, solver, {.resolution = R, .threads = 4});
  ASSERT_EQ(maps.g.resolution(), R);
  ASSERT_EQ(maps.h.resolution(), R);
  EXPECT_EQ(maps.g.family, Family::G);
  EXPECT_EQ(maps.h.family, Family::H);
  for (const DistanceMap* map : {&maps.g, &maps.h}) {
    const auto first = family_boundary(patch, map->family, 0);
    const auto second = family_boundary(patch, map->family, 1);
    for (int i = 0; i < R; ++i) {
      const Vec3 p = point_on_chain(patch.mesh, first, double(i) / (R - 1)).position(patch.mesh);
      for (int j = 0; j < R; ++j) {
        const Vec3 q = point_on_chain(patch.mesh, second, double(j) / (R - 1)).position(patch.mesh);
        EXPECT_LT(relative_error(map->distances(i, j), (p - q).norm()), 1e-12) << i << " " << j;
      }
    }
  }
  const auto L = side_lengths(patch);
  const double e = (corner(patch, 2) - corner(patch, 0)).norm();
  const double f = (corner(patch, 3) - corner(patch, 1)).norm();
  EXPECT_LT(relative_error(maps.g.distances(0, 0), L[3]), 1e-12);
  EXPECT_LT(relative_error(maps.g.distances(R - 1, R - 1), L[1]), 1e-12);
  EXPECT_LT(relative_error(maps.g.distances(0, R - 1), e), 1e-12);
  EXPECT_LT(relative_error(maps.g.distances(R - 1, 0), f), 1e-12);
  EXPECT_LT(relative_error(maps.h.distances(0, 0), L[0]), 1e-12);
  EXPECT_LT(relative_error(maps.h.distances(R - 1, R - 1), L[2]), 1e-12);
  EXPECT_LT(relative_error(maps.h.distances(0, R - 1), f), 1e-12);
  EXPECT_LT(relative_error(maps.h.distances(R - 1, 0), e), 1e-12);
}

TEST(DistanceMaps, SwappingSourcesAndTargetsTransposes) {
  const Patch& patch = bump_patch();
  const GeodesicSolver solver(patch.mesh);
  const int R = 12;
  const DistanceMaps maps = compute_distance_maps(patch, solver, {.resolution = R, .threads = 4});
  for (const DistanceMap* map : {&maps.g, &maps.h}) {
    const auto first = family_boundary(patch, map->family, 0);
    const auto second = family_boundary(patch, map->family, 1);
    for (int j = 0; j < R; ++j) {
      const DistanceField field =
          solver.solve(point_on_chain(patch.mesh, second, double(j) / (R - 1)));
      for (int i = 0; i < R; ++i) {
        const double swapped =
            field.distance_to(point_on_chain(patch.mesh, first, double(i) / (R - 1)));
        EXPECT_LT(relative_error(swapped, map->distances(i, j)), 1e-10) << i << " " << j;
      }
    }
  }
  // The bump makes geodesics longer than 3D chords (a genuinely curved test).
  EXPECT_GT(maps.g.distances(0, R - 1), (corner(patch, 2) - corner(patch, 0)).norm() * (1 + 1e-3));
}

TEST(DistanceMaps, TargetOnlySolvesEqualQueriesOfCompleteFields) {
  // The maps are computed by solves that keep no windows and stop once the targets are final;
  // the same entries read off complete distance fields must agree (up to rounding).
  const Patch& patch = bump_patch();
  const GeodesicSolver solver(patch.mesh);
  const int R = 11;
  const DistanceMaps maps = compute_distance_maps(patch, solver, {.resolution = R, .threads = 2});
  for (const DistanceMap* map : {&maps.g, &maps.h}) {
    const auto first = family_boundary(patch, map->family, 0);
    const auto second = family_boundary(patch, map->family, 1);
    for (int i = 0; i < R; ++i) {
      const DistanceField field =
          solver.solve(point_on_chain(patch.mesh, first, double(i) / (R - 1)));
      for (int j = 0; j < R; ++j) {
        const double full =
            field.distance_to(point_on_chain(patch.mesh, second, double(j) / (R - 1)));
        EXPECT_LT(relative_error(map->distances(i, j), full), 1e-13) << i << " " << j;
      }
    }
  }
}

TEST(DistanceMaps, ResultDoesNotDependOnThreadCount) {
  const Patch& patch = bump_patch();
  const GeodesicSolver solver(patch.mesh);
  const DistanceMaps one = compute_distance_maps(patch, solver, {.resolution = 16, .threads = 1});
  const DistanceMaps four = compute_distance_maps(patch, solver, {.resolution = 16, .threads = 4});
  const DistanceMaps many = compute_distance_maps(patch, solver, {.resolution = 16, .threads = 0});
  EXPECT_TRUE(one.g.distances == four.g.distances);  // bit-identical
  EXPECT_TRUE(one.h.distances == four.h.distances);
  EXPECT_TRUE(one.g.distances == many.g.distances);
  EXPECT_TRUE(one.h.distances == many.h.distances);
  EXPECT_TRUE(one.g.distances.allFinite());
}

TEST(DistanceMaps, ReportsMonotoneProgressEndingAtOne) {
  const Patch& patch = flat_patch();
  const GeodesicSolver solver(patch.mesh);
  std::mutex mutex;
  std::vector<double> fractions;
  const Progress progress([&](std::string_view stage, double fraction) {
    std::lock_guard lock(mutex);
    EXPECT_EQ(stage, "distance maps");
    fractions.push_back(fraction);
  });
  compute_distance_maps(patch, solver, {.resolution = 10, .threads = 3}, progress);
  ASSERT_GE(fractions.size(), 2u);
  EXPECT_EQ(fractions.front(), 0.0);
  EXPECT_EQ(fractions.back(), 1.0);
  for (size_t k = 1; k < fractions.size(); ++k) EXPECT_GE(fractions[k], fractions[k - 1]);
}

TEST(DistanceMaps, CancellationThrowsCancelled) {
  const Patch& patch = bump_patch();
  const GeodesicSolver solver(patch.mesh);
  for (int threads : {1, 4}) {
    // Already cancelled.
    std::atomic<bool> cancel{true};
    EXPECT_THROW(compute_distance_maps(patch, solver, {.resolution = 20, .threads = threads},
                                       Progress(nullptr, &cancel)),
                 Cancelled);
    // Cancelled part way through, from the progress callback.
    std::atomic<bool> later{false};
    const Progress progress(
        [&later](std::string_view, double fraction) {
          if (fraction > 0.1) later = true;
        },
        &later);
    EXPECT_THROW(
        compute_distance_maps(patch, solver, {.resolution = 40, .threads = threads}, progress),
        Cancelled);
  }
}

TEST(DistanceMaps, ErrorsFromWorkersAndCallbackPropagate) {
  const Patch& patch = bump_patch();
  // A solver built on another (tiny) mesh: the sources' faces are out of its range, so the solves
  // on the worker threads throw InvalidInput, which must reach the caller.
  const TriangleMesh tiny({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)},
                          {{0, 1, 2}, {1, 3, 2}});
  const GeodesicSolver wrong(tiny);
  for (int threads : {1, 4}) {
    EXPECT_THROW(compute_distance_maps(patch, wrong, {.resolution = 20, .threads = threads}),
                 InvalidInput);
  }
  // A throwing progress callback (called on the calling thread) stops and joins the workers.
  const GeodesicSolver solver(patch.mesh);
  const Progress throwing([](std::string_view, double fraction) {
    if (fraction > 0) throw std::logic_error("callback failed");
  });
  EXPECT_THROW(compute_distance_maps(patch, solver, {.resolution = 20, .threads = 4}, throwing),
               std::logic_error);
  EXPECT_THROW(compute_distance_maps(patch, solver, {.resolution = 20, .threads = -1}),
               InvalidInput);
}

// KEY TEST: on developable surfaces, at ᾱ = the surface corner angle at c0, the planar patch is
// the development of the surface patch, so D = D̄ for both families.
//
// That needs every side to be a straight line in the development. The examples' own corners
// qualify (the cone's near corners sit far enough out along the rulings for their chord to clear
// the concave inner arc of its annular-sector development). The cone is also cut with interior
// corners, grid vertices (i, j) = (2,6), (42,9), (40,30), (5,31) of the 45 x 33 grid, whose
// four chords lie inside the sector -- a general (non-symmetric) quadrilateral.
struct DevelopableCase {
  std::string name;
  std::vector<std::array<int, 2>> grid_corners;  // empty: the example's suggested corners
};

void PrintTo(const DevelopableCase& c, std::ostream* os) {
  *os << c.name << (c.grid_corners.empty() ? "" : " (interior corners)");
}

class DevelopableExample : public ::testing::TestWithParam<DevelopableCase> {};

TEST_P(DevelopableExample, SurfaceMapsEqualPlanarMapsAtTheSurfaceAngle) {
  const ExampleSurface example = make_example(GetParam().name);
  std::array<int, 4> corner_vertices = example.corners;
  if (!GetParam().grid_corners.empty()) {
    // corners[2] and corners[3] are grid vertices (nu-1, nv-1) and (0, nv-1).
    const int nu = example.corners[2] - example.corners[3] + 1;
    for (int k = 0; k < 4; ++k) {
      corner_vertices[k] = GetParam().grid_corners[k][0] + nu * GetParam().grid_corners[k][1];
    }
  }
  std::array<SurfacePoint, 4> corners;
  for (int k = 0; k < 4; ++k) {
    corners[k] = SurfacePoint::at_vertex(example.mesh, corner_vertices[k]);
  }
  const Patch patch = cut_patch(example.mesh, corners);
  const GeodesicSolver solver(patch.mesh);
  const int R = 33;
  const DistanceMaps maps = compute_distance_maps(patch, solver, {.resolution = R});

  const auto lengths = side_lengths(patch);
  const auto surface_angles = corner_angles(patch);
  const double alpha = surface_angles[0];
  const auto planar = make_planar_patch(lengths, alpha);
  ASSERT_TRUE(planar.has_value());
  // The development's other corner angles are the surface's too (sides are straight there).
  const auto planar_angles = planar_corner_angles(*planar);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(planar_angles[k], surface_angles[k], 1e-9) << k;

  double worst = 0;
  for (const DistanceMap* map : {&maps.g, &maps.h}) {
    const Eigen::MatrixXd planar_map = planar_distance_map(*planar, map->family, R);
    for (int i = 0; i < R; ++i) {
      for (int j = 0; j < R; ++j) {
        const double error = std::abs(map->distances(i, j) - planar_map(i, j)) / planar_map(i, j);
        worst = std::max(worst, error);
        EXPECT_LT(error, 1e-9) << (map->family == Family::G ? "G " : "H ") << i << " " << j;
      }
    }
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", worst);
  RecordProperty("worst_relative_error", text);
}

INSTANTIATE_TEST_SUITE_P(
    Examples, DevelopableExample,
    ::testing::Values(DevelopableCase{"cylinder", {}}, DevelopableCase{"plane", {}},
                      DevelopableCase{"cone", {}},
                      DevelopableCase{"cone", {{{2, 6}}, {{42, 9}}, {{40, 30}}, {{5, 31}}}}),
    [](const ::testing::TestParamInfo<DevelopableCase>& info) {
      return info.param.name + (info.param.grid_corners.empty() ? "" : "_interior_corners");
    });

// Issue 17: the maps of a large patch on a simplified copy. The copy keeps the maps' sample
// points as vertices at exactly the positions point_on_chain gives on the patch, has about the
// asked vertex count, and its maps stay close to the exact ones (measured: 2.3e-3 relative here,
// on a coarse 441-vertex bump simplified to 150; 5e-5 at 15k -> 4k, docs/decisions.md).
TEST(MapCopy, KeepsTheSamplePointsAndApproximatesTheMaps) {
  const Patch& patch = bump_patch();
  constexpr int kSamples = 12;
  const MapCopy copy = make_map_copy(patch, 150, kSamples);
  EXPECT_LT(copy.patch.mesh.vertex_count(), patch.mesh.vertex_count() / 2);
  EXPECT_LE(copy.patch.mesh.vertex_count(), 160);
  for (int c = 0; c < 4; ++c) {
    const std::vector<int> chain = family_boundary(patch, static_cast<Family>(c % 2), c / 2);
    ASSERT_EQ(copy.chains[c].size(), static_cast<size_t>(kSamples));
    for (int i = 0; i < kSamples; ++i) {
      const Vec3 exact =
          point_on_chain(patch.mesh, chain, i / (kSamples - 1.0)).position(patch.mesh);
      EXPECT_EQ(copy.patch.mesh.vertices()[copy.chains[c][i]], exact) << c << " " << i;
    }
  }
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(copy.patch.mesh.vertices()[copy.patch.corners[i]], corner(patch, i));

  const GeodesicSolver solver(patch.mesh);
  const DistanceMaps exact =
      compute_distance_maps(patch, solver, {.resolution = kSamples, .max_vertices = 0});
  const DistanceMaps coarse =
      compute_distance_maps(patch, solver, {.resolution = kSamples, .max_vertices = 150});
  EXPECT_EQ(exact.mesh_vertices, patch.mesh.vertex_count());
  EXPECT_EQ(exact.copy, nullptr);
  ASSERT_NE(coarse.copy, nullptr);
  EXPECT_EQ(coarse.mesh_vertices, coarse.copy->patch.mesh.vertex_count());
  double worst = 0;
  for (const auto& [e, c] : {std::pair{&exact.g, &coarse.g}, std::pair{&exact.h, &coarse.h}})
    for (int i = 0; i < kSamples; ++i)
      for (int j = 0; j < kSamples; ++j)
        worst =
            std::max(worst, std::abs(c->distances(i, j) - e->distances(i, j)) / e->distances(i, j));
  EXPECT_GT(worst, 0.0);   // it is a different mesh
  EXPECT_LT(worst, 1e-2);  // but close
  // The corner entries are the patch's side lengths (its sides are shortest geodesics).
  const std::array<double, 4> sides = side_lengths(patch);
  EXPECT_EQ(coarse.g.distances(0, 0), sides[3]);
  EXPECT_EQ(coarse.h.distances(kSamples - 1, kSamples - 1), sides[2]);
  EXPECT_NEAR(coarse.g.distances(0, 0), exact.g.distances(0, 0), 1e-12 * sides[3]);
  // Deterministic.
  const MapCopy again = make_map_copy(patch, 150, kSamples);
  EXPECT_EQ(again.patch.mesh.vertices(), copy.patch.mesh.vertices());

  EXPECT_THROW(make_map_copy(patch, 150, 1), InvalidInput);
  EXPECT_THROW(make_map_copy(patch, 0, kSamples), InvalidInput);
  EXPECT_THROW(compute_distance_maps(patch, solver, {.resolution = kSamples, .max_vertices = -1}),
               InvalidInput);
  std::atomic<bool> cancel{true};
  EXPECT_THROW(make_map_copy(patch, 150, kSamples, Progress(nullptr, &cancel)), Cancelled);
}

}  // namespace
}  // namespace gridshell

namespace gridshell {
namespace {

TEST(SimplifyMesh, KeepsTheGivenVerticesAndTheBoundaryAndApproachesTheSurface) {
  // waves-bump (3481 vertices) down to 300: the kept vertices stay where they were, the
  // boundary stays one loop, and the area stays within 1 %.
  const TriangleMesh mesh = make_example("waves-bump").mesh;
  const std::vector<int> keep = {0, 7, mesh.vertex_count() / 2, mesh.vertex_count() - 1};
  const SimplifiedMesh copy = simplify_mesh(mesh, 300, keep);
  EXPECT_LE(copy.mesh.vertex_count(), 300);
  EXPECT_GT(copy.mesh.vertex_count(), 250);
  ASSERT_EQ(copy.of_input.size(), static_cast<size_t>(mesh.vertex_count()));
  int kept = 0;
  for (int v = 0; v < mesh.vertex_count(); ++v) kept += copy.of_input[v] >= 0;
  EXPECT_EQ(kept, static_cast<int>(keep.size()));
  for (int v : keep) {
    ASSERT_GE(copy.of_input[v], 0) << v;
    EXPECT_EQ(copy.mesh.vertices()[copy.of_input[v]], mesh.vertices()[v]) << v;
  }
  EXPECT_EQ(copy.mesh.topology().boundary_loops.size(), 1u);
  EXPECT_NEAR(surface_area(copy.mesh) / surface_area(mesh), 1, 0.01);
  // Smaller than asked: unchanged.
  const SimplifiedMesh same = simplify_mesh(mesh, mesh.vertex_count(), keep);
  EXPECT_EQ(same.mesh.vertices(), mesh.vertices());
  EXPECT_THROW(simplify_mesh(mesh, 300, {mesh.vertex_count()}), InvalidInput);
}

}  // namespace
}  // namespace gridshell
