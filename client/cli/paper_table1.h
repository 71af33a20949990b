// SPDX-License-Identifier: GPL-3.0-or-later
// Pillwein et al. 2020, Table 1: the paper's seven models (grid design in MATLAB, simulation in
// C++, on a Xeon E5-2687W v4). The yardstick of `gridshell bench` and of `gridshell run`'s
// summary on the built-in paper-like examples.
#pragma once

#include <string>

namespace gridshell::cli {

struct PaperModel {
  const char* name;  ///< the built-in example modelled on it
  double width, depth, height;
  int mesh_vertices, grid_vertices;  ///< |M_V|, |G_V|
  double t_smooth;                   ///< seconds; 0 = no smoothing needed
  double t_grid, rms1, rms2, t1, t2;
};

inline constexpr PaperModel kPaperTable1[] = {
    {"torus-wide", 100, 61.9, 27.2, 2122, 767, 0, 5.33, 1.17, 0.27, 1.92, 6.48},
    {"waves-bump", 100, 100, 12.7, 3385, 388, 31.63, 5.62, 1.47, 0.78, 12.60, 57.22},
    {"sphere", 100, 100, 29.9, 1083, 414, 0, 1.29, 1.09, 0.58, 6.05, 4.25},
    {"double-vault", 100, 51.7, 14.6, 571, 300, 0, 0.68, 0.69, 0.31, 2.25, 4.05},
    {"waves", 100, 65.5, 15.1, 1929, 328, 10.22, 2.10, 0.59, 0.43, 3.03, 9.56},
    {"archway", 100, 58.0, 20.7, 975, 625, 4.14, 1.50, 0.63, 0.42, 37.74, 85.43},
    {"triple-vault", 100, 42.8, 16.3, 1322, 494, 0, 1.67, 0.69, 0.46, 3.50, 5.80},
};

/// The paper model for `input` ("example:NAME" of a paper-like example), or null.
inline const PaperModel* paper_model_for(const std::string& input) {
  const std::string prefix = "example:";
  if (input.rfind(prefix, 0) != 0) return nullptr;
  for (const PaperModel& m : kPaperTable1)
    if (input.substr(prefix.size()) == m.name) return &m;
  return nullptr;
}

}  // namespace gridshell::cli
