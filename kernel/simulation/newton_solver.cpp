// SPDX-License-Identifier: GPL-3.0-or-later
#include "newton_solver.h"

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <unordered_map>

#include "cholmod_cholesky.h"
#include "gridshell/foundation/parallel.h"
#include "sparse_cholesky.h"

namespace gridshell {

namespace {
/// Adds the seconds of its scope to a total.
class Timed {
 public:
  explicit Timed(double& total) : total_(total), start_(std::chrono::steady_clock::now()) {}
  ~Timed() {
    total_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  Timed(const Timed&) = delete;
  Timed& operator=(const Timed&) = delete;

 private:
  double& total_;
  std::chrono::steady_clock::time_point start_;
};

/// Fraction to the boundary: a barrier coordinate moves at most this fraction of the way to
/// the bound of its domain in one step.
constexpr double kToBoundary = 0.95;
/// Held steps for at most this many barrier coordinates at once (a right-hand side each).
constexpr int kMaxHeld = 64;
}  // namespace

struct NewtonSolver::Impl {
  std::vector<std::pair<double*, int>> blocks;
  std::vector<Term> terms;
  int unknowns = 0;
  struct TermLayout {
    std::vector<int> offset;  // per parameter: global offset, -1 if constant
    std::vector<int> local;   // per parameter: local offset among the free ones
    int free_size = 0;
    int residuals = 0;
    std::vector<int> value_index;       // per local (p, q) with p <= q in global terms, or -1
    mutable Eigen::MatrixXd curvature;  // last numeric curvature (written by one thread only)
  };
  std::vector<TermLayout> layout;
  std::unordered_map<const double*, int> offset_of;
  std::vector<int> block_offset;        // per block: its first unknown
  std::vector<double> limits;           // per block, 0 = unlimited
  Eigen::SparseMatrix<double> hessian;  // upper triangle
  Eigen::SparseMatrix<double> damped;   // step(): hessian + lambda D (same pattern)
  std::vector<int> diagonal;            // value index of each diagonal entry
  Eigen::VectorXd gradient;
  // The unknowns are numbered in a fill-reducing order already (see the constructor): minimum
  // degree of the blocks for the block kernel, nested dissection of the blocks for CHOLMOD
  // (which then only postorders its elimination tree).
  mutable NewtonSolver::Stats stats;
  struct Factorization {
    BlockCholesky block;
    std::shared_ptr<CholmodCholesky> cholmod;  // in place of `block` when set
    bool factorize(const Eigen::SparseMatrix<double>& a) {
      return cholmod ? cholmod->factorize(a) : block.factorize(a);
    }
    Eigen::VectorXd solve(const Eigen::VectorXd& b) const {
      return cholmod ? cholmod->solve(b) : block.solve(b);
    }
    Eigen::MatrixXd inverse_submatrix(const std::vector<int>& unknowns) const {
      return cholmod ? cholmod->inverse_submatrix(unknowns) : block.inverse_submatrix(unknowns);
    }
  } cholesky;
  int threads = 1;
  /// Scratch of one term's evaluation (per worker, reused across terms and evaluations).
  struct Scratch {
    std::vector<double> residuals, jacobian_storage, rr, js;
    std::vector<double*> jacobians, jp;
    std::vector<std::vector<double>> copies;
    std::vector<const double*> pointers;
    Eigen::MatrixXd J, H, C;
    Eigen::VectorXd g, g0, gk;
    double cost = 0;
  };
  std::vector<Scratch> scratch;  // one per worker
  // With several workers, every term's local Hessian, gradient and cost are kept until they are
  // added up in term order (the same order as with one worker: the sums do not depend on the
  // thread count).
  std::vector<size_t> term_offset;  // per term: start of its local Hessian in term_hessian
  std::vector<double> term_hessian, term_gradient, term_cost;
  std::vector<size_t> term_gradient_offset;

  bool exact_hessian = false;
  bool refresh_curvature = true;
  int evaluations = 0;

