// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — feasible suggestions for an infeasible design (issue 18 item 4).
//
// When a design fails as infeasible on a patch (no feasible planar angle; too few members fit;
// members that do not cross once), suggest_feasible_designs tries small changes of the request
// and keeps those whose complete design succeeds, ranked by the size of the change:
//   - slope bounds: k_max raised and/or k_min lowered by the smallest factor of a ladder that
//     gives a feasible planar angle range on the same maps (refined by bisection, rounded
//     outwards to 3 significant digits);
//   - corners: each corner moved along its two patch sides by 5 % and 10 % of the side's length
//     (snapped to the input mesh's nearest vertex), screened on coarse maps (R = 32), and a
//     complete design on the design's maps for those that pass the screen;
//   - members: narrower lamellas, or fewer explicit members, when members are what fails.
// Nothing is guessed: every suggestion carries the feasible planar angle range of the design
// that was actually computed with it. The work is bounded (SuggestionOptions) and cancellable.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "gridshell/design/design.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {

struct DesignSuggestion {
  enum class Kind { SlopeBounds, Corners, Members, LamellaWidth };
  Kind kind = Kind::SlopeBounds;
  std::string description;           ///< one line, plain text
  std::array<int, 4> corners{};      ///< Kind::Corners: input mesh vertices, in the patch's order
  double k_min = 0, k_max = 0;       ///< the slope bounds of the suggested design
  int members_g = 0, members_h = 0;  ///< explicit counts (0 = automatic)
  double lamella_width = 0;          ///< 0 = automatic
  AlphaRange alpha;                  ///< feasible planar angles of the suggested design
  double change = 0;                 ///< relative size of the change (the ranking key)
};

struct SuggestionOptions {
  int count = 3;               // suggestions wanted (the best this many are returned)
  int max_designs = 12;        // complete designs (new patch or grid) tried at most
  int max_corner_screens = 8;  // moved-corner patches screened on coarse maps at most
};

/// "slope_bounds" | "corners" | "members" | "lamella_width".
const char* to_string(DesignSuggestion::Kind kind);

/// Ranked feasible changes for a design that failed with `failure` (an Infeasible) on `work`
/// (the patch and maps of `mesh` with `options`). Empty if none was found within the bounds.
std::vector<DesignSuggestion> suggest_feasible_designs(
    const TriangleMesh& mesh, const PatchWork& work, const DesignOptions& options,
    const Error& failure, const SuggestionOptions& limits = {}, const Progress& progress = {});

}  // namespace gridshell
