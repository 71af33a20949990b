// SPDX-License-Identifier: GPL-3.0-or-later
// The hand-derived second-order blocks of the deployment simulation (rod_terms.h: the geometric
// stiffness of a rod edge, the curvatures of the friction and notch-limit log barriers) against
// central differences of their terms' exact (automatic) Jacobians, on many random states with
// fixed seeds: well-conditioned ones and near-degenerate but valid ones (edges compressed to a
// thousandth of their rest length or stretched tenfold, barrier parameters within 1e-9 of their
// bounds). And the bending-twisting term's reference twist, unwrapped across +-pi, whose
// Jacobian must not see the wrap.
//
// Two central-difference references (central_differences.h), with steps 1e-5 of the length over
// which the term varies (the edge's length, the barrier's gap), exact to ~1e-10:
//   C_fd  = d/dx (J^T r) - J^T J        (Hess(1/2 |r|^2) = J^T J + sum_i r_i Hess(r_i));
//           its error is ~1e-10 of the term's whole Hessian. The block must agree to 1e-6 of its
//           own size plus 1e-8 of the term's Hessian (the second part only matters where the
//           block nearly vanishes against J^T J: an edge near its rest length).
//   C_fd' = d/dx (J^T rbar), rbar = r fixed (= Hess(rbar . r)): the curvature alone, its error
//           ~1e-10 of the curvature itself, however small. The block must agree to 1e-6 of it.
#include <ceres/autodiff_cost_function.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <string>

#include "central_differences.h"
#include "newton_solver.h"
#include "rod_terms.h"

