// SPDX-License-Identifier: GPL-3.0-or-later
// The deployment simulation on whole grids: mechanisms, notches, solvers, bad input, and the
// paper-like examples.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <ostream>

#include "gridshell/design/design.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"
#include "gridshell/simulation/auto_anchors.h"
#include "gridshell/simulation/simulation.h"
#include "support.h"

namespace gridshell {
namespace {

/// A flat square plate (the target surface of the planar tests), normal +z.
TriangleMesh plate(double size) {
  return TriangleMesh(
      {Vec3(-size, -size, 0), Vec3(size, -size, 0), Vec3(size, size, 0), Vec3(-size, size, 0)},
      {{0, 1, 2}, {0, 2, 3}});
}

Member straight_member(Family family, int index, int count, const Vec3& a, const Vec3& b) {
  Member m;
  m.family = family;
  m.index = index;
  m.boundary = index == 0 || index == count - 1;
  for (int k = 0; k <= 8; ++k) m.surface.push_back(a + (b - a) * (k / 8.0));
  m.planar = {Vec2(a.x(), a.y()), Vec2(b.x(), b.y())};
  m.length = m.planar_length = (b - a).norm();
  return m;
}

/// An n x n planar grid on [0, L]^2: g_i along x at y = i L / (n-1), h_j along y; crossings with
/// s = s̄ (no notches) and anchors at the four corners (positions and normals +z).
struct PlanarGrid {
  Grid grid;
  std::vector<Anchor> anchors;
};

PlanarGrid planar_grid(int n, double L) {
  PlanarGrid out;
  for (int i = 0; i < n; ++i) {
    const double c = L * i / (n - 1);
    out.grid.g.push_back(straight_member(Family::G, i, n, Vec3(0, c, 0), Vec3(L, c, 0)));
    out.grid.h.push_back(straight_member(Family::H, i, n, Vec3(c, 0, 0), Vec3(c, L, 0)));
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      Crossing x;
      x.g = i;
      x.h = j;
      x.surface_point = Vec3(L * j / (n - 1), L * i / (n - 1), 0);
      x.planar_point = Vec2(x.surface_point.x(), x.surface_point.y());
      x.s_g = x.s_bar_g = x.surface_point.x();
      x.s_h = x.s_bar_h = x.surface_point.y();
      x.on_boundary = i == 0 || j == 0 || i == n - 1 || j == n - 1;
      out.grid.crossings.push_back(x);
    }
  for (const auto& [g, h] : {std::pair{0, 0}, {0, n - 1}, {n - 1, n - 1}, {n - 1, 0}}) {
    Anchor a;
    a.g = g;
    a.h = h;
    a.corner = true;
    a.position = Vec3(L * h / (n - 1), L * g / (n - 1), 0);
    a.normal = Vec3::UnitZ();
    out.anchors.push_back(a);
  }
  return out;
}

double elastic_energy(const DeploymentRun& run) {
  return run.energies.at("stretch") + run.energies.at("bend_weak") +
         run.energies.at("bend_strong") + run.energies.at("twist");
}

TEST(Simulation, ParallelMemberLinkageShearsInPlaneAtZeroEnergy) {
  // Paper Figure 2 (top): with all members of each family parallel the grid is a mechanism.
  // Deploy it like the real thing, shearing its corner anchors onto parallelograms with the
  // same sides in steps of 5 degrees, each step starting from the last: the rods rotate about
  // their connections and stay straight, flat and unstressed.
  const int n = 4;
  const double L = 3.0;
  PlanarGrid p = planar_grid(n, L);
  SimulationOptions options;
  options.notches = false;
  // A mechanism only while its supports let the lamellas turn about the normal: held in their
  // directions (the default, anchor_tangents) the corner members cannot shear.
  options.anchor_tangents = false;
  const double EI = options.material.young_modulus * 0.05 * std::pow(0.005, 3) / 12;
  const double scale = options.reference_extent / 20;  // the plate is 20 wide
  // Reference: the bending energy of one member bent into a quarter circle (scaled units).
  const double reference =
      EI * std::pow(scale, 4) * std::pow(std::numbers::pi / 2, 2) / (2 * L * scale);
  DeploymentRun run;
  Vec3 side_h;
  for (int degrees = 5; degrees <= 20; degrees += 5) {
    const double shear = degrees * std::numbers::pi / 180;
    side_h = Vec3(L * std::sin(shear), L * std::cos(shear), 0);  // c0 -> c3, was (0, L)
    // anchors: (g0, h0) c0, (g0, h_last) c1 = (L, 0), (g_last, h_last) c2, (g_last, h0) c3.
    p.anchors[2].position = side_h + Vec3(L, 0, 0);
    p.anchors[3].position = side_h;
    run = simulate_deployment(p.grid, p.anchors, plate(10), 0.05, 0.005, options);
    ASSERT_TRUE(run.converged) << degrees << " degrees: " << run.termination;
    EXPECT_LT(elastic_energy(run), 1e-8 * reference) << degrees << " degrees";
    // The next step starts from this one (the rods are laid on the centerlines, flattened).
    for (size_t l = 0; l < run.lamellas.size(); ++l) {
      Member& m = l < p.grid.g.size() ? p.grid.g[l] : p.grid.h[l - p.grid.g.size()];
      m.surface = run.lamellas[l].centerline;
      for (Vec3& v : m.surface) v.z() = 0;
    }
  }
  for (const SimulatedLamella& l : run.lamellas)
    for (const Vec3& v : l.centerline) EXPECT_NEAR(std::abs(v.z()), 0.0025, 1e-6);
  // The grid really sheared: the top member starts at c3, and every member is straight.
  const SimulatedLamella& top = run.lamellas[n - 1];  // g_{n-1}
  EXPECT_LT((top.centerline.front() - side_h).head<2>().norm(), 1e-6);
  for (const SimulatedLamella& l : run.lamellas) {
    const Vec3 a = l.centerline.front(), b = l.centerline.back();
    for (const Vec3& v : l.centerline)
      EXPECT_LT(((v - a).cross(b - a)).norm() / (b - a).norm(), 1e-6);
  }
  // Control: a grid that is not a mechanism (anchors stretched apart) stores energy.
  PlanarGrid q = planar_grid(n, L);
  q.anchors[2].position = Vec3(L + 0.1, L + 0.1, 0);
  const DeploymentRun stressed =
      simulate_deployment(q.grid, q.anchors, plate(10), 0.05, 0.005, options);
  EXPECT_GT(elastic_energy(stressed), 1e-3 * reference);
}

/// A 3 x 3 grid where member h1 lies at x = 3 on the "surface" but its planar crossing with g1
/// is at s̄ = 2: the connection pulls h1 sideways unless it slides along g1 towards x = 3.
PlanarGrid sliding_grid(double notch_end) {
  PlanarGrid p = planar_grid(3, 4.0);
  p.grid.h[1] = straight_member(Family::H, 1, 3, Vec3(3, 0, 0), Vec3(3, 4, 0));
  for (Crossing& x : p.grid.crossings) {
    if (x.h != 1) continue;
    x.surface_point.x() = 3;
    x.s_g = 3;
    x.s_bar_g = x.on_boundary ? 3 : 2;
    if (!x.on_boundary) x.s_g = notch_end;  // the notch along g1: [s̄, s] = [2, notch_end]
  }
  for (Anchor& a : p.anchors) a.position.z() = 0;
  // Anchor the ends of h1 and of the boundary members so nothing else moves.
  for (const auto& [g, h] : {std::pair{0, 1}, {2, 1}}) {
    Anchor a;
    a.g = g;
    a.h = h;
    a.position = Vec3(3, 4.0 * g / 2, 0);
    a.normal = Vec3::UnitZ();
    p.anchors.push_back(a);
  }
  return p;
}

TEST(Simulation, NotchSlidesTowardsLowerEnergyAndStopsAtItsLimit) {
  SimulationOptions options;
  options.notch_start = SimulationOptions::NotchStart::Planar;  // start at s̄ = 2
  options.friction_mu = 0.01;
  // Short notch [2, 2.4]: the connection wants x = 3, slides and stops at the limit.
  PlanarGrid p = sliding_grid(2.4);
  options.notches = true;
  const DeploymentRun with = simulate_deployment(p.grid, p.anchors, plate(10), 0.1, 0.01, options);
  options.notches = false;
  const DeploymentRun without =
      simulate_deployment(p.grid, p.anchors, plate(10), 0.1, 0.01, options);
  ASSERT_TRUE(with.converged) << with.termination;
  ASSERT_TRUE(without.converged) << without.termination;
  const SimulatedConnection* centre = nullptr;
  for (const SimulatedConnection& c : with.connections)
    if (c.g == 1 && c.h == 1) centre = &c;
  ASSERT_NE(centre, nullptr);
  ASSERT_TRUE(centre->sliding_g);
  EXPECT_NEAR(centre->notch_g, 0.4, 1e-12);
  EXPECT_GT(centre->slide_g, 0.4 - 0.01);  // at the limit (a log barrier keeps it inside)
  EXPECT_LE(centre->slide_g, 0.4);
  EXPECT_LT(elastic_energy(with), 0.8 * elastic_energy(without));

  // Long notch [2, 3.5]: it slides to where h1 is straight (x = 3) and stops there, inside.
  PlanarGrid q = sliding_grid(3.5);
  options.notches = true;
  const DeploymentRun free = simulate_deployment(q.grid, q.anchors, plate(10), 0.1, 0.01, options);
  ASSERT_TRUE(free.converged) << free.termination;
  for (const SimulatedConnection& c : free.connections)
    if (c.g == 1 && c.h == 1) {
      EXPECT_NEAR(c.slide_g, 1.0, 0.05);
    }
  EXPECT_LT(elastic_energy(free), 0.2 * elastic_energy(with));
}

TEST(Simulation, NewtonAndCeresLevenbergMarquardtFindTheSameEquilibrium) {
  // A small bent grid: two corners lifted so the members bend out of plane. Ceres'
  // Levenberg-Marquardt (Gauss-Newton) crawls here too: it stops on its function tolerance
  // near |g| 1e-5 after thousands of iterations, so it is run to 1e-4 and the two equilibria
  // must agree to that accuracy.
  PlanarGrid p = planar_grid(3, 4.0);
  p.anchors[1].position.z() = 0.4;
  p.anchors[3].position.z() = 0.4;
  SimulationOptions options;
  options.notches = false;
  options.gradient_tolerance = 1e-10;
  const DeploymentRun newton =
      simulate_deployment(p.grid, p.anchors, plate(10), 0.1, 0.01, options);
  options.solver = SimulationSolver::Ceres;
  options.gradient_tolerance = 1e-4;
  options.max_iterations = 20000;
  const DeploymentRun ceres = simulate_deployment(p.grid, p.anchors, plate(10), 0.1, 0.01, options);
  ASSERT_TRUE(newton.converged) << newton.termination;
  ASSERT_TRUE(ceres.converged) << ceres.termination;
  EXPECT_LT(10 * newton.iterations, ceres.iterations);
  double largest = 0;
  for (size_t l = 0; l < newton.lamellas.size(); ++l)
    for (size_t v = 0; v < newton.lamellas[l].centerline.size(); ++v)
      largest = std::max(
          largest, (newton.lamellas[l].centerline[v] - ceres.lamellas[l].centerline[v]).norm());
  EXPECT_LT(largest, 2e-3);  // the grid is 4 wide and bends by 0.4
  EXPECT_NEAR(elastic_energy(newton), elastic_energy(ceres), 1e-4 * elastic_energy(ceres));
  auto total = [](const DeploymentRun& run) {
    double sum = 0;
    for (const auto& [term, value] : run.energies) sum += value;
    return sum;
  };
  EXPECT_LE(total(newton), total(ceres) * (1 + 1e-12));  // Newton went further down
}

TEST(Simulation, RejectsInconsistentGridsWithTheField) {
  PlanarGrid p = planar_grid(3, 4.0);
  auto message = [&](const PlanarGrid& q, double width = 0.1) {
    try {
      simulate_deployment(q.grid, q.anchors, plate(10), width, 0.01);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  PlanarGrid bad = p;
  bad.grid.crossings[4].h = 7;
  EXPECT_NE(message(bad).find("crossings"), std::string::npos);
  bad = p;
  bad.anchors[0].h = 5;  // no such crossing
  EXPECT_NE(message(bad).find("anchors"), std::string::npos);
  bad = p;
  bad.grid.g[1].surface[3].x() = std::nan("");
  EXPECT_NE(message(bad).find("non-finite"), std::string::npos);
  EXPECT_NE(message(p, -1.0).find("lamella_width"), std::string::npos);
  bad = p;
  bad.grid.h.resize(1);
  EXPECT_NE(message(bad).find("members"), std::string::npos);
}

// SimulationOptions::compression_stiffness shapes the Gauss-Newton model only: archway without
// notches ends in the same equilibrium with the exact compressive softening and with 3/4 of it
// (the full Hessian ends each run), on another path; with sliding connections the setting is
// not used at all.
/// A design's deployment with the given options.
DeploymentRun simulate_design(const Design& design, const SimulationOptions& options) {
  return simulate_deployment(design.grid, design.anchors, design.target.patch.mesh,
                             design.lamella_width, design.lamella_thickness, options);
}

TEST(Simulation, CompressionStiffnessShapesThePathNotTheEquilibrium) {
  ExampleSurface example = make_example("archway");
  const Design design = make_design(example.mesh, CornerSpec::at_vertices(example.corners), {});
  auto run = [&](bool notches, double scale) {
    SimulationOptions options;
    options.notches = notches;
    options.compression_stiffness = scale;
    return simulate_design(design, options);
  };
  const DeploymentRun exact = run(false, 1.0), softer = run(false, 0.75);
  ASSERT_TRUE(exact.converged) << exact.termination;
  ASSERT_TRUE(softer.converged) << softer.termination;
  EXPECT_NE(exact.iterations, softer.iterations);  // the option reached the solver
  double largest = 0;
  for (size_t l = 0; l < exact.lamellas.size(); ++l)
    for (size_t v = 0; v < exact.lamellas[l].centerline.size(); ++v)
      largest = std::max(
          largest, (softer.lamellas[l].centerline[v] - exact.lamellas[l].centerline[v]).norm());
  EXPECT_LT(largest, 1e-6) << largest;  // the patch is 100 wide
  EXPECT_NEAR(elastic_energy(softer), elastic_energy(exact), 1e-9 * elastic_energy(exact));
  // Notched: the same run whatever the setting.
  const DeploymentRun notched = run(true, 1.0), notched_softer = run(true, 0.75);
  EXPECT_EQ(notched.iterations, notched_softer.iterations);
  EXPECT_EQ(notched.rms, notched_softer.rms);
  EXPECT_THROW(
      {
        try {
          run(false, 1.5);
        } catch (const InvalidInput& e) {
          EXPECT_NE(std::string(e.what()).find("options.compression_stiffness"), std::string::npos)
              << e.what();
          throw;
        }
      },
      InvalidInput);
}

// CHOLMOD (taken for large systems) and the block kernel solve the same Newton systems: with
// the switch forced down to a small example, both modes reach the same equilibrium, and the
// profile says which factorization ran and where the time went.
TEST(Simulation, CholmodAndTheBlockKernelFindTheSameEquilibrium) {
  ExampleSurface example = make_example("archway");
  const Design design = make_design(example.mesh, CornerSpec::at_vertices(example.corners), {});
  auto run = [&](bool notches, int cholmod_from) {
    SimulationOptions options;
    options.notches = notches;
    options.cholmod_from = cholmod_from;
    return simulate_design(design, options);
  };
  for (bool notches : {false, true}) {
    const DeploymentRun block = run(notches, 0), cholmod = run(notches, 1);
    ASSERT_TRUE(block.converged) << block.termination;
    ASSERT_TRUE(cholmod.converged) << cholmod.termination;
    EXPECT_EQ(block.profile.factorization, "block");
    EXPECT_EQ(block.profile.analyses, block.outer_iterations);  // the block kernel: each rebuild
    EXPECT_EQ(cholmod.profile.factorization, "cholmod");
    for (const DeploymentRun* r : {&block, &cholmod}) {
      const SolverProfile& p = r->profile;
      EXPECT_EQ(p.factorizations, r->iterations);  // an iteration is a linear solve
      EXPECT_GE(p.analyses, 1);
      EXPECT_LE(p.analyses, r->outer_iterations);  // one per rebuild at most
      EXPECT_GT(p.evaluations, 0);
      EXPECT_GT(p.unknowns, 0);
      EXPECT_GT(p.factor_nonzeros, p.unknowns);
      EXPECT_GE(p.factorize_seconds, 0);
    }
    double largest = 0;
    for (size_t l = 0; l < block.lamellas.size(); ++l)
      for (size_t v = 0; v < block.lamellas[l].centerline.size(); ++v)
        largest = std::max(
            largest, (cholmod.lamellas[l].centerline[v] - block.lamellas[l].centerline[v]).norm());
    EXPECT_LT(largest, 1e-6) << "notches " << notches;  // the patch is 100 wide
    EXPECT_NEAR(cholmod.rms, block.rms, 1e-7 * block.rms) << "notches " << notches;
  }
}

// The cap counts linear solves, also those of a step that needs several: never exceeded.
TEST(Simulation, IterationCapIsNeverExceeded) {
  PlanarGrid p = planar_grid(3, 4.0);
  p.anchors[2].position.z() = 1;
  for (int cap : {1, 2, 3, 5}) {
    SimulationOptions options;
    options.max_iterations = cap;
    const DeploymentRun run = simulate_deployment(p.grid, p.anchors, plate(10), 0.1, 0.01, options);
    EXPECT_LE(run.iterations, cap);
    EXPECT_FALSE(run.converged);
    EXPECT_NE(run.termination.find("iteration cap"), std::string::npos) << run.termination;
  }
}

TEST(Simulation, CancellationStopsTheSolve) {
  PlanarGrid p = planar_grid(3, 4.0);
  p.anchors[2].position.z() = 1;
  std::atomic<bool> cancel{true};
  EXPECT_THROW(
      simulate_deployment(p.grid, p.anchors, plate(10), 0.1, 0.01, {}, Progress(nullptr, &cancel)),
      Cancelled);
}

// A connection that the grid pulls into a vertex of its rod from both sides: along the member
// the energy has a kink there (the nearest point of a bent polyline to the partner is the
// vertex) and no smooth equilibrium exists. With one rod edge per interval torus-wide has one;
// before connections were held at such vertices the steps cycled over it until the iteration
// cap (2000 iterations, |g| 0.2). Held, the run converges (the solver accepts the hold only
// where the one-sided derivatives at the vertex both point uphill), and each held end sits
// exactly at a vertex of its rod.
TEST(Simulation, ConnectionPulledIntoARodVertexIsHeldThere) {
  ExampleSurface example = make_example("torus-wide");
  const Design design = make_design(example.mesh, CornerSpec::at_vertices(example.corners), {});
  SimulationOptions options;
  options.notches = true;
  options.edges_per_interval = 1;
  options.max_iterations = 600;
  // The equilibrium with the kink is the one reached with anchors free to turn about their
  // normals; held in direction (the default) torus-wide settles with no end at a vertex.
  options.anchor_tangents = false;
  const DeploymentRun run =
      simulate_deployment(design.grid, design.anchors, design.target.patch.mesh,
                          design.lamella_width, design.lamella_thickness, options);
  EXPECT_TRUE(run.converged) << run.termination;
  EXPECT_LE(run.gradient_norm, options.gradient_tolerance);
  ASSERT_GE(run.connections_at_vertices, 1) << run.termination;
  int flagged = 0;
  for (const SimulatedConnection& c : run.connections)
    for (const bool on_g : {true, false}) {
      if (!(on_g ? c.at_vertex_g : c.at_vertex_h)) continue;
      ++flagged;
      const Member& member = on_g ? design.grid.g[c.g] : design.grid.h[c.h];
      const SimulatedLamella& rod =
          run.lamellas[on_g ? c.g : static_cast<int>(design.grid.g.size()) + c.h];
      const int edges = static_cast<int>(rod.centerline.size()) - 1;
      const Crossing* crossing = nullptr;
      for (const Crossing& x : design.grid.crossings)
        if (x.g == c.g && x.h == c.h) crossing = &x;
      ASSERT_NE(crossing, nullptr);
      EXPECT_TRUE(on_g ? c.sliding_g : c.sliding_h);
      const double at =
          ((on_g ? crossing->s_bar_g : crossing->s_bar_h) + (on_g ? c.slide_g : c.slide_h)) /
          (member.planar_length / edges);
      EXPECT_NEAR(at, std::round(at), 1e-9) << "held end not at a rod vertex";
      // Inside its notch.
      const double slide = on_g ? c.slide_g : c.slide_h, notch = on_g ? c.notch_g : c.notch_h;
      EXPECT_GT(slide * notch, 0);
      EXPECT_LT(std::abs(slide), std::abs(notch));
    }
  EXPECT_EQ(flagged, run.connections_at_vertices);
}

// Anchors hold the lamellas' directions as well as their normals (issue 18: a support's
// inclined contact area fixes the lamella's orientation). Without that, each anchored lamella
// may turn about the surface normal at its support, and the boundary members of a doubly
// curved patch swing away between the anchors: double-vault deploys measurably closer to its
// target with the directions held, and the anchored lamellas keep the geodesics' directions.
TEST(Simulation, AnchorsHoldingTheLamellasDirectionsBringTheGridCloserToTheTarget) {
  const ExampleSurface example = make_example("double-vault");
  const Design design = make_design(example.mesh, CornerSpec::at_vertices(example.corners), {});
  SimulationOptions options;
  options.anchor_tangents = false;
  const DeploymentRun free_direction =
      simulate_deployment(design.grid, design.anchors, design.target.patch.mesh,
                          design.lamella_width, design.lamella_thickness, options);
  options.anchor_tangents = true;
  const DeploymentRun held =
      simulate_deployment(design.grid, design.anchors, design.target.patch.mesh,
                          design.lamella_width, design.lamella_thickness, options);
  ASSERT_TRUE(free_direction.converged) << free_direction.termination;
  ASSERT_TRUE(held.converged) << held.termination;
  EXPECT_LT(held.rms, 0.95 * free_direction.rms);
}

// `--interior-anchors auto` (issue 18): held at its boundary only, waves-bump snaps into a dome
// (RMS2 3.3); inner anchors are added one at a time at the crossing deployed farthest from the
// target while each lowers the RMS by 5% or more. The first lands on the bump and keeps the
// waves; the search stops at the first anchor that does not help enough, which is not kept.
TEST(Simulation, AutomaticInnerAnchorsKeepWavesBumpFromSnappingIntoADome) {
  const ExampleSurface example = make_example("waves-bump");
  const Design design = make_design(example.mesh, CornerSpec::at_vertices(example.corners), {});
  SimulationOptions options;
  options.notches = true;
  std::atomic<int> reports{0};
  double last = -1;
  bool monotone = true;
  const Progress progress([&](std::string_view, double f) {
    monotone = monotone && f >= last - 1e-12 && f <= 1;
    last = f;
    ++reports;
  });
  const AutoAnchorResult result =
      auto_interior_anchors(design.grid, design.anchors, design.target.patch.mesh,
                            design.lamella_width, design.lamella_thickness, options, {}, progress);
  std::printf("  RMS2 per trial:");
  for (double r : result.rms_trials) std::printf(" %.3f", r);
  std::printf(" (%d inner anchors kept)\n", result.added);
  ASSERT_GE(result.added, 1);
  ASSERT_EQ(result.anchors.size(), design.anchors.size() + result.added);
  ASSERT_GE(result.rms_trials.size(), static_cast<size_t>(result.added + 1));
  const double boundary_only = result.rms_trials.front();
  EXPECT_GT(boundary_only, 2.0);   // the dome
  EXPECT_LT(result.run.rms, 0.5);  // the waves kept (0.29 with one anchor at the bump)
  EXPECT_EQ(result.run.rms, result.rms_trials[result.added]);
  for (int k = 1; k <= result.added; ++k)  // each kept anchor helped by 5% or more
    EXPECT_LE(result.rms_trials[k], 0.95 * result.rms_trials[k - 1]) << k;
  if (result.added < AutoAnchorOptions{}.max_anchors) {  // stopped by the rule
    ASSERT_EQ(result.rms_trials.size(), static_cast<size_t>(result.added + 2));
    EXPECT_GT(result.rms_trials.back(), 0.95 * result.run.rms);
  }
  const int ng = static_cast<int>(design.grid.g.size()),
            nh = static_cast<int>(design.grid.h.size());
  for (size_t k = design.anchors.size(); k < result.anchors.size(); ++k) {
    const Anchor& a = result.anchors[k];
    EXPECT_TRUE(a.g > 0 && a.g < ng - 1 && a.h > 0 && a.h < nh - 1) << "inner";
    EXPECT_EQ(a.side, -1);
    EXPECT_NEAR(a.normal.norm(), 1.0, 1e-12);
  }
  EXPECT_TRUE(monotone);
  EXPECT_GT(reports.load(), 2);
  EXPECT_EQ(last, 1.0);
  // A goal: no anchor when the design's anchors already reach it, and no trial past it.
  AutoAnchorOptions goal;
  goal.goal_rms = 1.01 * boundary_only;
  const AutoAnchorResult none =
      auto_interior_anchors(design.grid, design.anchors, design.target.patch.mesh,
                            design.lamella_width, design.lamella_thickness, options, goal);
  EXPECT_EQ(none.added, 0);
  EXPECT_EQ(none.anchors.size(), design.anchors.size());
  ASSERT_EQ(none.rms_trials.size(), 1u);
  EXPECT_NEAR(none.run.rms, boundary_only, 1e-9 * boundary_only);
  goal.goal_rms = 1.01 * result.rms_trials[1];  // reached with the first anchor
  const AutoAnchorResult one =
      auto_interior_anchors(design.grid, design.anchors, design.target.patch.mesh,
                            design.lamella_width, design.lamella_thickness, options, goal);
  EXPECT_EQ(one.added, 1);
  ASSERT_EQ(one.rms_trials.size(), 2u);
  EXPECT_NEAR(one.run.rms, result.rms_trials[1], 1e-9 * result.rms_trials[1]);
  EXPECT_EQ(one.anchors.back().g, result.anchors[design.anchors.size()].g);
  EXPECT_EQ(one.anchors.back().h, result.anchors[design.anchors.size()].h);
  // Cancelled: stops with Cancelled, not a partial answer.
  std::atomic<bool> cancel{true};
  EXPECT_THROW(auto_interior_anchors(design.grid, design.anchors, design.target.patch.mesh,
                                     design.lamella_width, design.lamella_thickness, options, {},
                                     Progress(nullptr, &cancel)),
               Cancelled);
}

// The paper-like examples (Table 1) and the shared meshes: converged without and with notches,
// and notches bring the grid closer to the target. waves-bump is the exception, documented in
// docs/decisions.md ("Deployment simulation"): held only at its boundary, the grid does not
// keep the waves and pops into a dome with or without notches; there the test checks
// convergence only. With one inner anchor at its bump (AnchorOptions::interior, the remedy the
// paper's Section 7 suggests) it keeps its shape and the notches help again. enneper2 (a
// saddle) is infeasible with its grid corners (Design.EnneperSaddleIsInfeasibleWithAClearReason);
// an inner patch with lamellas of 0.05 (the default 1% of its side fits fewer than three
// members) deploys within 0.03-0.07 of it, and there the notches do not help at every ᾱ
// (docs/decisions.md): convergence only.
struct Case {
  std::string name;
  bool notches_help = true;
  int interior_anchors = 0;
  std::vector<int> corner_vertices = {};  ///< empty: the example's corners, or auto for a mesh
  double lamella_width = 0;               ///< 0: automatic
  std::string label() const {
    return interior_anchors ? name + "+" + std::to_string(interior_anchors) + "inner" : name;
  }
};

void PrintTo(const Case& c, std::ostream* out) { *out << c.label(); }

class ExampleDeployment : public ::testing::TestWithParam<Case> {};

TEST_P(ExampleDeployment, ConvergesAndNotchesReduceTheDeviation) {
  const Case c = GetParam();
  TriangleMesh mesh;
  CornerSpec corners;
  if (c.name.rfind("mesh:", 0) == 0) {
    mesh = load_mesh(testing::test_mesh_path(c.name.substr(5)));
    corners.kind = CornerSpec::Kind::Auto;
    if (!c.corner_vertices.empty())
      corners = CornerSpec::at_vertices(
          {c.corner_vertices[0], c.corner_vertices[1], c.corner_vertices[2], c.corner_vertices[3]});
  } else {
    ExampleSurface example = make_example(c.name);
    mesh = std::move(example.mesh);
    corners = CornerSpec::at_vertices(example.corners);
  }
  DesignOptions design_options;
  design_options.anchors.interior = c.interior_anchors;
  design_options.members.lamella_width = c.lamella_width;
  const Design design = make_design(mesh, corners, design_options);
  SimulationOptions options;
  options.notches = false;
  const DeploymentRun without =
      simulate_deployment(design.grid, design.anchors, design.target.patch.mesh,
                          design.lamella_width, design.lamella_thickness, options);
  options.notches = true;
  const DeploymentRun with =
      simulate_deployment(design.grid, design.anchors, design.target.patch.mesh,
                          design.lamella_width, design.lamella_thickness, options);
  EXPECT_TRUE(without.converged) << without.termination;
  EXPECT_TRUE(with.converged) << with.termination;
  EXPECT_LE(without.gradient_norm, options.gradient_tolerance);
  EXPECT_LE(with.gradient_norm, options.gradient_tolerance);
  EXPECT_LT(without.iterations, options.max_iterations);
  EXPECT_LT(with.iterations, options.max_iterations);
  if (c.notches_help) {
    EXPECT_LT(with.rms, without.rms);
  }
  // Connections stay closed: gaps far below the lamella thickness.
  for (const SimulatedConnection& x : with.connections)
    EXPECT_LT(x.gap, 0.01 * design.lamella_thickness);
}

INSTANTIATE_TEST_SUITE_P(
    PaperExamplesAndSharedMeshes, ExampleDeployment,
    ::testing::Values(Case{"double-vault"}, Case{"sphere"}, Case{"archway"}, Case{"triple-vault"},
                      Case{"waves"}, Case{"torus-wide"}, Case{"waves-bump", false},
                      Case{"waves-bump", true, 1}, Case{"mesh:knet1.obj"},
                      Case{"mesh:pillow_1.obj"},
                      Case{"mesh:enneper2.obj", false, 0, {100, 130, 860, 830}, 0.05}),
    [](const ::testing::TestParamInfo<Case>& info) {
      std::string name = info.param.label();
      for (char& ch : name)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      return name;
    });

}  // namespace
}  // namespace gridshell
