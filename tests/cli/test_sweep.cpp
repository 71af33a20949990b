// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell sweep` with the local engine: manifests (CSV, JSON Lines) checked before anything
// runs, rows run as `gridshell run` into folders that are complete or absent, status.json, the
// summaries read back, resuming, and a sweep killed mid-row.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "gridshell/batch/sweep.h"
#include "support.h"

namespace gridshell {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::run_cli;

// Rows small enough for the test suite: the quickest example at a low resolution.
const std::string kSmall = "resolution,members-u,members-v,edges-per-interval";
const std::string kSmallValues = "16,3,3,1";

std::vector<std::vector<std::string>> read_csv_lines(const std::string& path) {
  // The summary's fields here hold no quotes or commas except in error texts, which this test
  // does not split.
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(testing::read_text(path));
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::string field;
    bool quoted = false;
    for (char c : line) {
      if (c == '"') {
        quoted = !quoted;
      } else if (c == ',' && !quoted) {
        fields.push_back(field);
        field.clear();
      } else {
        field += c;
      }
    }
    fields.push_back(field);
    rows.push_back(fields);
  }
  return rows;
}

size_t column(const std::vector<std::string>& header, const std::string& name) {
  const auto it = std::find(header.begin(), header.end(), name);
  EXPECT_NE(it, header.end()) << name;
  return it - header.begin();
}

TEST(SweepManifest, CsvAndJsonLinesGiveTheSameRows) {
  const std::string dir = testing::temp_dir();
  fs::create_directories(dir + "/meshes");
  testing::write_text(dir, "m.csv",
                      "id,mesh,corners,alpha,members_u\n"
                      "a,example:plane,\"0,40,1680,1640\",min,4\n"
                      "\n"
                      "b, meshes/x.obj ,,70deg,\n");
  testing::write_text(dir, "m.jsonl",
                      "{\"id\": \"a\", \"mesh\": \"example:plane\", \"corners\": [0, 40, 1680, "
                      "1640], \"alpha\": \"min\", \"members-u\": 4}\n"
                      "{\"id\": \"b\", \"mesh\": \"meshes/x.obj\", \"alpha\": \"70deg\", "
                      "\"members-u\": null}\n");
  const auto csv = sweep::read_manifest(dir + "/m.csv");
  const auto jsonl = sweep::read_manifest(dir + "/m.jsonl");
  ASSERT_EQ(csv.rows.size(), 2u);
  ASSERT_EQ(jsonl.rows.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(csv.rows[i].id, jsonl.rows[i].id);
    EXPECT_EQ(csv.rows[i].values, jsonl.rows[i].values) << i;
    EXPECT_EQ(csv.rows[i].mesh, jsonl.rows[i].mesh);
  }
  EXPECT_EQ(csv.rows[0].line, 2);
  EXPECT_EQ(csv.rows[1].line, 4);  // after a blank line
  EXPECT_EQ(*csv.rows[0].value("corners"), "0,40,1680,1640");
  EXPECT_EQ(*csv.rows[0].value("members-u"), "4");     // members_u normalised
  EXPECT_EQ(csv.rows[1].value("members-u"), nullptr);  // empty: the default
  EXPECT_EQ(csv.rows[1].mesh, (fs::path(dir) / "meshes/x.obj").lexically_normal().string());
  EXPECT_EQ(csv.rows[0].run_arguments(),
            (std::vector<std::string>{"example:plane", "--corners=0,40,1680,1640", "--alpha=min",
                                      "--members-u=4"}));
}

TEST(SweepManifest, MalformedFilesNameTheLine) {
  const std::string dir = testing::temp_dir();
  testing::write_text(dir, "q.csv", "id,mesh\na,\"example:plane\nb,x\n");
  auto r = run_cli("sweep '" + dir + "/q.csv' --out '" + dir + "/out'");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("quoted field is not closed"), std::string::npos) << r.err;
  testing::write_text(dir, "f.csv", "id,mesh,alpha\na,example:plane\n");
  r = run_cli("sweep '" + dir + "/f.csv' --out '" + dir + "/out'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("line 2: 2 fields, the header has 3"), std::string::npos) << r.err;
  testing::write_text(dir, "j.jsonl", "{\"id\": \"a\", \"mesh\": \"example:plane\"}\n[1, 2]\n");
  r = run_cli("sweep '" + dir + "/j.jsonl' --out '" + dir + "/out'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("line 2: expected a JSON object"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/out/rows"));
}

