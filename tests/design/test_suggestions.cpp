// SPDX-License-Identifier: GPL-3.0-or-later
// Feasible suggestions for infeasible designs (gridshell/design/suggestions.h, issue 18 item 4):
// every suggestion, applied to the request, gives a design that succeeds with the planar angle
// range the suggestion states; slope-bound suggestions are near the smallest change (a little
// less is infeasible); they are ranked by the size of the change.
#include <gtest/gtest.h>

#include <string>

#include "gridshell/design/suggestions.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

/// The design's failure and its suggestions.
struct Failed {
  std::string field, message;
  std::vector<DesignSuggestion> suggestions;
};

Failed fail_and_suggest(const TriangleMesh& mesh, const CornerSpec& corners,
                        const DesignOptions& options, int count = 3) {
  const PatchWork work =
      prepare_patch_work(make_target_patch(mesh, corners, patch_options(options)), options);
  try {
    design_on_patch(work, options);
  } catch (const Infeasible& e) {
    SuggestionOptions limits;
    limits.count = count;
    return {e.field(), e.message(), suggest_feasible_designs(mesh, work, options, e, limits)};
  }
  ADD_FAILURE() << "the design did not fail";
  return {};
}

/// The request with the suggestion applied.
std::pair<CornerSpec, DesignOptions> applied(const DesignSuggestion& s, const CornerSpec& corners,
                                             DesignOptions options) {
  CornerSpec spec = corners;
  switch (s.kind) {
    case DesignSuggestion::Kind::SlopeBounds:
      options.cladding.k_min = s.k_min;
      options.cladding.k_max = s.k_max;
      break;
    case DesignSuggestion::Kind::Corners:
      spec = CornerSpec::at_vertices(s.corners);
      break;
    case DesignSuggestion::Kind::Members:
      options.members_g = s.members_g;
      options.members_h = s.members_h;
      break;
    case DesignSuggestion::Kind::LamellaWidth:
      options.members.lamella_width = s.lamella_width;
      break;
  }
  return {spec, options};
}

void expect_each_works(const TriangleMesh& mesh, const CornerSpec& corners,
                       const DesignOptions& options, const std::vector<DesignSuggestion>& found) {
  for (size_t k = 0; k < found.size(); ++k) {
    SCOPED_TRACE(found[k].description);
    EXPECT_FALSE(found[k].description.empty());
    if (k > 0) {
      EXPECT_LE(found[k - 1].change, found[k].change);  // ranked
    }
    const auto [spec, changed] = applied(found[k], corners, options);
    const Design design = make_design(mesh, spec, changed);
    EXPECT_NEAR(design.alpha_range.min, found[k].alpha.min, 1e-12);
    EXPECT_NEAR(design.alpha_range.max, found[k].alpha.max, 1e-12);
  }
}

TEST(Suggestions, SlopeBoundTooTightGetsTheSmallestFeasibleBound) {
  const ExampleSurface example = make_example("double-vault", 0.5);
  const CornerSpec corners = CornerSpec::at_vertices(example.corners);
  DesignOptions options;
  options.maps.resolution = 48;  // a quicker design; the suggestions use the same
  options.cladding.k_max = 1.5;
  const Failed failed = fail_and_suggest(example.mesh, corners, options);
  EXPECT_EQ(failed.field, "corners");
  EXPECT_NE(failed.message.find("k_max"), std::string::npos) << failed.message;
  ASSERT_FALSE(failed.suggestions.empty());
  expect_each_works(example.mesh, corners, options, failed.suggestions);
  const DesignSuggestion& best = failed.suggestions.front();
  ASSERT_EQ(best.kind, DesignSuggestion::Kind::SlopeBounds);
  EXPECT_GT(best.k_max, 1.5);
  // Computed, not guessed: 2 % less than the suggested bound is infeasible again.
  DesignOptions less = options;
  less.cladding.k_max = best.k_max / 1.02;
  EXPECT_THROW(make_design(example.mesh, corners, less), Infeasible);
}

TEST(Suggestions, TooWideLamellasGetNarrowerOnesOrFewerMembers) {
  const ExampleSurface example = make_example("double-vault", 0.5);
  const CornerSpec corners = CornerSpec::at_vertices(example.corners);
  DesignOptions options;
  options.maps.resolution = 48;       // a quicker design; the suggestions use the same
  options.members.lamella_width = 8;  // 8 % of the longest side: two members fit, not three
  const Failed failed = fail_and_suggest(example.mesh, corners, options);
  EXPECT_EQ(failed.field, "options.lamella_width");
  ASSERT_FALSE(failed.suggestions.empty());
  expect_each_works(example.mesh, corners, options, failed.suggestions);
  for (const DesignSuggestion& s : failed.suggestions)
    EXPECT_TRUE(s.kind == DesignSuggestion::Kind::LamellaWidth ||
                s.kind == DesignSuggestion::Kind::Members);
}

TEST(Suggestions, NoneAskedNoneComputed) {
  const ExampleSurface example = make_example("double-vault", 0.5);
  DesignOptions options;
  options.maps.resolution = 48;  // a quicker design; the suggestions use the same
  options.cladding.k_max = 1.5;
  const Failed failed =
      fail_and_suggest(example.mesh, CornerSpec::at_vertices(example.corners), options, 0);
  EXPECT_TRUE(failed.suggestions.empty());
}

}  // namespace
}  // namespace gridshell
