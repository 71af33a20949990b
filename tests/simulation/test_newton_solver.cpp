// SPDX-License-Identifier: GPL-3.0-or-later
// The Newton solver's assembly (newton_solver.h) against central differences, on small random
// problems built from the real rod terms the way Deployment::build_terms builds them: two rods
// of four edges crossing at a sliding connection (member g with its neighbouring edge, member h
// on a fixed coordinate) with an anchor there, friction and both notch limits on the sliding
// coordinate, one twist angle held constant.
//
// Checked: the assembled gradient against central differences of the solver's own cost; the
// assembled Hessian against central differences of the terms' exact (automatic) gradients,
// in both modes:
//   Gauss-Newton + curvature: J^T J of every term plus the hand-derived curvature of the terms
//     that have one (stretch, friction, notch limits), the full Hessian of exactly those;
//   exact Hessian: the numeric curvature (forward differences of the exact Jacobian) of the
//     others too (bending-twisting, connection, anchor): the full Hessian of the cost.
//
// The solver exposes its gradient only as gradient_at(block) (a block's first entry) and its
// Hessian not at all, so both are read through its steps: step() solves (H + lambda D) d = -g and
// first evaluates the cost at x + d. A zero residual over every free block (TrialSpy, the first
// term) records that point whether or not the step is then accepted. One probe term per unknown
// k, r = x_k - x_k(0) + shift, whose curvature -1 cancels its J^T J = 1, adds `shift` to the
// gradient and nothing to the Hessian; d(shift = s e_k) - d(0) = -s (H + lambda D)^-1 e_k gives
// the inverse of the damped Hessian column by column, and g = -(H + lambda D) d(0) the whole
// gradient (the round trip loses little: that g agrees with the automatic J^T r to ~1e-12).
// lambda is chosen so that H + lambda D is positive definite (the factorization must succeed);
// the expected D = diag(max(|H_ii|, floor)) is the solver's. In exact-Hessian mode the solver
// reuses its numeric curvature for 7 of every 8 evaluations (Options::curvature_refresh), here
// at the same state: both paths are exercised.
#include <ceres/autodiff_cost_function.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <random>

#include "central_differences.h"
#include "newton_solver.h"
#include "rod_terms.h"

namespace gridshell {
namespace {

namespace cd = central_differences;
using rod_terms::EdgeReference;
using Vec3 = Eigen::Vector3d;

/// A zero residual reading every free block; its first evaluation without Jacobians (the first
/// trial point x + d of NewtonSolver::step) records the blocks' values.
class TrialSpy : public ceres::CostFunction {
 public:
  explicit TrialSpy(const cd::Unknowns& unknowns) {
    for (const auto& block : unknowns.blocks)
      mutable_parameter_block_sizes()->push_back(block.second);
    set_num_residuals(1);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    residuals[0] = 0;
    const auto& sizes = parameter_block_sizes();
    if (jacobians) {
      for (size_t p = 0; p < sizes.size(); ++p)
        if (jacobians[p]) std::fill(jacobians[p], jacobians[p] + sizes[p], 0.0);
    } else if (!recorded) {
      values.clear();
      for (size_t p = 0; p < sizes.size(); ++p)
        for (int c = 0; c < sizes[p]; ++c) values.push_back(parameters[p][c]);
      recorded = true;
    }
    return true;
  }
  mutable bool recorded = false;
  mutable std::vector<double> values;
};

/// r = x_c - x0 + shift on coordinate c of one block of `size`.
class GradientProbe : public ceres::CostFunction {
 public:
  GradientProbe(int size, int coordinate, double x0) : c_(coordinate), x0_(x0) {
    mutable_parameter_block_sizes()->push_back(size);
    set_num_residuals(1);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    residuals[0] = parameters[0][c_] - x0_ + shift;
    if (jacobians && jacobians[0]) {
      std::fill(jacobians[0], jacobians[0] + parameter_block_sizes()[0], 0.0);
      jacobians[0][c_] = 1;
    }
    return true;
  }
  double shift = 0;