TEST(SweepManifest, EveryBadRowIsListedAndNothingStarts) {
  const std::string dir = testing::temp_dir();
  testing::write_text(dir, "bad-header.csv", "id,mesh,alpah\na,example:plane,min\n");
  auto r = run_cli("sweep '" + dir + "/bad-header.csv' --out '" + dir + "/out'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("line 1, column alpah: not an option of gridshell run"), std::string::npos)
      << r.err;
  testing::write_text(dir, "bad.csv",
                      "id,mesh,corners,alpha,members-u,notches,lamella-width,material\n"
                      "ok,example:double-vault,,min,3,both,,\n"
                      "ok,example:double-vault,,min,3,both,,\n"
                      "a/b,example:double-vault,,min,3,both,,\n"
                      "r4,example:double-vault,,abc,3,both,,\n"
                      "r5,example:double-vault,,min,x,both,,\n"
                      "r6,example:double-vault,,min,3,maybe,,\n"
                      "r7,example:double-vault,\"0,1,2,99999\",min,3,both,,\n"
                      "r8,/nonexistent/mesh.obj,,min,3,both,,\n"
                      "r9,example:double-vault,,min,3,both,-1,\n"
                      "r10,example:double-vault,,min,3,both,,unobtainium\n"
                      ",example:double-vault,,min,3,both,,\n");
  r = run_cli("sweep '" + dir + "/bad.csv' --out '" + dir + "/out'");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  for (const char* expected : {
           "line 3 (id ok), column id: 'ok' is also the id of line 2",
           "line 4 (id a/b), column id: 'a/b' cannot name a folder",
           "line 5 (id r4), column alpha:",
           "line 6 (id r5), column members-u:",
           "line 7 (id r6), column notches:",
           "line 8 (id r7), column corners: vertex index 99999 is out of range",
           "line 9 (id r8), column mesh:",
           "line 10 (id r9), column lamella-width:",
           "line 11 (id r10), column material:",
           "line 12, column id: empty",
       })
    EXPECT_NE(r.err.find(expected), std::string::npos) << expected << "\n" << r.err;
  // One error line, after the list; nothing ran.
  EXPECT_NE(r.err.find("error: "), std::string::npos);
  EXPECT_EQ(r.err.find("error: "), r.err.rfind("error: ")) << r.err;
  EXPECT_NE(r.err.find("nothing was started"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/out/rows"));
  EXPECT_EQ(r.err.find("line 2 "), std::string::npos) << "a good row was listed:\n" << r.err;
}

struct Sweep {
  std::string dir, manifest, out;
};

/// Four rows: two designs, one infeasible angle, one lamella too wide for the patch (found by
/// the kernel, so it passes the up-front checks and fails at run time with exit 2).
Sweep four_rows() {
  Sweep s;
  s.dir = testing::temp_dir();
  s.out = s.dir + "/out";
  s.manifest = testing::write_text(s.dir, "rows.csv",
                                   "id,mesh,alpha,lamella-width," + kSmall + "\n" +
                                       "min,example:double-vault,min,," + kSmallValues + "\n" +
                                       "deg40,example:double-vault,40deg,," + kSmallValues + "\n" +
                                       "steep,example:double-vault,5deg,," + kSmallValues + "\n" +
                                       "wide,example:double-vault,min,1000," + kSmallValues + "\n");
  return s;
}

// A row whose simulation does not converge is "unconverged" (exit 4), not a result: its error
// names the run; it is not retried; the sweep's counts show it.
TEST(SweepLocal, AnUnconvergedRowIsNotAResult) {
  const std::string dir = testing::temp_dir();
  const std::string manifest = testing::write_text(
      dir, "rows.csv",
      "id,mesh,max-iterations," + kSmall + "\n" + "capped,example:double-vault,3," + kSmallValues +
          "\n" + "free,example:double-vault,2000," + kSmallValues + "\n");
  const auto r = run_cli("sweep '" + manifest + "' --out '" + dir + "/out' --workers 2 --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("2: 1 ok, 1 unconverged"), std::string::npos) << r.out;
  const json capped = json::parse(testing::read_text(dir + "/out/rows/capped/status.json"));
  EXPECT_EQ(capped["status"], "unconverged");
  EXPECT_EQ(capped["exit_code"], 4);
  EXPECT_EQ(capped["attempt"], 1);
  EXPECT_NE(capped["error"].get<std::string>().find("not converged"), std::string::npos) << capped;
  const json free = json::parse(testing::read_text(dir + "/out/rows/free/status.json"));
  EXPECT_EQ(free["status"], "ok");
}

TEST(SweepLocal, RowsAreWrittenWholeWithTheirStatusAndSummaries) {
  const Sweep s = four_rows();
  const auto r = run_cli("sweep '" + s.manifest + "' --out '" + s.out + "' --workers 2 --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("4: 2 ok, 1 invalid, 1 infeasible"), std::string::npos) << r.out;
  // Finished rows: the files of gridshell run, the log and status.json; nothing left over.
  for (const char* id : {"min", "deg40"}) {
    const std::string row = s.out + "/rows/" + id;
    for (const char* file : {"design.json", "report.json", "deployment.json", "planar.svg",
                             "deployed.obj", "run.log", "status.json"})
      EXPECT_TRUE(fs::exists(row + "/" + file)) << row << "/" << file;
    const json status = json::parse(testing::read_text(row + "/status.json"));
    EXPECT_EQ(status["status"], "ok");
    EXPECT_EQ(status["exit_code"], 0);
    EXPECT_EQ(status["attempt"], 1);
    EXPECT_EQ(status["engine"], "local");
    EXPECT_FALSE(status["host"].get<std::string>().empty());
    const json deployment = json::parse(testing::read_text(row + "/deployment.json"));
    const json design = json::parse(testing::read_text(row + "/design.json"));
    EXPECT_EQ(status["results"]["rms_with_notches"].get<double>(),
              deployment["rms_with_notches"].get<double>());
    EXPECT_EQ(status["results"]["rms_without_notches"].get<double>(),
              deployment["rms_without_notches"].get<double>());
    EXPECT_EQ(status["results"]["alpha_bar"].get<double>(), design["alpha_bar"].get<double>());
    EXPECT_EQ(status["options"]["alpha"], id == std::string("min") ? "min" : "40deg");
  }
  const json steep = json::parse(testing::read_text(s.out + "/rows/steep/status.json"));
  EXPECT_EQ(steep["status"], "infeasible");
  EXPECT_EQ(steep["exit_code"], 3);
  EXPECT_NE(steep["error"].get<std::string>().find("--alpha"), std::string::npos) << steep;
  EXPECT_FALSE(fs::exists(s.out + "/rows/steep/deployment.json"));
  const json wide = json::parse(testing::read_text(s.out + "/rows/wide/status.json"));
  EXPECT_EQ(wide["status"], "invalid");
  EXPECT_EQ(wide["exit_code"], 2);
  EXPECT_NE(wide["error"].get<std::string>().find("--lamella-width"), std::string::npos);
  std::error_code ec;
  EXPECT_TRUE(fs::is_empty(s.out + "/rows/.tmp", ec)) << "left-over attempt folders";

  // summary.csv: one line per row, its options, status and results as in status.json.
  const auto csv = read_csv_lines(s.out + "/summary.csv");
  ASSERT_EQ(csv.size(), 5u);
  const auto& header = csv[0];
  for (const char* name : {"id", "mesh", "alpha", "lamella-width", "status", "exit_code", "error",
                           "alpha_bar", "members", "crossings", "rms_without_notches",
                           "rms_with_notches", "max_bending_stress", "t_grid", "t1", "t2"})
    column(header, name);
  std::map<std::string, std::vector<std::string>> by_id;
  for (size_t i = 1; i < csv.size(); ++i) by_id[csv[i][0]] = csv[i];
  ASSERT_EQ(by_id.size(), 4u);
  const json min_status = json::parse(testing::read_text(s.out + "/rows/min/status.json"));
  EXPECT_EQ(std::stod(by_id["min"][column(header, "rms_with_notches")]),
            min_status["results"]["rms_with_notches"].get<double>());
  EXPECT_EQ(by_id["steep"][column(header, "status")], "infeasible");
  EXPECT_EQ(by_id["steep"][column(header, "exit_code")], "3");
  EXPECT_EQ(by_id["steep"][column(header, "rms_with_notches")], "");
  EXPECT_EQ(by_id["deg40"][column(header, "alpha")], "40deg");
  // summary.json: the same rows.
  const json summary = json::parse(testing::read_text(s.out + "/summary.json"));
  ASSERT_EQ(summary.size(), 4u);
  for (const json& row : summary) {
    EXPECT_EQ(row["status"].get<std::string>(), by_id[row["id"]][column(header, "status")]);
    if (row["status"] == "ok") {
      EXPECT_EQ(row["rms_with_notches"].get<double>(),
                std::stod(by_id[row["id"]][column(header, "rms_with_notches")]));
      EXPECT_GT(row["members"].get<double>(), 0);
      EXPECT_GT(row["crossings"].get<double>(), 0);
      EXPECT_GT(row["max_bending_stress"].get<double>(), 0);
    }
  }
  // summary.svg: RMS2 against the swept parameters (alpha, lamella-width), the best row marked.
  const std::string svg = testing::read_text(s.out + "/summary.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("alpha (planar angle, degrees)"), std::string::npos);
  EXPECT_NE(svg.find(">lamella-width<"), std::string::npos);
  const std::string best =
      min_status["results"]["rms_with_notches"].get<double>() <
              json::parse(testing::read_text(
                  s.out + "/rows/deg40/status.json"))["results"]["rms_with_notches"]
                  .get<double>()
          ? "min"
          : "deg40";
  EXPECT_NE(svg.find("fill=\"#d62728\">" + best + "</text>"), std::string::npos) << svg;
  EXPECT_EQ(svg.find("fill=\"#d62728\">steep</text>"), std::string::npos);

  // The same command again: every row is finished, nothing runs.
  const std::string started = min_status["started"];
  const auto again =
      run_cli("sweep '" + s.manifest + "' --out '" + s.out + "' --workers 2 --quiet");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(json::parse(testing::read_text(s.out + "/rows/min/status.json"))["started"], started);
  // A removed row runs again; the others stay as they were.
  fs::remove_all(s.out + "/rows/deg40");
  const auto resumed =
      run_cli("sweep '" + s.manifest + "' --out '" + s.out + "' --workers 2 --quiet");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_EQ(json::parse(testing::read_text(s.out + "/rows/min/status.json"))["started"], started);
  EXPECT_EQ(json::parse(testing::read_text(s.out + "/rows/deg40/status.json"))["status"], "ok");

  // `sweep status`: the counts and every row that is not ok, with its error.
  const auto status = run_cli("sweep status '" + s.out + "'");
  ASSERT_EQ(status.exit_code, 0) << status.err;
  EXPECT_NE(status.out.find("4: 2 ok, 1 invalid, 1 infeasible"), std::string::npos) << status.out;
  EXPECT_NE(status.out.find("steep"), std::string::npos);
  EXPECT_NE(status.out.find("exit 3"), std::string::npos);
  EXPECT_NE(status.out.find("--lamella-width"), std::string::npos);

  // Finished rows whose values the manifest now changes are refused, naming them.
  testing::write_text(s.dir, "rows.csv",
                      "id,mesh,alpha,lamella-width," + kSmall + "\n" +
                          "min,example:double-vault,max,," + kSmallValues + "\n");
  const auto changed = run_cli("sweep '" + s.manifest + "' --out '" + s.out + "' --quiet");
  EXPECT_EQ(changed.exit_code, 2) << changed.err;
  EXPECT_NE(changed.err.find("row min: finished"), std::string::npos) << changed.err;
}

/// Process ids whose command line contains `text`.
std::vector<pid_t> processes_with(const std::string& text) {
  std::vector<pid_t> pids;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "cmdline");
    std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (cmdline.find(text) != std::string::npos) pids.push_back(std::stoi(name));
  }
  return pids;
}

TEST(SweepLocal, ASweepKilledMidRowLeavesNoPartialRowAndResumes) {
  const std::string dir = testing::temp_dir();
  const std::string out = dir + "/out";
  // One row long enough to be caught running (about 2 s of CPU: archway at its defaults).
  const std::string manifest =
      testing::write_text(dir, "one.jsonl",
                          "{\"id\": \"slow\", \"mesh\": \"example:archway\"}\n"
                          "{\"id\": \"quick\", \"mesh\": \"example:double-vault\", "
                          "\"resolution\": 16, \"members-u\": 3, \"members-v\": 3}\n");
  const pid_t pid = fork();
  if (pid == 0) {
    execl(GRIDSHELL_CLI, GRIDSHELL_CLI, "sweep", manifest.c_str(), "--out", out.c_str(),
          "--workers", "1", "--quiet", static_cast<char*>(nullptr));
    _exit(127);
  }
  ASSERT_GT(pid, 0);
  const std::string attempt = out + "/rows/.tmp/slow.1";
  bool running = false;
  for (int i = 0; i < 600 && !running; ++i) {  // up to 60 s for the sweep to start the row
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    running = !processes_with(attempt).empty();
  }
  ASSERT_TRUE(running) << "the row never started";
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // mid-row
  ASSERT_EQ(kill(pid, SIGKILL), 0);
  int status = 0;
  waitpid(pid, &status, 0);
  // The row's `gridshell run` dies with the sweep (PR_SET_PDEATHSIG).
  bool gone = false;
  for (int i = 0; i < 100 && !gone; ++i) {
    gone = processes_with(attempt).empty();
    if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_TRUE(gone) << "gridshell run outlived the sweep";
  EXPECT_FALSE(fs::exists(out + "/rows/slow")) << "a partial row";
  EXPECT_TRUE(fs::exists(attempt + "/run.log"));
  const auto pending = run_cli("sweep status '" + out + "'");
  EXPECT_NE(pending.out.find("attempt 1 running or interrupted"), std::string::npos) << pending.out;
  // The same command again finishes the rows; the interrupted attempt is cleaned up.
  const auto resumed = run_cli("sweep '" + manifest + "' --out '" + out + "' --quiet");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  const json slow = json::parse(testing::read_text(out + "/rows/slow/status.json"));
  EXPECT_EQ(slow["status"], "ok");
  EXPECT_EQ(slow["attempt"], 2);
  EXPECT_FALSE(fs::exists(attempt));
}

TEST(SweepCollect, SyntheticRowsSummariseWithoutTheRunFiles) {
  // Status files only (collect never opens the large result files): 500 rows, every tenth
  // infeasible, two pending.
  const std::string dir = testing::temp_dir();
  sweep::Manifest manifest;
  manifest.path = dir + "/m.csv";
  manifest.columns = {"id", "mesh", "alpha"};
  for (int i = 0; i < 500; ++i) {
    sweep::Row row;
    row.id = "r" + std::to_string(i);
    row.line = i + 2;
    row.mesh = "example:plane";
    row.values = {{"mesh", "example:plane"}, {"alpha", std::to_string(0.6 + i * 1e-3)}};
    manifest.rows.push_back(row);
    if (i >= 498) continue;
    sweep::RowStatus s;
    s.id = row.id;
    s.options = row.values;
    s.attempt = 1;
    s.exit_code = i % 10 == 9 ? 3 : 0;
    s.status = sweep::status_of_exit_code(s.exit_code);
    if (s.status == "ok")
      s.results = {{"alpha_bar", 0.6 + i * 1e-3}, {"rms_with_notches", 1.0 + (i % 37) * 0.01}};
    else
      s.error = "infeasible: --alpha: outside";
    fs::create_directories(dir + "/rows/" + row.id);
    std::ofstream(dir + "/rows/" + row.id + "/status.json") << sweep::to_json(s);
  }
  sweep::write_sweep_file(dir, manifest);
  const auto r = run_cli("sweep collect '" + dir + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("500: 449 ok, 49 infeasible, 2 pending"), std::string::npos) << r.out;
  const auto csv = read_csv_lines(dir + "/summary.csv");
  ASSERT_EQ(csv.size(), 501u);
  EXPECT_EQ(csv[1][0], "r0");
  EXPECT_EQ(csv[500][column(csv[0], "status")], "pending");
  EXPECT_EQ(csv[10][column(csv[0], "status")], "infeasible");
  EXPECT_EQ(std::stod(csv[2][column(csv[0], "rms_with_notches")]), 1.0 + 1 * 0.01);
  // The best three (RMS2 1.0: rows 0, 37, 74, ...) are marked; i % 37 == 0.
  const std::string svg = testing::read_text(dir + "/summary.svg");
  EXPECT_NE(svg.find(">r0</text>"), std::string::npos);
  EXPECT_NE(svg.find(">r37</text>"), std::string::npos);
  EXPECT_NE(svg.find(">r74</text>"), std::string::npos);
  EXPECT_EQ(svg.find(">r1</text>"), std::string::npos);
}

// A `layout` column: rows of several patches (a layout file, auto) next to a one-patch row; their
// status and the summary carry the whole's coverage, patch count, RMS and largest seam gap.
TEST(SweepLocal, ALayoutColumnRunsSeveralPatchesPerRow) {
  const std::string dir = testing::temp_dir();
  const std::string file =
      testing::write_text(dir, "sphere-layout.json", testing::sphere_layout_json());
  const std::string knet = testing::test_mesh_path("knet1.obj");
  const std::string manifest =
      testing::write_text(dir, "rows.csv",
                          "id,mesh,layout,max-patches,members-u,members-v,notches\n"
                          "one,example:sphere,,,3,3,on\n"
                          "four,example:sphere," +
                              file +
                              ",,3,3,on\n"
                              "auto," +
                              knet + ",auto,30,3,3,on\n");
  auto r = run_cli("sweep check '" + manifest + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  r = run_cli("sweep '" + manifest + "' --out '" + dir + "/out' --workers 2 --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  for (const char* id : {"four", "auto"}) {
    const std::string row = dir + "/out/rows/" + id;
    const json status = json::parse(testing::read_text(row + "/status.json"));
    EXPECT_EQ(status["status"], "ok") << status;
    const json deployment = json::parse(testing::read_text(row + "/deployment.json"));
    const json design = json::parse(testing::read_text(row + "/design.json"));
    EXPECT_EQ(status["results"]["rms_with_notches"].get<double>(),
              deployment["rms_with_notches"].get<double>());
    EXPECT_EQ(status["results"]["max_seam_gap"].get<double>(),
              deployment["max_seam_gap"].get<double>());
    EXPECT_TRUE(deployment["seams_joined"].get<bool>());
    EXPECT_EQ(status["results"]["max_bolt_force"].get<double>(),
              deployment["max_bolt_force"].get<double>());
    EXPECT_EQ(status["results"]["coverage"].get<double>(),
              design["layout"]["coverage"].get<double>());
    EXPECT_EQ(status["results"]["patches"].get<int>(),
              static_cast<int>(deployment["patches"].size()));
    EXPECT_TRUE(fs::exists(row + "/patches/P1/design.json"));
  }
  const json four = json::parse(testing::read_text(dir + "/out/rows/four/status.json"));
  EXPECT_EQ(four["results"]["patches"].get<int>(), 4);
  EXPECT_NEAR(four["results"]["coverage"].get<double>(), 1.0, 1e-9);
  const auto csv = read_csv_lines(dir + "/out/summary.csv");
  ASSERT_EQ(csv.size(), 4u);
  const auto& header = csv[0];
  std::map<std::string, std::vector<std::string>> by_id;
  for (size_t i = 1; i < csv.size(); ++i) by_id[csv[i][0]] = csv[i];
  EXPECT_EQ(by_id["one"][column(header, "coverage")], "");
  EXPECT_EQ(by_id["four"][column(header, "patches")], "4");
  EXPECT_NE(by_id["auto"][column(header, "max_seam_gap")], "");
  EXPECT_NE(by_id["four"][column(header, "max_bolt_force")], "");
  EXPECT_EQ(by_id["one"][column(header, "max_bolt_force")], "");
  // The layout's flags are checked before anything runs, naming the row and the column.
  const std::string bad = testing::write_text(dir, "bad.csv",
                                              "id,mesh,layout,max-patches\n"
                                              "nolayout,example:sphere,,4\n"
                                              "missing,example:sphere,/nonexistent/layout.json,\n");
  r = run_cli("sweep check '" + bad + "'");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  const std::string text = r.out + r.err;
  EXPECT_NE(text.find("max-patches"), std::string::npos) << text;
  EXPECT_NE(text.find("only with --layout auto"), std::string::npos) << text;
  EXPECT_NE(text.find("missing"), std::string::npos) << text;
}

}  // namespace
}  // namespace gridshell
