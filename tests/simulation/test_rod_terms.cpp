// SPDX-License-Identifier: GPL-3.0-or-later
// The residual blocks of the deployment simulation (kernel/simulation/rod_terms.h): Jacobians
// against central finite differences, and the discrete elastic rod against closed forms.
#include <ceres/autodiff_cost_function.h>
#include <ceres/dynamic_autodiff_cost_function.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "newton_solver.h"
#include "rod_derivatives.h"
#include "rod_terms.h"

namespace gridshell {
namespace {

using rod_terms::EdgeReference;
using Vec3 = Eigen::Vector3d;

/// Compares the automatic Jacobian of `cost` at `parameters` with central differences.
void expect_jacobian_matches_differences(const ceres::CostFunction& cost,
                                         std::vector<std::vector<double>> parameters) {
  const auto& sizes = cost.parameter_block_sizes();
  ASSERT_EQ(sizes.size(), parameters.size());
  const int R = cost.num_residuals();
  std::vector<double*> pointers;
  std::vector<std::vector<double>> jacobians(sizes.size());
  std::vector<double*> jacobian_pointers;
  for (size_t p = 0; p < sizes.size(); ++p) {
    ASSERT_EQ(static_cast<int>(parameters[p].size()), sizes[p]);
    pointers.push_back(parameters[p].data());
    jacobians[p].assign(static_cast<size_t>(R) * sizes[p], 0.0);
    jacobian_pointers.push_back(jacobians[p].data());
  }
  std::vector<double> r(R), plus(R), minus(R);
  ASSERT_TRUE(cost.Evaluate(pointers.data(), r.data(), jacobian_pointers.data()));
  double largest = 0;
  for (const auto& j : jacobians)
    for (double v : j) largest = std::max(largest, std::abs(v));
  for (size_t p = 0; p < sizes.size(); ++p)
    for (int c = 0; c < sizes[p]; ++c) {
      double& x = parameters[p][c];
      const double keep = x, h = 1e-6 * std::max(1.0, std::abs(keep));
      x = keep + h;
      ASSERT_TRUE(cost.Evaluate(pointers.data(), plus.data(), nullptr));
      x = keep - h;
      ASSERT_TRUE(cost.Evaluate(pointers.data(), minus.data(), nullptr));
      x = keep;
      for (int i = 0; i < R; ++i) {
        const double numeric = (plus[i] - minus[i]) / (2 * h);
        const double automatic = jacobians[p][i * sizes[p] + c];
        EXPECT_NEAR(automatic, numeric, 1e-6 * std::max(1.0, largest))
            << "residual " << i << ", parameter block " << p << ", coordinate " << c;
      }
    }
}

std::vector<double> v3(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

/// A reference frame near the edge a -> b (as after a frame update a few steps ago).
EdgeReference reference_near(const Vec3& a, const Vec3& b, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 0.05);
  EdgeReference ref;
  ref.tangent = ((b - a).normalized() + Vec3(n(rng), n(rng), n(rng))).normalized();
  Vec3 d = Vec3(n(rng), n(rng), n(rng)) + ref.tangent.unitOrthogonal();
  ref.d1 = (d - d.dot(ref.tangent) * ref.tangent).normalized();
  return ref;
}

Vec3 random_vector(std::mt19937& rng, double scale = 1) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return Vec3(u(rng), u(rng), u(rng));
}

TEST(RodTermJacobian, Stretch) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 5; ++trial) {
    const Vec3 a = random_vector(rng), b = a + Vec3(1, 0.2, -0.3) + random_vector(rng, 0.2);
    ceres::AutoDiffCostFunction<rod_terms::Stretch, 1, 3, 3> cost(new rod_terms::Stretch{7.5, 1.1});
    expect_jacobian_matches_differences(cost, {v3(a), v3(b)});
  }
}

TEST(RodTermJacobian, BendTwist) {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 5; ++trial) {
    const Vec3 x0 = random_vector(rng), x1 = x0 + Vec3(1, 0, 0) + random_vector(rng, 0.3),
               x2 = x1 + Vec3(1, 0.2, 0) + random_vector(rng, 0.3);
    const EdgeReference r0 = reference_near(x0, x1, rng), r1 = reference_near(x1, x2, rng);
    ceres::AutoDiffCostFunction<rod_terms::BendTwist, 3, 3, 3, 3, 1, 1> cost(
        new rod_terms::BendTwist{&r0, &r1, 1.3, 4.0, 0.7});
    expect_jacobian_matches_differences(cost, {v3(x0), v3(x1), v3(x2), {0.3}, {-0.2}});
  }
}

