// SPDX-License-Identifier: GPL-3.0-or-later
// Fabricate through the daemon: `gridshell fabricate --server` writes the same kit as the
// in-process run, POST /v1/fabricate returns kit.json and the sheet files as the CLI writes them,
// and a bad request names its field.
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "gridshell/application/fabricate.h"
#include "gridshell/application/files.h"
#include "server_support.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::read_text;
using testing::run_cli;
using testing::TestDaemon;

const std::map<std::string, std::string> kJson = {{"Content-Type", "application/json"}};

std::string design_dir() {
  static const std::string dir = [] {
    const std::string out = testing::temp_dir() + "/d";
    const auto r = run_cli("design example:double-vault --quiet --out '" + out + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return out;
  }();
  return dir;
}

TEST(FabricateRemote, CliServerWritesTheSameKit) {
  TestDaemon daemon;
  const std::string local = testing::temp_dir(), remote = testing::temp_dir();
  const std::string args = "fabricate '" + design_dir() + "/design.json' --unit cm --quiet ";
  auto r = run_cli(args + "--out '" + local + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli(args + "--server " + daemon.grpc_address() + " --out '" + remote + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* file : {"kit.json", "assembly.svg", "supports.csv", "bom.csv",
                           "sheets/sheet-01.dxf", "sheets/sheet-01.svg"})
    EXPECT_EQ(read_text(remote + "/" + file), read_text(local + "/" + file)) << file;
  // Errors come back as the in-process ones: exit 2, the flag named.
  r = run_cli("fabricate '" + design_dir() + "/design.json' --unit cm --sheet 900x600 --quiet " +
              "--server " + daemon.grpc_address() + " --out '" + remote + "/x'");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: --sheet: lamella h7 is"), std::string::npos) << r.err;
}

TEST(FabricateRemote, HttpReturnsTheKitFiles) {
  TestDaemon daemon;
  v1::FabricateRequest request;
  const std::string design_text = read_text(design_dir() + "/design.json");
  ASSERT_TRUE(
      google::protobuf::util::JsonStringToMessage(design_text, request.mutable_design()).ok());
  request.mutable_options()->set_unit("cm");
  request.set_design_name("design.json");
  const auto reply = testing::http_request(daemon.http_port(), "POST", "/v1/fabricate",
                                           to_json(request, false), kJson);
  ASSERT_EQ(reply.status, 200) << reply.body;
  v1::FabricateResult result;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(reply.body, &result).ok());
  const FileBundle files = fabricate_files(result);
  const std::string local = testing::temp_dir();
  ASSERT_EQ(run_cli("fabricate '" + design_dir() + "/design.json' --unit cm --quiet --out '" +
                    local + "'")
                .exit_code,
            0);
  for (const auto& [name, content] : files)
    EXPECT_EQ(content, read_text(local + "/" + name)) << name;
  EXPECT_EQ(files.count("sheets/sheet-01.dxf"), 1u);
  EXPECT_GT(result.kit().parts_size(), 0);
  // Without a unit: 400 with the field.
  request.mutable_options()->clear_unit();
  const auto bad = testing::http_request(daemon.http_port(), "POST", "/v1/fabricate",
                                         to_json(request, false), kJson);
  EXPECT_EQ(bad.status, 400) << bad.body;
  const auto error = nlohmann::json::parse(bad.body)["error"];
  EXPECT_EQ(error["field"], "options.unit");
}

}  // namespace
}  // namespace gridshell
