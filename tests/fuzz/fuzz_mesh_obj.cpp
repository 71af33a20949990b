// SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer target: the OBJ reader (read_mesh), with the loader's repairs and checks.
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, std::size_t size) {
  return gridshell::fuzz::read_mesh_input(data, size, gridshell::MeshFormat::Obj);
}
