// SPDX-License-Identifier: GPL-3.0-or-later
// What the web page needs from gridshelld's HTTP gateway (issue 16), over real loopback HTTP:
// the CORS allow-list, the security headers on every kind of response, the body limit, the
// static files at / and the per-patch cache seen from a client.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "server_support.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::http_request;
using testing::HttpReply;
using testing::TestDaemon;

const std::map<std::string, std::string> kJson = {{"Content-Type", "application/json"}};
constexpr const char* kPage = "http://localhost:5173";

/// The headers every response carries: a CSP that allows no inline script, nosniff, no referrer.
void expect_security_headers(const HttpReply& reply, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_TRUE(reply.headers.count("content-security-policy"));
  const std::string csp = reply.headers.at("content-security-policy");
  EXPECT_NE(csp.find("default-src 'self'"), std::string::npos) << csp;
  EXPECT_NE(csp.find("script-src 'self'"), std::string::npos) << csp;
  const auto script = csp.substr(csp.find("script-src"));
  EXPECT_EQ(script.substr(0, script.find(';')).find("unsafe"), std::string::npos) << csp;
  EXPECT_NE(csp.find("frame-ancestors 'none'"), std::string::npos) << csp;
  ASSERT_TRUE(reply.headers.count("x-content-type-options"));
  EXPECT_EQ(reply.headers.at("x-content-type-options"), "nosniff");
  ASSERT_TRUE(reply.headers.count("referrer-policy"));
  EXPECT_EQ(reply.headers.at("referrer-policy"), "no-referrer");
}

std::string examples_body() { return "{}"; }

TEST(WebServing, AllowedOriginGetsTheCorsHeaders) {
  auto options = testing::test_options();
  options.cors_origins = {"http://example.org", kPage};
  TestDaemon daemon(options);
  const int port = daemon.http_port();
  const std::map<std::string, std::string> origin = {
      {"Origin", kPage},
      {"Access-Control-Request-Method", "POST"},
      {"Access-Control-Request-Headers", "content-type"}};
  const HttpReply preflight = http_request(port, "OPTIONS", "/v1/design", "", origin);
  EXPECT_EQ(preflight.status, 204) << preflight.body;
  EXPECT_EQ(preflight.headers.at("access-control-allow-origin"), kPage);
  EXPECT_NE(preflight.headers.at("access-control-allow-methods").find("POST"), std::string::npos);
  EXPECT_NE(preflight.headers.at("access-control-allow-headers").find("Content-Type"),
            std::string::npos);
  EXPECT_NE(preflight.headers.at("access-control-allow-headers").find("Authorization"),
            std::string::npos);
  EXPECT_EQ(preflight.headers.at("vary"), "Origin");
  expect_security_headers(preflight, "preflight");

  auto headers = kJson;
  headers["Origin"] = kPage;
  const HttpReply call = http_request(port, "POST", "/v1/examples", examples_body(), headers);
  EXPECT_EQ(call.status, 200) << call.body;
  EXPECT_EQ(call.headers.at("access-control-allow-origin"), kPage);
  EXPECT_EQ(call.headers.at("access-control-expose-headers"), "X-Request-Id");
  // Errors carry them too, so that the page can read the message.
  const HttpReply error = http_request(port, "POST", "/v1/design", "{\"meshes\": 1}", headers);
  EXPECT_EQ(error.status, 400);
  EXPECT_EQ(error.headers.at("access-control-allow-origin"), kPage);
  // And the event stream.
  const HttpReply sse =
      http_request(port, "POST", "/v1/patch", to_json(testing::patch_request("plane"), false),
                   {{"Origin", kPage}, {"Accept", "text/event-stream"}});
  EXPECT_EQ(sse.status, 200);
  EXPECT_EQ(sse.headers.at("access-control-allow-origin"), kPage);
}

