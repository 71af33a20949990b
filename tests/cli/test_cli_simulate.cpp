// SPDX-License-Identifier: GPL-3.0-or-later
// End-to-end tests of `gridshell simulate`: files, deployment.json fields, exit codes, errors.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "support.h"

namespace gridshell {
namespace {

using nlohmann::json;
using testing::run_cli;

/// One design of the double vault shared by the tests of this file.
const std::string& design_dir() {
  static const std::string dir = [] {
    const std::string out = testing::temp_dir() + "/design";
    const auto result = run_cli("design example:double-vault --quiet --out '" + out + "'");
    EXPECT_EQ(result.exit_code, 0) << result.err;
    return out;
  }();
  return dir;
}

TEST(CliSimulate, WritesDeploymentFilesWithBothRuns) {
  const std::string out = testing::temp_dir() + "/sim";
  const auto result =
      run_cli("simulate '" + design_dir() + "/design.json' --quiet --unit cm --out '" + out + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const json d = json::parse(testing::read_text(out + "/deployment.json"));
  for (const char* key : {"rms_without_notches", "rms_with_notches", "seconds_without_notches",
                          "seconds_with_notches", "converged", "iterations", "rods",
                          "rods_without_notches", "grid_vertices", "options"})
    EXPECT_TRUE(d.contains(key)) << key;
  EXPECT_TRUE(d["converged"].get<bool>());
  EXPECT_LT(d["rms_with_notches"].get<double>(), d["rms_without_notches"].get<double>());
  ASSERT_EQ(d["rods"].size(), d["rods_without_notches"].size());
  int vertices = 0;
  for (const auto& rod : d["rods"]) {
    EXPECT_TRUE(rod["member"]["family"] == "g" || rod["member"]["family"] == "h");
    ASSERT_EQ(rod["centerline"].size(), rod["normals"].size());
    ASSERT_EQ(rod["centerline"].size(), rod["deviation"].size());
    vertices += static_cast<int>(rod["centerline"].size());
    for (const auto& n : rod["normals"]) {
      const double x = n[0], y = n[1], z = n[2];
      EXPECT_NEAR(x * x + y * y + z * z, 1.0, 1e-9);
    }
    EXPECT_GT(rod["max_bending_stress"].get<double>(), 0.0);
  }
  EXPECT_EQ(vertices, d["grid_vertices"].get<int>());
  EXPECT_EQ(d["with_notches"]["energy_unit"], "J");  // --unit given
  EXPECT_EQ(d["options"]["material"], "lime-wood");
  // The views: boxes of the lamellas and the coloured centerlines.
  for (const char* file : {"deployed.obj", "deviation.ply", "deployed_without_notches.obj",
                           "deviation_without_notches.ply"})
    EXPECT_TRUE(std::filesystem::exists(out + "/" + file)) << file;
  const std::string ply = testing::read_text(out + "/deviation.ply");
  EXPECT_NE(ply.find("element vertex " + std::to_string(vertices)), std::string::npos);
  const std::string obj = testing::read_text(out + "/deployed.obj");
  size_t boxes = 0;
  for (size_t at = obj.find("\no "); at != std::string::npos; at = obj.find("\no ", at + 1))
    ++boxes;
  EXPECT_EQ(boxes, d["rods"].size());
  EXPECT_NE(result.out.find("with notches"), std::string::npos);
}

/// A small design (4 + 4 inner members) for tests that simulate it several times.
const std::string& small_design() {
  static const std::string file = [] {
    const std::string out = testing::temp_dir() + "/small-design";
    const auto result = run_cli(
        "design example:double-vault --members-u 4 --members-v 4 --quiet "
        "--out '" +
        out + "'");
    EXPECT_EQ(result.exit_code, 0) << result.err;
    return out + "/design.json";
  }();
  return file;
}

// A run that does not converge is not a result: exit code 4, one error line naming each run,
// why it stopped and what to change; the files stay for diagnosis, marked unconverged. With
// the cap raised, the same design converges and exits 0.
TEST(CliSimulate, AnUnconvergedRunExitsWithCode4AndKeepsItsFilesMarked) {
  const std::string out = testing::temp_dir() + "/unconverged";
  const auto result = run_cli("simulate '" + design_dir() +
                              "/design.json' --quiet --max-iterations 5 --out '" + out + "'");
  EXPECT_EQ(result.exit_code, 4) << result.err;
  EXPECT_NE(result.err.find("error: not converged: without notches: iteration cap reached (5)"),
            std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("with notches: iteration cap reached (5)"), std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("raise --max-iterations"), std::string::npos) << result.err;
  EXPECT_NE(result.out.find("NOT converged"), std::string::npos) << result.out;
  const json d = json::parse(testing::read_text(out + "/deployment.json"));
  EXPECT_FALSE(d["converged"].get<bool>());
  EXPECT_FALSE(d["without_notches"]["converged"].get<bool>());
  EXPECT_TRUE(std::filesystem::exists(out + "/deployed.obj"));
  // The solver's profile: the block kernel at this size, one linear solve per iteration.
  const json& profile = d["without_notches"]["solver_profile"];
  EXPECT_EQ(profile["factorization"], "block");
  EXPECT_EQ(profile["factorizations"].get<int>(), d["without_notches"]["iterations"].get<int>());

  const auto enough = run_cli("simulate '" + design_dir() + "/design.json' --quiet --notches off" +
                              " --max-iterations 2000 --out '" + out + "-enough'");
  EXPECT_EQ(enough.exit_code, 0) << enough.err;
}

TEST(CliSimulate, StressesAgainstTheMaterialsStrengths) {
  // Lime wood (the default): utilization = the largest corner stress / 60 MPa; the corner stress
  // adds both bending stresses at one vertex, so it lies between the larger of a rod's two
  // maxima and their sum; stresses are scale-free (no unit needed, the same with one).
  const std::string out = testing::temp_dir() + "/stress";
  auto result =
      run_cli("simulate '" + small_design() + "' --quiet --notches on --out '" + out + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const json d = json::parse(testing::read_text(out + "/deployment.json"));
  EXPECT_EQ(d["options"]["bending_strength"].get<double>(), 60e6);
  EXPECT_EQ(d["options"]["shear_strength"].get<double>(), 6.8e6);
  double normal = 0, torsion = 0, bending = 0;
  int over = 0;
  for (const auto& rod : d["rods"]) {
    const double n = rod["max_normal_stress"], b = rod["max_bending_stress"],
                 st = rod["max_strong_bending_stress"], t = rod["max_torsion_stress"];
    EXPECT_GE(n, std::max(b, st) * (1 - 1e-12));
    EXPECT_LE(n, (b + st) * (1 + 1e-12));
    normal = std::max(normal, n), torsion = std::max(torsion, t), bending = std::max(bending, b);
    over += n > 60e6 || t > 6.8e6;
  }
  const json& run = d["with_notches"];
  EXPECT_EQ(run["max_normal_stress"].get<double>(), normal);
  EXPECT_EQ(run["max_torsion_stress"].get<double>(), torsion);
  EXPECT_EQ(run["max_bending_stress"].get<double>(), bending);
  EXPECT_GT(normal, 1e5);
  EXPECT_DOUBLE_EQ(run["bending_utilization"].get<double>(), normal / 60e6);
  EXPECT_DOUBLE_EQ(run["shear_utilization"].get<double>(), torsion / 6.8e6);
  EXPECT_EQ(run["overstressed_lamellas"].get<int>(), over);
  EXPECT_NE(result.out.find("% of 60 MPa"), std::string::npos) << result.out;

  // The same in metres: the same stresses.
  const std::string metres = testing::temp_dir() + "/stress-m";
  result = run_cli("simulate '" + small_design() + "' --quiet --notches on --unit m " + "--out '" +
                   metres + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const json m = json::parse(testing::read_text(metres + "/deployment.json"));
  EXPECT_NEAR(m["with_notches"]["max_normal_stress"].get<double>(), normal, 1e-9 * normal);

  // A strength of one's own, below the stresses: every lamella above it counts, EXCEEDED shown.
  const double low = normal / 2;
  const std::string own = testing::temp_dir() + "/stress-own";
  result = run_cli("simulate '" + small_design() + "' --quiet --notches on " +
                   "--bending-strength " + std::to_string(low) + " --out '" + own + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const json o = json::parse(testing::read_text(own + "/deployment.json"));
  EXPECT_NEAR(o["with_notches"]["bending_utilization"].get<double>(), 2.0, 1e-6);
  EXPECT_GE(o["with_notches"]["overstressed_lamellas"].get<int>(), 1);
  EXPECT_NE(result.out.find("EXCEEDED"), std::string::npos) << result.out;

  // A custom material (moduli without a name): strengths unknown, no utilization.
  const std::string custom = testing::temp_dir() + "/stress-custom";
  result = run_cli("simulate '" + small_design() + "' --quiet --notches on " +
                   "--young 8e9 --shear 5e8 --out '" + custom + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const json c = json::parse(testing::read_text(custom + "/deployment.json"));
  EXPECT_EQ(c["options"]["material"], "custom");
  EXPECT_EQ(c["options"]["bending_strength"].get<double>(), 0.0);
  EXPECT_FALSE(c["with_notches"].contains("bending_utilization"));
  EXPECT_NE(result.out.find("strength unknown"), std::string::npos) << result.out;

  // Bad strengths name their flag.
  result = run_cli("simulate '" + small_design() + "' --quiet --bending-strength -3 " + "--out '" +
                   testing::temp_dir() + "/bad'");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("--bending-strength"), std::string::npos) << result.err;
  result = run_cli("simulate '" + small_design() + "' --quiet --shear-strength 1e20 " + "--out '" +
                   testing::temp_dir() + "/bad2'");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("--shear-strength"), std::string::npos) << result.err;
}

TEST(CliSimulate, OneRunOnly) {
  const std::string out = testing::temp_dir() + "/off";
  const auto result = run_cli("simulate '" + design_dir() +
                              "/design.json' --quiet --notches off --out '" + out + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const json d = json::parse(testing::read_text(out + "/deployment.json"));
  EXPECT_TRUE(d.contains("rms_without_notches"));
  EXPECT_FALSE(d.contains("rms_with_notches"));
  EXPECT_TRUE(d["rods"].empty());
  EXPECT_FALSE(d["rods_without_notches"].empty());
  EXPECT_EQ(d["without_notches"]["energy_unit"], "scaled");
}

TEST(CliSimulate, BadInputsNameTheProblem) {
  const std::string dir = testing::temp_dir();
  struct Case {
    std::string arguments, expected;
  };
  json design = json::parse(testing::read_text(design_dir() + "/design.json"));
  json broken = design;
  broken["crossings"][3]["h"] = 999;
  const std::string broken_path = testing::write_text(dir, "broken.json", broken.dump());
  json no_width = design;
  no_width["options"]["lamella_width"] = -1;
  const std::string width_path = testing::write_text(dir, "width.json", no_width.dump());
  json thick = design;  // accepted by design once; the simulation left its domain (exit 1)
  thick["options"]["lamella_thickness"] = 1e10;
  const std::string thick_path = testing::write_text(dir, "thick.json", thick.dump());
  json far = design;  // a patch vertex at 1e300 used to be reported as a lamella_width problem
  far["patch"]["vertices"][0][2] = 1e300;
  const std::string far_path = testing::write_text(dir, "far.json", far.dump());
  const std::string good = "'" + design_dir() + "/design.json'";
  const std::vector<Case> cases{
      {"/nonexistent/design.json", "cannot open"},
      {"'" + testing::write_text(dir, "garbage.json", "{not json") + "'", "not a gridshell design"},
      {"'" + broken_path + "'", "crossings[3].h"},
      {"'" + width_path + "'", "options.lamella_width"},
      {good + " --material unobtainium", "--material: expected one of lime-wood, birch-plywood"},
      {good + " --unit parsec", "--unit"},
      {good + " --young -5", "--young"},
      {good + " --mu -1", "--mu"},  // 0 is the default (0.1), as in the request
      {good + " --edges-per-interval 100", "--edges-per-interval"},
      // Extremes that used to give Infinity / NaN in deployment.json with exit code 0.
      {good + " --young 1e-300 --shear 1e-301", "--young"},
      {good + " --young 1e300 --shear 1e299", "--young"},
      {good + " --mu 1e300", "--mu"},
      {good + " --unit 1e300", "--unit"},
      {"'" + thick_path + "'", "lamella_thickness"},
      {"'" + far_path + "'", "patch.vertices[0]"},
  };
  for (const Case& c : cases) {
    const auto result = run_cli("simulate " + c.arguments + " --quiet --out '" + dir + "/x'");
    EXPECT_EQ(result.exit_code, 2) << c.arguments << ": " << result.err;
    EXPECT_EQ(result.err.rfind("error:", 0), 0u) << result.err;
    EXPECT_NE(result.err.find(c.expected), std::string::npos) << c.arguments << ": " << result.err;
  }
}

TEST(CliRun, DesignsSimulatesAndPrintsTheTable) {
  const std::string out = testing::temp_dir() + "/run";
  const auto result = run_cli(
      "run example:hypar --quiet --resolution 16 --members-u 7 "
      "--members-v 7 --notches on --out '" +
      out + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  for (const char* file : {"design.json", "report.json", "planar.svg", "spatial.obj", "maps.svg",
                           "deployment.json", "deployed.obj", "deviation.ply"})
    EXPECT_TRUE(std::filesystem::exists(out + "/" + file)) << file;
  EXPECT_FALSE(std::filesystem::exists(out + "/deployed_without_notches.obj"));
  // The summary table carries the numbers of the files.
  const json d = json::parse(testing::read_text(out + "/deployment.json"));
  EXPECT_TRUE(d["converged"].get<bool>());
  EXPECT_FALSE(d.contains("rms_without_notches"));
  char rms2[32];
  std::snprintf(rms2, sizeof rms2, "%.3f", d["rms_with_notches"].get<double>());
  EXPECT_NE(result.out.find("RMS2 (notches)"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find(rms2), std::string::npos) << result.out;
  EXPECT_EQ(result.out.find("paper"), std::string::npos);  // hypar is not one of the paper's
  // Its design is the one `gridshell design` writes with the same options.
  const std::string design = testing::temp_dir() + "/design";
  ASSERT_EQ(run_cli("design example:hypar --quiet --resolution 16 --members-u 7 --members-v 7 "
                    "--out '" +
                    design + "'")
                .exit_code,
            0);
  EXPECT_EQ(testing::read_text(design + "/design.json"), testing::read_text(out + "/design.json"));
}

TEST(CliRun, BadInputsStopBeforeAnyWork) {
  const std::string dir = testing::temp_dir();
  struct Case {
    std::string arguments, expected;
  } cases[] = {{"example:hypar --material balsa", "--material: expected one of lime-wood"},
               {"example:hypar --young -5", "--young"},
               {"example:hypar --eta-max 0.5", "--eta-max"},
               {"example:nothing", "nothing"},
               {"example:hypar --corners 1,2,3", "--corners"}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.arguments);
    const auto result = run_cli("run " + c.arguments + " --quiet --out '" + dir + "/x'");
    EXPECT_EQ(result.exit_code, 2) << result.err;
    EXPECT_NE(result.err.find("error: "), std::string::npos) << result.err;
    EXPECT_NE(result.err.find(c.expected), std::string::npos) << result.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/x/design.json"));
  }
}

// Ctrl-C during the simulation: exit code 130, and the design computed before it is kept.
TEST(CliRun, InterruptedSimulationKeepsTheDesign) {
  const std::string out = testing::temp_dir() + "/run";
  const pid_t pid = fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    dup2(null, STDOUT_FILENO);
    dup2(null, STDERR_FILENO);
    execl(GRIDSHELL_CLI, GRIDSHELL_CLI, "run", "example:waves", "--quiet", "--out", out.c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  ASSERT_GT(pid, 0);
  bool designed = false;
  for (int i = 0; i < 6000 && !designed; ++i) {
    designed = std::filesystem::exists(out + "/design.json");
    if (!designed) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // inside the simulation
  kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(designed);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const json design = json::parse(testing::read_text(out + "/design.json"));
  EXPECT_FALSE(design["members"].empty());
  EXPECT_TRUE(std::filesystem::exists(out + "/planar.svg"));
  EXPECT_FALSE(std::filesystem::exists(out + "/deployment.json"));
}

}  // namespace
}  // namespace gridshell