 private:
  int c_;
  double x0_;
};

/// A reference frame near the edge a -> b with d1 near +z (as after a frame update a few steps
/// ago).
EdgeReference reference_near(const Vec3& a, const Vec3& b, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 0.05);
  EdgeReference ref;
  ref.tangent = ((b - a).normalized() + Vec3(n(rng), n(rng), n(rng))).normalized();
  const Vec3 d = Vec3(0, 0, 1) + Vec3(n(rng), n(rng), n(rng));
  ref.d1 = (d - d.dot(ref.tangent) * ref.tangent).normalized();
  return ref;
}

struct Rod {
  std::vector<Vec3> x;
  std::vector<double> theta;
  std::vector<EdgeReference> ref;
  std::vector<double> reference_twist;  // per interior vertex, as Deployment tracks it
  double rest = 1;
};

/// Two rods of four edges, a along x, b along y, crossing on a's edge 1 and b's edge 2.
struct SmallGrid {
  Rod a, b;
  double beta_g = 0.7;  // on a's edge 1, sliding (free); >= 1/2: blended towards a's edge 2
  double beta_h = 0.4;  // on b's edge 2, fixed (a constant block)
  std::vector<std::unique_ptr<ceres::CostFunction>> owned;
  std::vector<NewtonSolver::Term> terms;
  cd::Unknowns unknowns;

