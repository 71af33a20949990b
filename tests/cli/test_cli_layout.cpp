// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell layout`: a layout file cut into patches that share seams; the files it writes are
// read back (layout.json's coverage and seams, layout.obj's objects), and bad layouts are
// refused naming the field, a failing patch with exit 3 after the files are written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "gridshell/mesh/mesh_io.h"
#include "support.h"

namespace gridshell {
namespace {

using json = nlohmann::json;
using testing::run_cli;

/// The sphere's 2 x 2 layout; its third patch named "north-west".
json sphere_layout() {
  json layout = json::parse(testing::sphere_layout_json());
  layout["patches"][2]["name"] = "north-west";
  return layout;
}

TEST(CliLayout, ATwoByTwoLayoutCoversTheSphereAndItsFilesReadBack) {
  const std::string dir = testing::temp_dir();
  const std::string file = testing::write_text(dir, "layout.json", sphere_layout().dump());
  const auto r =
      run_cli("layout example:sphere --layout '" + file + "' --quiet --out '" + dir + "/out'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json report = json::parse(testing::read_text(dir + "/out/layout.json"));
  EXPECT_NEAR(report["coverage"].get<double>(), 1.0, 1e-9);
  ASSERT_EQ(report["patches"].size(), 4u);
  double areas = 0;
  int vertices = 0;
  for (const json& p : report["patches"]) {
    EXPECT_TRUE(p["ok"].get<bool>()) << p.dump();
    areas += p["area"].get<double>();
    vertices += p["vertices"].get<int>();
  }
  EXPECT_NEAR(areas, report["input_area"].get<double>(), 1e-9 * areas);
  EXPECT_EQ(report["layout"]["patches"][0]["name"], "P1");
  EXPECT_EQ(report["layout"]["patches"][2]["name"], "north-west");
  EXPECT_EQ(report["layout"]["corners"][4]["vertex"], 16 * 33 + 16);  // file order, as given
  int shared = 0;
  for (const json& s : report["seams"])
    if (s["patches"].size() == 2) {
      ++shared;
      EXPECT_LE(s["mismatch"].get<double>(), 1e-9 * 100);
    }
  EXPECT_EQ(shared, 4);
  // layout.obj: one object per patch, faces within the vertices before them.
  std::istringstream obj(testing::read_text(dir + "/out/layout.obj"));
  int objects = 0, v = 0;
  for (std::string line; std::getline(obj, line);) {
    if (line.rfind("o ", 0) == 0) ++objects;
    if (line.rfind("v ", 0) == 0) ++v;
    if (line.rfind("f ", 0) == 0) {
      std::istringstream f(line.substr(2));
      for (int k; f >> k;) EXPECT_TRUE(k >= 1 && k <= v) << line;
    }
  }
  EXPECT_EQ(objects, 4);
  EXPECT_EQ(v, vertices);
  // layout.svg: the input's boundary dashed, the 4 patches filled, 4 seams, 9 corners.
  const std::string svg = testing::read_text(dir + "/out/layout.svg");
  const auto count = [&](const std::string& what) {
    int n = 0;
    for (size_t at = svg.find(what); at != std::string::npos; at = svg.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("<polygon fill=\"none\""), 1);
  EXPECT_EQ(count("<polygon fill=\"#"), 4);
  EXPECT_EQ(count("<polyline"), 4);
  EXPECT_EQ(count("<circle"), 9);
  EXPECT_NE(svg.find(">north-west</text>"), std::string::npos);
  EXPECT_NE(svg.rfind("</svg>"), std::string::npos);
}

TEST(CliLayout, BadLayoutsAreRefusedNamingTheFieldAndAFailingPatchIsExitThree) {
  const std::string dir = testing::temp_dir();
  const auto run = [&](const json& layout) {
    const std::string file = testing::write_text(dir, "l.json", layout.dump());
    return run_cli("layout example:sphere --layout '" + file + "' --quiet --out '" + dir + "/out'");
  };
  json bad = sphere_layout();
  bad["patches"][0]["corners"][2] = 12;
  auto r = run(bad);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("layout.patches[0].corners[2]: corner 12 is out of range"),
            std::string::npos)
      << r.err;
  bad = sphere_layout();
  bad["corners"][8]["vertex"] = 5000;
  r = run(bad);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("layout.corners[8]"), std::string::npos) << r.err;
  bad = sphere_layout();
  bad["patches"][1]["corners"] = {4, 5, 2, 1};  // on P1's side of their seam
  r = run(bad);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("layout.patches[1]: patches P1 and P2"), std::string::npos) << r.err;
  r = run_cli("layout example:sphere --layout /nonexistent.json --quiet --out '" + dir + "/o'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--layout"), std::string::npos) << r.err;
  // A patch whose corners make a bow-tie: reported, the others covered, exit 3 after writing.
  bad = sphere_layout();
  bad["patches"][3]["corners"] = {4, 8, 5, 7};
  r = run(bad);
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("layout.patches[3]"), std::string::npos) << r.err;
  const json report = json::parse(testing::read_text(dir + "/out/layout.json"));
  EXPECT_FALSE(report["patches"][3]["ok"].get<bool>());
  EXPECT_EQ(report["patches"][3]["problem_code"], "infeasible");
  EXPECT_NEAR(report["coverage"].get<double>(), 0.75, 0.01);
}

