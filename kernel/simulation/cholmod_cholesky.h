// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — supernodal sparse Cholesky from CHOLMOD (SuiteSparse) for large Newton systems
// (private header).
//
// The block kernel (sparse_cholesky.h) is an up-looking factorization: every update is a small
// dense product, so its cost grows with the factor's entries times their rows, without the
// dense-matrix speed of large panels: 1.39 s per factorization on a 100 x 100-member grid
// (165k unknowns). CHOLMOD's supernodal factorization on a nested-dissection (METIS) order
// works on dense supernodes through BLAS 3: 0.55 s there (docs/solver.md has the measurements
// and the size where the Newton solver switches).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

namespace gridshell {

class CholmodCholesky {
 public:
  CholmodCholesky();
  ~CholmodCholesky();
  CholmodCholesky(const CholmodCholesky&) = delete;
  CholmodCholesky& operator=(const CholmodCholesky&) = delete;

  /// Symbolic analysis (elimination tree, its postorder, supernodes) of a symmetric matrix given
  /// by its upper triangle (column-major, compressed, sorted), its unknowns already numbered in
  /// a fill-reducing order (the Newton solver's: nested_dissection_order of its blocks).
  void analyze(const Eigen::SparseMatrix<double>& upper);
  /// Numeric factorization of a matrix with the analysed pattern (std::invalid_argument if its
  /// size differs); false if it is not (numerically) positive definite.
  bool factorize(const Eigen::SparseMatrix<double>& upper);
  bool ok() const { return ok_; }
  /// Solves A x = b with the last successful factorization (std::logic_error without one).
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  /// Solves A X = B for all columns of B.
  Eigen::MatrixXd solve_many(const Eigen::MatrixXd& b) const;
  /// The principal submatrix of A^-1 at the given unknowns (one solve per unknown).
  Eigen::MatrixXd inverse_submatrix(const std::vector<int>& unknowns) const;
  /// Stored entries of the factor (supernodes' dense blocks).
  long factor_nonzeros() const;
  /// Floating-point operations of one factorization, from the analysis.
  double factor_flops() const;
  /// Bytes CHOLMOD holds at most (factor, workspace), since construction.
  long peak_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  bool ok_ = false;
};

/// Nested dissection (METIS, through CHOLMOD) of a symmetric graph given by its adjacency lists
/// (sorted; a node may list itself): the nodes in elimination order.
std::vector<int> nested_dissection_order(const std::vector<std::vector<int>>& adjacent);

}  // namespace gridshell