  /// `all_terms` false: only the terms with a hand-derived curvature (stretch, friction, notch
  /// limits), whose Gauss-Newton + curvature Hessian is the exact one.
  SmallGrid(std::mt19937& rng, bool all_terms) {
    std::uniform_real_distribution<double> u(-1, 1);
    const double thickness = 0.1;
    for (int k = 0; k <= 4; ++k) {
      a.x.push_back(Vec3(k, 0, -thickness / 2) + 0.1 * Vec3(u(rng), u(rng), u(rng)));
      b.x.push_back(Vec3(1.7, k - 2.4, thickness / 2) + 0.1 * Vec3(u(rng), u(rng), u(rng)));
    }
    for (Rod* rod : {&a, &b}) {
      rod->rest = 1 + 0.1 * u(rng);  // the edges are 0.8 .. 1.2: compressed and stretched
      for (int k = 0; k < 4; ++k) {
        rod->ref.push_back(reference_near(rod->x[k], rod->x[k + 1], rng));
        rod->theta.push_back(0.2 * u(rng));
      }
      for (int k = 1; k < 4; ++k) {
        const auto f0 = rod_terms::edge_frame(rod->x[k - 1].data(), rod->x[k].data(),
                                              &rod->theta[k - 1], rod->ref[k - 1]);
        const auto f1 = rod_terms::edge_frame(rod->x[k].data(), rod->x[k + 1].data(),
                                              &rod->theta[k], rod->ref[k]);
        rod->reference_twist.push_back(rod_terms::raw_reference_twist(f0, f1));
      }
    }
    beta_g = 0.725 + 0.1 * u(rng);  // >= 0.075 inside both notch limits
    // Free: every vertex and twist but b's first twist, and beta_g (as in build_terms: the
    // vertices, then the twists, then the sliding coordinates). A stretch term's vertices must
    // both be free (add_stretch_curvature writes a 6 x 6 local Hessian). Without the bending
    // terms the twists enter no term: not unknowns then.
    for (Rod* rod : {&a, &b}) {
      for (Vec3& x : rod->x) unknowns.blocks.emplace_back(x.data(), 3);
      if (!all_terms) continue;
      for (size_t k = rod == &b ? 1 : 0; k < rod->theta.size(); ++k)
        unknowns.blocks.emplace_back(&rod->theta[k], 1);
    }
    unknowns.blocks.emplace_back(&beta_g, 1);

    using ceres::AutoDiffCostFunction;
    auto add = [&](ceres::CostFunction* cost, std::vector<double*> parameters,
                   std::function<void(const double*, Eigen::MatrixXd&)> curvature = nullptr) {
      owned.emplace_back(cost);
      const bool numeric = !curvature;
      // The barriers' domains (Term::lower, upper) only shape the steps, not the gradient or
      // the Hessian; left open so that no step is shortened (see the spy).
      terms.push_back({cost, std::move(parameters), std::move(curvature), numeric});
    };
    const double EA = 20, EI_weak = 1, EI_strong = 4, GJ = 0.8;
    for (Rod* rod : {&a, &b}) {
      const double stretch = std::sqrt(EA / rod->rest);
      for (int k = 0; k < 4; ++k) {
        double* xa = rod->x[k].data();
        double* xb = rod->x[k + 1].data();
        const rod_terms::Stretch term{stretch, rod->rest};
        add(new AutoDiffCostFunction<rod_terms::Stretch, 1, 3, 3>(new rod_terms::Stretch(term)),
            {xa, xb}, [xa, xb, term](const double* r, Eigen::MatrixXd& H) {
              rod_terms::add_stretch_curvature(term, xa, xb, r, H);
            });
      }
      if (!all_terms) continue;
      for (int k = 1; k < 4; ++k)
        add(new AutoDiffCostFunction<rod_terms::BendTwist, 3, 3, 3, 3, 1, 1>(
                new rod_terms::BendTwist{&rod->ref[k - 1], &rod->ref[k],
                                         std::sqrt(EI_weak / rod->rest),
                                         std::sqrt(EI_strong / rod->rest),
                                         std::sqrt(GJ / rod->rest), &rod->reference_twist[k - 1]}),
            {rod->x[k - 1].data(), rod->x[k].data(), rod->x[k + 1].data(), &rod->theta[k - 1],
             &rod->theta[k]});
    }
    double* beta = &beta_g;
    const rod_terms::Friction friction{0.1, 1e-4};
    add(new AutoDiffCostFunction<rod_terms::Friction, 2, 1>(new rod_terms::Friction(friction)),
        {beta}, [beta, friction](const double* r, Eigen::MatrixXd& H) {
          rod_terms::add_friction_curvature(friction, beta, r, H);
        });
    for (const auto& limit :
         {rod_terms::NotchLimit{0.55, false, 0.1}, rod_terms::NotchLimit{0.9, true, 0.1}})
      add(new AutoDiffCostFunction<rod_terms::NotchLimit, 1, 1>(new rod_terms::NotchLimit(limit)),
          {beta}, [beta, limit](const double* r, Eigen::MatrixXd& H) {
            rod_terms::add_notch_limit_curvature(limit, beta, r, H);
          });
    if (!all_terms) return;
    const rod_terms::MemberEdge g{&a.ref[1], &a.ref[2], +1}, h{&b.ref[2], nullptr, 0};
    std::vector<double*> parameters{a.x[1].data(), a.x[2].data(), &a.theta[1],   &beta_g,
                                    a.x[3].data(), &a.theta[2],   b.x[2].data(), b.x[3].data(),
                                    &b.theta[2],   &beta_h};
    using Connection = rod_terms::PairFunctor<rod_terms::ConnectionResidual, 6, 4>;
    add(new AutoDiffCostFunction<Connection, 9, 3, 3, 1, 1, 3, 1, 3, 3, 1, 1>(new Connection{
            rod_terms::ConnectionResidual{g, h, thickness, std::sqrt(2 * 4.0), std::sqrt(2.0)}}),
        parameters);
    rod_terms::AnchorResidual anchor;
    anchor.g = g;
    anchor.h = h;
    anchor.position = Vec3(1.7, 0, 0);
    anchor.normal = Vec3(0.1, -0.05, 1).normalized();
    anchor.thickness = thickness;
    anchor.sqrt_position = std::sqrt(2 * 5.0);
    anchor.sqrt_direction = std::sqrt(2 * 2.0);
    using Anchor = rod_terms::PairFunctor<rod_terms::AnchorResidual, 6, 4>;
    add(new AutoDiffCostFunction<Anchor, 12, 3, 3, 1, 1, 3, 1, 3, 3, 1, 1>(new Anchor{anchor}),
        parameters);
  }

