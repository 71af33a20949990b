// SPDX-License-Identifier: GPL-3.0-or-later
// The HTTP/JSON gateway of gridshelld: the same results as gRPC in protobuf's JSON mapping,
// Server-Sent Events, status codes (docs/api.md), limits, cancellation on disconnect and static
// files that never leave their folder.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <boost/asio.hpp>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/mesh/curvature.h"
#include "server_support.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::http_request;
using testing::TestDaemon;

const std::map<std::string, std::string> kJson = {{"Content-Type", "application/json"}};

/// The error body's "field: message" (the field apart, as data, and the message without it).
std::string error_message(const std::string& body) {
  const auto error = nlohmann::json::parse(body)["error"];
  const std::string field = error.at("field").get<std::string>();
  const std::string message = error.at("message").get<std::string>();
  if (!field.empty()) {
    EXPECT_EQ(message.rfind(field + ":", 0), std::string::npos) << "field repeated: " << body;
  }
  return field.empty() ? message : field + ": " + message;
}

TEST(Gateway, DesignAsJsonMatchesTheInProcessFiles) {
  TestDaemon daemon;
  const v1::DesignRequest request = testing::design_request("double-vault", 48);
  const auto reply =
      http_request(daemon.http_port(), "POST", "/v1/design", to_json(request, false), kJson);
  ASSERT_EQ(reply.status, 200) << reply.body;
  EXPECT_EQ(reply.headers.at("content-type"), "application/json");
  EXPECT_TRUE(reply.headers.count("x-request-id"));
  v1::DesignResult result;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(reply.body, &result).ok());
  const FileBundle local = design_files(run_design(request, {}, {1}));
  const FileBundle remote = design_files(result);
  for (const char* name : {"design.json", "planar.svg", "spatial.obj", "maps.svg"})
    EXPECT_EQ(remote.at(name), local.at(name)) << name;
}

TEST(Gateway, DesignWithFilesReturnsTheCliFilesByteForByte) {
  TestDaemon daemon;
  v1::DesignRequest request = testing::design_request("double-vault", 48);
  request.set_files(true);
  const auto reply =
      http_request(daemon.http_port(), "POST", "/v1/design", to_json(request, false), kJson);
  ASSERT_EQ(reply.status, 200) << reply.body;
  v1::DesignResult result;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(reply.body, &result).ok());
  std::map<std::string, std::string> views;
  for (const v1::File& view : result.views()) views[view.name()] = view.content();
  ASSERT_TRUE(views.count("design.json") && views.count("report.json"));
  // design.json is deterministic: the bytes a local run writes.
  EXPECT_EQ(views.at("design.json"), design_files(run_design(request, {}, {1})).at("design.json"));
  EXPECT_EQ(views.at("report.json"), to_json(result.report()) + "\n");
}

/// A mesh file's bytes in a Load request, as the web page sends them (base64 in the JSON).
std::string load_body(const std::string& file, const std::string& format) {
  v1::LoadRequest request;
  request.mutable_mesh()->set_name("upload." + format);
  request.mutable_mesh()->set_file(file);
  request.mutable_mesh()->set_format(format);
  return to_json(request, false);
}

TEST(Gateway, LoadReadsFileBytesWithTheCliLoader) {
  TestDaemon daemon;
  // A quad OBJ with a duplicate vertex: triangulated and welded, with the loader's warnings.
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 0\nf 5 2 3 4\n";
  const auto reply =
      http_request(daemon.http_port(), "POST", "/v1/load", load_body(obj, "obj"), kJson);
  ASSERT_EQ(reply.status, 200) << reply.body;
  v1::LoadResult result;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(reply.body, &result).ok());
  LoadReport local;
  const TriangleMesh mesh = read_mesh(obj, MeshFormat::Obj, "upload.obj", &local);
  EXPECT_EQ(result.mesh().positions_size(), 3 * mesh.vertex_count());
  EXPECT_EQ(result.mesh().indices_size(), 3 * mesh.face_count());
  EXPECT_EQ(result.report().format(), "obj");
  EXPECT_EQ(result.report().polygons_triangulated(), 1);
  EXPECT_EQ(result.report().duplicate_vertices_merged(), local.duplicate_vertices_merged);
  ASSERT_EQ(result.report().warnings_size(), static_cast<int>(local.warnings.size()));
  EXPECT_EQ(result.report().bounding_box_size(), 6);
  EXPECT_EQ(result.report().bounding_box(3), 1.0);
  // Where each file vertex went: the duplicate (file vertex 4) was welded to vertex 0.
  EXPECT_EQ(std::vector<int>(result.vertex_map().begin(), result.vertex_map().end()),
            (std::vector<int>{0, 1, 2, 3, 0}));
  // The loaded arrays come back as a mesh to send as it is.
  v1::PatchRequest patch;
  *patch.mutable_mesh() = result.mesh();
  LoadReport again;
  EXPECT_EQ(to_mesh(patch.mesh(), &again).face_count(), mesh.face_count());
}

