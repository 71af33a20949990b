// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the elimination kernels' one definition, compiled once per instruction set.
//
// Included only by cholesky_kernels.cpp (baseline) and cholesky_kernels_avx2.cpp (-mavx2).
// Everything here has internal linkage (an unnamed namespace) and calls no library template, so
// no AVX2 instruction can leak into the baseline code through a shared inline function.
#pragma once

#include "cholesky_kernels.h"

namespace gridshell::cholesky {
namespace {

template <int BI, int BK>
void eliminate(const EliminateState& s, int K, int I, double* D) {
  constexpr int M = kMaxBlock;
  const int ci = s.start[I];
  double* x = s.x;
  // Y = L_II^-1 x_I (BI x BK), then x_I = 0. Rows of x are kMaxBlock wide whatever BK is (the
  // columns beyond it hold zeros); the loops over BK columns are unrolled at compile time.
  double y[BI * M];
  const double* L = s.dx + s.dp[I];
#pragma GCC unroll 4
  for (int a = 0; a < BI; ++a) {
    const double inverse = 1.0 / L[a * BI + a];
#pragma GCC unroll 4
    for (int c = 0; c < BK; ++c) {
      double v = x[(ci + a) * M + c];
      for (int b = 0; b < a; ++b) v -= L[a * BI + b] * y[b * M + c];
      y[a * M + c] = v * inverse;
    }
  }
  for (int k = ci * M; k < (ci + BI) * M; ++k) x[k] = 0.0;
  // x_R -= L(R, I) Y for the entries of column I so far (rows above K).
  for (int e = s.lp[I]; e < s.next[I]; ++e) {
    const int br = s.size[s.li[e]];
    const double* B = s.lx + s.lv[e];
    double* row = x + s.start[s.li[e]] * M;
    for (int a = 0; a < br; ++a, row += M, B += BI) {
      double r[M];
#pragma GCC unroll 4
      for (int c = 0; c < BK; ++c) r[c] = row[c];
#pragma GCC unroll 4
      for (int b = 0; b < BI; ++b)
#pragma GCC unroll 4
        for (int c = 0; c < BK; ++c) r[c] -= B[b] * y[b * M + c];
#pragma GCC unroll 4
      for (int c = 0; c < BK; ++c) row[c] = r[c];
    }
  }
  // D -= Y^T Y; store L(K, I) = Y^T (BK x BI).
  for (int c = 0; c < BK; ++c)
    for (int d = 0; d <= c; ++d) {
      double sum = 0;
#pragma GCC unroll 4
      for (int a = 0; a < BI; ++a) sum += y[a * M + c] * y[a * M + d];
      D[c * M + d] -= sum;
    }
  const int e = s.next[I]++, offset = s.vnext[I];
  s.vnext[I] += BK * BI;
  s.li[e] = K;
  s.lv[e] = offset;
  double* out = s.lx + offset;
  for (int c = 0; c < BK; ++c)
#pragma GCC unroll 4
    for (int a = 0; a < BI; ++a) out[c * BI + a] = y[a * M + c];
}

constexpr EliminateKernels make_kernels() {
  static_assert(kMaxBlock == 4);
  return {{eliminate<1, 1>, eliminate<1, 2>, eliminate<1, 3>, eliminate<1, 4>,  //
           eliminate<2, 1>, eliminate<2, 2>, eliminate<2, 3>, eliminate<2, 4>,  //
           eliminate<3, 1>, eliminate<3, 2>, eliminate<3, 3>, eliminate<3, 4>,  //
           eliminate<4, 1>, eliminate<4, 2>, eliminate<4, 3>, eliminate<4, 4>}};
}

}  // namespace
}  // namespace gridshell::cholesky
