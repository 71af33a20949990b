// SPDX-License-Identifier: GPL-3.0-or-later
// The Newton solver's block sparse Cholesky (kernel/simulation/sparse_cholesky.h) and its
// CHOLMOD factorization for large systems (cholmod_cholesky.h) against Eigen's SimplicialLLT,
// the oracle: same solutions for any block partition or ordering, the same factor with scalar
// blocks, refactorization on the same pattern, and indefinite matrices rejected.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <cstring>
#include <random>

#include "cholmod_cholesky.h"
#include "sparse_cholesky.h"

namespace gridshell {
namespace {

/// A random symmetric positive definite matrix (upper triangle stored) with a band of width
/// `band`, `extra` random couplings, and its last `arrow` unknowns coupled to everything (an
/// arrowhead: a dense trailing block in the factor, like the grid's separators).
Eigen::SparseMatrix<double> random_spd(int n, int band, int extra, int arrow, unsigned seed,
                                       double shift = 1.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::uniform_int_distribution<int> index(0, n - 1);
  std::vector<Eigen::Triplet<double>> entries;
  auto couple = [&](int i, int j) {
    if (i == j) return;
    const double v = value(rng);
    entries.emplace_back(i, j, v);
    entries.emplace_back(j, i, v);
  };
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j <= std::min(n - 1, i + band); ++j) couple(i, j);
  for (int e = 0; e < extra; ++e) couple(index(rng), index(rng));
  for (int a = n - arrow; a < n; ++a)
    for (int j = 0; j < n; j += 3) couple(a, j);
  Eigen::SparseMatrix<double> full(n, n);
  full.setFromTriplets(entries.begin(), entries.end());
  // Diagonal: the row's absolute sum plus `shift` (> 0: diagonally dominant, positive definite).
  Eigen::VectorXd diagonal = Eigen::VectorXd::Constant(n, shift);
  for (int k = 0; k < full.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(full, k); it; ++it)
      diagonal[it.row()] += std::abs(it.value());
  for (int i = 0; i < n; ++i) full.coeffRef(i, i) = diagonal[i];
  Eigen::SparseMatrix<double> upper = full.triangularView<Eigen::Upper>();
  upper.makeCompressed();
  return upper;
}

double relative_difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / b.norm();
}

/// Block sizes 1-5 summing to n (5 exceeds the maximum and is split by the factorization).
std::vector<int> random_blocks(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> size(1, 5);
  std::vector<int> sizes;
  for (int left = n; left > 0;) {
    sizes.push_back(std::min(left, size(rng)));
    left -= sizes.back();
  }
  return sizes;
}

/// For a factorization analysed on A (random_spd(300, 5, 200, 30, 5)): a matrix made indefinite
/// on one diagonal entry is refused and leaves nothing behind (the next factorization of A is
/// exact again); a right-hand side of another size, a matrix of another pattern or size are
/// refused.
template <typename Factorization>
void expect_refuses_indefinite_and_other_patterns(Factorization& cholesky,
                                                  const Eigen::SparseMatrix<double>& A) {
  const int n = static_cast<int>(A.rows());
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>>
      oracle(A);
  for (int row : {0, n / 2, n - 1}) {
    Eigen::SparseMatrix<double> B = A;
    B.coeffRef(row, row) = -B.coeffRef(row, row);
    EXPECT_FALSE(cholesky.factorize(B)) << "row " << row;
    EXPECT_FALSE(cholesky.ok());
    EXPECT_THROW(cholesky.solve(b), std::logic_error);
    ASSERT_TRUE(cholesky.factorize(A)) << "row " << row;
    EXPECT_LT(relative_difference(cholesky.solve(b), oracle.solve(b)), 1e-12) << "row " << row;
  }
  EXPECT_THROW(cholesky.solve(Eigen::VectorXd::Ones(n + 1)), std::invalid_argument);
  EXPECT_THROW(cholesky.factorize(random_spd(n, 2, 0, 0, 5)), std::invalid_argument);
  EXPECT_THROW(cholesky.factorize(random_spd(n + 1, 5, 200, 30, 5)), std::invalid_argument);
}

