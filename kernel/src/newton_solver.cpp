#include "newton_solver.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <unordered_map>

namespace gridshell {

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
  std::vector<double> limits;           // per block, 0 = unlimited
  Eigen::SparseMatrix<double> hessian;  // upper triangle
  std::vector<int> diagonal;            // value index of each diagonal entry
  Eigen::VectorXd gradient;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Upper> cholesky;
  int threads = 1;

  bool exact_hessian = false;
  bool refresh_curvature = true;
  int evaluations = 0;

  void accumulate(size_t begin, size_t end, double* values, double* gradient_out, double* cost_out,
                  bool* ok_out) const {
    std::vector<double> residuals, jacobian_storage;
    std::vector<double*> jacobians;
    Eigen::MatrixXd J, H;
    double cost = 0;
    bool ok = true;
    for (size_t t = begin; t < end; ++t) {
      const Term& term = terms[t];
      const TermLayout& l = layout[t];
      const auto& sizes = term.cost->parameter_block_sizes();
      residuals.assign(l.residuals, 0.0);
      jacobian_storage.assign(static_cast<size_t>(l.residuals) * l.free_size, 0.0);
      jacobians.assign(sizes.size(), nullptr);
      for (size_t p = 0; p < sizes.size(); ++p)
        if (l.offset[p] >= 0)
          jacobians[p] = jacobian_storage.data() + static_cast<size_t>(l.residuals) * l.local[p];
      if (!term.cost->Evaluate(term.parameters.data(), residuals.data(), jacobians.data())) {
        ok = false;
        break;
      }
      // Each block's Jacobian is row-major residuals x size; gather into J (residuals x m).
      J.resize(l.residuals, l.free_size);
      for (size_t p = 0; p < sizes.size(); ++p) {
        if (l.offset[p] < 0) continue;
        const double* block = jacobians[p];
        for (int r = 0; r < l.residuals; ++r)
          for (int c = 0; c < sizes[p]; ++c) J(r, l.local[p] + c) = block[r * sizes[p] + c];
      }
      const Eigen::Map<const Eigen::VectorXd> r(residuals.data(), l.residuals);
      for (double v : residuals) cost += 0.5 * v * v;
      H.noalias() = J.transpose() * J;
      if (term.curvature) {
        term.curvature(residuals.data(), H);
      } else if (exact_hessian && term.numeric_curvature && !refresh_curvature &&
                 l.curvature.rows() == l.free_size) {
        H += l.curvature;  // lagged: from the last refresh
      } else if (exact_hessian && term.numeric_curvature) {
        // sum_i r_i Hess(r_i) = Hess(rbar . r) at rbar = r, by forward differences of the exact
        // (automatic) gradient J(x + e_k h)^T rbar, symmetrized.
        const Eigen::VectorXd g0 = J.transpose() * r;
        Eigen::MatrixXd C(l.free_size, l.free_size);
        // Perturb private copies: other threads read the shared blocks meanwhile.
        std::vector<std::vector<double>> copies(sizes.size());
        std::vector<const double*> pointers(sizes.size());
        for (size_t p = 0; p < sizes.size(); ++p) {
          copies[p].assign(term.parameters[p], term.parameters[p] + sizes[p]);
          pointers[p] = copies[p].data();
        }
        std::vector<double> rr(l.residuals), js(jacobian_storage.size());
        std::vector<double*> jp(sizes.size(), nullptr);
        for (size_t p = 0; p < sizes.size(); ++p)
          if (l.offset[p] >= 0) jp[p] = js.data() + static_cast<size_t>(l.residuals) * l.local[p];
        for (size_t p = 0; p < sizes.size(); ++p) {
          if (l.offset[p] < 0) continue;
          for (int c = 0; c < sizes[p]; ++c) {
            double& v = copies[p][c];
            const double keep = v, h = 1e-7 * std::max(1.0, std::abs(keep));
            v = keep + h;
            const double step = v - keep;  // exactly representable
            term.cost->Evaluate(pointers.data(), rr.data(), jp.data());
            v = keep;
            Eigen::VectorXd gk = Eigen::VectorXd::Zero(l.free_size);
            for (size_t q = 0; q < sizes.size(); ++q) {
              if (l.offset[q] < 0) continue;
              for (int r2 = 0; r2 < l.residuals; ++r2)
                for (int b = 0; b < sizes[q]; ++b)
                  gk[l.local[q] + b] += jp[q][r2 * sizes[q] + b] * residuals[r2];
            }
            C.col(l.local[p] + c) = (gk - g0) / step;
          }
        }
        l.curvature = 0.5 * (C + C.transpose());
        H += l.curvature;
      }
      const Eigen::VectorXd g = J.transpose() * r;
      for (size_t p = 0; p < sizes.size(); ++p) {
        if (l.offset[p] < 0) continue;
        for (int a = 0; a < sizes[p]; ++a) gradient_out[l.offset[p] + a] += g[l.local[p] + a];
      }
      size_t k = 0;
      for (int p = 0; p < l.free_size; ++p)
        for (int q = 0; q < l.free_size; ++q, ++k)
          if (l.value_index[k] >= 0) values[l.value_index[k]] += H(p, q);
    }
    *cost_out = cost;
    *ok_out = ok;
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
  std::unordered_map<const double*, int>& offset_of = m.offset_of;
  for (const auto& [pointer, size] : m.blocks) {
    offset_of[pointer] = m.unknowns;
    m.unknowns += size;
  }
  // Layout of every term and the Hessian's sparsity pattern (upper triangle).
  std::vector<Eigen::Triplet<double>> pattern;
  m.layout.resize(m.terms.size());
  for (size_t t = 0; t < m.terms.size(); ++t) {
    const Term& term = m.terms[t];
    Impl::TermLayout& l = m.layout[t];
    const auto& sizes = term.cost->parameter_block_sizes();
    l.residuals = term.cost->num_residuals();
    for (size_t p = 0; p < sizes.size(); ++p) {
      const auto it = offset_of.find(term.parameters[p]);
      l.offset.push_back(it == offset_of.end() ? -1 : it->second);
      l.local.push_back(l.free_size);
      if (it != offset_of.end()) l.free_size += sizes[p];
    }
    for (size_t p = 0; p < sizes.size(); ++p)
      for (size_t q = 0; q < sizes.size(); ++q) {
        if (l.offset[p] < 0 || l.offset[q] < 0) continue;
        for (int a = 0; a < sizes[p]; ++a)
          for (int b = 0; b < sizes[q]; ++b) {
            const int row = l.offset[p] + a, col = l.offset[q] + b;
            if (row <= col) pattern.emplace_back(row, col, 0.0);
          }
      }
  }
  for (int i = 0; i < m.unknowns; ++i) pattern.emplace_back(i, i, 0.0);
  m.hessian.resize(m.unknowns, m.unknowns);
  m.hessian.setFromTriplets(pattern.begin(), pattern.end());
  m.hessian.makeCompressed();
  const int* outer = m.hessian.outerIndexPtr();
  const int* inner = m.hessian.innerIndexPtr();
  auto index_of = [&](int row, int col) {
    const int* first = inner + outer[col];
    const int* last = inner + outer[col + 1];
    const int* it = std::lower_bound(first, last, row);
    return static_cast<int>(it - inner);
  };
  for (int i = 0; i < m.unknowns; ++i) m.diagonal.push_back(index_of(i, i));
  for (size_t t = 0; t < m.terms.size(); ++t) {
    Impl::TermLayout& l = m.layout[t];
    const auto& sizes = m.terms[t].cost->parameter_block_sizes();
    // Global index of each local free unknown.
    std::vector<int> global;
    for (size_t p = 0; p < sizes.size(); ++p)
      if (l.offset[p] >= 0)
        for (int a = 0; a < sizes[p]; ++a) global.push_back(l.offset[p] + a);
    l.value_index.assign(static_cast<size_t>(l.free_size) * l.free_size, -1);
    for (int p = 0; p < l.free_size; ++p)
      for (int q = 0; q < l.free_size; ++q) {
        const int row = global[p], col = global[q];
        // Each unordered pair once: the entry (row, col) with row <= col, taken from the local
        // (p, q) with row < col, or p <= q when the same global unknown repeats.
        if (row < col || (row == col && p == q))
          l.value_index[p * l.free_size + q] = index_of(row, col);
      }
  }
  m.cholesky.analyzePattern(m.hessian);
  m.gradient = Eigen::VectorXd::Zero(m.unknowns);
}

NewtonSolver::~NewtonSolver() = default;

bool NewtonSolver::evaluate() {
  Impl& m = *impl_;
  // The numeric curvature changes slowly; refresh it every options_.curvature_refresh calls.
  m.refresh_curvature = m.evaluations % std::max(1, options_.curvature_refresh) == 0;
  if (m.exact_hessian) ++m.evaluations;
  // A fixed number of chunks summed in a fixed order: the result does not depend on the thread
  // count.
  constexpr int kChunks = 8;
  const size_t count = m.terms.size();
  const int nnz = static_cast<int>(m.hessian.nonZeros());
  std::vector<std::vector<double>> values(kChunks, std::vector<double>(nnz, 0.0));
  std::vector<Eigen::VectorXd> gradients(kChunks, Eigen::VectorXd::Zero(m.unknowns));
  std::vector<double> costs(kChunks, 0.0);
  std::vector<char> oks(kChunks, 1);
  std::atomic<int> next{0};
  auto work = [&] {
    for (int c = next++; c < kChunks; c = next++) {
      const size_t begin = count * c / kChunks, end = count * (c + 1) / kChunks;
      bool ok = true;
      m.accumulate(begin, end, values[c].data(), gradients[c].data(), &costs[c], &ok);
      oks[c] = ok;
    }
  };
  const int threads = std::clamp(m.threads, 1, kChunks);
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
  for (char ok : oks)
    if (!ok) return false;
  double* out = m.hessian.valuePtr();
  std::copy(values[0].begin(), values[0].end(), out);
  m.gradient = gradients[0];
  cost_ = costs[0];
  for (int c = 1; c < kChunks; ++c) {
    for (int k = 0; k < nnz; ++k) out[k] += values[c][k];
    m.gradient += gradients[c];
    cost_ += costs[c];
  }
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

double NewtonSolver::gradient_max_norm() const {
  return impl_->gradient.size() ? impl_->gradient.cwiseAbs().maxCoeff() : 0.0;
}

bool NewtonSolver::evaluate_cost(double* cost) const {
  const Impl& m = *impl_;
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
  Eigen::VectorXd x(impl_->unknowns);
  int k = 0;
  for (const auto& [pointer, size] : impl_->blocks)
    for (int a = 0; a < size; ++a) x[k++] = pointer[a];
  return x;
}

void NewtonSolver::write(const Eigen::VectorXd& x) const {
  int k = 0;
  for (const auto& [pointer, size] : impl_->blocks)
    for (int a = 0; a < size; ++a) pointer[a] = x[k++];
}

NewtonSolver::StepResult NewtonSolver::step(int max_trials) {
  Impl& m = *impl_;
  StepResult result;
  const Eigen::VectorXd x0 = read();
  Eigen::SparseMatrix<double> A = m.hessian;
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
    m.cholesky.factorize(A);
    if (m.cholesky.info() != Eigen::Success) {
      lambda_ = std::max(lambda_ * nu_, 1e-8);
      nu_ *= 2;
      continue;
    }
    const Eigen::VectorXd d = m.cholesky.solve(-m.gradient);
    // The step taken is alpha d: the fraction to the boundary of every barrier's domain, and
    // the trust radii.
    double alpha = 1;
    for (const Term& term : m.terms) {
      if (!std::isfinite(term.lower) && !std::isfinite(term.upper)) continue;
      const auto it = m.offset_of.find(term.parameters[0]);
      if (it == m.offset_of.end()) continue;
      const double value = *term.parameters[0], step = d[it->second];
      if (step < 0 && std::isfinite(term.lower))
        alpha = std::min(alpha, 0.95 * (value - term.lower) / -step);
      if (step > 0 && std::isfinite(term.upper))
        alpha = std::min(alpha, 0.95 * (term.upper - value) / step);
    }
    // Trust radii: shorten the step along the same direction (no new factorization).
    double alpha_trust = 1;
    for (size_t b = 0, k = 0; b < m.limits.size(); k += m.blocks[b].second, ++b)
      if (m.limits[b] > 0) {
        const double longest = d.segment(k, m.blocks[b].second).cwiseAbs().maxCoeff();
        if (longest > m.limits[b]) alpha_trust = std::min(alpha_trust, m.limits[b] / longest);
      }
    alpha = std::min(alpha, alpha_trust);
    const Eigen::VectorXd Hd = m.hessian.selfadjointView<Eigen::Upper>() * d;
    const double gd = m.gradient.dot(d), dHd = d.dot(Hd);
    if (!(gd < 0) || !d.allFinite()) {  // not a descent direction: damp more
      lambda_ = std::max(lambda_ * nu_, 1e-8);
      nu_ *= 2;
      continue;
    }
    // Try the (shortened) step, then back off along it twice before damping more: a cost
    // evaluation is far cheaper than another factorization.
    const double rounding = 1e-13 * std::abs(cost_);
    double step = std::max(alpha, 0.0);
    for (int attempt = 0; attempt < 3; ++attempt, step *= 0.5) {
      const double predicted = -(step * gd + 0.5 * step * step * dHd);
      double trial = 0;
      write(x0 + step * d);
      const bool ok = predicted > 0 && evaluate_cost(&trial);
      double rho = ok ? (cost_ - trial) / predicted : -1;
      // Near the minimum the predicted decrease drops below the cost's rounding: accept a step
      // that does not raise the cost beyond rounding and let the gradient decide convergence.
      if (ok && predicted < rounding && trial <= cost_ + rounding) rho = 1;
      if (ok && rho > 1e-4) {
        // Less damping when the model predicted the first trial well. A step shortened by the
        // fraction to a barrier's boundary still validates the model (it is the same quadratic
        // model along d); one shortened by a trust radius or by backtracking does not.
        if (attempt == 0 && alpha_trust >= 1)
          lambda_ = std::max(options_.min_lambda,
                             lambda_ * std::max(1.0 / 3.0, 1.0 - std::pow(2 * rho - 1, 3)));
        nu_ = 2;
        result.accepted = true;
        result.relative_step = (step * d.array().abs() / (1 + x0.array().abs())).maxCoeff();
        return result;
      }
    }
    write(x0);
    lambda_ = std::max(lambda_ * nu_, 1e-8);
    nu_ *= 2;
  }
}

}  // namespace gridshell