/// The residuals and Jacobians of two cost functions at the same parameters agree to `tolerance`
/// relative to the largest Jacobian entry.
void expect_same_jacobians(const ceres::CostFunction& a, const ceres::CostFunction& b,
                           std::vector<std::vector<double>> parameters, double tolerance) {
  const auto& sizes = a.parameter_block_sizes();
  ASSERT_EQ(sizes, b.parameter_block_sizes());
  ASSERT_EQ(a.num_residuals(), b.num_residuals());
  const int R = a.num_residuals();
  std::vector<double*> pointers;
  std::vector<std::vector<double>> ja(sizes.size()), jb(sizes.size());
  std::vector<double*> pa, pb;
  for (size_t p = 0; p < sizes.size(); ++p) {
    pointers.push_back(parameters[p].data());
    ja[p].assign(static_cast<size_t>(R) * sizes[p], 0.0);
    jb[p].assign(static_cast<size_t>(R) * sizes[p], 0.0);
    pa.push_back(ja[p].data());
    pb.push_back(jb[p].data());
  }
  std::vector<double> ra(R), rb(R);
  ASSERT_TRUE(a.Evaluate(pointers.data(), ra.data(), pa.data()));
  ASSERT_TRUE(b.Evaluate(pointers.data(), rb.data(), pb.data()));
  double largest = 0, largest_r = 0;
  for (const auto& j : ja)
    for (double v : j) largest = std::max(largest, std::abs(v));
  for (double v : ra) largest_r = std::max(largest_r, std::abs(v));
  for (int i = 0; i < R; ++i) EXPECT_NEAR(ra[i], rb[i], tolerance * std::max(1.0, largest_r));
  for (size_t p = 0; p < sizes.size(); ++p)
    for (size_t k = 0; k < ja[p].size(); ++k)
      EXPECT_NEAR(ja[p][k], jb[p][k], tolerance * std::max(1.0, largest))
          << "parameter block " << p << ", entry " << k;
}

// The hand-derived Jacobians (rod_derivatives.h) against the automatic ones of the same
// functors and against central differences, on bent, twisted edges with references that lag
// behind the edges (as between frame updates), where the parallel transport's dependence on the
// current tangent matters.
TEST(RodTermAnalyticJacobian, StretchMatchesAutomaticAndDifferences) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    const Vec3 a = random_vector(rng), b = a + Vec3(1, 0.2, -0.3) + random_vector(rng, 0.4);
    const rod_terms::Stretch term{7.5, 1.1};
    ceres::AutoDiffCostFunction<rod_terms::Stretch, 1, 3, 3> automatic(
        new rod_terms::Stretch(term));
    rod_terms::StretchCost analytic(term);
    expect_same_jacobians(analytic, automatic, {v3(a), v3(b)}, 1e-12);
    expect_jacobian_matches_differences(analytic, {v3(a), v3(b)});
  }
}

TEST(RodTermAnalyticJacobian, BendTwistMatchesAutomaticAndDifferences) {
  std::mt19937 rng(12);
  for (int trial = 0; trial < 20; ++trial) {
    // Strongly bent (up to ~100 degrees between the edges) and references up to ~30 degrees off.
    const Vec3 x0 = random_vector(rng), x1 = x0 + Vec3(1, 0, 0) + random_vector(rng, 0.5),
               x2 = x1 + Vec3(0.6, 0.7, 0) + random_vector(rng, 0.6);
    std::normal_distribution<double> n(0, 0.3);
    auto lagging = [&](const Vec3& a, const Vec3& b) {
      EdgeReference ref;
      ref.tangent = ((b - a).normalized() + Vec3(n(rng), n(rng), n(rng))).normalized();
      const Vec3 d = Vec3(n(rng), n(rng), n(rng)) + ref.tangent.unitOrthogonal();
      ref.d1 = (d - d.dot(ref.tangent) * ref.tangent).normalized();
      return ref;
    };
    const EdgeReference r0 = lagging(x0, x1), r1 = lagging(x1, x2);
    const double previous = trial % 2 ? 2 * std::numbers::pi + 0.1 * trial : 0.0;
    const rod_terms::BendTwist term{&r0, &r1, 1.3, 4.0, 0.7, trial % 2 ? &previous : nullptr};
    ceres::AutoDiffCostFunction<rod_terms::BendTwist, 3, 3, 3, 3, 1, 1> automatic(
        new rod_terms::BendTwist(term));
    rod_terms::BendTwistCost analytic(term);
    std::uniform_real_distribution<double> angle(-3, 3);
    const std::vector<std::vector<double>> parameters{
        v3(x0), v3(x1), v3(x2), {angle(rng)}, {angle(rng)}};
    expect_same_jacobians(analytic, automatic, parameters, 1e-11);
    expect_jacobian_matches_differences(analytic, parameters);
  }
}