/// One solve case of the oracle tests: a random SPD matrix (a trailing arrowhead for seed 3),
/// Eigen's solution of A x = b, and A whole for residuals.
struct SolveCase {
  explicit SolveCase(int n, unsigned seed)
      : A(random_spd(n, 4, 300, seed == 3 ? 40 : 0, seed)),
        oracle(A),
        b(Eigen::VectorXd::LinSpaced(n, -2.0, 1.0).array().sin()),
        expected(oracle.solve(b)),
        full(A.selfadjointView<Eigen::Upper>()) {}
  Eigen::SparseMatrix<double> A;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>>
      oracle;
  Eigen::VectorXd b, expected;
  Eigen::SparseMatrix<double> full;
};

TEST(BlockCholesky, SolvesLikeEigensSimplicialLltForAnyBlockPartition) {
  const int n = 400;
  for (unsigned seed : {1u, 2u, 3u}) {
    const SolveCase c(n, seed);
    ASSERT_EQ(c.oracle.info(), Eigen::Success);
    const auto& [A, oracle, b, expected, full] = c;
    for (const std::vector<int>& sizes :
         {std::vector<int>(n, 1), std::vector<int>(n / 4, 4), random_blocks(n, seed)}) {
      BlockCholesky cholesky;
      cholesky.analyze(A, sizes);
      ASSERT_TRUE(cholesky.factorize(A));
      const Eigen::VectorXd x = cholesky.solve(b);
      EXPECT_LT(relative_difference(x, expected), 1e-12) << "seed " << seed;
      EXPECT_LT((full * x - b).norm() / b.norm(), 1e-12) << "seed " << seed;
      // The block factor holds the scalar one and at most the zeros inside its blocks.
      EXPECT_GE(cholesky.factor_nonzeros(), oracle.matrixL().nestedExpression().nonZeros());
    }
    // Scalar blocks without amalgamation: exactly the simplicial factor.
    BlockCholesky scalar;
    scalar.analyze(A, std::vector<int>(n, 1), false);
    ASSERT_TRUE(scalar.factorize(A));
    EXPECT_EQ(scalar.factor_nonzeros(), oracle.matrixL().nestedExpression().nonZeros());
    EXPECT_LT(relative_difference(scalar.solve(b), expected), 1e-12);
  }
}

// The AVX2 kernels (cholesky_kernels.h) add in the same order without fused multiply-adds: the
// solutions are the baseline kernels' to the bit, on every partition, and both sets reject the
// same indefinite matrix.
TEST(BlockCholesky, Avx2KernelsGiveTheBaselineFactorToTheBit) {
  const cholesky::EliminateKernels* avx2 = cholesky::avx2_eliminate_kernels();
  if (!avx2) GTEST_SKIP() << "no AVX2 kernels in this build or on this CPU";
  EXPECT_EQ(&cholesky::eliminate_kernels(), avx2);  // the default where the CPU has it
  const int n = 400;
  for (unsigned seed : {1u, 2u, 3u}) {
    const Eigen::SparseMatrix<double> A = random_spd(n, 4, 300, seed == 3 ? 40 : 0, seed);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -2.0, 1.0).array().sin();
    for (const std::vector<int>& sizes :
         {std::vector<int>(n, 1), std::vector<int>(n / 4, 4), random_blocks(n, seed)}) {
      BlockCholesky baseline, wide;
      baseline.use_kernels(cholesky::baseline_eliminate_kernels());
      wide.use_kernels(*avx2);
      baseline.analyze(A, sizes);
      wide.analyze(A, sizes);
      ASSERT_TRUE(baseline.factorize(A));
      ASSERT_TRUE(wide.factorize(A));
      const Eigen::VectorXd x = baseline.solve(b), y = wide.solve(b);
      EXPECT_EQ(std::memcmp(x.data(), y.data(), sizeof(double) * n), 0) << "seed " << seed;
      Eigen::SparseMatrix<double> indefinite = A;
      indefinite.coeffRef(n / 2, n / 2) = -1;
      EXPECT_FALSE(baseline.factorize(indefinite));
      EXPECT_FALSE(wide.factorize(indefinite));
    }
  }
}

