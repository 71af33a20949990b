// SPDX-License-Identifier: GPL-3.0-or-later
// Requests -> kernel inputs (application/requests.cpp): option parsing, field paths of errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <numbers>

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(ParseAlpha, AcceptsMinMaxRadiansAndDegrees) {
  DesignOptions options;
  parse_alpha("max", options);
  EXPECT_EQ(options.alpha, DesignOptions::Alpha::Max);
  parse_alpha("min", options);
  EXPECT_EQ(options.alpha, DesignOptions::Alpha::Min);
  parse_alpha("90deg", options);
  EXPECT_EQ(options.alpha, DesignOptions::Alpha::Value);
  EXPECT_NEAR(options.alpha_value, kPi / 2, 1e-15);
  parse_alpha("1.25", options);
  EXPECT_DOUBLE_EQ(options.alpha_value, 1.25);
}

TEST(ParseAlpha, RejectsEverythingElseNamingTheField) {
  DesignOptions options;
  for (const char* bad : {"", "abc", "4", "-1", "0", "200deg", "nan", "inf", "1.2.3", "deg"}) {
    try {
      parse_alpha(bad, options);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(e.field(), "options.alpha") << bad;
      EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
      EXPECT_EQ(std::string(e.message()).find("--"), std::string::npos) << e.message();
    }
  }
}

v1::DesignRequest example_request() {
  const ExampleSurface example = make_example("double-vault");
  v1::DesignRequest request;
  *request.mutable_mesh() = to_proto(example.mesh, "example:double-vault");
  for (int v : example.corners) request.mutable_corners()->add_vertices(v);
  return request;
}

/// The field of the InvalidInput that prepare_design throws for `request`.
std::string rejected_field(const v1::DesignRequest& request) {
  try {
    prepare_design(request);
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.what(), e.field() + ": " + e.message());
    EXPECT_EQ(e.message().find("--"), std::string::npos) << "CLI syntax in " << e.message();
    return e.field();
  }
  ADD_FAILURE() << "request accepted";
  return "";
}

TEST(PrepareDesign, ErrorsNameTheRequestField) {
  EXPECT_NO_THROW(prepare_design(example_request()));
  {
    v1::DesignRequest r = example_request();
    r.mutable_corners()->set_vertices(2, 1 << 30);
    EXPECT_EQ(rejected_field(r), "corners.vertices[2]");
  }
  {
    v1::DesignRequest r = example_request();
    r.mutable_options()->set_lamella_width(-1);
    EXPECT_EQ(rejected_field(r), "options.lamella_width");
  }
  {
    v1::DesignRequest r = example_request();
    r.mutable_options()->set_alpha("sideways");
    EXPECT_EQ(rejected_field(r), "options.alpha");
  }
  {
    v1::DesignRequest r = example_request();
    r.mutable_options()->set_members_v(-3);
    EXPECT_EQ(rejected_field(r), "options.members_v");
  }
  {
    v1::DesignRequest r = example_request();
    r.mutable_mesh()->set_indices(31, -1);
    EXPECT_EQ(rejected_field(r), "mesh.indices[31]");
  }
  {
    // A topology problem found by the loader names the face as packed indices.
    v1::DesignRequest r = example_request();
    const int a = r.mesh().indices(0), b = r.mesh().indices(1);
    const int far = r.mesh().positions_size() / 3 - 1;  // on no face with a or b
    r.mutable_mesh()->add_indices(a);                   // a third face on edge (a, b): non-manifold
    r.mutable_mesh()->add_indices(b);
    r.mutable_mesh()->add_indices(far);
    const std::string field = rejected_field(r);
    EXPECT_EQ(field.rfind("mesh.", 0), 0u) << field;
  }
}

TEST(PrepareSimulation, ErrorsNameTheFieldUnderThePrefix) {
  v1::SimulationOptions options;
  options.set_friction_mu(-1);
  try {
    prepare_simulation_options(options, "simulation");
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), "simulation.friction_mu");
  }
  options.set_friction_mu(0);
  options.set_material("unobtainium");
  try {
    prepare_simulation_options(options);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), "options.material");
    EXPECT_NE(e.message().find("lime-wood"), std::string::npos) << e.message();
  }
}

TEST(ToJson, MapsComeOutSortedWhateverTheirInsertionOrder) {
  // protobuf's maps iterate in a per-process hash order; files must not depend on it.
  const std::vector<std::string> keys{"patch",   "grid",    "cladding", "distance_maps",
                                      "members", "anchors", "zeta",     "alpha",
                                      "m1",      "m2",      "m10"};
  std::string first;
  for (int permutation = 0; permutation < 8; ++permutation) {
    v1::DesignReport report;
    std::vector<std::string> order = keys;
    std::rotate(order.begin(), order.begin() + permutation % order.size(), order.end());
    if (permutation % 2) std::reverse(order.begin(), order.end());
    for (const std::string& key : order) (*report.mutable_stage_seconds())[key] = key.size();
    const std::string json = to_json(report, false);
    if (permutation == 0) first = json;
    EXPECT_EQ(json, first);
  }
  size_t previous = 0;
  for (const char* key : {"alpha", "anchors", "cladding", "distance_maps", "grid", "m1", "m10",
                          "m2", "members", "patch", "zeta"}) {
    const size_t at = first.find(std::string("\"") + key + "\"");
    ASSERT_NE(at, std::string::npos) << key;
    EXPECT_GT(at, previous) << key << " out of order in " << first;
    previous = at;
  }
}

}  // namespace
}  // namespace gridshell