TEST(RodTermAnalyticJacobian, AnchorTangentMatchesAutomaticAndDifferences) {
  std::mt19937 rng(13);
  for (int trial = 0; trial < 5; ++trial) {
    const Vec3 a = random_vector(rng), b = a + Vec3(1, 0.2, -0.3) + random_vector(rng, 0.4);
    const rod_terms::AnchorTangent term{Vec3(0.1, 1, 0.2).normalized(), 3.5};
    ceres::AutoDiffCostFunction<rod_terms::AnchorTangent, 1, 3, 3> automatic(
        new rod_terms::AnchorTangent(term));
    rod_terms::AnchorTangentCost analytic(term);
    expect_same_jacobians(analytic, automatic, {v3(a), v3(b)}, 1e-12);
    expect_jacobian_matches_differences(analytic, {v3(a), v3(b)});
  }
}

/// Parameters of one member at a connection: edge (x_a, x_b), theta, beta [, neighbour].
struct MemberSetup {
  std::vector<std::vector<double>> parameters;
  EdgeReference ref, neighbour;
  rod_terms::MemberEdge edge;
};

MemberSetup member_setup(std::mt19937& rng, const Vec3& origin, const Vec3& direction, int side,
                         double beta) {
  MemberSetup m;
  const Vec3 a = origin, b = origin + direction + random_vector(rng, 0.1);
  m.ref = reference_near(a, b, rng);
  m.parameters = {v3(a), v3(b), {0.1}, {beta}};
  m.edge.ref = &m.ref;
  if (side != 0) {
    const Vec3 n = side > 0 ? Vec3(b + direction + random_vector(rng, 0.2))
                            : Vec3(a - direction + random_vector(rng, 0.2));
    m.neighbour = side > 0 ? reference_near(b, n, rng) : reference_near(n, a, rng);
    m.parameters.push_back(v3(n));
    m.parameters.push_back({-0.15});
    m.edge.neighbour = &m.neighbour;
    m.edge.side = side;
  }
  return m;
}

template <typename Residual, int G, int H>
void check_pair(Residual residual, MemberSetup& g, MemberSetup& h) {
  residual.g = g.edge;
  residual.h = h.edge;
  std::vector<std::vector<double>> parameters = g.parameters;
  parameters.insert(parameters.end(), h.parameters.begin(), h.parameters.end());
  using Functor = rod_terms::PairFunctor<Residual, G, H>;
  constexpr int R = Residual::kResiduals;
  std::unique_ptr<ceres::CostFunction> cost;
  if constexpr (G == 4 && H == 4)
    cost.reset(
        new ceres::AutoDiffCostFunction<Functor, R, 3, 3, 1, 1, 3, 3, 1, 1>(new Functor{residual}));
  else if constexpr (G == 6 && H == 4)
    cost.reset(new ceres::AutoDiffCostFunction<Functor, R, 3, 3, 1, 1, 3, 1, 3, 3, 1, 1>(
        new Functor{residual}));
  else if constexpr (G == 4 && H == 6)
    cost.reset(new ceres::AutoDiffCostFunction<Functor, R, 3, 3, 1, 1, 3, 3, 1, 1, 3, 1>(
        new Functor{residual}));
  else
    cost.reset(new ceres::AutoDiffCostFunction<Functor, R, 3, 3, 1, 1, 3, 1, 3, 3, 1, 1, 3, 1>(
        new Functor{residual}));
  expect_jacobian_matches_differences(*cost, parameters);
  // The hand-derived Jacobian (rod_derivatives.h) against the automatic one and differences.
  const rod_terms::PairCost<Residual> analytic(residual);
  expect_same_jacobians(analytic, *cost, parameters, 1e-11);
  expect_jacobian_matches_differences(analytic, parameters);
}