/// A random matrix (random_spd) factorized on a random block partition.
struct Factored {
  Eigen::SparseMatrix<double> A;
  BlockCholesky cholesky;
  bool ok = false;
};
Factored factored(int n, int band, int extra, int arrow, unsigned seed) {
  Factored f{random_spd(n, band, extra, arrow, seed), {}};
  f.cholesky.analyze(f.A, random_blocks(n, seed));
  f.ok = f.cholesky.factorize(f.A);
  return f;
}

TEST(BlockCholesky, SolvesManyRightHandSidesAtOnceLikeOneAtATime) {
  const int n = 250;
  const auto [A, cholesky, ok] = factored(n, 6, 150, 20, 4);
  ASSERT_TRUE(ok);
  std::mt19937 rng(6);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd B(n, 7);
  for (int i = 0; i < B.size(); ++i) B.data()[i] = normal(rng);
  const Eigen::MatrixXd X = cholesky.solve_many(B);
  ASSERT_EQ(X.rows(), n);
  ASSERT_EQ(X.cols(), 7);
  const Eigen::SparseMatrix<double> full = A.selfadjointView<Eigen::Upper>();
  for (int c = 0; c < B.cols(); ++c) {
    const Eigen::VectorXd one = cholesky.solve(B.col(c));
    EXPECT_LT((X.col(c) - one).norm(), 1e-14 * one.norm()) << c;
    EXPECT_LT((full * X.col(c) - B.col(c)).norm(), 1e-12 * B.col(c).norm()) << c;
  }
}

TEST(BlockCholesky, InverseSubmatrixEqualsTheDenseInversesEntries) {
  const int n = 200;
  const auto [A, cholesky, ok] = factored(n, 5, 120, 15, 12);
  ASSERT_TRUE(ok);
  const Eigen::MatrixXd inverse =
      Eigen::MatrixXd(Eigen::SparseMatrix<double>(A.selfadjointView<Eigen::Upper>())).inverse();
  const std::vector<int> unknowns = {0, 7, 8, 9, 57, 120, 121, 199, 3};
  const Eigen::MatrixXd S = cholesky.inverse_submatrix(unknowns);
  ASSERT_EQ(S.rows(), static_cast<int>(unknowns.size()));
  for (size_t a = 0; a < unknowns.size(); ++a)
    for (size_t b = 0; b < unknowns.size(); ++b)
      EXPECT_NEAR(S(a, b), inverse(unknowns[a], unknowns[b]), 1e-12 * inverse.diagonal().maxCoeff())
          << unknowns[a] << ", " << unknowns[b];
  EXPECT_THROW(cholesky.inverse_submatrix({n}), std::invalid_argument);
}

TEST(BlockCholesky, RefactorizesAndRejectsIndefiniteMatrices) {
  const int n = 300;
  const Eigen::SparseMatrix<double> A = random_spd(n, 5, 200, 30, 5);
  BlockCholesky cholesky;
  cholesky.analyze(A, random_blocks(n, 8));
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
  for (double scale : {1.0, 3.0}) {
    Eigen::SparseMatrix<double> B = A * scale;
    ASSERT_TRUE(cholesky.factorize(B));
    Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>>
        oracle(B);
    EXPECT_LT(relative_difference(cholesky.solve(b), oracle.solve(b)), 1e-12) << scale;
  }
  expect_refuses_indefinite_and_other_patterns(cholesky, A);
  EXPECT_THROW(cholesky.analyze(A, {n - 1}), std::invalid_argument);
}

TEST(CholmodCholesky, SolvesLikeEigensSimplicialLlt) {
  const int n = 400;
  for (unsigned seed : {1u, 2u, 3u}) {
    const SolveCase c(n, seed);
    ASSERT_EQ(c.oracle.info(), Eigen::Success);
    const auto& [A, oracle, b, expected, full] = c;
    CholmodCholesky cholesky;
    cholesky.analyze(A);
    ASSERT_TRUE(cholesky.factorize(A));
    const Eigen::VectorXd x = cholesky.solve(b);
    EXPECT_LT(relative_difference(x, expected), 1e-12) << "seed " << seed;
    EXPECT_LT((full * x - b).norm() / b.norm(), 1e-12) << "seed " << seed;
    EXPECT_GT(cholesky.factor_nonzeros(), 0);
    EXPECT_GT(cholesky.factor_flops(), 0);
    // Several right-hand sides at once: each column as alone.
    Eigen::MatrixXd B(n, 3);
    B << b, -b, Eigen::VectorXd::Ones(n);
    const Eigen::MatrixXd X = cholesky.solve_many(B);
    for (int k = 0; k < 3; ++k)
      EXPECT_LT(relative_difference(X.col(k), oracle.solve(Eigen::VectorXd(B.col(k)))), 1e-12);
  }
}