  std::vector<const NewtonSolver::Term*> term_pointers() const {
    std::vector<const NewtonSolver::Term*> out;
    for (const NewtonSolver::Term& t : terms) out.push_back(&t);
    return out;
  }
};

/// The Hessian the solver should assemble: per term J^T J, plus its curvature where it has a
/// hand-derived one or (exact-Hessian mode) a numeric one, by central differences of the exact
/// gradient (steps 1e-5: the edges are ~1 long, the barrier coordinate >= 0.05 from its bounds).
Eigen::MatrixXd expected_hessian(const SmallGrid& grid, bool exact) {
  const int n = grid.unknowns.size();
  const std::vector<double> steps(n, 1e-5);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  for (const NewtonSolver::Term& term : grid.terms) {
    if (term.curvature || (exact && term.numeric_curvature)) {
      Eigen::MatrixXd full;
      EXPECT_TRUE(cd::hessian({&term}, grid.unknowns, steps, full));
      H += full;
    } else {
      H += cd::gauss_newton({&term}, grid.unknowns);
    }
  }
  return H;
}

/// Central differences of the solver's cost (NewtonSolver::cost after evaluate()).
Eigen::VectorXd cost_gradient(const SmallGrid& grid) {
  NewtonSolver solver(grid.unknowns.blocks, grid.terms, {});
  const int n = grid.unknowns.size();
  Eigen::VectorXd g(n);
  for (int k = 0; k < n; ++k) {
    double& x = grid.unknowns.at(k);
    const double keep = x, h = cd::power_of_two_step(1e-5);
    x = keep + h;
    EXPECT_TRUE(solver.evaluate());
    const double plus = solver.cost();
    x = keep - h;
    EXPECT_TRUE(solver.evaluate());
    const double minus = solver.cost();
    x = keep;
    g[k] = (plus - minus) / (2 * h);
  }
  return g;
}

struct Worst {
  const char* name;
  double hessian = 0, gradient = 0, gradient_at = 0, gradient_exact = 0;
  int problems = 0;
  ~Worst() {
    std::printf(
        "[ %s ] %d problems: max |H - H_fd| / |H_fd| = %.2e; |g - g_fd| / |g_fd| = %.2e "
        "(gradient_at: %.2e; against the automatic J^T r: %.2e)\n",
        name, problems, hessian, gradient, gradient_at, gradient_exact);
  }
};

/// Reads the solver's damped Hessian and gradient through its steps (see the top) and compares
/// them with central differences. `tolerance`: relative, in the max-norm.
void check_assembly(SmallGrid& grid, bool exact, double tolerance, Worst& worst) {
  const cd::Unknowns& unknowns = grid.unknowns;
  const int n = unknowns.size();
  const Eigen::VectorXd x0 = unknowns.read();

  // References.
  const Eigen::MatrixXd H_fd = expected_hessian(grid, exact);
  const Eigen::VectorXd g_fd = cost_gradient(grid);
  {
    // The cost's central differences agree with the exact gradient (automatic J^T r).
    Eigen::VectorXd g;
    ASSERT_TRUE(cd::gradient(grid.term_pointers(), unknowns, g));
    ASSERT_LE((g - g_fd).cwiseAbs().maxCoeff(), 1e-7 * g_fd.cwiseAbs().maxCoeff());
  }
  // Damping that makes H + lambda D positive definite (lambda = 0 if H is already). The
  // solver's D = diag(max(|H_ii|, floor)): a negative H_ii enters the damped matrix as
  // (1 - lambda) H_ii (so lambda > 1 then); lambda >= 2 keeps it from vanishing there.
  const double floor = 1e-12 * H_fd.diagonal().cwiseAbs().maxCoeff();
  const Eigen::VectorXd D = H_fd.diagonal().cwiseAbs().cwiseMax(floor);
  const Eigen::VectorXd scale = D.cwiseSqrt().cwiseInverse();
  const double mu =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scale.asDiagonal() * H_fd * scale.asDiagonal())
          .eigenvalues()
          .minCoeff();
  double lambda = mu >= 0.05 ? 0.0 : 0.1 - mu;
  if (H_fd.diagonal().minCoeff() < -floor) lambda = std::max(lambda, 2.0);
  const Eigen::MatrixXd A_fd = H_fd + lambda * Eigen::MatrixXd(D.asDiagonal());

