// SPDX-License-Identifier: GPL-3.0-or-later
#include "cholesky_kernels.h"

#include "cholesky_kernels_impl.h"

namespace gridshell::cholesky {

#if defined(GRIDSHELL_AVX2_KERNELS)
const EliminateKernels& avx2_kernels_compiled();  // cholesky_kernels_avx2.cpp
#endif

const EliminateKernels& baseline_eliminate_kernels() {
  static constexpr EliminateKernels kernels = make_kernels();
  return kernels;
}

const EliminateKernels* avx2_eliminate_kernels() {
#if defined(GRIDSHELL_AVX2_KERNELS)
  if (__builtin_cpu_supports("avx2")) return &avx2_kernels_compiled();
#endif
  return nullptr;
}

const EliminateKernels& eliminate_kernels() {
  static const EliminateKernels& chosen = []() -> const EliminateKernels& {
    const EliminateKernels* avx2 = avx2_eliminate_kernels();
    return avx2 ? *avx2 : baseline_eliminate_kernels();
  }();
  return chosen;
}

}  // namespace gridshell::cholesky
