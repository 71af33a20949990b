// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — damped Newton minimizer for sums of squared residual blocks (private header).
//
// Minimizes E(x) = 1/2 sum_b |r_b(x)|^2 over parameter blocks, where every residual block is a
// Ceres cost function (automatic Jacobians). Ceres' own Levenberg-Marquardt uses the
// Gauss-Newton Hessian J^T J, which drops sum_i r_i Hess(r_i). For the deployment simulation one
// dropped term is large: the geometric stiffness T / |e| (I - t t^T) of every rod edge under
// axial force T (a stiff stretching penalty with a non-zero multiplier). In a deployed gridshell
// axial forces exceed the weak-axis Euler loads by orders of magnitude, so Gauss-Newton crawls
// along the soft, near-buckling modes (thousands of iterations). This solver takes the
// Gauss-Newton Hessian of each block plus a per-block second-order correction supplied by the
// caller (the geometric stiffness, the exact curvature of the log barriers), damps it
// Levenberg-Marquardt style (which also handles the indefiniteness of compressed edges), and
// solves with a block sparse Cholesky factorization (kernel/simulation/sparse_cholesky.h; AMD order
// of the parameter blocks, pattern analysed once per structure).
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "gridshell/simulation/simulation.h"

namespace gridshell {

class CholmodCholesky;

class NewtonSolver {
 public:
  /// One residual block. `parameters` point at the blocks it reads; blocks that are not free
  /// (not among the solver's parameter blocks) are held constant.
  struct Term {
    const ceres::CostFunction* cost = nullptr;
    std::vector<double*> parameters;
    /// Adds the second-order correction sum_i r_i Hess(r_i) to `hessian` (local, rows/columns
    /// in the order of the term's free parameters, each block's entries consecutive) given the
    /// term's residuals. Optional.
    std::function<void(const double* residuals, Eigen::MatrixXd& hessian)> curvature;
    /// Without `curvature`: in exact-Hessian mode, take sum_i r_i Hess(r_i) by forward
    /// differences of the term's exact Jacobian. Otherwise the term contributes J^T J only.
    bool numeric_curvature = false;
    /// Domain of a barrier term's first parameter (a block of size 1): the parameter keeps 5%
    /// of its distance to these bounds in a step (fraction to the boundary, as in
    /// interior-point methods) instead of the step being rejected. First only the parameters
    /// that would go further are held there and the rest take the minimizer of the damped
    /// model with those fixed; if that trial fails, the whole step is shortened uniformly.
    double lower = -std::numeric_limits<double>::infinity();
    double upper = std::numeric_limits<double>::infinity();
    /// Optional: blocks the term may read after a rebuild (a sliding connection's edge on the
    /// other side of its middle). A CHOLMOD system holds their couplings in its pattern (as
    /// zeros), so a rebuild that only swaps them keeps the pattern, the order and the symbolic
    /// analysis (Options::order_cache).
    std::vector<double*> may_read = {};
  };

  struct Options {
    double initial_lambda = 1e-4;  ///< Levenberg-Marquardt damping, relative to diag(H)
    double min_lambda = 1e-12;
    double max_lambda = 1e16;
    int threads = 1;
    /// Exact-Hessian mode: recompute the numeric curvature every this many evaluations and
    /// reuse it in between (it varies slowly; a lagged Hessian keeps fast convergence).
    int curvature_refresh = 8;
    /// Systems of at least this many unknowns are factorized by CHOLMOD (supernodal, nested
    /// dissection of the blocks) instead of the block kernel (0: never); the simulation passes
    /// SimulationOptions::cholmod_from.
    int cholmod_from = 0;
    /// The block order of a CHOLMOD system (nested dissection of the blocks' graph), kept for
    /// the next solver on the same blocks and the same couplings (a rebuild that changes no
    /// coupling skips the ordering, ~0.2 s at 68k unknowns). An old order on changed couplings
    /// is not reused: on a notched 60 x 60-member run it left 13.4M factor entries against
    /// 8.9M freshly ordered (29 s of factorizations against 16 s). Optional; shared by the
    /// caller's successive solvers.
    struct OrderCache {
      std::vector<std::pair<double*, int>> blocks;
      std::vector<std::vector<int>> adjacent;
      std::vector<int> order;
      std::shared_ptr<CholmodCholesky> analysed;  // its symbolic analysis, reused with the order
    };
    std::shared_ptr<OrderCache> order_cache;
  };