/// Object names of an OBJ text, in order.
std::vector<std::string> obj_objects(const std::string& text) {
  std::vector<std::string> names;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("o ", 0) == 0) names.push_back(line.substr(2));
  return names;
}

TEST(CliLayout, RunWithALayoutDesignsAndDeploysEveryPatchAndMeasuresTheSeams) {
  const std::string dir = testing::temp_dir();
  const std::string file = testing::write_text(dir, "layout.json", sphere_layout().dump());
  const std::string out = dir + "/out";
  const auto r = run_cli("run example:sphere --layout '" + file +
                         "' --members-u 4 --members-v 4 --notches on --quiet --out '" + out + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("whole RMS2"), std::string::npos) << r.out;
  const json design = json::parse(testing::read_text(out + "/design.json"));
  const json deployment = json::parse(testing::read_text(out + "/deployment.json"));
  const json layout = json::parse(testing::read_text(out + "/layout.json"));
  EXPECT_NEAR(layout["coverage"].get<double>(), 1.0, 1e-9);
  EXPECT_EQ(design["layout"]["coverage"], layout["coverage"]);
  ASSERT_EQ(design["patch_designs"].size(), 4u);
  EXPECT_EQ(design["patch_designs"][2], "patches/north-west/design.json");
  // Each patch has today's single-patch files, and the whole reports what they say.
  ASSERT_EQ(deployment["patches"].size(), 4u);
  double squares = 0;
  int vertices = 0;
  for (const json& p : deployment["patches"]) {
    const std::string folder = out + "/patches/" + p["name"].get<std::string>();
    for (const char* f : {"design.json", "report.json", "planar.svg", "deployment.json",
                          "deployed.obj", "deviation.ply"})
      EXPECT_TRUE(std::filesystem::exists(folder + "/" + f)) << folder << "/" << f;
    const json own = json::parse(testing::read_text(folder + "/deployment.json"));
    EXPECT_EQ(own["rms_with_notches"], p["rms_with_notches"]);
    EXPECT_EQ(own["grid_vertices"], p["grid_vertices"]);
    EXPECT_TRUE(p["converged"].get<bool>());
    const double rms = p["rms_with_notches"].get<double>();
    squares += rms * rms * p["grid_vertices"].get<int>();
    vertices += p["grid_vertices"].get<int>();
  }
  // The patches alone: the RMS over every patch's rod vertices.
  EXPECT_EQ(deployment["grid_vertices"].get<int>(), vertices);
  EXPECT_NEAR(deployment["rms_before_joining"].get<double>(), std::sqrt(squares / vertices), 1e-12);
  // The whole joined in one equilibrium: its RMS is the joined run's, every patch's share of it
  // reported, within the target of 0.5 % of the diagonal.
  EXPECT_TRUE(deployment.value("seams_joined", false));
  EXPECT_FALSE(deployment.contains("rms_without_notches"));  // --notches on
  EXPECT_FALSE(deployment.contains("joined_without_notches"));
  const json& joined = deployment["joined_with_notches"];
  EXPECT_TRUE(joined["converged"].get<bool>()) << joined.dump();
  EXPECT_EQ(deployment["rms_with_notches"], joined["rms"]);
  EXPECT_LT(joined["rms"].get<double>(), 0.005 * deployment["diagonal"].get<double>());
  EXPECT_GT(joined["energies"]["bolts"].get<double>(), 0);
  double joined_squares = 0;
  for (const json& p : deployment["patches"]) {
    const double rms = p["joined_rms"].get<double>();
    joined_squares += rms * rms * p["grid_vertices"].get<int>();
  }
  EXPECT_NEAR(joined["rms"].get<double>(), std::sqrt(joined_squares / vertices), 1e-9);
  EXPECT_EQ(deployment["force_unit"], "Pa*unit^2");
  // Four seams; each joins two patches' boundary lamellas of the same length, with a bolt at
  // each corner that both patches' members end at, and the bolts' gaps reported one to one.
  ASSERT_EQ(design["seams"].size(), 4u);
  ASSERT_EQ(deployment["seams"].size(), 4u);
  int bolts = 0;
  double largest = 0;
  for (size_t k = 0; k < 4; ++k) {
    const json& seam = design["seams"][k];
    EXPECT_LE(seam.value("length_difference", 0.0), 1e-9 * 144);
    ASSERT_EQ(seam["lamellas"].size(), 2u);
    const json& joints = seam["joints"];
    ASSERT_GE(joints.size(), 2u);
    EXPECT_EQ(joints.front()["members"].size(), 2u);
    EXPECT_EQ(joints.back()["members"].size(), 2u);
    EXPECT_NEAR(joints.back()["s"].get<double>(), seam["length"].get<double>(), 1e-9 * 144);
    bolts += static_cast<int>(joints.size());
    const json& gaps = deployment["seams"][k];
    EXPECT_EQ(gaps["corners"], seam["corners"]);
    ASSERT_EQ(gaps["gaps"].size(), joints.size());
    ASSERT_EQ(gaps["gaps_before_joining"].size(), joints.size());
    ASSERT_EQ(gaps["forces"].size(), joints.size());
    for (const json& g : gaps["gaps"]) {
      EXPECT_GE(g.get<double>(), 0);
      EXPECT_LE(g.get<double>(), gaps["max_gap"].get<double>());
    }
    for (const json& f : gaps["forces"])
      EXPECT_LE(f.get<double>(), gaps["max_force"].get<double>());
    // Joined, the seams are closed within 0.1 % of the diagonal, and closer than the patches
    // alone were.
    EXPECT_LT(gaps["max_gap"].get<double>(), 1e-3 * deployment["diagonal"].get<double>());
    EXPECT_LT(gaps["max_gap"].get<double>(), gaps["max_gap_before_joining"].get<double>());
    largest = std::max(largest, gaps["max_gap"].get<double>());
  }
  EXPECT_EQ(design["seam_bolts"].get<int>(), bolts);
  EXPECT_EQ(deployment["max_seam_gap"].get<double>(), largest);
  EXPECT_GT(deployment["max_bolt_force"].get<double>(), 0);
  // The whole's deployed.obj holds every patch's lamellas, named by patch ("P1-g0").
  const std::vector<std::string> objects = obj_objects(testing::read_text(out + "/deployed.obj"));
  size_t expected = 0;
  for (const char* name : {"P1", "P2", "north-west", "P4"}) {
    const std::vector<std::string> own =
        obj_objects(testing::read_text(out + "/patches/" + name + "/deployed.obj"));
    expected += own.size();
    for (const std::string& o : own)
      EXPECT_NE(std::find(objects.begin(), objects.end(), std::string(name) + "-" + o),
                objects.end())
          << name << "-" << o;
  }
  EXPECT_EQ(objects.size(), expected);
}