TEST(RodTermJacobian, ConnectionWithAndWithoutNeighbourEdges) {
  std::mt19937 rng(3);
  rod_terms::ConnectionResidual connection;
  connection.thickness = 0.1;
  connection.sqrt_position = 3;
  connection.sqrt_direction = 2;
  // beta away from 1/2, where the normal's blending has its kink.
  MemberSetup g4 = member_setup(rng, Vec3(0, 0, 0), Vec3(1, 0, 0), 0, 0.3);
  MemberSetup h4 = member_setup(rng, Vec3(0.3, -0.5, 0.1), Vec3(0, 1, 0), 0, 0.45);
  MemberSetup g6 = member_setup(rng, Vec3(0, 0, 0), Vec3(1, 0, 0), +1, 0.8);
  MemberSetup h6 = member_setup(rng, Vec3(0.3, -0.5, 0.1), Vec3(0, 1, 0), -1, 0.2);
  check_pair<rod_terms::ConnectionResidual, 4, 4>(connection, g4, h4);
  check_pair<rod_terms::ConnectionResidual, 6, 4>(connection, g6, h4);
  check_pair<rod_terms::ConnectionResidual, 4, 6>(connection, g4, h6);
  check_pair<rod_terms::ConnectionResidual, 6, 6>(connection, g6, h6);
}

TEST(RodTermJacobian, Anchor) {
  std::mt19937 rng(4);
  rod_terms::AnchorResidual anchor;
  anchor.position = Vec3(0.2, 0.1, 0.3);
  anchor.normal = Vec3(0.1, 0.2, 1).normalized();
  anchor.thickness = 0.1;
  anchor.sqrt_position = 2;
  anchor.sqrt_direction = 5;
  MemberSetup g = member_setup(rng, Vec3(0, 0, 0), Vec3(1, 0, 0), +1, 0.9);
  MemberSetup h = member_setup(rng, Vec3(0.3, -0.5, 0.1), Vec3(0, 1, 0), 0, 0.0);
  check_pair<rod_terms::AnchorResidual, 6, 4>(anchor, g, h);
  MemberSetup g4 = member_setup(rng, Vec3(0, 0, 0), Vec3(1, 0, 0), 0, 0.4);
  MemberSetup h6 = member_setup(rng, Vec3(0.3, -0.5, 0.1), Vec3(0, 1, 0), -1, 0.3);
  check_pair<rod_terms::AnchorResidual, 4, 6>(anchor, g4, h6);
}

TEST(RodTermJacobian, FrictionAndNotchLimit) {
  for (double beta : {0.01, 0.3, 0.77, 0.999}) {
    ceres::AutoDiffCostFunction<rod_terms::Friction, 2, 1> friction(
        new rod_terms::Friction{0.1, 1e-4});
    expect_jacobian_matches_differences(friction, {{beta}});
  }
  ceres::AutoDiffCostFunction<rod_terms::NotchLimit, 1, 1> lower(
      new rod_terms::NotchLimit{0.2, false, 0.1});
  expect_jacobian_matches_differences(lower, {{0.35}});
  ceres::AutoDiffCostFunction<rod_terms::NotchLimit, 1, 1> upper(
      new rod_terms::NotchLimit{0.6, true, 0.1});
  expect_jacobian_matches_differences(upper, {{0.35}});
  // Beyond their domain the barriers refuse to evaluate (the solver rejects such a step).
  double r[2], beta = 0.7;
  const double* p[] = {&beta};
  EXPECT_FALSE(upper.Evaluate(p, r, nullptr));
  beta = 0.1;
  EXPECT_FALSE(lower.Evaluate(p, r, nullptr));
  EXPECT_TRUE(upper.Evaluate(p, r, nullptr));
  beta = -0.1;
  ceres::AutoDiffCostFunction<rod_terms::Friction, 2, 1> friction(
      new rod_terms::Friction{0.1, 1e-4});
  EXPECT_FALSE(friction.Evaluate(p, r, nullptr));
  beta = -0.5e-4;  // within eps past the edge's end: still defined
  EXPECT_TRUE(friction.Evaluate(p, r, nullptr));
}