TEST(WebServing, UnlistedOriginGetsNoCorsHeadersAndItsPreflightIs403) {
  auto options = testing::test_options();
  options.cors_origins = {kPage};
  TestDaemon listed(options);
  TestDaemon none;  // the default: no origin at all
  for (const int port : {listed.http_port(), none.http_port()}) {
    for (const char* origin : {"http://evil.example", "http://localhost:5174", "null",
                               "http://localhost:5173.evil.example"}) {
      SCOPED_TRACE(origin);
      const HttpReply preflight =
          http_request(port, "OPTIONS", "/v1/design", "",
                       {{"Origin", origin}, {"Access-Control-Request-Method", "POST"}});
      EXPECT_EQ(preflight.status, 403) << preflight.body;
      EXPECT_FALSE(preflight.headers.count("access-control-allow-origin"));
      EXPECT_NE(nlohmann::json::parse(preflight.body)["error"]["message"].get<std::string>().find(
                    "--cors-origin"),
                std::string::npos)
          << preflight.body;
      auto headers = kJson;
      headers["Origin"] = origin;
      const HttpReply call = http_request(port, "POST", "/v1/examples", examples_body(), headers);
      EXPECT_FALSE(call.headers.count("access-control-allow-origin"));  // the browser refuses it
    }
  }
  // The page's own origin is allowed only where listed.
  EXPECT_EQ(
      http_request(listed.http_port(), "OPTIONS", "/v1/design", "", {{"Origin", kPage}}).status,
      204);
  EXPECT_EQ(http_request(none.http_port(), "OPTIONS", "/v1/design", "", {{"Origin", kPage}}).status,
            403);
}

TEST(WebServing, SecurityHeadersOnJsonSseStaticAndErrors) {
  namespace fs = std::filesystem;
  const fs::path site = fs::path(testing::temp_dir()) / "site";
  fs::create_directories(site);
  std::ofstream(site / "index.html") << "<!doctype html><script src=app.js></script>";
  std::ofstream(site / "app.js") << "export {};";
  auto options = testing::test_options();
  options.static_dir = site.string();
  TestDaemon daemon(options);
  const int port = daemon.http_port();
  expect_security_headers(http_request(port, "POST", "/v1/examples", "{}", kJson), "json");
  expect_security_headers(
      http_request(port, "POST", "/v1/patch", to_json(testing::patch_request("plane"), false),
                   {{"Accept", "text/event-stream"}}),
      "sse");
  expect_security_headers(http_request(port, "GET", "/"), "index");
  expect_security_headers(http_request(port, "GET", "/app.js"), "script");
  expect_security_headers(http_request(port, "GET", "/missing.js"), "404");
  expect_security_headers(http_request(port, "GET", "/healthz"), "health");
  expect_security_headers(http_request(port, "POST", "/v1/design", "{", kJson), "400");
}

TEST(WebServing, OversizedBodyIs413NamingTheLimitAndTheDaemonKeepsServing) {
  auto options = testing::test_options();
  options.http_body_limit_mib = 1;
  TestDaemon daemon(options);
  const int port = daemon.http_port();
  // Just under the limit is read (valid JSON padded with spaces).
  const std::string fits = "{" + std::string((1u << 20) - 16, ' ') + "}";
  EXPECT_EQ(http_request(port, "POST", "/v1/examples", fits, kJson).status, 200);
  for (const std::size_t size : {(1u << 20) + 1, 5u << 20}) {
    SCOPED_TRACE(size);
    const std::string big = "{" + std::string(size - 2, ' ') + "}";
    const HttpReply reply = http_request(port, "POST", "/v1/load", big, kJson);
    EXPECT_EQ(reply.status, 413) << reply.body;
    EXPECT_EQ(reply.headers.at("content-type"), "application/json");
    const auto error = nlohmann::json::parse(reply.body)["error"];
    EXPECT_EQ(error["status"], "RESOURCE_EXHAUSTED");
    const std::string message = error["message"];
    EXPECT_NE(message.find("1 MiB"), std::string::npos) << message;
    EXPECT_NE(message.find("--http-body-limit-mib"), std::string::npos) << message;
  }
  // Still serving, JSON and designs alike.
  EXPECT_EQ(http_request(port, "GET", "/healthz").status, 200);
  const HttpReply design = http_request(
      port, "POST", "/v1/design", to_json(testing::design_request("plane", 16), false), kJson);
  EXPECT_EQ(design.status, 200) << design.body.substr(0, 300);
}