TEST(CholmodCholesky, InverseSubmatrixRefactorizationAndIndefiniteMatrices) {
  const int n = 300;
  const Eigen::SparseMatrix<double> A = random_spd(n, 5, 200, 30, 5);
  CholmodCholesky cholesky;
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
  EXPECT_THROW(cholesky.factorize(A), std::logic_error);  // before analyze
  cholesky.analyze(A);
  EXPECT_THROW(cholesky.solve(b), std::logic_error);  // before a factorization
  ASSERT_TRUE(cholesky.factorize(A));
  const Eigen::MatrixXd inverse =
      Eigen::MatrixXd(Eigen::SparseMatrix<double>(A.selfadjointView<Eigen::Upper>())).inverse();
  const std::vector<int> unknowns = {0, 7, 8, 9, 57, 120, 121, 299, 3};
  const Eigen::MatrixXd S = cholesky.inverse_submatrix(unknowns);
  for (size_t a = 0; a < unknowns.size(); ++a)
    for (size_t c = 0; c < unknowns.size(); ++c)
      EXPECT_NEAR(S(a, c), inverse(unknowns[a], unknowns[c]),
                  1e-12 * inverse.diagonal().maxCoeff());
  EXPECT_THROW(cholesky.inverse_submatrix({n}), std::invalid_argument);
  expect_refuses_indefinite_and_other_patterns(cholesky, A);
}

// Nested dissection of a k x k grid graph (the shape of a gridshell's Hessian): a permutation,
// and a factor far sparser than in the natural (banded) order.
TEST(CholmodCholesky, NestedDissectionOrdersAGridGraph) {
  const int k = 60, n = k * k;
  std::vector<std::vector<int>> adjacent(n);
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      const int v = i * k + j;
      adjacent[v].push_back(v);
      if (i > 0) adjacent[v].push_back(v - k);
      if (j > 0) adjacent[v].push_back(v - 1);
      if (j + 1 < k) adjacent[v].push_back(v + 1);
      if (i + 1 < k) adjacent[v].push_back(v + k);
      std::sort(adjacent[v].begin(), adjacent[v].end());
    }
  const std::vector<int> order = nested_dissection_order(adjacent);
  ASSERT_EQ(order.size(), static_cast<size_t>(n));
  std::vector<int> position(n, -1);
  for (int p = 0; p < n; ++p) {
    ASSERT_GE(order[p], 0);
    ASSERT_LT(order[p], n);
    ASSERT_EQ(position[order[p]], -1) << "node " << order[p] << " twice";
    position[order[p]] = p;
  }
  // The grid Laplacian plus identity, numbered naturally and in the nested-dissection order.
  const auto laplacian = [&](const std::vector<int>& number) {
    std::vector<Eigen::Triplet<double>> t;
    for (int v = 0; v < n; ++v)
      for (int w : adjacent[v]) {
        const int a = number[v], c = number[w];
        if (a <= c) t.emplace_back(a, c, v == w ? 5.0 : -1.0);
      }
    Eigen::SparseMatrix<double> m(n, n);
    m.setFromTriplets(t.begin(), t.end());
    m.makeCompressed();
    return m;
  };
  std::vector<int> natural(n);
  for (int v = 0; v < n; ++v) natural[v] = v;
  CholmodCholesky banded, dissected;
  banded.analyze(laplacian(natural));
  dissected.analyze(laplacian(position));
  ASSERT_TRUE(banded.factorize(laplacian(natural)));
  ASSERT_TRUE(dissected.factorize(laplacian(position)));
  EXPECT_LT(dissected.factor_flops(), 0.5 * banded.factor_flops());
}

}  // namespace
}  // namespace gridshell
