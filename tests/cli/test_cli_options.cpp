// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell options` and the CLI's flags read the one description of the options: every
// described flag is in the help, and a material added by a site's library (GRIDSHELL_MATERIALS)
// appears in the description, the help, the sweep check and a simulation with no other change.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "support.h"

namespace gridshell {
namespace {

using json = nlohmann::json;
using testing::run_cli;

/// A library with one material no part of gridshell knows of.
std::string larch_library(const std::string& dir) {
  return testing::write_text(dir, "materials.json", R"({"materials": [{
      "name": "test-larch", "label": "test larch", "young_modulus": 1.1e10,
      "shear_modulus": 7e8, "bending_strength": 7e7, "shear_strength": 8e6,
      "source": "a test"}]})");
}

TEST(CliOptions, JsonIsTheDescriptionAndEveryFlagIsInTheHelp) {
  const auto r = run_cli("options --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json d = json::parse(r.out);
  std::set<std::string> groups;
  for (const json& o : d["options"]) groups.insert(o["group"].get<std::string>());
  EXPECT_EQ(groups,
            (std::set<std::string>{"patch", "design", "simulation", "layout", "fabrication"}));
  ASSERT_GE(d["materials"].size(), 7u);
  EXPECT_EQ(d["materials"][0]["name"], "lime-wood");
  // Each command's help lists the flags of its groups, as described.
  const std::string run_help = run_cli("run --help").out, patch_help = run_cli("patch --help").out,
                    fabricate_help = run_cli("fabricate --help").out,
                    layout_help = run_cli("layout --help").out;
  int flags = 0;
  for (const json& o : d["options"]) {
    const std::string flag = o["flag"], group = o["group"];
    if (flag.empty() || flag == "--corner-angles") continue;  // takes degrees: its own help
    const std::string& help = group == "patch"         ? patch_help
                              : group == "fabrication" ? fabricate_help
                                                       : run_help;
    EXPECT_NE(help.find(flag), std::string::npos) << group << " " << flag;
    if (group == "layout") {
      EXPECT_NE(layout_help.find(flag), std::string::npos) << flag;
    }
    if (o["type"] == "number" || o["type"] == "integer") {
      const std::string dflt = "default " + o["default_value"].get<std::string>();
      EXPECT_NE(help.find(dflt), std::string::npos) << flag << " " << dflt;
    }
    ++flags;
  }
  EXPECT_GT(flags, 35);
  // The table form says the same.
  const auto table = run_cli("options --group simulation");
  ASSERT_EQ(table.exit_code, 0);
  EXPECT_NE(table.out.find("friction_mu"), std::string::npos);
  EXPECT_EQ(table.out.find("lamella_width  "), std::string::npos);  // design's: not this group
  EXPECT_EQ(run_cli("options --group nothing").exit_code, 2);
}

TEST(CliOptions, ASiteMaterialAppearsEverywhereWithNoOtherChange) {
  const std::string dir = testing::temp_dir();
  const std::string env = "GRIDSHELL_MATERIALS='" + larch_library(dir) + "' ";
  const json built_in = json::parse(run_cli("options --json").out);
  // The CLI with the library: `VAR=... gridshell ARGS` through the shell.
  const auto with = [&](const std::string& arguments) {
    return testing::run_command(env + "'" + std::string(GRIDSHELL_CLI) + "' " + arguments);
  };
  // The description, after the built-in ones.
  auto r = with("options --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json d = json::parse(r.out);
  ASSERT_EQ(d["materials"].size(), built_in["materials"].size() + 1);
  EXPECT_EQ(d["materials"].back()["name"], "test-larch");
  EXPECT_EQ(d["materials"].back()["site"], true);
  // The help of the flag that picks it.
  EXPECT_NE(with("simulate --help").out.find("test-larch"), std::string::npos);
  // The sweep check: the same manifest is fine with the library and refused without it.
  const std::string manifest = testing::write_text(
      dir, "m.csv",
      "id,mesh,resolution,notches,material\na,example:double-vault,16,off,test-larch\n");
  r = with("sweep check '" + manifest + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("1 rows"), std::string::npos) << r.out;
  r = run_cli("sweep check '" + manifest + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("line 2 (id a), column material: expected one of lime-wood"),
            std::string::npos)
      << r.err;
  // A simulation with it takes its moduli and strengths.
  r = with(
      "run example:double-vault --resolution 16 --notches off --material test-larch --quiet "
      "--out '" +
      dir + "/run'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json deployment = json::parse(testing::read_text(dir + "/run/deployment.json"));
  EXPECT_EQ(deployment["options"]["material"], "test-larch");
  EXPECT_EQ(deployment["options"]["young_modulus"], 1.1e10);
  EXPECT_EQ(deployment["options"]["bending_strength"], 7e7);
  // A library that is not one stops the CLI before anything, naming the file and the field.
  const std::string bad = testing::write_text(dir, "bad.json", R"({"materials": [{"name": 3}]})");
  r = testing::run_command("GRIDSHELL_MATERIALS='" + bad + "' '" + std::string(GRIDSHELL_CLI) +
                           "' options");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.json.materials[0].name"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace gridshell