TEST(Gateway, LoadMapsEverySentVertexToTheLoadedMesh) {
  TestDaemon daemon;
  // Packed arrays with an isolated vertex (1, removed) and a duplicate of vertex 2 (5, welded):
  // the loaded mesh renumbers 0 2 3 4 as 0 1 2 3.
  const std::string body = R"({"mesh": {"positions": [0,0,0, 5,5,5, 1,0,0, 1,1,0, 0,1,0, 1,0,0],
                                         "indices": [0,5,3, 0,3,4]}})";
  const auto reply = http_request(daemon.http_port(), "POST", "/v1/load", body, kJson);
  ASSERT_EQ(reply.status, 200) << reply.body;
  v1::LoadResult result;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(reply.body, &result).ok());
  EXPECT_EQ(result.report().isolated_vertices_removed(), 1);
  EXPECT_EQ(result.report().duplicate_vertices_merged(), 1);
  EXPECT_EQ(std::vector<int>(result.vertex_map().begin(), result.vertex_map().end()),
            (std::vector<int>{0, -1, 1, 2, 3, 1}));
  // Each sent vertex that stayed is where the map says.
  const std::vector<double> sent = {0, 0, 0, 5, 5, 5, 1, 0, 0, 1, 1, 0, 0, 1, 0, 1, 0, 0};
  ASSERT_EQ(result.vertex_map_size(), 6);
  for (int v = 0; v < 6; ++v) {
    if (result.vertex_map(v) < 0) continue;
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(result.mesh().positions(3 * result.vertex_map(v) + k), sent[3 * v + k]) << v;
  }
}

TEST(Gateway, LoadErrorsNameTheFileFieldAndTheLine) {
  TestDaemon daemon;
  const struct {
    std::string body, field, message;
  } cases[] = {
      {load_body("v 0 0 0\nv 1 0 x\n", "obj"), "mesh.file",
       "line 2: cannot parse vertex coordinate"},
      {load_body("solid x\nendsolid x\n", "stl"), "mesh.file", "no faces"},
      {load_body("ply\nformat ascii 1.0\n", "PLY"), "mesh.file", "end_header"},
      {load_body("v 0 0 0\n", "3ds"), "mesh.format", "expected obj, off, ply, stl"},
      {load_body("", "obj"), "mesh.file", "empty"},
      {R"({"mesh": {"example": "moebius"}})", "mesh.example", "unknown example 'moebius'"},
      {R"({"mesh": {"example": "sphere", "positions": [0, 0, 0]}})", "mesh", "give one of"},
  };
  for (const auto& c : cases) {
    const auto reply = http_request(daemon.http_port(), "POST", "/v1/load", c.body, kJson);
    EXPECT_EQ(reply.status, 400) << reply.body;
    const auto error = nlohmann::json::parse(reply.body)["error"];
    EXPECT_EQ(error["field"], c.field) << reply.body;
    EXPECT_NE(error["message"].get<std::string>().find(c.message), std::string::npos) << reply.body;
  }
}