  /// Cost, gradient and local Hessian (J^T J plus the curvature correction) of term t into
  /// `s` (s.H: free x free in local order, s.g: free). False if the term cannot be evaluated.
  bool evaluate_term(size_t t, Scratch& s) const {
    const Term& term = terms[t];
    const TermLayout& l = layout[t];
    const auto& sizes = term.cost->parameter_block_sizes();
    s.residuals.assign(l.residuals, 0.0);
    s.jacobian_storage.assign(static_cast<size_t>(l.residuals) * l.free_size, 0.0);
    s.jacobians.assign(sizes.size(), nullptr);
    for (size_t p = 0; p < sizes.size(); ++p)
      if (l.offset[p] >= 0)
        s.jacobians[p] = s.jacobian_storage.data() + static_cast<size_t>(l.residuals) * l.local[p];
    if (!term.cost->Evaluate(term.parameters.data(), s.residuals.data(), s.jacobians.data()))
      return false;
    // Each block's Jacobian is row-major residuals x size; gather into J (residuals x m).
    Eigen::MatrixXd& J = s.J;
    J.resize(l.residuals, l.free_size);
    for (size_t p = 0; p < sizes.size(); ++p) {
      if (l.offset[p] < 0) continue;
      const double* block = s.jacobians[p];
      for (int r = 0; r < l.residuals; ++r)
        for (int c = 0; c < sizes[p]; ++c) J(r, l.local[p] + c) = block[r * sizes[p] + c];
    }
    const Eigen::Map<const Eigen::VectorXd> r(s.residuals.data(), l.residuals);
    s.cost = 0;
    for (double v : s.residuals) s.cost += 0.5 * v * v;
    Eigen::MatrixXd& H = s.H;
    H.noalias() = J.transpose() * J;
    s.g.noalias() = J.transpose() * r;
    if (term.curvature) {
      term.curvature(s.residuals.data(), H);
    } else if (exact_hessian && term.numeric_curvature && !refresh_curvature &&
               l.curvature.rows() == l.free_size) {
      H += l.curvature;  // lagged: from the last refresh
    } else if (exact_hessian && term.numeric_curvature) {
      // sum_i r_i Hess(r_i) = Hess(rbar . r) at rbar = r, by forward differences of the exact
      // gradient J(x + e_k h)^T rbar, symmetrized.
      Eigen::MatrixXd& C = s.C;
      C.resize(l.free_size, l.free_size);
      // Perturb private copies: other threads read the shared blocks meanwhile.
      s.copies.resize(sizes.size());
      s.pointers.resize(sizes.size());
      for (size_t p = 0; p < sizes.size(); ++p) {
        s.copies[p].assign(term.parameters[p], term.parameters[p] + sizes[p]);
        s.pointers[p] = s.copies[p].data();
      }
      s.rr.resize(l.residuals);
      s.js.resize(s.jacobian_storage.size());
      s.jp.assign(sizes.size(), nullptr);
      for (size_t p = 0; p < sizes.size(); ++p)
        if (l.offset[p] >= 0) s.jp[p] = s.js.data() + static_cast<size_t>(l.residuals) * l.local[p];
      for (size_t p = 0; p < sizes.size(); ++p) {
        if (l.offset[p] < 0) continue;
        for (int c = 0; c < sizes[p]; ++c) {
          double& v = s.copies[p][c];
          const double keep = v, h = 1e-7 * std::max(1.0, std::abs(keep));
          v = keep + h;
          const double step = v - keep;  // exactly representable
          term.cost->Evaluate(s.pointers.data(), s.rr.data(), s.jp.data());
          v = keep;
          s.gk.setZero(l.free_size);
          for (size_t q = 0; q < sizes.size(); ++q) {
            if (l.offset[q] < 0) continue;
            for (int r2 = 0; r2 < l.residuals; ++r2)
              for (int b = 0; b < sizes[q]; ++b)
                s.gk[l.local[q] + b] += s.jp[q][r2 * sizes[q] + b] * s.residuals[r2];
          }
          C.col(l.local[p] + c) = (s.gk - s.g) / step;
        }
      }
      l.curvature = 0.5 * (C + C.transpose());
      H += l.curvature;
    }
    return true;
  }