namespace gridshell {
namespace {

namespace cd = central_differences;
using rod_terms::EdgeReference;
using Vec3 = Eigen::Vector3d;

constexpr double kRelative = 1e-6;  // of the block itself
constexpr double kFloor = 1e-8;     // of the term's Hessian J^T J + sum_i r_i Hess(r_i)

/// Worst agreement seen by one test, printed at its end (the numbers of the report).
struct Worst {
  std::string name;
  double weighted = 0;    ///< |C - C_fd'| / |C_fd'|
  double relative = 0;    ///< |C - C_fd| / |C_fd| where |C_fd| >= 1e-3 |Hess|
  double of_hessian = 0;  ///< |C - C_fd| / |Hess|
  int cases = 0;
  ~Worst() {
    std::printf(
        "[ %s ] %d states: max |C - C_fd'| / |C_fd'| = %.2e; |C - C_fd| / |C_fd| = %.2e "
        "(|C_fd| >= 1e-3 |Hess|), / |Hess| = %.2e\n",
        name.c_str(), cases, weighted, relative, of_hessian);
  }
};

/// The step for central differences: a fraction of the length `scale` over which the term
/// varies, at least a few ulps of x.
double step_for(double x, double scale) {
  const double ulp =
      std::nextafter(std::abs(x), std::numeric_limits<double>::infinity()) - std::abs(x);
  return std::max(1e-5 * scale, 16 * ulp);
}

/// Checks the term's hand-derived curvature (term.curvature, local Hessian in the order of its
/// parameters, all free) against central differences of its automatic J^T r.
void expect_curvature_matches(const NewtonSolver::Term& term, const cd::Unknowns& unknowns,
                              const std::vector<double>& steps, Worst& worst,
                              const std::string& where) {
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  ASSERT_TRUE(cd::evaluate(term, unknowns, r, J)) << where;
  const int n = unknowns.size();
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, n);
  term.curvature(r.data(), C);
  Eigen::MatrixXd H;
  ASSERT_TRUE(cd::hessian({&term}, unknowns, steps, H)) << where;
  const Eigen::MatrixXd C_fd = H - J.transpose() * J;
  const double error = cd::max_norm(C - C_fd), size = cd::max_norm(C_fd), hessian = cd::max_norm(H);
  EXPECT_LE(error, kRelative * size + kFloor * hessian) << where << "\nhand-derived:\n"
                                                        << C << "\nd/dx (J^T r) - J^T J:\n"
                                                        << C_fd;
  Eigen::MatrixXd W;
  ASSERT_TRUE(cd::weighted_hessian(term, unknowns, steps, r, W)) << where;
  const double weighted_error = cd::max_norm(C - W), weighted_size = cd::max_norm(W);
  EXPECT_LE(weighted_error, kRelative * weighted_size) << where << "\nhand-derived:\n"
                                                       << C << "\nd/dx (J^T rbar):\n"
                                                       << W;
  ++worst.cases;
  if (weighted_size > 0) worst.weighted = std::max(worst.weighted, weighted_error / weighted_size);
  if (size >= 1e-3 * hessian) worst.relative = std::max(worst.relative, error / size);
  if (hessian > 0) worst.of_hessian = std::max(worst.of_hessian, error / hessian);
}

Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

TEST(RodCurvature, StretchGeometricStiffnessMatchesCentralDifferences) {
  // |e| / l̄ from a thousandth (compressed: T < 0, the block negative semidefinite) over the
  // rest length itself (T = 0, the block vanishes) to ten (stretched).
  Worst worst{"stretch (T/|e|)(I - t t^T)"};
  std::mt19937 rng(101);
  std::uniform_real_distribution<double> u(0, 1);
  for (const double ratio : {1e-3, 1e-2, 0.3, 0.9, 1 - 1e-6, 1.0, 1 + 1e-6, 1.1, 2.0, 10.0})
    for (int trial = 0; trial < 20; ++trial) {
      const double rest = std::pow(10.0, -2 + 3 * u(rng));  // 0.01 .. 10
      const double sqrt_stiffness = std::pow(10.0, -1 + 3 * u(rng));
      const double length = ratio * rest;
      // Near the origin at the edge's own scale (coordinates far larger than the edge would
      // round its vector; the simulation's edges are far from that).
      Vec3 a = 2 * length * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
      Vec3 b = a + length * random_unit(rng);
      const rod_terms::Stretch stretch{sqrt_stiffness, rest};
      ceres::AutoDiffCostFunction<rod_terms::Stretch, 1, 3, 3> cost(
          new rod_terms::Stretch(stretch));
      NewtonSolver::Term term;
      term.cost = &cost;
      term.parameters = {a.data(), b.data()};
      term.curvature = [&](const double* r, Eigen::MatrixXd& H) {
        rod_terms::add_stretch_curvature(stretch, a.data(), b.data(), r, H);
      };
      const cd::Unknowns unknowns{{{a.data(), 3}, {b.data(), 3}}};
      std::vector<double> steps;
      for (int k = 0; k < 6; ++k) steps.push_back(step_for(unknowns.at(k), length));
      expect_curvature_matches(
          term, unknowns, steps, worst,
          "|e| / rest = " + std::to_string(ratio) + ", trial " + std::to_string(trial));
    }
}

// The Newton model's share of compression (SimulationOptions::compression_stiffness): a
// compressed edge's block scaled, a stretched edge's untouched.
TEST(RodCurvature, StretchCompressionScaleAppliesToCompressedEdgesOnly) {
  const rod_terms::Stretch stretch{3.0, 2.0};
  const Vec3 a(0.1, -0.2, 0.3);
  for (const double length : {1.5, 2.5}) {  // compressed, stretched
    const Vec3 b = a + length * Vec3(1, 2, 2).normalized();
    const double r = stretch.sqrt_stiffness * (length - stretch.rest_length);
    Eigen::MatrixXd exact = Eigen::MatrixXd::Zero(6, 6), scaled = exact;
    rod_terms::add_stretch_curvature(stretch, a.data(), b.data(), &r, exact);
    rod_terms::add_stretch_curvature(stretch, a.data(), b.data(), &r, scaled, 0.25);
    ASSERT_GT(exact.norm(), 0);
    const double factor = length < stretch.rest_length ? 0.25 : 1.0;
    EXPECT_LT((scaled - factor * exact).norm(), 1e-14 * exact.norm()) << "length " << length;
  }
}

TEST(RodCurvature, FrictionBarrierCurvatureMatchesCentralDifferences) {
  // b over the edge's domain (-eps, 1 + eps), and within 1e-1 .. 1e-9 of either end (1e-12 at
  // the lower one, where b itself is small).
  Worst worst{"friction log barriers"};
  std::mt19937 rng(102);
  std::uniform_real_distribution<double> u(0, 1);
  int count = 0;
  for (const double mu : {0.01, 0.1, 1.0})
    for (const double epsilon : {1e-6, 1e-4, 1e-2}) {
      std::vector<double> betas;
      for (int k = 0; k < 12; ++k) betas.push_back(-epsilon + (1 + 2 * epsilon) * u(rng));
      for (const double delta : {1e-1, 1e-3, 1e-5, 1e-7, 1e-9}) {
        betas.push_back(-epsilon + delta);
        betas.push_back(1 + epsilon - delta);
      }
      betas.push_back(-epsilon + 1e-12);
      for (double beta : betas) {
        const rod_terms::Friction friction{mu, epsilon};
        ceres::AutoDiffCostFunction<rod_terms::Friction, 2, 1> cost(
            new rod_terms::Friction(friction));
        NewtonSolver::Term term;
        term.cost = &cost;
        term.parameters = {&beta};
        term.curvature = [&](const double* r, Eigen::MatrixXd& H) {
          rod_terms::add_friction_curvature(friction, &beta, r, H);
        };
        const double gap = std::min({epsilon + beta, epsilon + 1 - beta, 1.0});
        ASSERT_GT(gap, 0);
        expect_curvature_matches(term, cd::Unknowns{{{&beta, 1}}}, {step_for(beta, gap)}, worst,
                                 "mu " + std::to_string(mu) + ", eps " + std::to_string(epsilon) +
                                     ", b = eps + " + std::to_string(epsilon + beta));
        ++count;
      }
    }
  EXPECT_EQ(count, 9 * 23);
}

TEST(RodCurvature, NotchLimitBarrierCurvatureMatchesCentralDifferences) {
  Worst worst{"notch-limit log barrier"};
  std::mt19937 rng(103);
  std::uniform_real_distribution<double> u(0, 1);
  for (const double weight : {0.01, 0.1, 1.0})
    for (const bool upper : {false, true})
      for (int trial = 0; trial < 8; ++trial) {
        // A lower bound on its edge lies in [0, 1), an upper one in (0, 1].
        const double bound = upper ? 1 - u(rng) : u(rng);
        std::vector<double> gaps{0.5 * u(rng), u(rng)};
        for (const double g : {1e-1, 1e-3, 1e-5, 1e-7, 1e-9}) gaps.push_back(g);
        for (const double gap : gaps) {
          double beta = upper ? bound - gap : bound + gap;
          const rod_terms::NotchLimit limit{bound, upper, weight};
          ceres::AutoDiffCostFunction<rod_terms::NotchLimit, 1, 1> cost(
              new rod_terms::NotchLimit(limit));
          NewtonSolver::Term term;
          term.cost = &cost;
          term.parameters = {&beta};
          term.curvature = [&](const double* r, Eigen::MatrixXd& H) {
            rod_terms::add_notch_limit_curvature(limit, &beta, r, H);
          };
          const double actual_gap = upper ? bound - beta : beta - bound;
          ASSERT_GT(actual_gap, 0);
          expect_curvature_matches(term, cd::Unknowns{{{&beta, 1}}},
                                   {step_for(beta, std::min(actual_gap, 1.0))}, worst,
                                   std::string(upper ? "upper" : "lower") + " bound " +
                                       std::to_string(bound) + ", gap " + std::to_string(gap));
        }
      }
}

/// A reference frame near the edge a -> b (as after a frame update a few steps ago).
EdgeReference reference_near(const Vec3& a, const Vec3& b, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 0.05);
  EdgeReference ref;
  ref.tangent = ((b - a).normalized() + Vec3(n(rng), n(rng), n(rng))).normalized();
  Vec3 d = Vec3(n(rng), n(rng), n(rng)) + ref.tangent.unitOrthogonal();
  ref.d1 = (d - d.dot(ref.tangent) * ref.tangent).normalized();
  return ref;
}

