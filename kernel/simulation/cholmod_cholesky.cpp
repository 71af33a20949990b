// SPDX-License-Identifier: GPL-3.0-or-later
#include "cholmod_cholesky.h"

#include <omp.h>
#include <suitesparse/cholmod.h>

#include <mutex>
#include <stdexcept>
#include <string>

namespace gridshell {

struct CholmodCholesky::Impl {
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  // cholmod_solve2's reusable workspace and result (solve() is logically const).
  mutable cholmod_dense *x = nullptr, *y = nullptr, *e = nullptr;
  int n = 0;
  long nnz = 0;

  Impl() { cholmod_start(&common); }
  ~Impl() {
    cholmod_free_dense(&x, &common);
    cholmod_free_dense(&y, &common);
    cholmod_free_dense(&e, &common);
    cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }

  /// A view of the upper triangle as a CHOLMOD matrix (no copy; CHOLMOD only reads it).
  static cholmod_sparse view(const Eigen::SparseMatrix<double>& upper) {
    if (!upper.isCompressed())
      throw std::invalid_argument("CholmodCholesky: matrix not compressed");
    cholmod_sparse a{};
    a.nrow = a.ncol = static_cast<size_t>(upper.rows());
    a.nzmax = static_cast<size_t>(upper.nonZeros());
    a.p = const_cast<int*>(upper.outerIndexPtr());
    a.i = const_cast<int*>(upper.innerIndexPtr());
    a.x = const_cast<double*>(upper.valuePtr());
    a.stype = 1;  // the upper triangle of a symmetric matrix
    a.itype = CHOLMOD_INT;
    a.xtype = CHOLMOD_REAL;
    a.dtype = CHOLMOD_DOUBLE;
    a.sorted = 1;
    a.packed = 1;
    return a;
  }

  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const {
    if (factor == nullptr || !factor->is_ll)
      throw std::logic_error("CholmodCholesky::solve without a factorization");
    if (b.rows() != n) throw std::invalid_argument("CholmodCholesky::solve: size mismatch");
    cholmod_dense rhs{};
    rhs.nrow = static_cast<size_t>(n);
    rhs.ncol = static_cast<size_t>(b.cols());
    rhs.nzmax = rhs.nrow * rhs.ncol;
    rhs.d = rhs.nrow;
    rhs.x = const_cast<double*>(b.data());
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    cholmod_common& c = const_cast<cholmod_common&>(common);
    if (!cholmod_solve2(CHOLMOD_A, factor, &rhs, nullptr, &x, nullptr, &y, &e, &c))
      throw std::runtime_error("CHOLMOD solve failed (status " + std::to_string(c.status) + ")");
    return Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(x->x), n, b.cols());
  }
};

CholmodCholesky::CholmodCholesky() : impl_(std::make_unique<Impl>()) {
  // Debian's CHOLMOD runs a few loops per supernode (clearing its maps, zeroing a supernode)
  // as OpenMP regions of a compiled-in 4 threads, whatever OMP_NUM_THREADS says. On 2 cores
  // their wake-ups took 3.9 s of system time in a 30 x 30-member run (15.2 s against 6.5 s
  // without them); the work that counts is in BLAS. No OpenMP region of this process runs in
  // parallel after this (nothing else here uses OpenMP).
  static std::once_flag serial;
  std::call_once(serial, [] { omp_set_max_active_levels(0); });
  cholmod_common& c = impl_->common;
  c.print = 0;  // status is checked here, never printed
  c.supernodal = CHOLMOD_SUPERNODAL;
  c.quick_return_if_not_posdef = 1;  // a failed trial costs only up to the failing column
  c.final_ll = 1;
  c.nmethods = 1;  // the given order, postordered: no ordering of its own
  c.method[0].ordering = CHOLMOD_NATURAL;
  c.postorder = 1;
}

CholmodCholesky::~CholmodCholesky() = default;

