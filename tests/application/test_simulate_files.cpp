// SPDX-License-Identifier: GPL-3.0-or-later
// A Simulate request with `files` set answers deployment.json as a view, the bytes the CLI
// writes (a web page offers it as a download). It was once answered empty: the view was added
// before its content was made from the answer, and the empty view stood in for the file.
#include <gtest/gtest.h>

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"

namespace gridshell {
namespace {

TEST(SimulateFiles, DeploymentJsonIsTheFileTheCliWrites) {
  v1::DesignRequest design;
  design.mutable_mesh()->set_example("hypar");
  design.mutable_options()->set_resolution(16);
  design.mutable_options()->set_members_u(3);
  design.mutable_options()->set_members_v(3);
  v1::SimulateRequest request;
  *request.mutable_design() = run_design(design, {}, {1}).design();
  request.mutable_options()->set_notches("on");
  request.set_files(true);
  const v1::SimulateResult result = run_simulate(request, {}, {1});
  int found = 0;
  for (const v1::File& view : result.views())
    if (view.name() == "deployment.json") {
      ++found;
      EXPECT_EQ(view.content(), to_json(result.deployment()) + "\n");
      EXPECT_GT(view.content().size(), 100u);
    }
  EXPECT_EQ(found, 1);
}

}  // namespace
}  // namespace gridshell
