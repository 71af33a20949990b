// SPDX-License-Identifier: GPL-3.0-or-later
// The deployment's reported numbers against computations that share no code with the kernel:
// every deviation and the RMS against a brute-force point-to-triangle distance written in the
// tests (tests/support.cpp), curvatures, stresses and the bending energy of a lamella bent into
// a circular arc against their closed forms, and the automatic inner anchor against the crossing
// that is known to be deployed farthest from the target. These are the checks that catch a
// wrong answer that still converges (a lost square root, a unit slip, the wrong end of a rod).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "gridshell/design/design.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/simulation/auto_anchors.h"
#include "gridshell/simulation/simulation.h"
#include "support.h"

namespace gridshell {
namespace {

// The oracle itself, against closed forms: a point over the face, beyond an edge, beyond a
// vertex, and on the face.
TEST(DistanceOracle, MatchesClosedFormsOverFaceEdgeAndVertex) {
  const TriangleMesh square({Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(2, 2, 0), Vec3(0, 2, 0)},
                            {{0, 1, 2}, {0, 2, 3}});
  EXPECT_DOUBLE_EQ(testing::brute_force_distance(square, Vec3(0.5, 1.5, 3)), 3.0);
  EXPECT_DOUBLE_EQ(testing::brute_force_distance(square, Vec3(1, -3, 4)), 5.0);  // edge y = 0
  EXPECT_DOUBLE_EQ(testing::brute_force_distance(square, Vec3(4, 5, 6)), 7.0);   // vertex (2,2,0)
  EXPECT_DOUBLE_EQ(testing::brute_force_distance(square, Vec3(1.2, 0.7, 0)), 0.0);
  const Vec3 q = testing::closest_point_on_triangle(Vec3(-1, 1, 1), Vec3(0, 0, 0), Vec3(2, 0, 0),
                                                    Vec3(0, 2, 0));
  EXPECT_NEAR((q - Vec3(0, 1, 0)).norm(), 0, 1e-15);  // edge x = 0
}

/// archway, shrunk to 3.7 % and moved, so that the model's scale (its largest extent is scaled
/// to 100 inside the solver) differs from 1 and a missing conversion shows.
struct ScaledArchway {
  TriangleMesh mesh;
  Design design;
};

const ScaledArchway& scaled_archway() {
  static const ScaledArchway archway = [] {
    const ExampleSurface example = make_example("archway");
    std::vector<Vec3> x = example.mesh.vertices();
    for (Vec3& p : x) p = 0.037 * p + Vec3(3, -2, 1);
    ScaledArchway out;
    out.mesh = TriangleMesh(x, example.mesh.faces());
    out.design = make_design(out.mesh, CornerSpec::at_vertices(example.corners), {});
    return out;
  }();
  return archway;
}

// Every reported deviation is the distance of its reported rod vertex to the target patch, the
// RMS is the root of their mean square, and the maximum is their maximum: with and without
// notches.
TEST(DeploymentChecks, DeviationsRmsAndMaximumMatchABruteForceDistance) {
  const Design& design = scaled_archway().design;
  const TriangleMesh& target = design.target.patch.mesh;
  for (const bool notches : {false, true}) {
    SimulationOptions options;
    options.notches = notches;
    const DeploymentRun run =
        simulate_deployment(design.grid, design.anchors, target, design.lamella_width,
                            design.lamella_thickness, options);
    ASSERT_TRUE(run.converged) << run.termination;
    ASSERT_EQ(run.lamellas.size(), design.grid.g.size() + design.grid.h.size());
    double sum_sq = 0, largest = 0;
    int count = 0;
    for (const SimulatedLamella& lamella : run.lamellas) {
      ASSERT_EQ(lamella.deviation.size(), lamella.centerline.size());
      for (size_t k = 0; k < lamella.centerline.size(); ++k) {
        const double d = testing::brute_force_distance(target, lamella.centerline[k]);
        ASSERT_NEAR(lamella.deviation[k], d, 1e-9 * (1 + d))
            << "lamella " << lamella.index << " vertex " << k;
        sum_sq += d * d;
        largest = std::max(largest, d);
        ++count;
      }
    }
    EXPECT_EQ(run.grid_vertices, count);
    const double rms = std::sqrt(sum_sq / count);
    std::printf("  %s notches: RMS %.6g (brute force %.6g), max %.6g, %d rod vertices\n",
                notches ? "with" : "without", run.rms, rms, largest, count);
    EXPECT_NEAR(run.rms, rms, 1e-12 * rms);
    EXPECT_NEAR(run.max_deviation, largest, 1e-12 * largest);
    // The lamellas lie on the surface up to their half thickness and a little more: a scale
    // slip of the shrunk model would put them 27 times too far or too near.
    EXPECT_GT(rms, 0.25 * design.lamella_thickness);
    EXPECT_LT(rms, 0.01 * 0.037 * 100);
  }
}

/// A cylinder of radius R about the y axis, z up: (R sin t, y, R cos t) for t in [-t0, t0] and
/// y in [0, depth], fine enough (sag of a facet R (1 - cos(dt/2)) below 1e-4 R) that the mesh
/// stands for the surface.
TriangleMesh cylinder(double R, double t0, double depth) {
  return testing::grid_mesh(360, 20, [&](double u, double v) {
    const double t = -t0 + 2 * t0 * u;
    return Vec3(R * std::sin(t), depth * v, R * std::cos(t));
  });
}

/// A frame of four lamellas on the cylinder: g0 and g1 the circular arcs at y = 0 and y = depth,
/// h0 and h1 the rulings at t = -t0 and t = t0, anchored at the four corners. The arcs lie
/// below the surface (the simulation offsets g by half the thickness against the normal), on
/// circles of radius Rg = R - thickness / 2. A rod of `edges` equal edges whose rest length is
/// that of the polygon inscribed in such an arc, clamped at its ends with the arc's tangents,
/// is in equilibrium as that polygon: equal turning angles, end moments only, no axial force.
/// The anchors clamp the rod's end edge: its material normal is held to the anchor's normal, so
/// that normal is the one of the end chord (the radial direction half a turning angle inside
/// the corner), and the anchor point lies half a thickness outside the arc's end vertex. With
/// the arc's own normal and length instead, the clamped rod would be turned by half a turning
/// angle at each end and 1 - sin(x)/x too long, and bulge by a quarter of its thickness.
struct Frame {
  Grid grid;
  std::vector<Anchor> anchors;
};

Frame cylinder_frame(double R, double t0, double depth, double thickness, int edges) {
  const double Rg = R - thickness / 2;
  const double chords = 2 * edges * Rg * std::sin(t0 / edges);  // inscribed polygon
  Frame out;
  auto arc = [&](int index, double y) {
    Member m;
    m.family = Family::G;
    m.index = index;
    m.boundary = true;
    for (int k = 0; k <= 400; ++k) {
      const double t = -t0 + 2 * t0 * k / 400.0;
      m.surface.push_back(Vec3(R * std::sin(t), y, R * std::cos(t)));
    }
    m.length = 2 * t0 * R;
    m.planar_length = chords;
    m.planar = {Vec2(0, y), Vec2(m.planar_length, y)};
    return m;
  };
  auto ruling = [&](int index, double t) {
    Member m;
    m.family = Family::H;
    m.index = index;
    m.boundary = true;
    for (int k = 0; k <= 20; ++k)
      m.surface.push_back(Vec3(R * std::sin(t), depth * k / 20.0, R * std::cos(t)));
    m.length = m.planar_length = depth;
    m.planar = {Vec2(0, 0), Vec2(0, depth)};
    return m;
  };
  out.grid.g = {arc(0, 0), arc(1, depth)};
  out.grid.h = {ruling(0, -t0), ruling(1, t0)};
  for (int g = 0; g < 2; ++g)
    for (int h = 0; h < 2; ++h) {
      Crossing c;
      c.g = g;
      c.h = h;
      const double t = h == 0 ? -t0 : t0;
      const double y = g == 0 ? 0 : depth;
      c.surface_point = Vec3(R * std::sin(t), y, R * std::cos(t));
      c.s_g = h == 0 ? 0 : 2 * t0 * R;
      c.s_bar_g = h == 0 ? 0 : chords;
      c.s_h = c.s_bar_h = g == 0 ? 0 : depth;
      c.on_boundary = true;
      out.grid.crossings.push_back(c);
      Anchor a;
      a.g = g;
      a.h = h;
      a.corner = true;
      const double chord = h == 0 ? t + t0 / edges : t - t0 / edges;  // end chord's middle
      a.normal = Vec3(std::sin(chord), 0, std::cos(chord));
      a.position = Vec3(Rg * std::sin(t), y, Rg * std::cos(t)) + thickness / 2 * a.normal;
      out.anchors.push_back(a);
    }
  return out;
}

// A lamella bent into a circular arc of radius r: weak-axis curvature 1/r, bending stress
// E t / (2 r), no twist and no in-plane bending, bending energy E I / 2 / r^2 L with
// I = w t^3 / 12, in joules when the unit is known; the straight lamellas carry none of it.
// Every rod vertex lies half a thickness off the surface.
TEST(DeploymentChecks, LamellaBentIntoAnArcHasTheClosedFormCurvatureStressAndEnergy) {
  const double R = 62.5, t0 = 2 * std::atan(0.5), depth = 70, width = 2, thickness = 0.4;
  const double Rg = R - thickness / 2;
  const int edges = 64;  // one interval per lamella (two crossings), 64 edges on it
  const Frame frame = cylinder_frame(R, t0, depth, thickness, edges);
  const TriangleMesh target = cylinder(R, t0, depth);
  SimulationOptions options;
  options.notches = false;
  options.edges_per_interval = edges;
  options.unit_in_meters = 0.01;  // centimetres: energies in joules
  const DeploymentRun run =
      simulate_deployment(frame.grid, frame.anchors, target, width, thickness, options);
  ASSERT_TRUE(run.converged) << run.termination;
  const double E = options.material.young_modulus;
  const double stress = E * thickness / (2 * Rg);
  for (const SimulatedLamella& lamella : run.lamellas) {
    ASSERT_EQ(lamella.centerline.size(), static_cast<size_t>(edges + 1));
    if (lamella.family == Family::G) {
      EXPECT_NEAR(lamella.max_weak_curvature, 1 / Rg, 0.01 / Rg) << "arc " << lamella.index;
      EXPECT_NEAR(lamella.max_bending_stress, stress, 0.01 * stress);
      // Both bending stresses add at a corner of the section; the in-plane one is ~0 here.
      EXPECT_NEAR(lamella.max_normal_stress, lamella.max_bending_stress,
                  0.01 * lamella.max_bending_stress);
    } else {
      EXPECT_LT(lamella.max_weak_curvature, 0.01 / Rg) << "ruling " << lamella.index;
      EXPECT_LT(lamella.max_bending_stress, 0.01 * stress);
    }
    EXPECT_LT(lamella.max_strong_curvature, 0.001 / Rg);
    EXPECT_LT(lamella.max_twist_rate, 0.001 / Rg);
    EXPECT_LT(lamella.max_torsion_stress, 0.001 * stress);
    for (size_t k = 0; k < lamella.deviation.size(); ++k)
      EXPECT_NEAR(lamella.deviation[k], thickness / 2, 0.01 * thickness) << k;
  }
  // Two arcs. The discrete rod bends at its edges - 1 inner vertices, each standing for one
  // rest edge h of the lamella; the half edges at the clamped ends are held by the anchors. So
  // its energy is the closed form over (edges - 1) h, to the discretisation's cos(phi / 2).
  const double unit = options.unit_in_meters;
  const double I = (width * unit) * std::pow(thickness * unit, 3) / 12;
  const double arc = 2 * t0 * Rg;
  const double continuum = 2 * 0.5 * E * I / std::pow(Rg * unit, 2) * (arc * unit);
  const double expected = continuum * (edges - 1) / edges;
  std::printf(
      "  bending energy %.6g J (closed form %.6g J over the inner vertices, %.6g J over "
      "the whole arc), stress %.4g MPa (%.4g MPa)\n",
      run.energies.at("bend_weak"), expected, continuum, run.lamellas[0].max_bending_stress / 1e6,
      stress / 1e6);
  EXPECT_EQ(run.energy_unit, "J");
  EXPECT_NEAR(run.energies.at("bend_weak"), expected, 0.002 * expected);
  EXPECT_LT(run.energies.at("twist"), 1e-6 * expected);
  EXPECT_LT(run.energies.at("bend_strong"), 1e-6 * expected);
  EXPECT_NEAR(run.rms, thickness / 2, 0.01 * thickness);
}

/// A point at rest arc length s along a deployed lamella: its rod vertices are uniform in rest
/// length, so the point lies between vertices floor(s / h) and the next, h = rest / edges.
Vec3 point_at_rest_length(const SimulatedLamella& lamella, double s) {
  const int edges = static_cast<int>(lamella.centerline.size()) - 1;
  const double x = std::clamp(s / (lamella.rest_length / edges), 0.0, double(edges));
  const int k = std::min(static_cast<int>(std::floor(x)), edges - 1);
  const double f = x - k;
  return (1 - f) * lamella.centerline[k] + f * lamella.centerline[k + 1];
}

// `--interior-anchors auto` pins the inner crossing deployed farthest from the target. Which
// crossing that is, is known independently: each crossing's deployed connection points on both
// lamellas, interpolated at their rest arc lengths and measured by brute force. On the sphere
// held at its boundary the crown sags; the farthest crossing, (11, 11), stands out from the
// runner-up by 12 %, far more than the error of reading the deviation at the nearest rod vertex,
// and it lies off the middle of its lamellas, so reading from the wrong end of a rod would pick
// another one ((11, 3)).
TEST(DeploymentChecks, AutomaticInnerAnchorGoesToTheCrossingFarthestFromTheTarget) {
  const ExampleSurface example = make_example("sphere");
  const Design design = make_design(example.mesh, CornerSpec::at_vertices(example.corners), {});
  const TriangleMesh& target = design.target.patch.mesh;
  SimulationOptions options;
  options.notches = true;
  const DeploymentRun first = simulate_deployment(
      design.grid, design.anchors, target, design.lamella_width, design.lamella_thickness, options);
  const int ng = static_cast<int>(design.grid.g.size()),
            nh = static_cast<int>(design.grid.h.size());
  double best = -1, runner_up = -1;
  int best_g = -1, best_h = -1;
  for (const SimulatedConnection& c : first.connections) {
    if (c.g <= 0 || c.g >= ng - 1 || c.h <= 0 || c.h >= nh - 1) continue;
    const Crossing& crossing = design.grid.crossings[static_cast<size_t>(c.g) * nh + c.h];
    const Vec3 on_g = point_at_rest_length(first.lamellas[c.g], crossing.s_bar_g + c.slide_g);
    const Vec3 on_h = point_at_rest_length(first.lamellas[ng + c.h], crossing.s_bar_h + c.slide_h);
    const double d = std::max(testing::brute_force_distance(target, on_g),
                              testing::brute_force_distance(target, on_h));
    if (d > best) {
      runner_up = best;
      best = d, best_g = c.g, best_h = c.h;
    } else {
      runner_up = std::max(runner_up, d);
    }
  }
  std::printf("  farthest inner crossing (%d, %d) at %.4g, the next at %.4g\n", best_g, best_h,
              best, runner_up);
  ASSERT_GE(best_g, 0);
  ASSERT_GT(best - runner_up, 0.05 * best);  // a clear answer
  AutoAnchorOptions one;
  one.max_anchors = 1;
  one.min_improvement = -1;  // keep it whatever it does
  const AutoAnchorResult result =
      auto_interior_anchors(design.grid, design.anchors, target, design.lamella_width,
                            design.lamella_thickness, options, one);
  ASSERT_EQ(result.added, 1);
  EXPECT_EQ(result.rms_trials.front(), first.rms);
  const Anchor& added = result.anchors.back();
  EXPECT_EQ(added.g, best_g);
  EXPECT_EQ(added.h, best_h);
  const Crossing& crossing = design.grid.crossings[static_cast<size_t>(best_g) * nh + best_h];
  EXPECT_EQ(added.position, crossing.surface_point);
}

}  // namespace
}  // namespace gridshell