void CholmodCholesky::analyze(const Eigen::SparseMatrix<double>& upper) {
  Impl& m = *impl_;
  cholmod_free_factor(&m.factor, &m.common);
  ok_ = false;
  cholmod_sparse a = Impl::view(upper);
  m.factor = cholmod_analyze(&a, &m.common);
  if (m.factor == nullptr)
    throw std::runtime_error("CHOLMOD analysis failed (status " + std::to_string(m.common.status) +
                             ")");
  m.n = static_cast<int>(upper.rows());
  m.nnz = upper.nonZeros();
}

bool CholmodCholesky::factorize(const Eigen::SparseMatrix<double>& upper) {
  Impl& m = *impl_;
  if (m.factor == nullptr) throw std::logic_error("CholmodCholesky::factorize before analyze");
  if (upper.rows() != m.n || upper.nonZeros() != m.nnz)
    throw std::invalid_argument("CholmodCholesky::factorize: not the analysed pattern");
  cholmod_sparse a = Impl::view(upper);
  const int done = cholmod_factorize(&a, m.factor, &m.common);
  ok_ = done && m.common.status == CHOLMOD_OK && m.factor->minor == m.factor->n;
  if (!done && m.common.status < 0)
    throw std::runtime_error("CHOLMOD factorization failed (status " +
                             std::to_string(m.common.status) + ")");
  return ok_;
}

Eigen::VectorXd CholmodCholesky::solve(const Eigen::VectorXd& b) const {
  if (!ok_) throw std::logic_error("CholmodCholesky::solve without a successful factorization");
  return impl_->solve(b);
}

Eigen::MatrixXd CholmodCholesky::solve_many(const Eigen::MatrixXd& b) const {
  if (!ok_) throw std::logic_error("CholmodCholesky::solve without a successful factorization");
  return impl_->solve(b);
}

Eigen::MatrixXd CholmodCholesky::inverse_submatrix(const std::vector<int>& unknowns) const {
  const int k = static_cast<int>(unknowns.size());
  for (int u : unknowns)
    if (u < 0 || u >= impl_->n)
      throw std::invalid_argument("CholmodCholesky::inverse_submatrix: no unknown " +
                                  std::to_string(u));
  Eigen::MatrixXd e = Eigen::MatrixXd::Zero(impl_->n, k);
  for (int j = 0; j < k; ++j) e(unknowns[j], j) = 1;
  const Eigen::MatrixXd x = solve_many(e);
  Eigen::MatrixXd s(k, k);
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) s(i, j) = x(unknowns[i], j);
  return 0.5 * (s + s.transpose());
}

long CholmodCholesky::factor_nonzeros() const {
  const cholmod_factor* f = impl_->factor;
  if (f == nullptr) return 0;
  return static_cast<long>(f->is_super ? f->xsize : f->nzmax);
}

double CholmodCholesky::factor_flops() const { return impl_->common.fl; }

std::vector<int> nested_dissection_order(const std::vector<std::vector<int>>& adjacent) {
  const int n = static_cast<int>(adjacent.size());
  std::vector<int> p(static_cast<size_t>(n) + 1, 0), i;
  for (int j = 0; j < n; ++j) {
    for (int k : adjacent[j])
      if (k <= j) i.push_back(k);  // the upper triangle (CHOLMOD reads only that)
    p[j + 1] = static_cast<int>(i.size());
  }
  std::vector<int> order(static_cast<size_t>(n));
  if (n == 0) return order;
  cholmod_common c{};
  cholmod_start(&c);
  c.print = 0;
  cholmod_sparse a{};
  a.nrow = a.ncol = static_cast<size_t>(n);
  a.nzmax = i.size();
  a.p = p.data();
  a.i = i.data();
  a.stype = 1;
  a.itype = CHOLMOD_INT;
  a.xtype = CHOLMOD_PATTERN;
  a.dtype = CHOLMOD_DOUBLE;
  a.sorted = 1;
  a.packed = 1;
  const int done = cholmod_metis(&a, nullptr, 0, 1, order.data(), &c);
  const int status = c.status;
  cholmod_finish(&c);
  if (!done)
    throw std::runtime_error("METIS ordering failed (status " + std::to_string(status) + ")");
  return order;
}

long CholmodCholesky::peak_bytes() const { return static_cast<long>(impl_->common.memory_usage); }

}  // namespace gridshell