  /// Adds a term's local Hessian (free x free, column-major), gradient and cost to the totals.
  void scatter(size_t t, const double* H, const double* g, double cost, double* values,
               double* cost_out) {
    const Term& term = terms[t];
    const TermLayout& l = layout[t];
    const auto& sizes = term.cost->parameter_block_sizes();
    for (size_t p = 0; p < sizes.size(); ++p) {
      if (l.offset[p] < 0) continue;
      for (int a = 0; a < sizes[p]; ++a) gradient[l.offset[p] + a] += g[l.local[p] + a];
    }
    const int m = l.free_size;
    for (int p = 0; p < m; ++p)
      for (int q = 0; q < m; ++q) {
        const int index = l.value_index[static_cast<size_t>(p) * m + q];
        if (index >= 0) values[index] += H[static_cast<size_t>(q) * m + p];
      }
    *cost_out += cost;
  }
};

NewtonSolver::NewtonSolver(std::vector<std::pair<double*, int>> blocks, std::vector<Term> terms,
                           Options options)
    : impl_(std::make_unique<Impl>()), options_(options) {
  Impl& m = *impl_;
  m.blocks = std::move(blocks);
  m.terms = std::move(terms);
  m.threads = std::max(1, options.threads);
  lambda_ = options.initial_lambda;
  const int nb = static_cast<int>(m.blocks.size());
  std::unordered_map<const double*, int> block_of;
  for (int b = 0; b < nb; ++b) block_of[m.blocks[b].first] = b;
  // Per term and parameter: its free block, or -1 if constant.
  std::vector<std::vector<int>> term_blocks(m.terms.size());
  for (size_t t = 0; t < m.terms.size(); ++t)
    for (const double* p : m.terms[t].parameters) {
      const auto it = block_of.find(p);
      term_blocks[t].push_back(it == block_of.end() ? -1 : it->second);
    }

  // Unknowns are numbered block by block, the blocks in a fill-reducing order: approximate
  // minimum degree on the graph of blocks that share a term (a block's unknowns stay
  // consecutive, and the graph is 2-3x smaller than the unknowns'; the factor's fill was within
  // 1.5% of AMD on the unknowns on the examples). The Hessian is assembled in its factorization
  // order and the Cholesky needs no permutation.
  // The graph of blocks: per block, itself and every block it shares a term with (sorted).
  long total = 0;
  for (const auto& block : m.blocks) total += block.second;
  const bool use_cholmod = options_.cholmod_from > 0 && total >= options_.cholmod_from;
  std::vector<std::vector<int>> adjacent(nb);
  for (int b = 0; b < nb; ++b) adjacent[b].push_back(b);
  for (size_t t = 0; t < m.terms.size(); ++t) {
    std::vector<int> clique = term_blocks[t];
    if (use_cholmod)  // the couplings it may have after a rebuild, for a pattern that stays
      for (const double* p : m.terms[t].may_read) {
        const auto it = block_of.find(p);
        if (it != block_of.end()) clique.push_back(it->second);
      }
    for (int x : clique)
      if (x >= 0)
        for (int y : clique)
          if (y >= 0 && y != x) adjacent[x].push_back(y);
  }
  size_t edges = 0;
  for (std::vector<int>& list : adjacent) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    edges += list.size();
  }
  {
    const Timed timed(m.stats.analyze_seconds);  // the ordering is part of the analysis
    // AMD on the (symmetric) graph as it is; AMDOrdering would symmetrize it once more.
    Eigen::SparseMatrix<int> G(nb, nb);
    G.resizeNonZeros(static_cast<Eigen::Index>(edges));
    int k = 0;
    for (int b = 0; b < nb; ++b) {
      G.outerIndexPtr()[b] = k;
      for (int a : adjacent[b]) {
        G.innerIndexPtr()[k] = a;
        G.valuePtr()[k++] = 1;
      }
    }
    G.outerIndexPtr()[nb] = k;
    std::vector<int> order;  // order[k]: the block eliminated k-th
    if (use_cholmod) {
      // Nested dissection: for grids far better than minimum degree (docs/solver.md).
      const auto& cache = options_.order_cache;
      if (cache && cache->blocks == m.blocks && cache->adjacent == adjacent) {
        order = cache->order;
        m.cholesky.cholmod = cache->analysed;  // the same pattern in the same order
      } else {
        order = nested_dissection_order(adjacent);
        if (cache) {
          cache->blocks = m.blocks;
          cache->adjacent = adjacent;
          cache->order = order;
          cache->analysed.reset();
        }
      }
    } else {
      Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> amd;
      Eigen::internal::minimum_degree_ordering(G, amd);
      order.assign(amd.indices().data(), amd.indices().data() + nb);
    }
    m.block_offset.assign(nb, 0);
    for (int k = 0; k < nb; ++k) {
      const int b = order[k];
      m.block_offset[b] = m.unknowns;
      m.unknowns += m.blocks[b].second;
    }
    for (int b = 0; b < nb; ++b) m.offset_of[m.blocks[b].first] = m.block_offset[b];
  }

