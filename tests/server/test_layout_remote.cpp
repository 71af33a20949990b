// SPDX-License-Identifier: GPL-3.0-or-later
// Layouts through the daemon (issue 35): `gridshell run --layout --server` and `gridshell layout
// --server` write what the in-process runs write; POST /v1/layout computes an automatic layout
// and names a bad option's field; a RunLayout call streams progress and stops when cancelled,
// the daemon serving on.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>

#include "gridshell/application/files.h"
#include "gridshell/v1/layout.pb.h"
#include "server_support.h"
#include "support.h"

namespace gridshell {
namespace {

using json = nlohmann::json;
using testing::read_text;
using testing::run_cli;
using testing::TestDaemon;

/// A file's text without its timings ("seconds" members).
std::string without_seconds(const std::string& text) {
  return std::regex_replace(text, std::regex("\"seconds[a-z_]*\": [-0-9.e+]+,?"), "");
}

TEST(LayoutRemote, CliServerWritesWhatTheInProcessRunWrites) {
  TestDaemon daemon;
  const std::string dir = testing::temp_dir();
  const std::string file = testing::write_text(dir, "layout.json", testing::sphere_layout_json());
  const std::string args = "run example:sphere --layout '" + file +
                           "' --members-u 4 --members-v 4 --notches on --quiet ";
  auto r = run_cli(args + "--out '" + dir + "/local'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli(args + "--server " + daemon.grpc_address() + " --out '" + dir + "/remote'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* f : {"layout.json", "layout.svg", "layout.obj", "design.json", "deployment.json",
                        "deployed.obj", "deviation.ply", "patches/P1/design.json",
                        "patches/P4/deployment.json", "patches/P3/deployed.obj"})
    EXPECT_EQ(without_seconds(read_text(dir + "/remote/" + f)),
              without_seconds(read_text(dir + "/local/" + f)))
        << f;
  // The kit of the whole through the daemon: the same files.
  r = run_cli("fabricate '" + dir + "/local/design.json' --unit cm --quiet --out '" + dir +
              "/kit-local'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli("fabricate '" + dir + "/local/design.json' --unit cm --quiet --server " +
              daemon.grpc_address() + " --out '" + dir + "/kit-remote'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* f : {"kit.json", "bom.csv", "supports.csv", "joining.svg", "assembly-P2.svg",
                        "sheets/sheet-01.dxf"})
    EXPECT_EQ(read_text(dir + "/kit-remote/" + f), read_text(dir + "/kit-local/" + f)) << f;
  // gridshell layout --server too.
  r = run_cli("layout example:sphere --layout '" + file + "' --quiet --server " +
              daemon.grpc_address() + " --out '" + dir + "/cut'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_text(dir + "/cut/layout.json"), read_text(dir + "/local/layout.json"));
}

TEST(LayoutRemote, HttpComputesAnAutomaticLayoutAndNamesABadOption) {
  TestDaemon daemon;
  v1::LayoutRequest request;
  request.mutable_mesh()->set_name("knet1.obj");
  request.mutable_mesh()->set_format("obj");
  request.mutable_mesh()->set_file(read_text(testing::test_mesh_path("knet1.obj")));
  request.mutable_automatic()->set_max_patches(30);
  const std::map<std::string, std::string> headers = {{"Content-Type", "application/json"}};
  auto reply = testing::http_request(daemon.http_port(), "POST", "/v1/layout",
                                     to_json(request, false), headers);
  ASSERT_EQ(reply.status, 200) << reply.body;
  const json result = json::parse(reply.body);
  EXPECT_GE(result["report"]["coverage"].get<double>(), 0.95);
  EXPECT_GE(result["report"]["automatic"]["trials"].size(), 1u);
  EXPECT_EQ(result["report"]["patches"].size(), result["patches"].size());
  request.mutable_automatic()->set_max_patches(100);
  reply = testing::http_request(daemon.http_port(), "POST", "/v1/layout", to_json(request, false),
                                headers);
  EXPECT_EQ(reply.status, 400) << reply.body;
  EXPECT_EQ(json::parse(reply.body)["error"]["field"], "automatic.max_patches");
}

TEST(LayoutRemote, ACancelledRunLayoutStopsAndTheDaemonServesOn) {
  TestDaemon daemon;
  auto stub = daemon.stub();
  v1::LayoutRunRequest request;
  request.mutable_mesh()->set_name("pillow_1.obj");
  request.mutable_mesh()->set_format("obj");
  request.mutable_mesh()->set_file(read_text(testing::test_mesh_path("pillow_1.obj")));
  request.mutable_automatic();  // 16 patches, each designed and simulated: seconds of work
  grpc::ClientContext context;
  auto reader = stub->RunLayout(&context, request);
  v1::RunLayoutEvent event;
  bool working = false, result = false;
  // Cancel as soon as the patches are being built.
  while (reader->Read(&event)) {
    if (event.has_result()) result = true;
    if (event.has_progress() &&
        event.progress().stage().find("patches designed") != std::string::npos && !working) {
      working = true;
      context.TryCancel();
    }
  }
  EXPECT_TRUE(working);
  EXPECT_FALSE(result);
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.cancelled == 1 && s.running == 0; }));
  EXPECT_TRUE(testing::call_patch(*stub, testing::patch_request("plane")).status.ok());
}