  struct StepResult {
    bool accepted = false;
    int trials = 0;              ///< linear solves this step took
    bool stalled = false;        ///< damping hit its maximum without an acceptable step
    bool out_of_trials = false;  ///< the trial budget ran out first
    double relative_step = 0;    ///< max_i |d_i| / (1 + |x_i|) of the accepted step
  };

  /// Where the solver's time went since its construction (docs/solver.md): the profile a
  /// simulation sums over its solvers.
  using Stats = SolverProfile;
  const Stats& stats() const;

  /// `blocks`: the free parameter blocks (pointer, size); their order defines the unknowns.
  NewtonSolver(std::vector<std::pair<double*, int>> blocks, std::vector<Term> terms,
               Options options);
  ~NewtonSolver();

  /// Evaluates cost, gradient and Hessian at the current parameter values. Returns false if a
  /// residual block cannot be evaluated there.
  bool evaluate();
  double cost() const { return cost_; }
  /// Max-norm of the gradient from the last evaluate().
  double gradient_max_norm() const;
  /// The gradient's entry for the first unknown of parameter block `block` from the last
  /// evaluate(); 0 if the block is not free.
  double gradient_at(const double* block) const;
  /// Max-norm of the gradient over the `size` unknowns of parameter block `block` from the last
  /// evaluate(); 0 if the block is not free.
  double gradient_norm_at(const double* block, int size) const;
  /// One damped Newton step from the last evaluate(): tries (H + lambda D) d = -g until the
  /// cost decreases (gain ratio > 1e-4), increasing lambda otherwise; on success the
  /// parameters hold x + d (not yet re-evaluated).
  /// At most `max_trials` linear solves (the caller's iteration budget); when they run out
  /// without an acceptable step, `out_of_trials` is set and the parameters are unchanged.
  StepResult step(int max_trials = std::numeric_limits<int>::max());
  double lambda() const { return lambda_; }
  /// Full Hessian (numeric curvature of the flagged terms) from the next evaluate() on; costs
  /// one extra Jacobian evaluation per free parameter of each flagged term.
  void set_exact_hessian(bool exact);
  /// Trust radius per parameter block (max-norm of its change in one step, 0 = unlimited), in
  /// the order of the blocks: a longer step is rejected and the damping increased, so that the
  /// iterates follow the energy downhill to the nearest equilibrium instead of jumping to a
  /// distant one (a rotated connection, a flipped lamella).
  void set_step_limits(std::vector<double> limits);
  void set_lambda(double lambda) { lambda_ = lambda; }

 private:
  bool evaluate_cost(double* cost) const;
  /// The barrier coordinates that the step d would take beyond the fraction to the boundary of
  /// their domain, each with the step limited to that fraction (unknown index, limited step).
  std::vector<std::pair<int, double>> barrier_limits(const Eigen::VectorXd& d) const;
  /// Largest fraction of the step d that keeps every barrier coordinate within the fraction to
  /// the boundary of its domain (at most 1).
  double barrier_fraction(const Eigen::VectorXd& d) const;
  /// Largest fraction of the step d within every block's trust radius (at most 1).
  double trust_fraction(const Eigen::VectorXd& d) const;
  /// The step that holds the coordinates of barrier_limits(d) at their limits and minimizes the
  /// damped model over the rest. False if none is held, too many are, or the small system
  /// fails.
  bool held_step(const Eigen::VectorXd& d, Eigen::VectorXd& p) const;
  void write(const Eigen::VectorXd& x) const;
  Eigen::VectorXd read() const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
  Options options_;
  double cost_ = 0;
  double lambda_ = 1e-4, nu_ = 2;
};

}  // namespace gridshell