  // The Hessian's pattern (upper triangle, column-major) block by block: the columns of block
  // B hold, in this order, every unknown of each block A numbered before B that shares a term
  // with it (`above[B]`, by offset), then B's own unknowns up to the diagonal.
  std::vector<std::vector<int>> above(nb);
  for (int B = 0; B < nb; ++B)
    for (int A : adjacent[B])
      if (m.block_offset[A] < m.block_offset[B]) above[B].push_back(A);
  std::vector<std::vector<int>> prefix(nb);  // per B: rows before each block of above[B]
  std::vector<int> rows_above(nb, 0);
  for (int B = 0; B < nb; ++B) {
    auto& list = above[B];
    std::sort(list.begin(), list.end(),
              [&](int x, int y) { return m.block_offset[x] < m.block_offset[y]; });
    for (int A : list) {
      prefix[B].push_back(rows_above[B]);
      rows_above[B] += m.blocks[A].second;
    }
  }
  std::vector<int> outer(m.unknowns + 1, 0), column_block(m.unknowns);
  for (int B = 0; B < nb; ++B)
    for (int j = 0; j < m.blocks[B].second; ++j) {
      column_block[m.block_offset[B] + j] = B;
      outer[m.block_offset[B] + j + 1] = rows_above[B] + j + 1;
    }
  for (int c = 0; c < m.unknowns; ++c) outer[c + 1] += outer[c];
  std::vector<int> inner(outer[m.unknowns]);
  for (int c = 0; c < m.unknowns; ++c) {
    const int B = column_block[c];
    int k = outer[c];
    for (int A : above[B])
      for (int a = 0; a < m.blocks[A].second; ++a) inner[k++] = m.block_offset[A] + a;
    for (int r = m.block_offset[B]; r <= c; ++r) inner[k++] = r;
  }
  std::vector<double> zeros(inner.size(), 0.0);
  m.hessian = Eigen::Map<const Eigen::SparseMatrix<double>>(
      m.unknowns, m.unknowns, static_cast<int>(inner.size()), outer.data(), inner.data(),
      zeros.data());
  m.diagonal.resize(m.unknowns);
  for (int c = 0; c < m.unknowns; ++c) m.diagonal[c] = outer[c + 1] - 1;