TEST(CliLayout, FabricateARunOfALayoutGivesOneKitForAllItsPatches) {
  const std::string dir = testing::temp_dir();
  const std::string file = testing::write_text(dir, "layout.json", sphere_layout().dump());
  auto r = run_cli("run example:sphere --layout '" + file +
                   "' --members-u 4 --members-v 4 --notches on --quiet --out '" + dir + "/run'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli("fabricate '" + dir + "/run/design.json' --unit cm --quiet --out '" + dir + "/kit'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json kit = json::parse(testing::read_text(dir + "/kit/kit.json"));
  // Every patch's lamellas, named by patch; the partners of seam bolts are the neighbour's.
  int parts = 0;
  for (const char* name : {"P1", "P2", "north-west", "P4"}) {
    const json design =
        json::parse(testing::read_text(dir + "/run/patches/" + name + "/design.json"));
    parts += static_cast<int>(design["members"].size());
    EXPECT_TRUE(std::filesystem::exists(dir + "/kit/assembly-" + name + ".svg")) << name;
  }
  EXPECT_EQ(static_cast<int>(kit["parts"].size()), parts);
  int seam_holes = 0;
  for (const json& part : kit["parts"]) {
    const std::string name = part["name"];
    const std::string patch = name.substr(0, name.rfind('-'));
    for (const json& f : part["features"])
      if (f.value("crossing", 0) == -1) {
        ++seam_holes;
        EXPECT_NE(f["partner"].get<std::string>().rfind(patch + "-", 0), 0u) << name;
      }
  }
  EXPECT_GT(seam_holes, 0);
  const std::string bom = testing::read_text(dir + "/kit/bom.csv");
  EXPECT_NE(bom.find("seam bolts,"), std::string::npos) << bom;
  EXPECT_NE(bom.find(std::to_string(seam_holes) + " holes added"), std::string::npos) << bom;
  EXPECT_NE(testing::read_text(dir + "/kit/joining.svg").find("4. Deploy"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir + "/kit/sheets/sheet-01.dxf"));
  // supports.csv: the anchors that hold the whole (none on a seam), named by patch and by their
  // number on its assembly sheet, under one header: as many as held the joined whole.
  std::istringstream supports(testing::read_text(dir + "/kit/supports.csv"));
  std::string line;
  std::getline(supports, line);
  EXPECT_EQ(line.rfind("id,", 0), 0u);
  int anchors = 0;
  while (std::getline(supports, line)) {
    ++anchors;
    EXPECT_TRUE(line.rfind("P1-A", 0) == 0 || line.rfind("P2-A", 0) == 0 ||
                line.rfind("north-west-A", 0) == 0 || line.rfind("P4-A", 0) == 0)
        << line;
  }
  const json deployment = json::parse(testing::read_text(dir + "/run/deployment.json"));
  EXPECT_EQ(anchors, deployment["joined_with_notches"]["anchors"].get<int>());
  EXPECT_GE(anchors, 8);
  EXPECT_NE(bom.find("supports," + std::to_string(anchors) + ","), std::string::npos) << bom;
}

TEST(CliLayout, RunWithALayoutRefusesCornersTooAndNamesABadPatchName) {
  const std::string dir = testing::temp_dir();
  json layout = sphere_layout();
  std::string file = testing::write_text(dir, "layout.json", layout.dump());
  auto r = run_cli("run example:sphere --layout '" + file + "' --corners 0,1,2,3 --quiet --out '" +
                   dir + "/out'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--corners"), std::string::npos) << r.err;
  layout["patches"][1]["name"] = "../up";
  file = testing::write_text(dir, "layout.json", layout.dump());
  r = run_cli("run example:sphere --layout '" + file + "' --quiet --out '" + dir + "/out'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("layout.patches[1].name"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/up"));
}