  // The solver: the spy first (a failing term would end the cost evaluation before it), the
  // real terms, one probe per unknown.
  TrialSpy spy(unknowns);
  std::vector<NewtonSolver::Term> terms(1);
  terms[0].cost = &spy;
  for (const auto& [pointer, size] : unknowns.blocks) terms[0].parameters.push_back(pointer);
  terms.insert(terms.end(), grid.terms.begin(), grid.terms.end());
  std::vector<std::unique_ptr<GradientProbe>> probes;
  for (const auto& [pointer, size] : unknowns.blocks)
    for (int c = 0; c < size; ++c) {
      probes.emplace_back(new GradientProbe(size, c, pointer[c]));
      NewtonSolver::Term term;
      term.cost = probes.back().get();
      term.parameters = {pointer};
      term.curvature = [c](const double*, Eigen::MatrixXd& H) { H(c, c) -= 1; };
      terms.push_back(term);
    }
  NewtonSolver solver(unknowns.blocks, terms, {});
  solver.set_exact_hessian(exact);
  // The step with the gradient shifted by s e_k (k < 0: not shifted).
  const double s = std::max(g_fd.norm(), 1e-2 * cd::max_norm(A_fd));
  auto trial_step = [&](int k) -> Eigen::VectorXd {
    if (k >= 0) probes[k]->shift = s;
    EXPECT_TRUE(solver.evaluate());
    solver.set_lambda(lambda);
    spy.recorded = false;
    solver.step(1);
    if (k >= 0) probes[k]->shift = 0;
    unknowns.write(x0);
    EXPECT_TRUE(spy.recorded) << "no trial point (factorization failed?), probe " << k;
    if (!spy.recorded) return Eigen::VectorXd::Zero(n);
    return Eigen::Map<const Eigen::VectorXd>(spy.values.data(), n) - x0;
  };
  const Eigen::VectorXd d0 = trial_step(-1);
  Eigen::MatrixXd inverse(n, n);
  for (int k = 0; k < n; ++k) inverse.col(k) = (d0 - trial_step(k)) / s;
  const Eigen::MatrixXd A = inverse.partialPivLu().inverse();
  const Eigen::VectorXd g = -A * d0;
  // The undamped Hessian: A_ii = H_ii + lambda max(|H_ii|, floor), with the sign of H_ii of the
  // reference (a wrong sign shows as a wrong value).
  Eigen::MatrixXd H = A;
  for (int i = 0; i < n; ++i)
    H(i, i) = std::abs(H_fd(i, i)) > floor ? A(i, i) / (1 + lambda * (H_fd(i, i) > 0 ? 1 : -1))
                                           : A(i, i) - lambda * floor;