TEST(Gateway, ExamplesAndExampleMeshes) {
  TestDaemon daemon;
  const auto reply = http_request(daemon.http_port(), "POST", "/v1/examples", "{}", kJson);
  ASSERT_EQ(reply.status, 200) << reply.body;
  v1::ExamplesResult examples;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(reply.body, &examples).ok());
  ASSERT_GE(examples.examples_size(), 7);
  EXPECT_EQ(examples.examples(0).name(), "torus-wide");
  for (const auto& example : examples.examples()) {
    EXPECT_EQ(example.corners_size(), 4) << example.name();
    v1::LoadRequest load;
    load.mutable_mesh()->set_example(example.name());
    const auto mesh =
        http_request(daemon.http_port(), "POST", "/v1/load", to_json(load, false), kJson);
    ASSERT_EQ(mesh.status, 200) << mesh.body;
    v1::LoadResult loaded;
    ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(mesh.body, &loaded).ok());
    EXPECT_EQ(loaded.mesh().positions_size(), 3 * example.vertices()) << example.name();
    ASSERT_EQ(loaded.example_corners().vertices_size(), 4);
    EXPECT_EQ(loaded.vertex_map_size(), 0) << "nothing renumbered: empty (the identity)";
    for (int k = 0; k < 4; ++k) EXPECT_EQ(loaded.example_corners().vertices(k), example.corners(k));
  }
}

TEST(Gateway, PatchReturnsTheCurvatureOfEveryPatchVertex) {
  TestDaemon daemon;
  const v1::PatchRequest request = testing::patch_request("sphere");
  const auto reply =
      http_request(daemon.http_port(), "POST", "/v1/patch", to_json(request, false), kJson);
  ASSERT_EQ(reply.status, 200) << reply.body;
  v1::PatchResult result;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(reply.body, &result).ok());
  ASSERT_EQ(result.gaussian_curvature_size(), result.patch().positions_size() / 3);
  // The kernel's discrete curvature of the returned patch, vertex by vertex.
  LoadReport load;
  const std::vector<double> k = gaussian_curvature(to_mesh(result.patch(), &load));
  ASSERT_EQ(k.size(), static_cast<size_t>(result.gaussian_curvature_size()));
  for (size_t v = 0; v < k.size(); ++v) EXPECT_EQ(result.gaussian_curvature(v), k[v]) << v;
  // A spherical cap of radius 98.6: K = 1/R^2 inside (the median, to the discretisation; cut
  // vertices scatter by 20 %), 0 on the boundary.
  std::vector<double> inside;
  for (double value : k)
    if (value != 0) inside.push_back(value);
  ASSERT_GT(inside.size(), k.size() / 2);
  std::nth_element(inside.begin(), inside.begin() + inside.size() / 2, inside.end());
  const double expected = 1.0 / (98.6 * 98.6);
  EXPECT_NEAR(inside[inside.size() / 2], expected, 0.02 * expected);
}

TEST(Gateway, SimulateAsJsonAndAsServerSentEvents) {
  TestDaemon daemon;
  v1::SimulateRequest request;
  *request.mutable_design() = testing::small_design();
  request.mutable_options()->set_notches("on");
  const std::string body = to_json(request, false);
  const auto reply = http_request(daemon.http_port(), "POST", "/v1/simulate", body, kJson);
  ASSERT_EQ(reply.status, 200) << reply.body.substr(0, 500);
  v1::SimulateResult result;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(reply.body, &result).ok());
  const v1::SimulateResult local = run_simulate(request, {}, {1});
  EXPECT_EQ(simulate_files(result).at("deployed.obj"), simulate_files(local).at("deployed.obj"));
  EXPECT_TRUE(result.deployment().converged());
  EXPECT_EQ(result.deployment().rms_with_notches(), local.deployment().rms_with_notches());
  const auto sse = http_request(daemon.http_port(), "POST", "/v1/simulate", body,
                                {{"Accept", "text/event-stream"}});
  ASSERT_EQ(sse.status, 200);
  EXPECT_NE(sse.body.find("event: progress"), std::string::npos);
  EXPECT_NE(sse.body.find("simulat"), std::string::npos) << sse.body.substr(0, 800);
  EXPECT_NE(sse.body.find("event: result"), std::string::npos);
}