// ---------------------------------------------------------------------------------------------
// One discrete elastic rod, solved with the simulation's Newton solver.

struct Section {
  double EA = 1e4, EI_weak = 1, EI_strong = 100, GJ = 0.8;
};

struct RodFixture {
  std::vector<Vec3> x;
  std::vector<double> theta;
  std::vector<EdgeReference> ref;
  double h = 1;
  Section k;
  std::vector<std::unique_ptr<ceres::CostFunction>> owned;
  std::vector<NewtonSolver::Term> terms;

  /// A rod through `points` with reference directors `directors` (projected) and theta = 0.
  RodFixture(std::vector<Vec3> points, const std::vector<Vec3>& directors, double rest_length,
             Section section)
      : x(std::move(points)), h(rest_length), k(section) {
    for (size_t e = 0; e + 1 < x.size(); ++e) {
      EdgeReference r;
      r.tangent = (x[e + 1] - x[e]).normalized();
      const Vec3 d = directors[e];
      r.d1 = (d - d.dot(r.tangent) * r.tangent).normalized();
      ref.push_back(r);
      theta.push_back(0.0);
    }
    const int n = static_cast<int>(theta.size());
    for (int e = 0; e < n; ++e) {
      owned.emplace_back(new ceres::AutoDiffCostFunction<rod_terms::Stretch, 1, 3, 3>(
          new rod_terms::Stretch{std::sqrt(k.EA / h), h}));
      terms.push_back({owned.back().get(), {x[e].data(), x[e + 1].data()}, nullptr, true});
    }
    for (int v = 1; v < n; ++v) {
      owned.emplace_back(new ceres::AutoDiffCostFunction<rod_terms::BendTwist, 3, 3, 3, 3, 1, 1>(
          new rod_terms::BendTwist{&ref[v - 1], &ref[v], std::sqrt(k.EI_weak / h),
                                   std::sqrt(k.EI_strong / h), std::sqrt(k.GJ / h)}));
      terms.push_back({owned.back().get(),
                       {x[v - 1].data(), x[v].data(), x[v + 1].data(), &theta[v - 1], &theta[v]},
                       nullptr,
                       true});
    }
  }

  /// Energy, and gradient max-norm with respect to `free` blocks.
  double energy(std::vector<std::pair<double*, int>> free, double* gradient = nullptr) {
    NewtonSolver solver(free, terms, {});
    EXPECT_TRUE(solver.evaluate());
    if (gradient) *gradient = solver.gradient_max_norm();
    return solver.cost();
  }

  /// Every vertex and twist free except the first and last edge (clamped).
  std::vector<std::pair<double*, int>> interior() {
    std::vector<std::pair<double*, int>> free;
    for (size_t v = 2; v + 2 < x.size(); ++v) free.emplace_back(x[v].data(), 3);
    for (size_t e = 1; e + 1 < theta.size(); ++e) free.emplace_back(&theta[e], 1);
    return free;
  }

  /// Minimizes over `free` with frame updates between steps, until the gradient vanishes.
  void solve(std::vector<std::pair<double*, int>> free) {
    NewtonSolver solver(free, terms, {});
    solver.set_exact_hessian(true);
    for (int it = 0; it < 200; ++it) {
      ASSERT_TRUE(solver.evaluate());
      if (solver.gradient_max_norm() < 1e-9) return;
      ASSERT_TRUE(solver.step().accepted);
      for (size_t e = 0; e < ref.size(); ++e) {  // time-parallel transport of the references
        const Vec3 t = (x[e + 1] - x[e]).normalized();
        const Vec3 d1 = rod_terms::transport<double>(ref[e].tangent, t, ref[e].d1);
        ref[e].tangent = t;
        ref[e].d1 = d1;
      }
    }
    FAIL() << "no convergence";
  }
};

std::vector<std::pair<double*, int>> all_blocks(RodFixture& rod) {
  std::vector<std::pair<double*, int>> free;
  for (Vec3& v : rod.x) free.emplace_back(v.data(), 3);
  for (double& t : rod.theta) free.emplace_back(&t, 1);
  return free;
}

