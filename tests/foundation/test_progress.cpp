// SPDX-License-Identifier: GPL-3.0-or-later
// Progress (gridshell/foundation/progress.h): report forwards to the callback and throws Cancelled
// once the flag is set, check only checks, checker() keeps the flag but reports nowhere, and a
// default Progress reports nowhere and never cancels.
#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <utility>
#include <vector>

#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/progress.h"

namespace gridshell {
namespace {

TEST(Progress, DefaultReportsNowhereAndNeverCancels) {
  const Progress progress;
  EXPECT_FALSE(progress.cancelled());
  EXPECT_EQ(progress.cancel_flag(), nullptr);
  EXPECT_NO_THROW(progress.check());
  EXPECT_NO_THROW(progress.report("stage", 0.5));
}

TEST(Progress, ReportForwardsUntilCancelledThenThrows) {
  std::vector<std::pair<std::string, double>> calls;
  std::atomic<bool> cancel{false};
  const Progress progress(
      [&](std::string_view stage, double fraction) { calls.emplace_back(stage, fraction); },
      &cancel);
  EXPECT_EQ(progress.cancel_flag(), &cancel);
  progress.report("cut", 0.25);
  progress.report("maps", 1.0);
  ASSERT_EQ(calls.size(), 2u);
  EXPECT_EQ(calls[0], (std::pair<std::string, double>{"cut", 0.25}));
  EXPECT_EQ(calls[1], (std::pair<std::string, double>{"maps", 1.0}));
  cancel = true;
  EXPECT_TRUE(progress.cancelled());
  EXPECT_THROW(progress.check(), Cancelled);
  EXPECT_THROW(progress.report("maps", 0.5), Cancelled);
  EXPECT_EQ(calls.size(), 2u) << "a cancelled report must not reach the callback";
  cancel = false;  // the flag is read, not latched
  EXPECT_NO_THROW(progress.report("maps", 0.75));
  EXPECT_EQ(calls.size(), 3u);
}

TEST(Progress, CheckerKeepsTheFlagButReportsNowhere) {
  int calls = 0;
  std::atomic<bool> cancel{false};
  const Progress progress([&](std::string_view, double) { ++calls; }, &cancel);
  const Progress checker = progress.checker();
  EXPECT_EQ(checker.cancel_flag(), &cancel);
  checker.report("inner", 0.5);
  EXPECT_EQ(calls, 0);
  cancel = true;
  EXPECT_TRUE(checker.cancelled());
  EXPECT_THROW(checker.check(), Cancelled);
  EXPECT_THROW(checker.report("inner", 0.5), Cancelled);
  // Without a flag, neither cancels.
  const Progress no_flag([&](std::string_view, double) { ++calls; });
  EXPECT_FALSE(no_flag.checker().cancelled());
  no_flag.report("x", 1.0);
  EXPECT_EQ(calls, 1);
}

}  // namespace
}  // namespace gridshell