  // Layout of every term: where its free parameters' unknowns are, and where each entry of
  // its local Hessian goes.
  m.layout.resize(m.terms.size());
  for (size_t t = 0; t < m.terms.size(); ++t) {
    const Term& term = m.terms[t];
    Impl::TermLayout& l = m.layout[t];
    const auto& sizes = term.cost->parameter_block_sizes();
    l.residuals = term.cost->num_residuals();
    for (size_t p = 0; p < sizes.size(); ++p) {
      const int B = term_blocks[t][p];
      l.offset.push_back(B < 0 ? -1 : m.block_offset[B]);
      l.local.push_back(l.free_size);
      if (B >= 0) l.free_size += sizes[p];
    }
    l.value_index.assign(static_cast<size_t>(l.free_size) * l.free_size, -1);
    for (size_t p = 0; p < sizes.size(); ++p)
      for (size_t q = 0; q < sizes.size(); ++q) {
        const int A = term_blocks[t][p], B = term_blocks[t][q];
        if (A < 0 || B < 0 || m.block_offset[A] > m.block_offset[B]) continue;
        // Each local entry that maps to an upper entry (row <= col) adds to it; a diagonal
        // entry only from its own local diagonal (as when a block repeats in the term: its
        // off-diagonal local copies of a diagonal entry are not counted twice).
        const bool same = A == B;
        // The rows of block A in B's columns start here (relative to each column's start).
        int start = rows_above[B];
        if (!same) {
          const auto& list = above[B];
          const auto it = std::lower_bound(list.begin(), list.end(), A, [&](int x, int y) {
            return m.block_offset[x] < m.block_offset[y];
          });
          start = prefix[B][it - list.begin()];
        }
        for (int a = 0; a < sizes[p]; ++a)
          for (int b = 0; b < sizes[q]; ++b) {
            if (same && (p == q ? a > b : a >= b)) continue;
            l.value_index[(l.local[p] + a) * l.free_size + l.local[q] + b] =
                outer[m.block_offset[B] + b] + start + a;
          }
      }
  }
  {
    // The factorization's blocks: the parameter blocks, in the order of their unknowns.
    std::vector<int> sizes(m.unknowns, 0), block_sizes;
    for (int b = 0; b < nb; ++b) sizes[m.block_offset[b]] = m.blocks[b].second;
    for (int size : sizes)
      if (size > 0) block_sizes.push_back(size);
    const Timed timed(m.stats.analyze_seconds);
    m.stats.unknowns = m.unknowns;
    if (use_cholmod) {
      if (!m.cholesky.cholmod) {
        m.cholesky.cholmod = std::make_shared<CholmodCholesky>();
        m.cholesky.cholmod->analyze(m.hessian);
        if (options_.order_cache) options_.order_cache->analysed = m.cholesky.cholmod;
        ++m.stats.analyses;
      }
      m.stats.factorization = "cholmod";
    } else {
      m.cholesky.block.analyze(m.hessian, block_sizes);
      ++m.stats.analyses;
      m.stats.factorization = "block";
    }
  }
  m.gradient = Eigen::VectorXd::Zero(m.unknowns);
}

NewtonSolver::~NewtonSolver() = default;

const NewtonSolver::Stats& NewtonSolver::stats() const { return impl_->stats; }

bool NewtonSolver::evaluate() {
  Impl& m = *impl_;
  const Timed timed(m.stats.evaluate_seconds);
  ++m.stats.evaluations;
  // The numeric curvature changes slowly; refresh it every options_.curvature_refresh calls.
  m.refresh_curvature = m.evaluations % std::max(1, options_.curvature_refresh) == 0;
  if (m.exact_hessian) ++m.evaluations;
  const size_t count = m.terms.size();
  const int nnz = static_cast<int>(m.hessian.nonZeros());
  double* values = m.hessian.valuePtr();
  std::fill(values, values + nnz, 0.0);
  m.gradient.setZero(m.unknowns);
  double cost = 0;
  const int workers = std::max(1, std::min<int>(m.threads, static_cast<int>(count)));
  m.scratch.resize(workers);
  if (workers == 1) {
    // Term by term, added up as they come (the same order as below).
    Impl::Scratch& s = m.scratch[0];
    for (size_t t = 0; t < count; ++t) {
      if (!m.evaluate_term(t, s)) return false;
      m.scatter(t, s.H.data(), s.g.data(), s.cost, values, &cost);
    }
  } else {
    if (m.term_offset.size() != count + 1) {
      m.term_offset.assign(count + 1, 0);
      m.term_gradient_offset.assign(count + 1, 0);
      for (size_t t = 0; t < count; ++t) {
        const size_t free = static_cast<size_t>(m.layout[t].free_size);
        m.term_offset[t + 1] = m.term_offset[t] + free * free;
        m.term_gradient_offset[t + 1] = m.term_gradient_offset[t] + free;
      }
      m.term_hessian.resize(m.term_offset[count]);
      m.term_gradient.resize(m.term_gradient_offset[count]);
      m.term_cost.resize(count);
    }
    std::vector<char> oks(workers, 1);
    ParallelOptions parallel;
    parallel.threads = workers;
    parallel_for(
        workers,
        [&](std::size_t w, const Progress&) {
          Impl::Scratch& s = m.scratch[w];
          for (size_t t = count * w / workers; t < count * (w + 1) / workers; ++t) {
            if (!m.evaluate_term(t, s)) {
              oks[w] = 0;
              return;
            }
            std::copy(s.H.data(), s.H.data() + s.H.size(),
                      m.term_hessian.data() + m.term_offset[t]);
            std::copy(s.g.data(), s.g.data() + s.g.size(),
                      m.term_gradient.data() + m.term_gradient_offset[t]);
            m.term_cost[t] = s.cost;
          }
        },
        {}, parallel);
    for (char ok : oks)
      if (!ok) return false;
    for (size_t t = 0; t < count; ++t)
      m.scatter(t, m.term_hessian.data() + m.term_offset[t],
                m.term_gradient.data() + m.term_gradient_offset[t], m.term_cost[t], values, &cost);
  }
  cost_ = cost;
  return true;
}

void NewtonSolver::set_step_limits(std::vector<double> limits) {
  limits.resize(impl_->blocks.size(), 0.0);
  impl_->limits = std::move(limits);
}

void NewtonSolver::set_exact_hessian(bool exact) {
  if (exact && !impl_->exact_hessian) impl_->evaluations = 0;
  impl_->exact_hessian = exact;
}

double NewtonSolver::gradient_at(const double* block) const {
  const auto it = impl_->offset_of.find(block);
  return it == impl_->offset_of.end() || impl_->gradient.size() == 0 ? 0.0
                                                                     : impl_->gradient[it->second];
}

double NewtonSolver::gradient_norm_at(const double* block, int size) const {
  const auto it = impl_->offset_of.find(block);
  if (it == impl_->offset_of.end() || impl_->gradient.size() == 0) return 0.0;
  return impl_->gradient.segment(it->second, size).cwiseAbs().maxCoeff();
}

double NewtonSolver::gradient_max_norm() const {
  return impl_->gradient.size() ? impl_->gradient.cwiseAbs().maxCoeff() : 0.0;
}

bool NewtonSolver::evaluate_cost(double* cost) const {
  const Impl& m = *impl_;
  const Timed timed(m.stats.cost_seconds);
  ++m.stats.cost_evaluations;
  std::vector<double> residuals;
  double sum = 0;
  for (const Term& term : m.terms) {
    residuals.assign(term.cost->num_residuals(), 0.0);
    if (!term.cost->Evaluate(term.parameters.data(), residuals.data(), nullptr)) return false;
    for (double v : residuals) sum += 0.5 * v * v;
  }
  *cost = sum;
  return std::isfinite(sum);
}

Eigen::VectorXd NewtonSolver::read() const {
  const Impl& m = *impl_;
  Eigen::VectorXd x(m.unknowns);
  for (size_t b = 0; b < m.blocks.size(); ++b)
    for (int a = 0; a < m.blocks[b].second; ++a) x[m.block_offset[b] + a] = m.blocks[b].first[a];
  return x;
}

void NewtonSolver::write(const Eigen::VectorXd& x) const {
  const Impl& m = *impl_;
  for (size_t b = 0; b < m.blocks.size(); ++b)
    for (int a = 0; a < m.blocks[b].second; ++a) m.blocks[b].first[a] = x[m.block_offset[b] + a];
}

std::vector<std::pair<int, double>> NewtonSolver::barrier_limits(const Eigen::VectorXd& d) const {
  const Impl& m = *impl_;
  std::vector<std::pair<int, double>> limits;
  for (const Term& term : m.terms) {
    if (!std::isfinite(term.lower) && !std::isfinite(term.upper)) continue;
    const auto it = m.offset_of.find(term.parameters[0]);
    if (it == m.offset_of.end()) continue;
    const int i = it->second;
    const double value = *term.parameters[0];
    double limit = d[i];
    if (d[i] < 0 && std::isfinite(term.lower))
      limit = std::max(limit, -kToBoundary * (value - term.lower));
    if (d[i] > 0 && std::isfinite(term.upper))
      limit = std::min(limit, kToBoundary * (term.upper - value));
    if (limit == d[i]) continue;
    // A coordinate in several barrier terms (friction and notch limit): the tightest.
    const auto same =
        std::find_if(limits.begin(), limits.end(), [&](const auto& l) { return l.first == i; });
    if (same == limits.end())
      limits.emplace_back(i, limit);
    else if (std::abs(limit) < std::abs(same->second))
      same->second = limit;
  }
  return limits;
}

double NewtonSolver::barrier_fraction(const Eigen::VectorXd& d) const {
  double alpha = 1;
  for (const auto& [i, limit] : barrier_limits(d)) alpha = std::min(alpha, limit / d[i]);
  return alpha;
}

double NewtonSolver::trust_fraction(const Eigen::VectorXd& d) const {
  const Impl& m = *impl_;
  double alpha = 1;
  for (size_t b = 0; b < m.limits.size(); ++b)
    if (m.limits[b] > 0) {
      const double longest = d.segment(m.block_offset[b], m.blocks[b].second).cwiseAbs().maxCoeff();
      if (longest > m.limits[b]) alpha = std::min(alpha, m.limits[b] / longest);
    }
  return alpha;
}

bool NewtonSolver::held_step(const Eigen::VectorXd& d, Eigen::VectorXd& p) const {
  const Impl& m = *impl_;
  const std::vector<std::pair<int, double>> held = barrier_limits(d);
  const int k = static_cast<int>(held.size());
  if (k == 0 || k > kMaxHeld) return false;
  // Minimize the damped model g.p + p.A.p/2 (A = H + lambda D, factorized) subject to
  // p_i = limit_i for the held i: p = d + A^-1 E mu (E: their unit vectors) with mu from
  // S mu = limit - E^T d, S = E^T A^-1 E (a principal submatrix of A^-1, positive definite;
  // from k short forward substitutions), then one solve for A^-1 E mu.
  std::vector<int> unknowns;
  Eigen::VectorXd r(k);
  for (int j = 0; j < k; ++j) {
    unknowns.push_back(held[j].first);
    r[j] = held[j].second - d[held[j].first];
  }
  const Eigen::MatrixXd S = m.cholesky.inverse_submatrix(unknowns);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(S);
  if (ldlt.info() != Eigen::Success) return false;
  const Eigen::VectorXd mu = ldlt.solve(r);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(d.size());
  for (int j = 0; j < k; ++j) v[unknowns[j]] = mu[j];
  p = d + m.cholesky.solve(v);
  return p.allFinite();
}

NewtonSolver::StepResult NewtonSolver::step(int max_trials) {
  Impl& m = *impl_;
  StepResult result;
  const Eigen::VectorXd x0 = read();
  if (m.damped.nonZeros() != m.hessian.nonZeros()) m.damped = m.hessian;
  Eigen::SparseMatrix<double>& A = m.damped;
  const double* h = m.hessian.valuePtr();
  double max_diagonal = 0;
  for (int i : m.diagonal) max_diagonal = std::max(max_diagonal, std::abs(h[i]));
  const double floor = std::max(max_diagonal, 1e-300) * 1e-12;
  while (true) {
    if (lambda_ > options_.max_lambda) {
      result.stalled = true;
      write(x0);
      return result;
    }
    if (result.trials >= max_trials) {
      result.out_of_trials = true;
      write(x0);
      return result;
    }
    ++result.trials;
    std::copy(h, h + m.hessian.nonZeros(), A.valuePtr());
    for (int i : m.diagonal) A.valuePtr()[i] += lambda_ * std::max(std::abs(h[i]), floor);
    bool factorized = false;
    {
      const Timed timed(m.stats.factorize_seconds);
      ++m.stats.factorizations;
      factorized = m.cholesky.factorize(A);
    }
    if (!factorized) {
      ++m.stats.failed_factorizations;
      lambda_ = std::max(lambda_ * nu_, 1e-8);
      nu_ *= 2;
      continue;
    }
    m.stats.factor_nonzeros = m.cholesky.cholmod ? m.cholesky.cholmod->factor_nonzeros()
                                                 : m.cholesky.block.factor_nonzeros();
    Eigen::VectorXd d;
    {
      const Timed timed(m.stats.solve_seconds);
      d = m.cholesky.solve(-m.gradient);
    }
    // The fraction to the boundary of every barrier's domain (uniform: the step alpha d) and
    // the trust radii (alpha_trust d: shorten the step along the same direction).
    const double alpha_barrier = barrier_fraction(d);
    const double alpha_trust = trust_fraction(d);
    const double alpha = std::min(alpha_barrier, alpha_trust);
    const Eigen::VectorXd Hd = m.hessian.selfadjointView<Eigen::Upper>() * d;
    const double gd = m.gradient.dot(d), dHd = d.dot(Hd);
    if (!(gd < 0) || !d.allFinite()) {  // not a descent direction: damp more
      lambda_ = std::max(lambda_ * nu_, 1e-8);
      nu_ *= 2;
      continue;
    }
    const double rounding = 1e-13 * std::abs(cost_);
    // The gain ratio of the trial x0 + p against the quadratic model (gp = g.p, pHp = p.H.p),
    // or -1 if the cost cannot be evaluated there or the model predicts no decrease.
    const auto gain = [&](const Eigen::VectorXd& p, double gp, double pHp) {
      const double predicted = -(gp + 0.5 * pHp);
      double trial = 0;
      write(x0 + p);
      if (!(predicted > 0) || !evaluate_cost(&trial)) return -1.0;
      // Near the minimum the predicted decrease drops below the cost's rounding: accept a step
      // that does not raise the cost beyond rounding and let the gradient decide convergence.
      if (predicted < rounding && trial <= cost_ + rounding) return 1.0;
      return (cost_ - trial) / predicted;
    };
    // Less damping when the model predicted a first trial well. A step shortened by the
    // fraction to a barrier's boundary still validates the model (the same quadratic model
    // along the direction tried); one shortened by a trust radius or by backtracking does not.
    const auto accept = [&](const Eigen::VectorXd& p, double rho, bool validates_model) {
      if (validates_model)
        lambda_ = std::max(options_.min_lambda,
                           lambda_ * std::max(1.0 / 3.0, 1.0 - std::pow(2 * rho - 1, 3)));
      nu_ = 2;
      result.accepted = true;
      result.relative_step = (p.array().abs() / (1 + x0.array().abs())).maxCoeff();
      return result;
    };
    constexpr double kMinGain = 1e-4;
    if (alpha_barrier < alpha_trust) {
      // A barrier coordinate (a sliding connection reaching the end of its edge) binds: first
      // the step that holds only those coordinates back, the rest taking the minimizer of the
      // same damped model, then backtracking along it once.
      Eigen::VectorXd p;
      if (held_step(d, p)) {
        // Other barrier coordinates may now go (nearly) out of their domains in turn (the held
        // ones are at their fraction: ~1 for them), and the trust radii apply.
        const double p_trust = trust_fraction(p);
        p *= std::min(barrier_fraction(p), p_trust);
        const Eigen::VectorXd Hp = m.hessian.selfadjointView<Eigen::Upper>() * p;
        const double gp = m.gradient.dot(p), pHp = p.dot(Hp);
        double scale = 1;
        for (int attempt = 0; attempt < 2; ++attempt, scale *= 0.5) {
          const double rho = gain(scale * p, scale * gp, scale * scale * pHp);
          if (rho > kMinGain) return accept(scale * p, rho, attempt == 0 && p_trust >= 1);
        }
      }
    }
    // The (shortened) step along d, then back off along it twice before damping more: a cost
    // evaluation is far cheaper than another factorization.
    double step = std::max(alpha, 0.0);
    for (int attempt = 0; attempt < 3; ++attempt, step *= 0.5) {
      const double rho = gain(step * d, step * gd, step * step * dHd);
      if (rho > kMinGain) return accept(step * d, rho, attempt == 0 && alpha_trust >= 1);
    }
    write(x0);
    lambda_ = std::max(lambda_ * nu_, 1e-8);
    nu_ *= 2;
  }
}

}  // namespace gridshell