TEST(WebServing, StaticFilesAtTheRootWithTheirTypesAndNothingOutside) {
  namespace fs = std::filesystem;
  const fs::path root = testing::temp_dir();
  const fs::path site = root / "dist";
  fs::create_directories(site / "assets");
  std::ofstream(site / "index.html") << "<!doctype html><title>gridshell</title>";
  const std::map<std::string, std::string> types = {
      {"assets/index-3f2a.js", "text/javascript"},
      {"assets/index-3f2a.css", "text/css"},
      {"assets/logo.svg", "image/svg+xml"},
      {"assets/index-3f2a.js.map", "application/json"},
      {"assets/blob.bin", "application/octet-stream"}};
  for (const auto& [file, type] : types) std::ofstream(site / file) << file;
  std::ofstream(root / "secret.txt") << "secret";
  auto options = testing::test_options();
  options.static_dir = site.string();
  TestDaemon daemon(options);
  const int port = daemon.http_port();
  const HttpReply index = http_request(port, "GET", "/");
  EXPECT_EQ(index.status, 200);
  EXPECT_EQ(index.body, "<!doctype html><title>gridshell</title>");
  EXPECT_EQ(index.headers.at("content-type"), "text/html; charset=utf-8");
  EXPECT_EQ(http_request(port, "GET", "/index.html").body, index.body);
  for (const auto& [file, type] : types) {
    const HttpReply reply = http_request(port, "GET", "/" + file);
    EXPECT_EQ(reply.status, 200) << file;
    EXPECT_EQ(reply.body, file);
    EXPECT_EQ(reply.headers.at("content-type"), type) << file;
  }
  for (const char* target :
       {"/../secret.txt", "/assets/../../secret.txt", "/%2e%2e/secret.txt", "/%2E%2E%2Fsecret.txt",
        "/assets/%2e%2e/%2e%2e/secret.txt", "/assets%2f..%2f..%2fsecret.txt", "/..%5csecret.txt",
        "/%2e%2e%2f%2e%2e%2fetc%2fpasswd", "/./index.html", "/assets/./logo.svg",
        "/index.html%00.js", "/dist/../secret.txt"}) {
    const HttpReply reply = http_request(port, "GET", target);
    EXPECT_EQ(reply.status, 404) << target;
    EXPECT_NE(reply.body, "secret") << target;
  }
  // Only GET and HEAD: 405 with Allow, as docs/api.md says (it was 404 before issue 33).
  for (const char* method : {"POST", "PUT", "DELETE", "TRACE", "PATCH"}) {
    HttpReply reply = http_request(port, method, "/index.html");
    EXPECT_EQ(reply.status, 405) << method;
    EXPECT_EQ(reply.headers["allow"], "GET, HEAD") << method;
  }
  EXPECT_EQ(http_request(port, "PUT", "/v1/design", "{}").headers["allow"], "POST, OPTIONS");
  EXPECT_EQ(http_request(port, "DELETE", "/healthz").headers["allow"], "GET, HEAD");
}

TEST(WebServing, NoStaticFolderMeans404AtTheRoot) {
  TestDaemon daemon;  // static_dir empty, what --no-static gives
  for (const char* target : {"/", "/index.html", "/assets/app.js"})
    EXPECT_EQ(http_request(daemon.http_port(), "GET", target).status, 404) << target;
  EXPECT_EQ(http_request(daemon.http_port(), "GET", "/healthz").status, 200);
}

/// A Design over HTTP; its report.
v1::DesignReport design_over_http(int port, const v1::DesignRequest& request) {
  const HttpReply reply = http_request(port, "POST", "/v1/design", to_json(request, false), kJson);
  EXPECT_EQ(reply.status, 200) << reply.body.substr(0, 300);
  v1::DesignResult result;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(reply.body, &result).ok());
  return result.report();
}

TEST(WebServing, RedesignOnTheSamePatchUsesTheDaemonsCache) {
  TestDaemon daemon;
  v1::DesignRequest request = testing::design_request("double-vault", 32);
  const v1::DesignReport cold = design_over_http(daemon.http_port(), request);
  EXPECT_FALSE(cold.distance_maps_cached());
  request.mutable_options()->set_alpha("max");
  const v1::DesignReport warm = design_over_http(daemon.http_port(), request);
  EXPECT_TRUE(warm.distance_maps_cached());
  EXPECT_EQ(warm.stage_seconds().at("distance_maps"), 0);
  // Another patch of the same mesh misses.
  request.mutable_corners()->set_vertices(0, request.corners().vertices(0) + 1);
  EXPECT_FALSE(design_over_http(daemon.http_port(), request).distance_maps_cached());
}

TEST(WebServing, CacheOfZeroMibIsOff) {
  auto options = testing::test_options();
  options.cache_mib = 0;
  TestDaemon daemon(options);
  const v1::DesignRequest request = testing::design_request("double-vault", 32);
  EXPECT_FALSE(design_over_http(daemon.http_port(), request).distance_maps_cached());
  EXPECT_FALSE(design_over_http(daemon.http_port(), request).distance_maps_cached());
}

}  // namespace
}  // namespace gridshell
