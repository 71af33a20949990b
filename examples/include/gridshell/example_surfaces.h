// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — analytic example surfaces: generators for the paper's seven models (Table 1
// proportions and roughly its vertex counts) and analytic test cases.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "gridshell/mesh/mesh.h"

namespace gridshell {

struct ExampleSurface {
  std::string name;         ///< e.g. "double-vault"
  std::string description;  ///< one line
  TriangleMesh mesh;        ///< disk-like triangle mesh, one boundary loop, ccw faces (normal up)
  std::array<int, 4>
      corners;  ///< suggested patch corners (vertex indices), consecutive along the boundary
};

/// Names of all built-in examples, paper models first: torus-wide, waves-bump, sphere,
/// double-vault, waves, archway, triple-vault, then cylinder, cone, hypar, plane.
std::vector<std::string> example_names();

/// Builds the example. `resolution_scale` multiplies the number of samples per side (1 = the
/// default, near the paper's |M_V|); vertex count grows with its square. Throws InvalidInput for
/// an unknown name (listing the known ones).
ExampleSurface make_example(const std::string& name, double resolution_scale = 1.0);

}  // namespace gridshell
