// SPDX-License-Identifier: GPL-3.0-or-later
// Central differences of the exact (automatic) first derivatives of residual blocks, for the
// checks of the hand-derived second-order blocks (test_rod_curvature.cpp) and of the Newton
// solver's assembly (test_newton_solver.cpp).
//
// For a residual block r(x) with energy 1/2 |r|^2 the gradient is J^T r and the Hessian
//   Hess(1/2 |r|^2) = J^T J + sum_i r_i Hess(r_i),
// so the second-order correction the solver adds to Gauss-Newton is
//   sum_i r_i Hess(r_i) = d/dx (J^T r) - J^T J,
// with d/dx (J^T r) by central differences of the automatic J^T r (exact to rounding). A central
// difference with step h has truncation error h^2/6 |f'''| and rounding error ~ eps |f| / h; with
// h = 1e-5 of the length over which the term varies (an edge's length, a barrier's gap) both are
// ~1e-10 of the derivative, far below the 1e-6 the checks ask for.
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <cmath>
#include <utility>
#include <vector>

#include "newton_solver.h"

namespace gridshell::central_differences {

/// The unknowns: free parameter blocks (pointer, size), numbered block after block.
struct Unknowns {
  std::vector<std::pair<double*, int>> blocks;

  int size() const {
    int n = 0;
    for (const auto& b : blocks) n += b.second;
    return n;
  }
  /// The first unknown of `block`, or -1 if it is not free (held constant).
  int offset(const double* block) const {
    int n = 0;
    for (const auto& [pointer, size] : blocks) {
      if (pointer == block) return n;
      n += size;
    }
    return -1;
  }
  double& at(int k) const {
    for (const auto& [pointer, size] : blocks) {
      if (k < size) return pointer[k];
      k -= size;
    }
    return blocks.front().first[0];  // not reached for 0 <= k < size()
  }
  Eigen::VectorXd read() const {
    Eigen::VectorXd x(size());
    for (int k = 0; k < x.size(); ++k) x[k] = at(k);
    return x;
  }
  void write(const Eigen::VectorXd& x) const {
    for (int k = 0; k < x.size(); ++k) at(k) = x[k];
  }
};

/// Residuals and dense Jacobian (residuals x unknowns; a constant block's columns are dropped)
/// of one term at the current values of its parameter blocks. False if it cannot be evaluated.
inline bool evaluate(const NewtonSolver::Term& term, const Unknowns& unknowns, Eigen::VectorXd& r,
                     Eigen::MatrixXd& J) {
  const auto& sizes = term.cost->parameter_block_sizes();
  const int R = term.cost->num_residuals();
  std::vector<std::vector<double>> blocks(sizes.size());
  std::vector<double*> jacobians;
  for (size_t p = 0; p < sizes.size(); ++p) {
    blocks[p].assign(static_cast<size_t>(R) * sizes[p], 0.0);
    jacobians.push_back(blocks[p].data());
  }
  r.resize(R);
  if (!term.cost->Evaluate(term.parameters.data(), r.data(), jacobians.data())) return false;
  J = Eigen::MatrixXd::Zero(R, unknowns.size());
  for (size_t p = 0; p < sizes.size(); ++p) {
    const int offset = unknowns.offset(term.parameters[p]);
    if (offset < 0) continue;
    for (int i = 0; i < R; ++i)
      for (int c = 0; c < sizes[p]; ++c) J(i, offset + c) += blocks[p][i * sizes[p] + c];
  }
  return true;
}

/// The gradient sum_t J_t^T r_t of the terms' energy 1/2 sum_t |r_t|^2 over the unknowns, with
/// the automatic Jacobians. False if a term cannot be evaluated.
inline bool gradient(const std::vector<const NewtonSolver::Term*>& terms, const Unknowns& unknowns,
                     Eigen::VectorXd& g) {
  g = Eigen::VectorXd::Zero(unknowns.size());
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  for (const NewtonSolver::Term* term : terms) {
    if (!evaluate(*term, unknowns, r, J)) return false;
    g += J.transpose() * r;
  }
  return true;
}

/// The Gauss-Newton Hessian sum_t J_t^T J_t.
inline Eigen::MatrixXd gauss_newton(const std::vector<const NewtonSolver::Term*>& terms,
                                    const Unknowns& unknowns) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(unknowns.size(), unknowns.size());
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  for (const NewtonSolver::Term* term : terms)
    if (evaluate(*term, unknowns, r, J)) H += J.transpose() * J;
  return H;
}

/// A power of two near h: x + h and x - h are then exact for the x of the checks (multiples of
/// ulp(x) <= h, not at a binade's edge), so the difference is symmetric and divided by the exact
/// step.
inline double power_of_two_step(double h) { return std::exp2(std::round(std::log2(h))); }

/// The Hessian of the terms' energy by central differences of the automatic gradient, column k
/// with step steps[k] (rounded to a power of two; the steps actually taken are used). The state
/// is restored. False if a term cannot be evaluated at a perturbed state.
inline bool hessian(const std::vector<const NewtonSolver::Term*>& terms, const Unknowns& unknowns,
                    const std::vector<double>& steps, Eigen::MatrixXd& H) {
  const int n = unknowns.size();
  H.resize(n, n);
  Eigen::VectorXd plus, minus;
  for (int k = 0; k < n; ++k) {
    double& x = unknowns.at(k);
    const double keep = x, h = power_of_two_step(steps[k]);
    x = keep + h;
    const double up = x - keep;
    const bool ok_plus = gradient(terms, unknowns, plus);
    x = keep - h;
    const double down = keep - x;
    const bool ok_minus = gradient(terms, unknowns, minus);
    x = keep;
    if (!ok_plus || !ok_minus) return false;
    H.col(k) = (plus - minus) / (up + down);
  }
  return true;
}

/// sum_i rbar_i Hess(r_i) of one term by central differences of J(x)^T rbar at fixed weights
/// rbar (the term's residuals at the current state): the curvature alone, without subtracting
/// J^T J, so its error is relative to the curvature itself even where that is small against
/// J^T J (an edge near its rest length). Steps as in hessian().
inline bool weighted_hessian(const NewtonSolver::Term& term, const Unknowns& unknowns,
                             const std::vector<double>& steps, const Eigen::VectorXd& rbar,
                             Eigen::MatrixXd& C) {
  const int n = unknowns.size();
  C.resize(n, n);
  Eigen::VectorXd r;
  Eigen::MatrixXd plus, minus;
  for (int k = 0; k < n; ++k) {
    double& x = unknowns.at(k);
    const double keep = x, h = power_of_two_step(steps[k]);
    x = keep + h;
    const double up = x - keep;
    const bool ok_plus = evaluate(term, unknowns, r, plus);
    x = keep - h;
    const double down = keep - x;
    const bool ok_minus = evaluate(term, unknowns, r, minus);
    x = keep;
    if (!ok_plus || !ok_minus) return false;
    C.col(k) = (plus - minus).transpose() * rbar / (up + down);
  }
  return true;
}

/// Max-norm of a matrix (0 for an empty one).
inline double max_norm(const Eigen::MatrixXd& A) {
  return A.size() ? A.cwiseAbs().maxCoeff() : 0.0;
}

}  // namespace gridshell::central_differences
