// SPDX-License-Identifier: GPL-3.0-or-later
// The elimination kernels for AVX2 (this file is compiled with -mavx2 on x86-64; see
// cholesky_kernels.h). Elsewhere it defines nothing.
#if defined(GRIDSHELL_AVX2_KERNELS)
#include "cholesky_kernels_impl.h"

namespace gridshell::cholesky {
const EliminateKernels& avx2_kernels_compiled() {
  static constexpr EliminateKernels kernels = make_kernels();
  return kernels;
}
}  // namespace gridshell::cholesky
#endif
