// SPDX-License-Identifier: GPL-3.0-or-later
#include "sparse_cholesky.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <type_traits>

namespace gridshell {
namespace {
/// Calls f(std::integral_constant<int, S>()) for the block size S = size (1 to kMaxBlock), so
/// that the kernels are compiled for each size.
template <typename F>
void by_block_size(int size, F&& f) {
  static_assert(BlockCholesky::kMaxBlock == 4);
  switch (size) {
    case 1:
      return f(std::integral_constant<int, 1>());
    case 2:
      return f(std::integral_constant<int, 2>());
    case 3:
      return f(std::integral_constant<int, 3>());
    default:
      return f(std::integral_constant<int, 4>());
  }
}
}  // namespace

void BlockCholesky::analyze(const Eigen::SparseMatrix<double>& upper,
                            const std::vector<int>& block_sizes, bool amalgamate) {
  std::vector<int> sizes;
  int total = 0;
  for (int size : block_sizes)
    for (int left = size; left > 0; left -= kMaxBlock) {
      sizes.push_back(std::min(left, kMaxBlock));
      total += sizes.back();
    }
  if (total != upper.cols())
    throw std::invalid_argument("BlockCholesky: block sizes do not sum to the size");
  symbolic(upper, sizes);
  if (!amalgamate) return;
  // Amalgamation: a block whose elimination-tree parent is the next block and whose factor
  // column has exactly the parent's structure plus the parent (a fundamental supernode) joins
  // it while they fit in kMaxBlock: fewer, larger block products. The merged block's rows may
  // hold zeros in columns that reach only its first part (measured on the deployment Hessians:
  // sphere notched 1.30 -> 1.19 s, torus-wide without 1.13 -> 1.09 s, median of 5).
  std::vector<int> merged;
  for (int J = 0; J < blocks_;) {
    int size = size_[J];
    while (J + 1 < blocks_ && parent_[J] == J + 1 && size + size_[J + 1] <= kMaxBlock &&
           lp_[J + 1] - lp_[J] == lp_[J + 2] - lp_[J + 1] + 1) {
      size += size_[J + 1];
      ++J;
    }
    merged.push_back(size);
    ++J;
  }
  if (static_cast<int>(merged.size()) < blocks_) symbolic(upper, merged);
}

void BlockCholesky::symbolic(const Eigen::SparseMatrix<double>& upper,
                             const std::vector<int>& sizes) {
  const int n = static_cast<int>(upper.cols());
  const int* ap = upper.outerIndexPtr();
  const int* ai = upper.innerIndexPtr();
  n_ = n;
  ok_ = false;
  analysed_nonzeros_ = upper.nonZeros();
  start_.clear();
  size_ = sizes;
  int at = 0;
  for (int size : sizes) {
    start_.push_back(at);
    at += size;
  }
  const int nb = blocks_ = static_cast<int>(start_.size());
  block_of_.resize(n);
  for (int b = 0; b < nb; ++b)
    for (int j = 0; j < size_[b]; ++j) block_of_[start_[b] + j] = b;
  // A's block pattern above the diagonal block.
  std::vector<int> flag(nb, -1);
  pattern_p_.assign(nb + 1, 0);
  pattern_i_.clear();
  for (int K = 0; K < nb; ++K) {
    flag[K] = K;
    for (int c = start_[K]; c < start_[K] + size_[K]; ++c)
      for (int p = ap[c]; p < ap[c + 1]; ++p) {
        const int I = block_of_[ai[p]];
        if (flag[I] != K) {
          flag[I] = K;
          pattern_i_.push_back(I);
        }
      }
    pattern_p_[K + 1] = static_cast<int>(pattern_i_.size());
  }
  // Block elimination tree and the factor's block pattern (counts and value sizes).
  parent_.assign(nb, -1);
  std::vector<int> ancestor(nb, -1), count(nb, 0), values(nb, 0);
  for (int K = 0; K < nb; ++K)
    for (int p = pattern_p_[K]; p < pattern_p_[K + 1]; ++p)
      for (int I = pattern_i_[p]; I != -1 && I < K;) {
        const int next = ancestor[I];
        ancestor[I] = K;
        if (next == -1) parent_[I] = K;
        I = next;
      }
  std::fill(flag.begin(), flag.end(), -1);
  for (int K = 0; K < nb; ++K) {
    flag[K] = K;
    for (int p = pattern_p_[K]; p < pattern_p_[K + 1]; ++p)
      for (int I = pattern_i_[p]; I < K && flag[I] != K; I = parent_[I]) {
        flag[I] = K;
        ++count[I];
        values[I] += size_[K] * size_[I];
      }
  }
  lp_.assign(nb + 1, 0);
  vp_.assign(nb + 1, 0);
  dp_.assign(nb + 1, 0);
  for (int I = 0; I < nb; ++I) {
    lp_[I + 1] = lp_[I] + count[I];
    vp_[I + 1] = vp_[I] + values[I];
    dp_[I + 1] = dp_[I] + size_[I] * size_[I];
  }
  li_.resize(lp_[nb]);
  lv_.resize(lp_[nb]);
  lx_.resize(vp_[nb]);
  dx_.resize(dp_[nb]);
  flag_.assign(nb, -1);
  stack_.resize(nb);
  next_.resize(nb);
  vnext_.resize(nb);
  x_.assign(static_cast<size_t>(n) * kMaxBlock, 0.0);
}

bool BlockCholesky::factorize(const Eigen::SparseMatrix<double>& upper) {
  ok_ = false;
  if (upper.cols() != n_ || upper.rows() != n_ || upper.nonZeros() != analysed_nonzeros_)
    throw std::invalid_argument("BlockCholesky: the matrix does not have the analysed pattern");
  const int nb = blocks_;
  const int* ap = upper.outerIndexPtr();
  const int* ai = upper.innerIndexPtr();
  const double* ax = upper.valuePtr();
  for (int I = 0; I < nb; ++I) {
    next_[I] = lp_[I];
    vnext_[I] = vp_[I];
  }
  std::fill(flag_.begin(), flag_.end(), -1);
  double* x = x_.data();  // row r of the current block row's right-hand side: x[r * kMaxBlock]
  constexpr int M = kMaxBlock;
  const cholesky::EliminateKernels& kernels = kernels_ ? *kernels_ : cholesky::eliminate_kernels();
  const cholesky::EliminateState state{start_.data(), size_.data(), lp_.data(), next_.data(),
                                       vnext_.data(), li_.data(),   lv_.data(), lx_.data(),
                                       dx_.data(),    dp_.data(),   x};
  for (int K = 0; K < nb; ++K) {
    const int bk = size_[K], ck = start_[K];
    double D[M * M] = {};  // the diagonal block, row-major (lower part used)
    for (int c = 0; c < bk; ++c)
      for (int p = ap[ck + c]; p < ap[ck + c + 1]; ++p) {
        const int r = ai[p];
        if (r >= ck) {
          D[c * M + (r - ck)] = ax[p];  // (c, r - ck) with r - ck <= c: lower, row-major
        } else {
          x[r * M + c] = ax[p];
        }
      }
    // The block row's pattern: etree paths from A's blocks up to K, in topological order.
    int top = nb;
    flag_[K] = K;
    for (int p = pattern_p_[K]; p < pattern_p_[K + 1]; ++p) {
      int I = pattern_i_[p], length = 0;
      for (; I < K && flag_[I] != K; I = parent_[I]) {
        stack_[length++] = I;
        flag_[I] = K;
      }
      while (length > 0) stack_[--top] = stack_[--length];
    }
    const cholesky::EliminateFn* row_kernels = kernels.fn + (bk - 1);
    for (int q = top; q < nb; ++q) {
      const int I = stack_[q];
      row_kernels[(size_[I] - 1) * M](state, K, I, D);
    }
    // Dense Cholesky of the diagonal block.
    double* L = dx_.data() + dp_[K];
    for (int c = 0; c < bk; ++c) {
      for (int d = 0; d <= c; ++d) {
        double s = D[c * M + d];
        for (int b = 0; b < d; ++b) s -= L[c * bk + b] * L[d * bk + b];
        if (c == d) {
          if (!(s > 0) || !std::isfinite(s)) return false;
          L[c * bk + c] = std::sqrt(s);
        } else {
          L[c * bk + d] = s / L[d * bk + d];
        }
      }
      for (int d = c + 1; d < bk; ++d) L[c * bk + d] = 0;
    }
  }
  ok_ = true;
  return true;
}

template <int BJ, int KC>
void BlockCholesky::forward(int J, double* z, int runtime_k) const {
  const int k = KC > 0 ? KC : runtime_k;
  // z (row-major, k right-hand sides per unknown): y_J = L_JJ^-1 y_J, then y_R -= L(R, J) y_J.
  const int cj = start_[J];
  const double* L = dx_.data() + dp_[J];
  double* yj = z + static_cast<size_t>(cj) * k;
#pragma GCC unroll 4
  for (int a = 0; a < BJ; ++a) {
    const double inverse = 1.0 / L[a * BJ + a];
    for (int c = 0; c < k; ++c) {
      double v = yj[a * k + c];
      for (int b = 0; b < a; ++b) v -= L[a * BJ + b] * yj[b * k + c];
      yj[a * k + c] = v * inverse;
    }
  }
  for (int e = lp_[J]; e < lp_[J + 1]; ++e) {
    const int br = size_[li_[e]];
    const double* B = lx_.data() + lv_[e];
    double* row = z + static_cast<size_t>(start_[li_[e]]) * k;
    for (int a = 0; a < br; ++a, row += k, B += BJ)
      for (int c = 0; c < k; ++c) {
        double v = row[c];
#pragma GCC unroll 4
        for (int b = 0; b < BJ; ++b) v -= B[b] * yj[b * k + c];
        row[c] = v;
      }
  }
}

template <int BJ, int KC>
void BlockCholesky::backward(int J, double* z, int runtime_k) const {
  const int k = KC > 0 ? KC : runtime_k;
  // x_J = L_JJ^-T (y_J - sum_R L(R, J)^T x_R).
  const int cj = start_[J];
  double* yj = z + static_cast<size_t>(cj) * k;
  for (int e = lp_[J]; e < lp_[J + 1]; ++e) {
    const int br = size_[li_[e]];
    const double* B = lx_.data() + lv_[e];
    const double* row = z + static_cast<size_t>(start_[li_[e]]) * k;
    for (int a = 0; a < br; ++a, row += k, B += BJ)
      for (int c = 0; c < k; ++c)
#pragma GCC unroll 4
        for (int b = 0; b < BJ; ++b) yj[b * k + c] -= B[b] * row[c];
  }
  const double* L = dx_.data() + dp_[J];
#pragma GCC unroll 4
  for (int a = BJ - 1; a >= 0; --a) {
    const double inverse = 1.0 / L[a * BJ + a];
    for (int c = 0; c < k; ++c) {
      double v = yj[a * k + c];
      for (int b = a + 1; b < BJ; ++b) v -= L[b * BJ + a] * yj[b * k + c];
      yj[a * k + c] = v * inverse;
    }
  }
}

Eigen::MatrixXd BlockCholesky::solve_many(const Eigen::MatrixXd& b) const {
  if (!ok_) throw std::logic_error("BlockCholesky: solve without a successful factorization");
  if (b.rows() != n_) throw std::invalid_argument("BlockCholesky: right-hand side size");
  const int k = static_cast<int>(b.cols());
  // Row-major copy: the k right-hand sides of one unknown are contiguous.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> z = b;
  double* data = z.data();
  if (k == 1) {  // the Newton step's solve: loops over one right-hand side compiled as such
    for (int J = 0; J < blocks_; ++J)
      by_block_size(size_[J], [&](auto bj) { forward<bj(), 1>(J, data, 1); });
    for (int J = blocks_ - 1; J >= 0; --J)
      by_block_size(size_[J], [&](auto bj) { backward<bj(), 1>(J, data, 1); });
    return z;
  }
  for (int J = 0; J < blocks_; ++J)
    by_block_size(size_[J], [&](auto bj) { forward<bj(), 0>(J, data, k); });
  for (int J = blocks_ - 1; J >= 0; --J)
    by_block_size(size_[J], [&](auto bj) { backward<bj(), 0>(J, data, k); });
  return z;
}

Eigen::MatrixXd BlockCholesky::inverse_submatrix(const std::vector<int>& unknowns) const {
  if (!ok_) throw std::logic_error("BlockCholesky: inverse without a successful factorization");
  const int k = static_cast<int>(unknowns.size());
  // Columns of W = L^-1 E, dense over the unknowns, and the union of the paths' blocks.
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n_, k);
  std::vector<char> on_path(blocks_, 0);
  std::vector<int> path_blocks;
  for (int j = 0; j < k; ++j) {
    const int unknown = unknowns[j];
    if (unknown < 0 || unknown >= n_)
      throw std::invalid_argument("BlockCholesky: unknown out of range");
    double* z = W.col(j).data();
    z[unknown] = 1;
    for (int J = block_of_[unknown]; J != -1; J = parent_[J]) {
      by_block_size(size_[J], [&](auto bj) { forward<bj(), 1>(J, z, 1); });
      if (!on_path[J]) {
        on_path[J] = 1;
        path_blocks.push_back(J);
      }
    }
  }
  std::vector<int> rows;
  for (int J : path_blocks)
    for (int r = start_[J]; r < start_[J] + size_[J]; ++r) rows.push_back(r);
  const Eigen::MatrixXd C = W(rows, Eigen::all);
  return C.transpose() * C;
}

Eigen::VectorXd BlockCholesky::solve(const Eigen::VectorXd& b) const {
  return solve_many(b).col(0);
}

long BlockCholesky::factor_nonzeros() const {
  long diagonal = 0;
  for (int s : size_) diagonal += s * (s + 1) / 2;
  return static_cast<long>(lx_.size()) + diagonal;
}

}  // namespace gridshell
