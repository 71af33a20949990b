// SPDX-License-Identifier: GPL-3.0-or-later
// The gridshell command on surfaces a user brings (issue 18): meshes with a hole and closed
// meshes load and get exact geodesics, automatic corners and patches; a loop round a hole is
// exit 3 naming it; an infeasible design prints its computed suggestions after the one error
// line, and the printed flags make the design feasible.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>

#include "gridshell/mesh/mesh_io.h"
#include "support.h"

namespace gridshell {
namespace {

using nlohmann::json;
using testing::run_cli;

std::string write_mesh(const std::string& name, const TriangleMesh& mesh) {
  return testing::write_text(testing::temp_dir(), name, obj_text(mesh));
}

int count_lines_starting(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  int n = 0;
  for (std::string line; std::getline(in, line);) n += line.rfind(prefix, 0) == 0;
  return n;
}

TEST(CliAnySurface, GeodesicsOnAHoleAndOnAClosedSphereMatchCgal) {
  for (const auto& [name, mesh] : {std::pair{"annulus.obj", testing::annulus(1, 3, 6, 48)},
                                   std::pair{"sphere.obj", testing::icosphere(2, 5)}}) {
    const auto result =
        run_cli("geodesic '" + write_mesh(name, mesh) + "' --source 7 --compare cgal --json");
    ASSERT_EQ(result.exit_code, 0) << name << ": " << result.err;
    const json report = json::parse(result.out);
    EXPECT_LT(report["max_rel_diff"].get<double>(), 1e-9) << name;
    EXPECT_GT(report["max_distance"].get<double>(), 0.0) << name;
  }
}

TEST(CliAnySurface, AutomaticCornersOnAClosedSphereRecordTheSearch) {
  const std::string out = testing::temp_dir() + "/sphere";
  const auto result = run_cli("patch '" + write_mesh("sphere.obj", testing::icosphere(3, 10)) +
                              "' --corners auto --quiet --out '" + out + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const json report = json::parse(testing::read_text(out + "/patch.json"));
  const json& search = report["auto_corners"];
  ASSERT_GT(search["candidates"].size(), 0u);
  const json& chosen = search["candidates"][search["chosen"].get<int>()];
  EXPECT_TRUE(chosen["accepted"].get<bool>());
  EXPECT_EQ(chosen["kind"], "inner");
  EXPECT_EQ(chosen["input_vertices"].size(), 4u);
  EXPECT_EQ(chosen["alpha_bar_range"].size(), 2u);
  for (const json& c : search["candidates"]) EXPECT_FALSE(c["reason"].get<std::string>().empty());
  for (const json& e : report["boundary_geodesic_excess"]) EXPECT_LE(e.get<double>(), 1e-9);
  EXPECT_LE(report["eta_after"].get<double>(), 1.0015);
  EXPECT_NE(result.out.find("auto corners"), std::string::npos) << result.out;
}

TEST(CliAnySurface, LoopRoundAHoleIsInfeasibleAndNamesIt) {
  // Annulus 1..3, 8 rings x 64 sectors: ring 4 (radius 2) at four quarter turns.
  const std::string mesh = write_mesh("ring.obj", testing::annulus(1, 3, 8, 64));
  const auto result = run_cli("patch '" + mesh + "' --corners 256,272,288,304 --quiet --out '" +
                              testing::temp_dir() + "'");
  EXPECT_EQ(result.exit_code, 3) << result.err;
  EXPECT_EQ(count_lines_starting(result.err, "error:"), 1) << result.err;
  EXPECT_NE(result.err.find("contains a hole"), std::string::npos) << result.err;
}

TEST(CliAnySurface, InfeasibleDesignPrintsSuggestionsThatWork) {
  const std::string base =
      "design example:double-vault --resolution 50 --quiet --out '" + testing::temp_dir() + "'";
  const auto failed = run_cli(base + " --k-max 1.5 --suggest 2");
  EXPECT_EQ(failed.exit_code, 3) << failed.err;
  EXPECT_EQ(count_lines_starting(failed.err, "error:"), 1) << failed.err;
  ASSERT_GE(count_lines_starting(failed.err, "suggestion 1: "), 1) << failed.err;
  EXPECT_LE(count_lines_starting(failed.err, "suggestion "), 2) << failed.err;
  // The flags in brackets of the first suggestion make the design feasible.
  const size_t line = failed.err.find("suggestion 1: ");
  const size_t open = failed.err.find('[', line), close = failed.err.find(']', open);
  ASSERT_NE(close, std::string::npos) << failed.err;
  const std::string flags = failed.err.substr(open + 1, close - open - 1);
  const auto fixed = run_cli(base + " " + flags);
  EXPECT_EQ(fixed.exit_code, 0) << flags << ": " << fixed.err;
  // --suggest 0: the error alone.
  const auto bare = run_cli(base + " --k-max 1.5 --suggest 0");
  EXPECT_EQ(bare.exit_code, 3);
  EXPECT_EQ(count_lines_starting(bare.err, "suggestion"), 0) << bare.err;
}

TEST(CliAnySurface, BadCornerAnglesAreInvalidInput) {
  for (const char* angles : {"45", "135,45", "0,90", "x,90", "45,180"}) {
    const auto result = run_cli(std::string("patch example:plane --quiet --corners auto "
                                            "--corner-angles '") +
                                angles + "' --out '" + testing::temp_dir() + "'");
    EXPECT_EQ(result.exit_code, 2) << angles;
    EXPECT_NE(result.err.find("--corner-angles"), std::string::npos) << result.err;
  }
}

}  // namespace
}  // namespace gridshell