TEST(Gateway, ServerSentEventsStreamProgressThenTheResult) {
  TestDaemon daemon;
  const auto reply = http_request(daemon.http_port(), "POST", "/v1/patch",
                                  to_json(testing::patch_request("sphere"), false),
                                  {{"Accept", "text/event-stream"}});
  ASSERT_EQ(reply.status, 200) << reply.body;
  EXPECT_EQ(reply.headers.at("content-type"), "text/event-stream");
  std::vector<std::pair<std::string, std::string>> events;  // (event, data)
  std::istringstream lines(reply.body);
  std::string event;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("event: ", 0) == 0) event = line.substr(7);
    if (line.rfind("data: ", 0) == 0) events.emplace_back(event, line.substr(6));
  }
  ASSERT_GE(events.size(), 3u) << reply.body;
  EXPECT_EQ(events.back().first, "result");
  for (size_t i = 0; i + 1 < events.size(); ++i) {
    EXPECT_EQ(events[i].first, "progress");
    const auto progress = nlohmann::json::parse(events[i].second);
    EXPECT_TRUE(progress.contains("stage") && progress.contains("fraction"));
  }
  v1::PatchResult result;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(events.back().second, &result).ok());
  EXPECT_EQ(result.report().vertex_count(), result.patch().positions_size() / 3);
}

TEST(Gateway, EveryBadInputIs400WithItsMessage) {
  TestDaemon daemon;
  auto bad = testing::bad_inputs();
  // Only HTTP can send these; the JSON reader is strict (issue 33) and names the field.
  bad.push_back({"MalformedJson", "Patch", "{\"mesh\": {", "not valid JSON"});
  bad.push_back({"UnknownField", "Design", "{\"meshes\": {}}", "meshes"});
  bad.push_back({"WrongType", "Patch", "{\"mesh\": {\"positions\": \"abc\"}}",
                 "mesh.positions: expected an array"});
  bad.push_back({"EmptyBody", "Design", "", "not valid JSON"});
  bad.push_back(
      {"BoolAsString", "Design", "{\"files\": \"yes\"}", "files: expected true or false"});
  bad.push_back({"UnknownEscape", "Design", "{\"mesh\": {\"name\": \"\\q\"}}", "not valid JSON"});
  bad.push_back(
      {"NestedPositions", "Design",
       "{\"mesh\": {\"positions\": " + std::string(100000, '[') + std::string(100000, ']') + "}}",
       "mesh.positions[0]: expected a number"});
  bad.push_back({"TooDeep", "Simulate",
                 "{\"design\": {\"members\": [{\"surface\": " + std::string(100, '[') +
                     std::string(100, ']') + "}]}}",
                 "too deep"});
  int sse_400 = 0;
  for (const testing::BadInput& input : bad) {
    SCOPED_TRACE(input.name);
    std::string target = "/v1/" + input.method;
    for (char& c : target) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const auto reply = http_request(daemon.http_port(), "POST", target, input.json, kJson);
    EXPECT_EQ(reply.status, 400) << reply.body;
    const auto body = nlohmann::json::parse(reply.body);
    EXPECT_EQ(body["error"]["status"], "INVALID_ARGUMENT");
    EXPECT_EQ(body["error"]["code"], 3);
    EXPECT_NE(error_message(reply.body).find(input.expected), std::string::npos)
        << "'" << input.expected << "' not in: " << reply.body;
    // With SSE, errors found while checking the request keep their status; the few the kernel
    // finds after its first progress event arrive as an error event with the same content.
    const auto sse = http_request(daemon.http_port(), "POST", target, input.json,
                                  {{"Accept", "text/event-stream"}});
    if (sse.status == 200) {
      const auto at = sse.body.rfind("event: error\ndata: ");
      ASSERT_NE(at, std::string::npos) << sse.body;
      const std::string data = sse.body.substr(at + 19, sse.body.find('\n', at + 19) - at - 19);
      EXPECT_EQ(nlohmann::json::parse(data)["error"]["status"], "INVALID_ARGUMENT");
      EXPECT_NE(error_message(data).find(input.expected), std::string::npos) << sse.body;
    } else {
      EXPECT_EQ(sse.status, 400) << sse.body;
      ++sse_400;
    }
  }
  EXPECT_GE(sse_400, static_cast<int>(bad.size()) - 2);  // all but coincident corners
  EXPECT_EQ(http_request(daemon.http_port(), "GET", "/healthz").status, 200);
  EXPECT_TRUE(testing::call_patch(*daemon.stub(), testing::patch_request("plane")).status.ok());
}