TEST(CliLayout, AnAutomaticLayoutCoversASharedMeshAndItsLayoutJsonRunsAgain) {
  const std::string dir = testing::temp_dir();
  const std::string mesh = testing::test_mesh_path("knet1.obj");
  auto r = run_cli("layout '" + mesh + "' --layout auto --quiet --out '" + dir + "/auto'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("automatic"), std::string::npos) << r.out;
  const json report = json::parse(testing::read_text(dir + "/auto/layout.json"));
  const double coverage = report["coverage"].get<double>();
  EXPECT_GE(coverage, 0.95);
  // Fewest patches first: every trial before the last missed the goal.
  const json& trials = report["automatic"]["trials"];
  ASSERT_GE(trials.size(), 1u);
  for (size_t t = 0; t + 1 < trials.size(); ++t)
    EXPECT_LT(trials[t]["coverage"].get<double>(), 0.95);
  EXPECT_EQ(trials.back()["coverage"].get<double>(), coverage);
  const int patches =
      report["automatic"]["columns"].get<int>() * report["automatic"]["rows"].get<int>();
  EXPECT_EQ(static_cast<int>(report["patches"].size()), patches);
  EXPECT_LE(patches, 36);
  // What is not covered is accounted for: the input's area less the patches'.
  double cut = 0, uncovered = 0;
  for (const json& p : report["patches"]) cut += p.value("area", 0.0);
  for (const json& u : report["uncovered"]) uncovered += u["area"].get<double>();
  const double input = report["input_area"].get<double>();
  EXPECT_NEAR(uncovered, input - report["covered_area"].get<double>(), 1e-9 * input);
  EXPECT_NEAR(cut, report["covered_area"].get<double>(), 1e-9 * input);  // every patch passed
  // The layout it wrote is a layout file: run again from it, the same patches and coverage.
  r = run_cli("layout '" + mesh + "' --layout '" + dir + "/auto/layout.json' --quiet --out '" +
              dir + "/again'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json again = json::parse(testing::read_text(dir + "/again/layout.json"));
  EXPECT_NEAR(again["coverage"].get<double>(), coverage, 1e-6);
  EXPECT_FALSE(again.contains("automatic"));
  // The automatic layout's flags only with --layout auto, in their range.
  r = run_cli("layout '" + mesh + "' --layout '" + dir +
              "/auto/layout.json' --max-patches 4 --quiet --out '" + dir + "/x'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--max-patches: only with --layout auto"), std::string::npos) << r.err;
  r = run_cli("layout '" + mesh + "' --layout auto --max-patches 65 --quiet --out '" + dir + "/x'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--max-patches"), std::string::npos) << r.err;
  r = run_cli("run '" + mesh + "' --coverage-goal 0.9 --quiet --out '" + dir + "/x'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--coverage-goal: only with --layout auto"), std::string::npos) << r.err;
}

