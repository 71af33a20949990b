// SPDX-License-Identifier: GPL-3.0-or-later
// The CLI's --corners syntax (client/cli/cli_support.cpp) and how the CLI names request fields
// in its error lines (client/cli/cli_errors.cpp).
#include <gtest/gtest.h>

#include "cli_support.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::cli {
namespace {

TEST(ParseCorners, AcceptsTheThreeForms) {
  const CornerSpec v = parse_corners("0, 12,7,3");
  EXPECT_EQ(v.kind, CornerSpec::Kind::Vertices);
  EXPECT_EQ(v.vertices, (std::array<int, 4>{0, 12, 7, 3}));
  const CornerSpec p = parse_corners("0,0,0; 1,0,0.5;1,1,0;0,1,-2e-1");
  EXPECT_EQ(p.kind, CornerSpec::Kind::Points);
  EXPECT_DOUBLE_EQ(p.points[1].z(), 0.5);
  EXPECT_DOUBLE_EQ(p.points[3].z(), -0.2);
  EXPECT_EQ(parse_corners("auto").kind, CornerSpec::Kind::Auto);
}

TEST(ParseCorners, RejectsMalformedInputNamingTheField) {
  for (const char* bad :
       {"1,2,3", "1,2,3,4,5", "a,1,2,3", "-1,2,3,4", "1,2,2,3", "1.5,2,3,4", "0,0,0;1,1,1;2,2,2",
        "0,0;1,1,1;2,2,2;3,3,3", "0,0,x;1,1,1;2,2,2;3,3,3", "0,0,nan;1,1,1;2,2,2;3,3,3", ""}) {
    try {
      parse_corners(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(e.field(), "--corners") << e.what();
    }
  }
}

TEST(CliField, RequestFieldsBecomeFlagsAndFiles) {
  FieldContext context;
  context.mesh = "roof.obj";
  EXPECT_EQ(cli_field("options.lamella_width", context), "--lamella-width");
  EXPECT_EQ(cli_field("options.members_u", context), "--members-u");
  EXPECT_EQ(cli_field("options.geodesic_method", context), "--method");
  EXPECT_EQ(cli_field("simulation.young_modulus", context), "--young");
  EXPECT_EQ(cli_field("options.friction_mu", context), "--mu");
  EXPECT_EQ(cli_field("corners", context), "--corners");
  EXPECT_EQ(cli_field("corners.vertices[2]", context), "--corners (corner 3)");
  EXPECT_EQ(cli_field("corners.points[7]", context), "--corners (corner 3)");
  EXPECT_EQ(cli_field("corners[0]", context), "--corners (corner 1)");
  EXPECT_EQ(cli_field("mesh.indices[21]", context), "roof.obj (face 7)");
  EXPECT_EQ(cli_field("mesh.positions[6]", context), "roof.obj (vertex 2)");
  EXPECT_EQ(cli_field("design.options.alpha", context), "--alpha");  // gridshell run
  EXPECT_EQ(cli_field("design.corners.vertices[1]", context), "--corners (corner 2)");
  context.design = "out/design.json";  // gridshell simulate
  EXPECT_EQ(cli_field("design.members[4]", context), "out/design.json (members[4])");
  // Flags and file names the CLI named itself stay as they are.
  EXPECT_EQ(cli_field("--out", context), "--out");
  EXPECT_EQ(cli_field("roof.obj", context), "roof.obj");
  EXPECT_EQ(cli_field("", context), "");
}

}  // namespace
}  // namespace gridshell::cli