TEST(Gateway, StatusCodesForInfeasibleAndUnknownCalls) {
  TestDaemon daemon;
  const int port = daemon.http_port();
  v1::DesignRequest dart = testing::design_request("plane", 16);
  dart.mutable_corners()->clear_vertices();
  for (double p : {-40.0, -30.0, 0.0, 40.0, -30.0, 0.0, 0.0, -10.0, 0.0, -40.0, 30.0, 0.0})
    dart.mutable_corners()->add_points(p);
  auto reply = http_request(port, "POST", "/v1/design", to_json(dart, false), kJson);
  EXPECT_EQ(reply.status, 422) << reply.body;
  EXPECT_NE(error_message(reply.body).find("criterion iv"), std::string::npos);
  v1::RunRequest run;
  *run.mutable_design() = dart;
  reply = http_request(port, "POST", "/v1/run", to_json(run, false), kJson);
  EXPECT_EQ(reply.status, 422) << reply.body;
  EXPECT_NE(error_message(reply.body).find("criterion iv"), std::string::npos);
  EXPECT_EQ(http_request(port, "POST", "/v1/frobnicate", "{}", kJson).status, 404);
  EXPECT_EQ(http_request(port, "GET", "/v1/design").status, 405);
  EXPECT_EQ(http_request(port, "DELETE", "/healthz").status, 405);
  EXPECT_EQ(http_request(port, "GET", "/index.html").status, 404);  // no static folder
  const auto health = http_request(port, "GET", "/healthz");
  EXPECT_EQ(health.status, 200);
  EXPECT_EQ(nlohmann::json::parse(health.body)["status"], "SERVING");
}

TEST(Gateway, BodyLargerThanTheLimitIs413) {
  auto options = testing::test_options();
  options.http_body_limit_mib = 1;
  TestDaemon daemon(options);
  const std::string big(3u << 20, ' ');
  const auto reply = http_request(daemon.http_port(), "POST", "/v1/design", big, kJson);
  EXPECT_EQ(reply.status, 413) << reply.body;
  EXPECT_NE(error_message(reply.body).find("limit"), std::string::npos);
  EXPECT_EQ(http_request(daemon.http_port(), "GET", "/healthz").status, 200);
}

TEST(Gateway, DeadlineHeaderGives504AndStopsWork) {
  TestDaemon daemon;
  const auto reply = http_request(daemon.http_port(), "POST", "/v1/design",
                                  to_json(testing::design_request("waves-bump"), false),
                                  {{"Content-Type", "application/json"}, {"X-Timeout-Ms", "500"}});
  EXPECT_EQ(reply.status, 504) << reply.body;
  ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.cancelled == 1 && s.running == 0; }));
  EXPECT_EQ(daemon.daemon().stats().succeeded, 0u);
  EXPECT_EQ(http_request(daemon.http_port(), "POST", "/v1/design", "{}", {{"X-Timeout-Ms", "soon"}})
                .status,
            400);
}

TEST(Gateway, ClientThatGoesAwayCancelsItsJob) {
  TestDaemon daemon;
  const std::string body = to_json(testing::design_request("waves-bump"), false);
  {
    boost::asio::io_context io;
    boost::asio::ip::tcp::socket socket(io);
    socket.connect({boost::asio::ip::make_address("127.0.0.1"),
                    static_cast<unsigned short>(daemon.http_port())});
    const std::string request =
        "POST /v1/design HTTP/1.1\r\nHost: x\r\nContent-Length: " + std::to_string(body.size()) +
        "\r\n\r\n" + body;
    boost::asio::write(socket, boost::asio::buffer(request));
    ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.running == 1; }));
  }  // closed while the job runs
  ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.cancelled == 1 && s.running == 0; }));
  const auto stats = daemon.daemon().stats();
  EXPECT_EQ(stats.succeeded, 0u);
  ASSERT_EQ(stats.cancel_latency_ms.size(), 1u);
  std::printf("HTTP disconnect -> stopped in %.1f ms\n", stats.cancel_latency_ms[0]);
}

TEST(Gateway, FullQueueIs429) {
  TestDaemon daemon(testing::test_options(1, 0));
  const std::string body = to_json(testing::design_request("waves-bump"), false);
  std::jthread first([&] {
    http_request(daemon.http_port(), "POST", "/v1/design", body,
                 {{"Content-Type", "application/json"}, {"X-Timeout-Ms", "20000"}});
  });
  ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.running == 1; }));
  const auto reply = http_request(daemon.http_port(), "POST", "/v1/design", body, kJson);
  EXPECT_EQ(reply.status, 429) << reply.body;
  EXPECT_NE(error_message(reply.body).find("queue is full"), std::string::npos);
  daemon.daemon().shutdown();  // cancels the first
}