TEST(CliLayout, RunWithAnAutomaticLayoutBuildsEveryPatchOfASharedMesh) {
  const std::string dir = testing::temp_dir();
  const auto r = run_cli(
      "run '" + testing::test_mesh_path("pillow_1.obj") +
      "' --layout auto --members-u 3 --members-v 3 --notches on --quiet --out '" + dir + "/out'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json design = json::parse(testing::read_text(dir + "/out/design.json"));
  const json deployment = json::parse(testing::read_text(dir + "/out/deployment.json"));
  EXPECT_GE(design["layout"]["coverage"].get<double>(), 0.95);
  const size_t patches = design["patch_designs"].size();
  EXPECT_GE(patches, 2u);
  EXPECT_EQ(deployment["patches"].size(), patches);
  EXPECT_TRUE(deployment["converged"].get<bool>());
  for (const json& f : design["patch_designs"])
    EXPECT_TRUE(std::filesystem::exists(dir + "/out/" + f.get<std::string>())) << f;
  for (const json& seam : design["seams"])
    EXPECT_LE(seam.value("length_difference", 0.0), 1e-9 * 30);
  // Every seam of two built patches has its gaps, one per bolt.
  ASSERT_EQ(deployment["seams"].size(), design["seams"].size());
  for (size_t k = 0; k < design["seams"].size(); ++k)
    EXPECT_EQ(deployment["seams"][k]["gaps"].size(), design["seams"][k]["joints"].size());
  EXPECT_GT(deployment["rms_with_notches"].get<double>(), 0);
}

TEST(CliLayout, RunWithAnAutomaticLayoutBuildsAClosedSphereOnItsLowestPatchAndATube) {
  const std::string dir = testing::temp_dir();
  // A closed sphere (R = 10, 642 vertices): six patches of a cube, joined at all twelve seams;
  // no side is outer, so the whole stands on its lowest patch, held at that patch's anchors.
  save_obj(testing::icosphere(3, 10), dir + "/sphere.obj");
  auto r = run_cli("run '" + dir + "/sphere.obj' --layout auto --notches on --quiet --out '" + dir +
                   "/sphere'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json layout = json::parse(testing::read_text(dir + "/sphere/layout.json"));
  EXPECT_EQ(layout["automatic"]["surface"], "closed");
  EXPECT_EQ(layout["automatic"]["patches"], 6);
  EXPECT_NE(layout["automatic"]["cut"].get<std::string>().find("cube"), std::string::npos);
  EXPECT_NEAR(layout["coverage"].get<double>(), 1.0, 1e-9);
  json deployment = json::parse(testing::read_text(dir + "/sphere/deployment.json"));
  EXPECT_TRUE(deployment["converged"].get<bool>());
  EXPECT_TRUE(deployment["seams_joined"].get<bool>());
  // The patch it stands on: the one whose corners lie lowest.
  const json& corners = layout["layout"]["corners"];
  std::string lowest;
  double lowest_z = 1e300;
  for (const json& patch : layout["layout"]["patches"]) {
    double z = 0;
    for (const json& c : patch["corners"]) z += corners[c.get<int>()]["point"][2].get<double>();
    if (z < lowest_z) lowest_z = z, lowest = patch["name"];
  }
  const json& joined = deployment["joined_with_notches"];
  EXPECT_EQ(joined["held_by"], lowest);
  EXPECT_GT(joined["anchors"].get<int>(), 0);
  const double diagonal = deployment["diagonal"].get<double>();
  EXPECT_LE(deployment["rms_with_notches"].get<double>(), 0.005 * diagonal);
  EXPECT_LE(deployment["max_seam_gap"].get<double>(), 0.001 * diagonal);
  EXPECT_NE(r.out.find("stands on " + lowest), std::string::npos) << r.out;
  // Fewer patches than a cube's faces: refused naming the flag, nothing written.
  auto few = run_cli("layout '" + dir +
                     "/sphere.obj' --layout auto --max-patches 5 --quiet --out '" + dir + "/few'");
  EXPECT_EQ(few.exit_code, 2);
  EXPECT_NE(few.err.find("--max-patches: a closed surface needs at least 6"), std::string::npos)
      << few.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/few"));
  // Its kit's supports are that patch's anchors, as in the joined run.
  r = run_cli("fabricate '" + dir +
              "/sphere/design.json' --unit 0.1 --sheet 3000x1000 --quiet --out '" + dir +
              "/sphere-kit'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream supports(testing::read_text(dir + "/sphere-kit/supports.csv"));
  std::string line;
  std::getline(supports, line);
  int rows = 0;
  while (std::getline(supports, line)) {
    ++rows;
    EXPECT_EQ(line.rfind(lowest + "-A", 0), 0u) << line;
  }
  EXPECT_EQ(rows, joined["anchors"].get<int>());

  // A tube (radius 5, 20 long, open at both ends): a ring cut open along a straight line, three
  // patches round it, developable, so it is covered whole; held at its two rims.
  const int around = 64, along = 24;
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
  for (int j = 0; j <= along; ++j)
    for (int i = 0; i < around; ++i) {
      const double phi = 2 * std::numbers::pi * i / around;
      vertices.emplace_back(5 * std::cos(phi), 5 * std::sin(phi), 20.0 * j / along);
    }
  const auto at = [&](int i, int j) { return j * around + i % around; };
  for (int j = 0; j < along; ++j)
    for (int i = 0; i < around; ++i) {
      faces.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      faces.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  save_obj(TriangleMesh(vertices, faces), dir + "/tube.obj");
  r = run_cli("run '" + dir + "/tube.obj' --layout auto --notches on --quiet --out '" + dir +
              "/tube'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  layout = json::parse(testing::read_text(dir + "/tube/layout.json"));
  EXPECT_EQ(layout["automatic"]["surface"], "ring");
  EXPECT_EQ(layout["automatic"]["patches"], 3);
  EXPECT_NEAR(layout["coverage"].get<double>(), 1.0, 1e-6);
  // The cut runs straight up the tube, 20 long.
  const json& path = layout["automatic"]["cut_path"];
  ASSERT_GE(path.size(), 6u);
  EXPECT_NEAR(path[2].get<double>(), 0, 1e-12);
  EXPECT_NEAR(path[path.size() - 1].get<double>(), 20, 1e-12);
  deployment = json::parse(testing::read_text(dir + "/tube/deployment.json"));
  EXPECT_TRUE(deployment["converged"].get<bool>());
  EXPECT_EQ(deployment["joined_with_notches"].value("held_by", ""), "");
  EXPECT_LE(deployment["rms_with_notches"].get<double>(),
            0.005 * deployment["diagonal"].get<double>());
  EXPECT_LE(deployment["max_seam_gap"].get<double>(), 0.001 * deployment["diagonal"].get<double>());
}

TEST(CliLayout, PublicMeshesAreCoveredAndARingOfThemRunsWhole) {
  // Two meshes of WWmore/DOS (tests/data/meshes/README.md) nobody here made: an architectural
  // shell (a disk) and a geodesic net with two boundary loops (a ring). Every patch meets the
  // checks (a feasible planar angle included), 95 % of each is covered.
  const std::string dir = testing::temp_dir();
  for (const char* name : {"botanic-garden-bubble-0", "gnet1"}) {
    const auto r = run_cli("layout '" + testing::test_mesh_path(std::string(name) + ".obj") +
                           "' --layout auto --quiet --out '" + dir + "/" + name + "'");
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
    const json layout = json::parse(testing::read_text(dir + "/" + name + "/layout.json"));
    EXPECT_GE(layout["coverage"].get<double>(), 0.95) << name;
    for (const json& p : layout["patches"]) EXPECT_TRUE(p["ok"].get<bool>()) << name << p;
    EXPECT_EQ(layout["automatic"]["surface"], std::string(name) == "gnet1" ? "ring" : "disk");
  }
  // The ring built whole from its layout: joined at every seam round it, within the targets.
  const auto r = run_cli("run '" + testing::test_mesh_path("gnet1.obj") + "' --layout '" + dir +
                         "/gnet1/layout.json' --notches on --quiet --out '" + dir + "/run'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json deployment = json::parse(testing::read_text(dir + "/run/deployment.json"));
  EXPECT_TRUE(deployment["converged"].get<bool>());
  EXPECT_TRUE(deployment["seams_joined"].get<bool>());
  const double diagonal = deployment["diagonal"].get<double>();
  EXPECT_LE(deployment["rms_with_notches"].get<double>(), 0.005 * diagonal);
  EXPECT_LE(deployment["max_seam_gap"].get<double>(), 0.001 * diagonal);
  EXPECT_LT(deployment["max_seam_gap"].get<double>(),
            deployment["max_seam_gap_before_joining"].get<double>());
}

TEST(CliLayout, APatchsOwnAlphaAndCountsInTheLayoutOverrideTheRunsOptions) {
  // layout.json says P2 takes the largest feasible planar angle and 5 inner g-members; the others
  // take the run's options (the smallest angle, 4 x 4).
  const std::string dir = testing::temp_dir();
  json layout = json::parse(testing::sphere_layout_json());
  layout["patches"][1]["alpha"] = "max";
  layout["patches"][1]["members_u"] = 5;
  const std::string file = testing::write_text(dir, "layout.json", layout.dump());
  auto r = run_cli("run example:sphere --layout '" + file +
                   "' --members-u 4 --members-v 4 --notches on --quiet --out '" + dir + "/run'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto design = [&](const char* name) {
    return json::parse(testing::read_text(dir + "/run/patches/" + name + "/design.json"));
  };
  const auto inner = [](const json& d, const char* family) {
    int n = 0;
    for (const json& m : d["members"]) n += m["family"] == family && !m.value("boundary", false);
    return n;
  };
  const json p2 = design("P2"), p1 = design("P1");
  EXPECT_EQ(p2["alpha_bar"].get<double>(), p2["alpha_bar_range"][1].get<double>());
  EXPECT_EQ(p2["options"]["alpha"], "max");
  EXPECT_EQ(p2["options"]["members_u"], 5);
  EXPECT_EQ(inner(p2, "g"), 5);
  EXPECT_EQ(inner(p2, "h"), 4);
  EXPECT_EQ(p1["alpha_bar"].get<double>(), p1["alpha_bar_range"][0].get<double>());
  EXPECT_EQ(inner(p1, "g"), 4);
  // The layout's report gives each patch's feasible range, which the designs chose from.
  const json cut = json::parse(testing::read_text(dir + "/run/layout.json"));
  ASSERT_EQ(cut["patches"][1]["alpha_range"].size(), 2u);
  EXPECT_NEAR(cut["patches"][1]["alpha_range"][1].get<double>(),
              p2["alpha_bar_range"][1].get<double>(), 1e-6);
  // A bad choice is refused before any work, naming its field.
  layout["patches"][1]["alpha"] = "wide";
  testing::write_text(dir, "layout.json", layout.dump());
  r = run_cli("run example:sphere --layout '" + file + "' --quiet --out '" + dir + "/bad'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("layout.patches[1].alpha"), std::string::npos) << r.err;
  // The output folder it created is gone again (nothing was written); one that existed stays.
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad"));
  std::filesystem::create_directories(dir + "/existing");
  r = run_cli("run example:sphere --layout '" + file + "' --quiet --out '" + dir + "/existing'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(std::filesystem::is_directory(dir + "/existing"));
}

}  // namespace
}  // namespace gridshell