TEST(DiscreteRod, StraightAtRestAndUnderRigidMotionsHasZeroEnergyAndGradient) {
  std::mt19937 rng(5);
  const Vec3 direction = Vec3(1, 2, -0.5).normalized();
  std::vector<Vec3> points, directors;
  for (int v = 0; v <= 12; ++v) points.push_back(Vec3(0.3, -1, 2) + 0.5 * v * direction);
  for (int e = 0; e < 12; ++e) directors.push_back(Vec3(0, 0, 1));
  RodFixture rod(points, directors, 0.5, {});
  double gradient = 1;
  EXPECT_NEAR(rod.energy(all_blocks(rod), &gradient), 0.0, 1e-24);
  EXPECT_LT(gradient, 1e-10);
  // A rigid motion of the vertices and of the frames.
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.8, Vec3(0.2, -1, 0.4).normalized()).toRotationMatrix();
  const Vec3 shift(5, -2, 1);
  for (Vec3& v : rod.x) v = R * v + shift;
  for (EdgeReference& r : rod.ref) {
    r.tangent = R * r.tangent;
    r.d1 = R * r.d1;
  }
  EXPECT_NEAR(rod.energy(all_blocks(rod), &gradient), 0.0, 1e-20);
  EXPECT_LT(gradient, 1e-9);
  // A bent rod is not at rest: the test can fail.
  rod.x[6] += 0.05 * R * Vec3(0, 0, 1);
  EXPECT_GT(rod.energy(all_blocks(rod), &gradient), 1e-4);
}

TEST(DiscreteRod, ClampedIntoACircularArcHasTheArcsEnergyAndShape) {
  // n edges of length h on a circle; the first and last edge are clamped, the vertices between
  // start perturbed. The rod bends over the n - 1 Voronoi cells between the clamped edges:
  // L = (n - 1) h, total turning phi, so E = EI phi^2 / (2 L) (weak axis: the material normal
  // lies in the arc's plane).
  const int n = 40;
  const double phi = 1.2, h = 0.25;
  const double alpha = phi / (n - 1);              // turning per interior vertex
  const double R = h / (2 * std::sin(alpha / 2));  // circumradius of the polygon
  std::vector<Vec3> points, directors;
  for (int v = 0; v <= n; ++v) {
    const double a = (v - n / 2.0) * alpha;
    points.push_back(R * Vec3(std::sin(a), 1 - std::cos(a), 0));
  }
  for (int e = 0; e < n; ++e) {
    const Vec3 mid = 0.5 * (points[e] + points[e + 1]);
    directors.push_back(Vec3(0, R, 0) - mid);  // towards the centre: in the arc's plane
  }
  std::mt19937 rng(6);
  std::vector<Vec3> start = points;
  for (int v = 2; v <= n - 2; ++v) start[v] += random_vector(rng, 0.02 * h);
  Section section;
  RodFixture rod(start, directors, h, section);
  rod.solve(rod.interior());
  const double energy = rod.energy(rod.interior());
  const double L = (n - 1) * h;
  EXPECT_NEAR(energy, section.EI_weak * phi * phi / (2 * L), 0.005 * energy);
  for (const Vec3& p : rod.x) EXPECT_NEAR((p - Vec3(0, R, 0)).norm(), R, 0.005 * R);
}

TEST(DiscreteRod, ClampedAndTwistedHasTorsionEnergy) {
  const int n = 30;
  const double h = 0.2, phi = 1.5;
  std::vector<Vec3> points, directors;
  for (int v = 0; v <= n; ++v) points.push_back(Vec3(h * v, 0, 0));
  for (int e = 0; e < n; ++e) directors.push_back(Vec3(0, 0, 1));
  Section section;
  RodFixture rod(points, directors, h, section);
  rod.theta.back() = phi;  // the last edge's frame turned by phi about the rod
  rod.solve(rod.interior());
  const double L = (n - 1) * h;
  EXPECT_NEAR(rod.energy(rod.interior()), section.GJ * phi * phi / (2 * L),
              1e-6 * section.GJ * phi * phi / L);
  for (const Vec3& p : rod.x) EXPECT_NEAR(p.y(), 0.0, 1e-9);  // twisting alone does not bend
}

