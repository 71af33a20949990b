// SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer target: the CLI's corner syntax (--corners: "auto", "i,j,k,l" or four points
// "x,y,z;...") and the planar-angle syntax shared by the CLI and the API (--alpha / options.alpha:
// "min", "max", radians, "70deg"). The first byte picks the parser.
#include <cmath>
#include <string>

#include "cli_syntax.h"
#include "fuzz_support.h"
#include "gridshell/application/requests.h"

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, std::size_t size) {
  using namespace gridshell;
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    if (data[0] % 2 == 0) {
      const CornerSpec spec = cli::parse_corners(text);
      if (spec.kind == CornerSpec::Kind::Vertices) {
        for (int i = 0; i < 4; ++i) {
          if (spec.vertices[i] < 0) fuzz::fail("negative corner vertex accepted");
          for (int j = i + 1; j < 4; ++j)
            if (spec.vertices[i] == spec.vertices[j]) fuzz::fail("repeated corner accepted");
        }
      } else if (spec.kind == CornerSpec::Kind::Points) {
        for (const auto& p : spec.points)
          if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
            fuzz::fail("non-finite corner point accepted");
      }
    } else {
      DesignOptions options;
      parse_alpha(text, options);
    }
  } catch (const Error& e) {
    fuzz::expect_invalid_input(e);
  }
  return 0;
}
