// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the block Cholesky's elimination kernels, compiled per instruction set (private
// header).
//
// BlockCholesky spends ~40% of a deployment run in one small dense update, x_R -= L(R, I) Y, per
// pair of blocks. On x86-64 the kernels are compiled twice: for the baseline (SSE2) and for
// AVX2 (4 doubles a register: one padded row of x in one register), and the factorization takes
// the AVX2 set where the CPU has it. Neither set uses fused multiply-adds, and both add in the
// same order, so the factors are the same to the bit on any machine
// (tests/simulation/test_sparse_cholesky.cpp compares the two sets on the CPUs that have AVX2).
#pragma once

namespace gridshell::cholesky {

/// Largest block (unknowns); the rows of the right-hand side x are this wide.
constexpr int kMaxBlock = 4;

/// The factor's arrays that one elimination step reads and writes (see BlockCholesky).
struct EliminateState {
  const int* start;  // per block: first unknown
  const int* size;   // per block: unknowns
  const int* lp;     // per block column: first entry
  int* next;         // per block column: next free entry
  int* vnext;        // per block column: next free value offset
  int* li;           // per entry: block row
  int* lv;           // per entry: value offset
  double* lx;        // L(R, I) blocks, row-major size[R] x size[I]
  const double* dx;  // diagonal factors, row-major, lower
  const int* dp;     // per block: offset of its diagonal factor
  double* x;         // right-hand side rows, kMaxBlock wide
};

/// Block row K's step for block column I (sizes BI of I, BK of K, 1..kMaxBlock): L(K, I) from
/// the right-hand side x_I, x_R -= L(R, I) L(K, I)^T over the entries of column I so far, and
/// D -= L(K, I) L(K, I)^T for the diagonal block (row-major, kMaxBlock wide).
using EliminateFn = void (*)(const EliminateState& state, int K, int I, double* D);

/// One kernel per pair of block sizes: fn[(BI - 1) * kMaxBlock + BK - 1].
struct EliminateKernels {
  EliminateFn fn[kMaxBlock * kMaxBlock];
};

/// The kernels for this CPU (AVX2 where it has it, else the baseline).
const EliminateKernels& eliminate_kernels();
/// The baseline kernels, and the AVX2 ones (nullptr where this build or CPU has none).
const EliminateKernels& baseline_eliminate_kernels();
const EliminateKernels* avx2_eliminate_kernels();

}  // namespace gridshell::cholesky