TEST(DiscreteRod, StrongToWeakBendingEnergyIsTheSquaredAspectRatio) {
  // The same kink, once with the material normal in the kink's plane (weak axis: the lamella
  // bends out of its own plane) and once perpendicular to it (strong axis: in its plane).
  const double w = 1.0, t = 0.1, E = 1e9;
  Section section;
  section.EI_weak = E * w * t * t * t / 12;
  section.EI_strong = E * t * w * w * w / 12;
  const std::vector<Vec3> points{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0.3, 0)};
  RodFixture weak(points, {Vec3(0, 1, 0), Vec3(0, 1, 0)}, 1.0, section);
  RodFixture strong(points, {Vec3(0, 0, 1), Vec3(0, 0, 1)}, 1.0, section);
  // The bending-twisting block alone (unit Voronoi length).
  auto bending = [&](RodFixture& rod) {
    double r[3];
    rod_terms::BendTwist{&rod.ref[0], &rod.ref[1], std::sqrt(section.EI_weak),
                         std::sqrt(section.EI_strong), std::sqrt(section.GJ)}(
        rod.x[0].data(), rod.x[1].data(), rod.x[2].data(), &rod.theta[0], &rod.theta[1], r);
    return 0.5 * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  };
  EXPECT_NEAR(bending(strong) / bending(weak), (w / t) * (w / t), 1e-9 * (w / t) * (w / t));
}

// ---------------------------------------------------------------------------------------------
// The Newton solver's steps at a barrier.

/// r = weight * log(upper - x): defined for x < upper only.
struct UpperBarrier {
  double weight, upper;
  template <class T>
  bool operator()(const T* x, T* r) const {
    if (!(x[0] < T(upper))) return false;
    r[0] = weight * log(T(upper) - x[0]);
    return true;
  }
};
/// r = weight * (x - target).
struct Spring {
  double weight, target;
  template <class T>
  bool operator()(const T* x, T* r) const {
    r[0] = weight * (x[0] - T(target));
    return true;
  }
};

TEST(NewtonSolver, BarrierCoordinateAtItsBoundDoesNotShortenTheOthersSteps) {
  // x is pulled towards 2 but lives in x < 1 (a slider reaching the end of its edge); y, on
  // its own, wants to go to 3. The Newton step takes x past its bound. Holding x at the
  // fraction to the boundary must leave y its full Newton step (y = 3 up to the damping), not
  // the 47.5% a uniformly shortened step would give it.
  double x = 0, y = 0;
  ceres::AutoDiffCostFunction<UpperBarrier, 1, 1> barrier(new UpperBarrier{0.1, 1.0});
  ceres::AutoDiffCostFunction<Spring, 1, 1> pull(new Spring{10, 2});
  ceres::AutoDiffCostFunction<Spring, 1, 1> spring(new Spring{1, 3});
  std::vector<NewtonSolver::Term> terms(3);
  terms[0].cost = &barrier;
  terms[0].parameters = {&x};
  terms[0].upper = 1.0;
  terms[0].numeric_curvature = true;  // the exact Hessian near the bound
  terms[1].cost = &pull;
  terms[1].parameters = {&x};
  terms[2].cost = &spring;
  terms[2].parameters = {&y};
  NewtonSolver solver({{&x, 1}, {&y, 1}}, terms, {});
  ASSERT_TRUE(solver.evaluate());
  const NewtonSolver::StepResult step = solver.step();
  ASSERT_TRUE(step.accepted);
  EXPECT_EQ(step.trials, 1);
  EXPECT_NEAR(y, 3.0, 1e-3);
  EXPECT_GT(x, 0.9);  // 95% of the way to the bound
  EXPECT_LT(x, 1.0);
  // And it converges to the minimum inside the domain (x = 0.99928: barrier and pull balance).
  solver.set_exact_hessian(true);
  for (int it = 0; it < 50 && solver.gradient_max_norm() > 1e-10; ++it) {
    ASSERT_TRUE(solver.evaluate());
    if (solver.gradient_max_norm() <= 1e-10) break;
    ASSERT_TRUE(solver.step().accepted);
  }
  ASSERT_TRUE(solver.evaluate());
  EXPECT_LT(solver.gradient_max_norm(), 1e-8);
  EXPECT_NEAR(y, 3.0, 1e-12);
  EXPECT_NEAR(x, 0.999277274, 1e-9);
}