  const double hessian_error = cd::max_norm(H - H_fd) / cd::max_norm(H_fd);
  EXPECT_LE(hessian_error, tolerance) << "lambda " << lambda << "\nsolver - expected:\n"
                                      << H - H_fd;
  EXPECT_LE(cd::max_norm(A - A_fd), tolerance * cd::max_norm(A_fd));
  const double gradient_error = (g - g_fd).cwiseAbs().maxCoeff() / g_fd.cwiseAbs().maxCoeff();
  EXPECT_LE(gradient_error, tolerance)
      << "solver: " << g.transpose() << "\ncentral differences: " << g_fd.transpose();
  // The difference above is the cost's rounding over the step (~1e-10); against the automatic
  // gradient sum J^T r (the reference's own check above) the solver's agrees to rounding.
  Eigen::VectorXd g_exact;
  ASSERT_TRUE(cd::gradient(grid.term_pointers(), unknowns, g_exact));
  const double exact_error = (g - g_exact).cwiseAbs().maxCoeff() / g_exact.cwiseAbs().maxCoeff();
  EXPECT_LE(exact_error, 1e-10);
  // And the entries gradient_at reads directly.
  double direct_error = 0;
  ASSERT_TRUE(solver.evaluate());
  for (const auto& [pointer, size] : unknowns.blocks) {
    const int k = unknowns.offset(pointer);
    direct_error = std::max(direct_error, std::abs(solver.gradient_at(pointer) - g_fd[k]));
  }
  direct_error /= g_fd.cwiseAbs().maxCoeff();
  EXPECT_LE(direct_error, tolerance);
  ++worst.problems;
  worst.hessian = std::max(worst.hessian, hessian_error);
  worst.gradient = std::max(worst.gradient, gradient_error);
  worst.gradient_at = std::max(worst.gradient_at, direct_error);
  worst.gradient_exact = std::max(worst.gradient_exact, exact_error);
}

TEST(NewtonSolverDerivatives, GaussNewtonWithCurvatureIsTheExactHessianOfTheCurvatureTerms) {
  // Only stretch, friction and notch limits: J^T J + their hand-derived curvature is the whole
  // Hessian of the cost.
  Worst worst{"Gauss-Newton + curvature, curvature terms only"};
  for (int seed = 0; seed < 4; ++seed) {
    std::mt19937 rng(200 + seed);
    SmallGrid grid(rng, false);
    check_assembly(grid, false, 1e-6, worst);
  }
}

TEST(NewtonSolverDerivatives, GaussNewtonWithCurvatureOnTheWholeProblem) {
  Worst worst{"Gauss-Newton + curvature, all terms"};
  for (int seed = 0; seed < 4; ++seed) {
    std::mt19937 rng(300 + seed);
    SmallGrid grid(rng, true);
    check_assembly(grid, false, 1e-6, worst);
  }
}

TEST(NewtonSolverDerivatives, ExactHessianModeIsTheHessianOfTheCost) {
  // The numeric curvature takes forward differences with steps 1e-7 max(1, |x|) (truncation
  // ~1e-7 of the Hessian here), the rest is exact.
  Worst worst{"exact Hessian, all terms"};
  for (int seed = 0; seed < 4; ++seed) {
    std::mt19937 rng(400 + seed);
    SmallGrid grid(rng, true);
    check_assembly(grid, true, 1e-6, worst);
  }
}

// The simulation evaluates on one thread (solve_newton); the solver's several-worker path adds
// every term's local Hessian in term order too, so its steps are the one-worker steps to the bit.
TEST(NewtonSolverDerivatives, SeveralWorkersTakeTheOneWorkerStepsToTheBit) {
  for (int seed = 0; seed < 3; ++seed) {
    std::mt19937 rng(500 + seed);
    SmallGrid grid(rng, true);
    const Eigen::VectorXd x0 = grid.unknowns.read();
    std::vector<Eigen::VectorXd> ends;
    std::vector<double> costs;
    for (int threads : {1, 2}) {
      grid.unknowns.write(x0);
      NewtonSolver::Options options;
      options.threads = threads;
      NewtonSolver solver(grid.unknowns.blocks, grid.terms, options);
      for (int step = 0; step < 3; ++step) {
        ASSERT_TRUE(solver.evaluate());
        ASSERT_TRUE(solver.step().accepted);
      }
      ASSERT_TRUE(solver.evaluate());
      costs.push_back(solver.cost());
      ends.push_back(grid.unknowns.read());
    }
    EXPECT_EQ(costs[0], costs[1]) << "seed " << seed;
    ASSERT_EQ(ends[0].size(), ends[1].size());
    EXPECT_EQ(std::memcmp(ends[0].data(), ends[1].data(), sizeof(double) * ends[0].size()), 0)
        << "seed " << seed;
    EXPECT_NE((ends[0] - x0).norm(), 0);  // the steps moved
  }
}

}  // namespace
}  // namespace gridshell