TEST(Gateway, StaticFilesNeverLeaveTheirFolder) {
  namespace fs = std::filesystem;
  const fs::path root = testing::temp_dir();
  const fs::path site = root / "site";
  fs::create_directories(site / "js");
  std::ofstream(site / "index.html") << "<h1>gridshell</h1>";
  std::ofstream(site / "js" / "app.js") << "console.log(1);";
  std::ofstream(site / ".secret") << "hidden";
  std::ofstream(root / "outside.txt") << "outside";
  fs::create_symlink(root / "outside.txt", site / "link.txt");
  auto options = testing::test_options();
  options.static_dir = site.string();
  TestDaemon daemon(options);
  const int port = daemon.http_port();
  auto reply = http_request(port, "GET", "/");
  EXPECT_EQ(reply.status, 200);
  EXPECT_EQ(reply.body, "<h1>gridshell</h1>");
  EXPECT_EQ(reply.headers.at("content-type"), "text/html; charset=utf-8");
  reply = http_request(port, "GET", "/js/app.js?v=3");
  EXPECT_EQ(reply.status, 200);
  EXPECT_EQ(reply.headers.at("content-type"), "text/javascript");
  EXPECT_EQ(http_request(port, "HEAD", "/index.html").status, 200);
  for (const char* target : {"/../outside.txt", "/js/../../outside.txt", "/%2e%2e/outside.txt",
                             "/js/%2E%2E/%2E%2E/outside.txt", "/.secret", "/link.txt",
                             "/nothing.html", "/js", "/%zz", "//etc/passwd"})
    EXPECT_EQ(http_request(port, "GET", target).status, 404) << target;
}

// Issue 18: an infeasible design's error carries its computed suggestions, in the JSON body
// and in the Server-Sent Events' error event; the CLI shows them from the gRPC details.
TEST(Gateway, InfeasibleDesignErrorCarriesSuggestions) {
  TestDaemon daemon;
  v1::DesignRequest request = testing::design_request("double-vault", 50);
  request.mutable_options()->set_k_max(1.5);
  request.mutable_options()->set_suggest(2);
  auto expect_suggestions = [](const nlohmann::json& error) {
    ASSERT_TRUE(error.contains("suggestions")) << error.dump();
    ASSERT_GE(error["suggestions"].size(), 1u);
    ASSERT_LE(error["suggestions"].size(), 2u);
    const auto& first = error["suggestions"][0];
    EXPECT_EQ(first["rank"], 1);
    EXPECT_EQ(first["kind"], "slope_bounds");
    EXPECT_GT(first["k_max"].get<double>(), 1.5);
    EXPECT_EQ(first["alpha_bar_range"].size(), 2u);
    EXPECT_FALSE(first["description"].get<std::string>().empty());
  };
  auto reply =
      http_request(daemon.http_port(), "POST", "/v1/design", to_json(request, false), kJson);
  EXPECT_EQ(reply.status, 422) << reply.body;
  expect_suggestions(nlohmann::json::parse(reply.body)["error"]);
  auto headers = kJson;
  headers["Accept"] = "text/event-stream";
  reply = http_request(daemon.http_port(), "POST", "/v1/design", to_json(request, false), headers);
  const size_t event = reply.body.find("event: error\ndata: ");
  ASSERT_NE(event, std::string::npos) << reply.body;
  const size_t data = event + 19, end = reply.body.find('\n', data);
  expect_suggestions(nlohmann::json::parse(reply.body.substr(data, end - data))["error"]);
  // The CLI through gRPC: the suggestions from the status details, as in-process.
  const auto cli = testing::run_cli(
      "design example:double-vault --resolution 50 --k-max 1.5 "
      "--suggest 2 --quiet --server " +
      daemon.grpc_address() + " --out '" + testing::temp_dir() + "'");
  EXPECT_EQ(cli.exit_code, 3) << cli.err;
  EXPECT_NE(cli.err.find("\nsuggestion 1: slope bounds k_max"), std::string::npos) << cli.err;
}

}  // namespace
}  // namespace gridshell