/// A RunLayout call's result (no result: the status).
std::optional<v1::LayoutRunResult> run_layout(v1::Gridshell::Stub& stub,
                                              const v1::LayoutRunRequest& request) {
  grpc::ClientContext context;
  auto reader = stub.RunLayout(&context, request);
  v1::RunLayoutEvent event;
  std::optional<v1::LayoutRunResult> out;
  while (reader->Read(&event))
    if (event.has_result()) out = event.result();
  const grpc::Status status = reader->Finish();
  EXPECT_TRUE(status.ok()) << status.error_message();
  return out;
}

TEST(LayoutRemote, ARedesignOfOnePatchOfALayoutSkipsTheCutAndTheMaps) {
  TestDaemon daemon;
  auto stub = daemon.stub();
  // The sphere's 2 x 2 layout built whole: the daemon keeps every patch's work.
  v1::LayoutRunRequest run;
  *run.mutable_mesh() = testing::patch_request("sphere").mesh();
  from_json(testing::sphere_layout_json(), *run.mutable_layout());
  run.mutable_design()->set_members_u(4);
  run.mutable_design()->set_members_v(4);
  run.mutable_simulation()->set_notches("on");
  const std::optional<v1::LayoutRunResult> built = run_layout(*stub, run);
  ASSERT_TRUE(built);
  ASSERT_EQ(built->patches_size(), 4);
  const v1::Design& p2 = built->patches(1).design().design();
  // P2 designed alone with the same options and the layout's cross-section: from the cache, the
  // same design as within the layout.
  v1::DesignRequest request;
  *request.mutable_mesh() = run.mesh();
  *request.mutable_layout_patch()->mutable_layout() = built->layout().report().layout();
  request.mutable_layout_patch()->set_patch("P2");
  *request.mutable_options() = run.design();
  request.mutable_options()->set_lamella_width(p2.options().lamella_width());
  auto again = testing::call_design(*stub, request);
  ASSERT_TRUE(again.status.ok()) << again.status.error_message();
  EXPECT_TRUE(again.result->report().distance_maps_cached());
  const v1::Design& alone = again.result->design();
  EXPECT_EQ(alone.alpha_bar(), p2.alpha_bar());
  ASSERT_EQ(alone.crossings_size(), p2.crossings_size());
  for (int k = 0; k < p2.crossings_size(); ++k)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(alone.crossings(k).surface_point(c), p2.crossings(k).surface_point(c)) << k;
  // A redesign with other counts and alpha: cached too, and a different grid.
  request.mutable_options()->set_members_u(6);
  request.mutable_options()->set_alpha("max");
  auto other = testing::call_design(*stub, request);
  ASSERT_TRUE(other.status.ok()) << other.status.error_message();
  EXPECT_TRUE(other.result->report().distance_maps_cached());
  EXPECT_NE(other.result->design().crossings_size(), p2.crossings_size());
  EXPECT_GT(other.result->design().alpha_bar(), p2.alpha_bar());
  // The patch's own choice in the layout overrides the request's options (the page's per-patch
  // slider): the same key, so cached too.
  v1::DesignRequest own = request;
  own.mutable_options()->set_alpha("min");
  own.mutable_layout_patch()->mutable_layout()->mutable_patches(1)->set_alpha("max");
  auto chosen = testing::call_design(*stub, own);
  ASSERT_TRUE(chosen.status.ok()) << chosen.status.error_message();
  EXPECT_TRUE(chosen.result->report().distance_maps_cached());
  EXPECT_EQ(chosen.result->design().alpha_bar(), chosen.result->design().alpha_bar_range(1));
  // Another layout (the same with corners as given): a miss cuts it once, then every other patch
  // of it is cached.
  request.mutable_layout_patch()->set_patch("P4");
  request.mutable_options()->set_eta_max(1.002);  // other patch options: another key
  auto cold = testing::call_design(*stub, request);
  ASSERT_TRUE(cold.status.ok()) << cold.status.error_message();
  EXPECT_FALSE(cold.result->report().distance_maps_cached());
  request.mutable_layout_patch()->set_patch("P1");
  auto warm = testing::call_design(*stub, request);
  ASSERT_TRUE(warm.status.ok()) << warm.status.error_message();
  EXPECT_TRUE(warm.result->report().distance_maps_cached());
  // Bad requests name their field.
  request.mutable_layout_patch()->set_patch("P9");
  auto bad = testing::call_design(*stub, request);
  EXPECT_EQ(bad.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(bad.status.error_message().find("layout_patch.patch"), std::string::npos)
      << bad.status.error_message();
  request.mutable_layout_patch()->set_patch("P1");
  request.mutable_corners()->add_vertices(0);
  bad = testing::call_design(*stub, request);
  EXPECT_EQ(bad.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(bad.status.error_message().find("corners"), std::string::npos);
}

}  // namespace
}  // namespace gridshell