/// r = A x_blocks - b for a fixed 4 x (sum of sizes) matrix: a quadratic coupling its blocks.
struct Coupling {
  std::vector<int> sizes;
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  template <class T>
  bool operator()(T const* const* x, T* r) const {
    for (int i = 0; i < A.rows(); ++i) {
      T sum = T(-b[i]);
      int column = 0;
      for (size_t p = 0; p < sizes.size(); ++p)
        for (int a = 0; a < sizes[p]; ++a) sum += A(i, column++) * x[p][a];
      r[i] = sum;
    }
    return true;
  }
};

TEST(NewtonSolver, OneUndampedStepSolvesAQuadraticWhateverTheBlockOrder) {
  // Blocks of sizes 3, 1, 2, 3, 1 coupled in overlapping groups of one to three blocks (most
  // blocks in three terms): the solver numbers the unknowns in its own fill-reducing order, so
  // a wrong mapping of blocks, pattern or local Hessians would show as a wrong step.
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0, 1);
  const std::vector<int> sizes{3, 1, 2, 3, 1};
  std::vector<std::vector<double>> x;
  for (int s : sizes) {
    x.emplace_back(s);
    for (double& v : x.back()) v = n(rng);
  }
  const std::vector<std::vector<int>> groups{{0, 1}, {1, 2, 3}, {3, 4}, {4, 0}, {2, 4, 1}, {0}};
  std::vector<std::unique_ptr<ceres::DynamicAutoDiffCostFunction<Coupling>>> costs;
  std::vector<NewtonSolver::Term> terms;
  const int total = 10;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(total, total);  // dense reference: J^T J, J^T r
  Eigen::VectorXd g = Eigen::VectorXd::Zero(total);
  std::vector<int> offset{0, 3, 4, 6, 9};
  for (const auto& group : groups) {
    auto* c = new Coupling;
    int width = 0;
    for (int b : group) {
      c->sizes.push_back(sizes[b]);
      width += sizes[b];
    }
    c->A = Eigen::MatrixXd::NullaryExpr(4, width, [&] { return n(rng); });
    c->b = Eigen::VectorXd::NullaryExpr(4, [&] { return n(rng); });
    costs.emplace_back(new ceres::DynamicAutoDiffCostFunction<Coupling>(c));
    NewtonSolver::Term term;
    term.cost = costs.back().get();
    for (int b : group) {
      costs.back()->AddParameterBlock(sizes[b]);
      term.parameters.push_back(x[b].data());
    }
    costs.back()->SetNumResiduals(4);
    terms.push_back(term);
    // Dense J of this term and its residual at x.
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(4, total);
    Eigen::VectorXd r = -c->b;
    int column = 0;
    for (int b : group)
      for (int a = 0; a < sizes[b]; ++a, ++column) {
        J.col(offset[b] + a) += c->A.col(column);
        r += c->A.col(column) * x[b][a];
      }
    H += J.transpose() * J;
    g += J.transpose() * r;
  }
  Eigen::VectorXd x0(total);
  for (size_t b = 0; b < sizes.size(); ++b)
    for (int a = 0; a < sizes[b]; ++a) x0[offset[b] + a] = x[b][a];
  const Eigen::VectorXd expected = x0 - H.ldlt().solve(g);

  std::vector<std::pair<double*, int>> blocks;
  for (size_t b = 0; b < sizes.size(); ++b) blocks.emplace_back(x[b].data(), sizes[b]);
  NewtonSolver::Options options;
  options.initial_lambda = 0;  // a plain Newton step
  NewtonSolver solver(blocks, terms, options);
  ASSERT_TRUE(solver.evaluate());
  for (size_t b = 0; b < sizes.size(); ++b)  // the gradient, block by block
    EXPECT_NEAR(solver.gradient_at(x[b].data()), g[offset[b]], 1e-9 * (1 + g.norm()));
  ASSERT_TRUE(solver.step().accepted);
  for (size_t b = 0; b < sizes.size(); ++b)
    for (int a = 0; a < sizes[b]; ++a)
      EXPECT_NEAR(x[b][a], expected[offset[b] + a], 1e-9 * (1 + expected.norm()))
          << "block " << b << ", unknown " << a;
  ASSERT_TRUE(solver.evaluate());
  EXPECT_LT(solver.gradient_max_norm(), 1e-8 * (1 + g.norm()));
}

}  // namespace
}  // namespace gridshell
