// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — block sparse Cholesky for the Newton solver (private header).
//
// The Newton solver's Hessians (~3000 unknowns: rod vertices in blocks of 3, twists and
// connection coordinates of 1, numbered block by block in an approximate minimum degree order)
// took 35-47% of a deployment run in Eigen's SimplicialLLT, an up-looking factorization that
// pays an indirect load and store per scalar multiply-add (~0.9 G/s here). This one runs the
// same up-looking algorithm (Davis' cs_chol) on the blocks: elimination tree, row patterns and
// column lists per block, every update a small dense block product with fixed-width inner
// loops. Eigen's SimplicialLLT is the oracle in the tests (tests/test_sparse_cholesky.cpp).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

#include "cholesky_kernels.h"

namespace gridshell {

/// Sparse Cholesky on a block partition of the unknowns (consecutive groups of at most
/// kMaxBlock, e.g. a rod vertex's three coordinates): elimination tree, pattern and updates per
/// block, each update a small dense product, so the indirect addressing of a simplicial
/// factorization is paid once per block pair instead of once per scalar entry.
class BlockCholesky {
 public:
  static constexpr int kMaxBlock = cholesky::kMaxBlock;

  /// Symbolic analysis of a symmetric matrix given by its upper triangle (column-major, sorted,
  /// diagonal present), in elimination order, with its unknowns grouped into consecutive blocks
  /// of the given sizes (summing to the matrix size; larger blocks are split). With
  /// `amalgamate`, a block joins the next one where that is its elimination-tree parent with the
  /// same column structure below (explicit zeros appear only in rows of the merged block).
  void analyze(const Eigen::SparseMatrix<double>& upper, const std::vector<int>& block_sizes,
               bool amalgamate = true);
  /// Numeric factorization of a matrix with the analysed pattern (std::invalid_argument if its
  /// size or number of stored entries differs); false if it is not (numerically) positive
  /// definite.
  bool factorize(const Eigen::SparseMatrix<double>& upper);
  bool ok() const { return ok_; }
  /// Solves A x = b with the last successful factorization (std::logic_error without one).
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  /// Solves A X = B for all columns of B at once (cheaper than one at a time).
  Eigen::MatrixXd solve_many(const Eigen::MatrixXd& b) const;
  /// The principal submatrix of A^-1 at the given unknowns, E^T A^-1 E = W^T W with
  /// W = L^-1 E: each column of W is nonzero only on the elimination-tree path from its unknown's
  /// block to the root, so this costs k short forward substitutions and a k x k product over
  /// the paths' rows instead of k full solves. Needs a successful factorization.
  Eigen::MatrixXd inverse_submatrix(const std::vector<int>& unknowns) const;
  /// Stored entries of the factor (dense blocks, diagonal blocks' lower triangles).
  long factor_nonzeros() const;
  /// The elimination kernels factorize() uses (default: the best for this CPU, see
  /// cholesky_kernels.h); the tests compare the sets.
  void use_kernels(const cholesky::EliminateKernels& kernels) { kernels_ = &kernels; }

 private:
  int n_ = 0, blocks_ = 0;
  std::vector<int> start_, size_, block_of_;  // per block: first unknown, size; per unknown
  std::vector<int> parent_;                   // block elimination tree
  std::vector<int> pattern_p_, pattern_i_;    // per block column: A's block rows above it
  std::vector<int> lp_, li_, lv_;             // per block column: entries (block row, value offset)
  std::vector<int> vp_;                       // per block column: first value offset
  std::vector<double> lx_;                    // L(R, I) blocks, row-major size[R] x size[I]
  std::vector<int> dp_;                       // per block: offset of its diagonal factor
  std::vector<double> dx_;                    // diagonal factors, row-major, lower
  /// Elimination tree, patterns and storage for the given partition (each size <= kMaxBlock).
  void symbolic(const Eigen::SparseMatrix<double>& upper, const std::vector<int>& sizes);
  /// Forward / backward substitution for block J (size BJ) on k row-major right-hand sides
  /// (KC > 0: k == KC known at compile time; 0: k = runtime_k).
  template <int BJ, int KC>
  void forward(int J, double* z, int runtime_k) const;
  template <int BJ, int KC>
  void backward(int J, double* z, int runtime_k) const;
  long analysed_nonzeros_ = 0;  // of the matrix given to analyze()
  // factorize() workspaces; x_ (n x kMaxBlock) is all zero between calls, also after a failure
  // (every entry a row scatters into lies in that row's pattern and is cleared there).
  std::vector<int> flag_, stack_, next_, vnext_;
  std::vector<double> x_;
  const cholesky::EliminateKernels* kernels_ = nullptr;
  bool ok_ = false;
};

}  // namespace gridshell