TEST(RodTwistUnwrap, BendTwistJacobianIsSmoothAcrossTheReferenceTwistsWrapAtPi) {
  // The reference twist is atan2(...) in (-pi, pi], unwrapped against its value at the last
  // frame update by a multiple of 2 pi (rod_terms::BendTwist::previous_reference_twist): a
  // piecewise constant offset, so the residual is smooth and its automatic Jacobian exact
  // across the wrap. States 1e-9 from +-pi; the differences (step 1e-6) straddle the wrap.
  std::mt19937 rng(104);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  double worst = 0;
  int straddled = 0;
  for (int trial = 0; trial < 12; ++trial) {
    Vec3 x[3];
    x[0] = Vec3(u(rng), u(rng), u(rng));
    x[1] = x[0] + Vec3(1, 0, 0) + Vec3(u(rng), u(rng), u(rng));
    x[2] = x[1] + Vec3(1, 0.2, 0) + Vec3(u(rng), u(rng), u(rng));
    double theta[2] = {u(rng), u(rng)};
    const EdgeReference r0 = reference_near(x[0], x[1], rng);
    EdgeReference r1 = reference_near(x[1], x[2], rng);
    // Turn the second reference director about its tangent until the raw twist is 1e-9 inside
    // +pi or -pi (the raw twist turns with it).
    const double target = (trial % 2 ? 1 : -1) * (std::numbers::pi - 1e-9);
    for (int it = 0; it < 3; ++it) {
      const auto f0 = rod_terms::edge_frame(x[0].data(), x[1].data(), &theta[0], r0);
      const auto f1 = rod_terms::edge_frame(x[1].data(), x[2].data(), &theta[1], r1);
      const double phi = target - rod_terms::raw_reference_twist(f0, f1);
      r1.d1 = std::cos(phi) * r1.d1 + std::sin(phi) * r1.tangent.cross(r1.d1);
    }
    const auto f0 = rod_terms::edge_frame(x[0].data(), x[1].data(), &theta[0], r0);
    const auto f1 = rod_terms::edge_frame(x[1].data(), x[2].data(), &theta[1], r1);
    ASSERT_NEAR(rod_terms::raw_reference_twist(f0, f1), target, 1e-12);
    // Tracked from the last update, possibly turns away (a rod twisted by more than pi).
    const double previous = target + 2 * std::numbers::pi * (trial % 3 - 1);
    ceres::AutoDiffCostFunction<rod_terms::BendTwist, 3, 3, 3, 3, 1, 1> cost(
        new rod_terms::BendTwist{&r0, &r1, 1.3, 4.0, 0.7, &previous});
    rod_terms::BendTwist wrapped{&r0, &r1, 1.3, 4.0, 0.7, nullptr};
    NewtonSolver::Term term;
    term.cost = &cost;
    term.parameters = {x[0].data(), x[1].data(), x[2].data(), &theta[0], &theta[1]};
    const cd::Unknowns unknowns{
        {{x[0].data(), 3}, {x[1].data(), 3}, {x[2].data(), 3}, {&theta[0], 1}, {&theta[1], 1}}};
    Eigen::VectorXd r, plus(3), minus(3), wrapped_plus(3), wrapped_minus(3);
    Eigen::MatrixXd J;
    ASSERT_TRUE(cd::evaluate(term, unknowns, r, J));
    // The unwrapped twist residual: sqrt(GJ / l̄) (theta1 - theta0 + target + turns * 2 pi).
    EXPECT_NEAR(r[2], 0.7 * (theta[1] - theta[0] + previous), 1e-9);
    const double largest = cd::max_norm(J);
    for (int k = 0; k < unknowns.size(); ++k) {
      double& v = unknowns.at(k);
      const double keep = v, h = cd::power_of_two_step(1e-6);
      const double* p[] = {x[0].data(), x[1].data(), x[2].data(), &theta[0], &theta[1]};
      v = keep + h;
      ASSERT_TRUE(cost.Evaluate(p, plus.data(), nullptr));
      wrapped(x[0].data(), x[1].data(), x[2].data(), &theta[0], &theta[1], wrapped_plus.data());
      v = keep - h;
      ASSERT_TRUE(cost.Evaluate(p, minus.data(), nullptr));
      wrapped(x[0].data(), x[1].data(), x[2].data(), &theta[0], &theta[1], wrapped_minus.data());
      v = keep;
      // Without the unwrapping the twist would jump by 2 pi sqrt(GJ / l̄) here.
      if (std::abs(wrapped_plus[2] - wrapped_minus[2]) > 0.7 * std::numbers::pi) ++straddled;
      const Eigen::VectorXd numeric = (plus - minus) / (2 * h);
      const double error = (J.col(k) - numeric).cwiseAbs().maxCoeff();
      EXPECT_LE(error, 1e-7 * largest) << "trial " << trial << ", unknown " << k;
      worst = std::max(worst, error / largest);
    }
  }
  // The differences did cross the wrap (most coordinates turn the twist by more than 1e-9).
  EXPECT_GT(straddled, 12 * 5);
  std::printf(
      "[ reference twist unwrap ] max |J - J_fd| / |J| = %.2e, %d differences across the "
      "wrap\n",
      worst, straddled);
}

}  // namespace
}  // namespace gridshell
