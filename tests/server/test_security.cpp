// SPDX-License-Identifier: GPL-3.0-or-later
// Security of gridshelld: loopback by default, TLS and a bearer token for anything else, the
// token checked on every gRPC call (health included) and every HTTP API call.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "gridshell/application/files.h"
#include "gridshell/foundation/errors.h"
#include "server_support.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::TestDaemon;

constexpr const char* kToken = "s3cret-token-42";

/// A daemon with a token, over TLS (the default) or plaintext on loopback.
struct SecureDaemon {
  testing::Certificate certificate = testing::make_self_signed_certificate();
  std::unique_ptr<TestDaemon> daemon;
  explicit SecureDaemon(bool tls = true) {
    const std::string dir = testing::temp_dir();
    auto options = testing::test_options();
    if (tls) {
      options.tls_cert = testing::write_text(dir, "cert.pem", certificate.cert_pem);
      options.tls_key = testing::write_text(dir, "key.pem", certificate.key_pem);
    } else {
      certificate = {};  // the clients connect in plaintext
    }
    options.token_file = testing::write_text(dir, "token", std::string(kToken) + "\n");
    daemon = std::make_unique<TestDaemon>(options);
  }
};

/// A raw call on the secure daemon's channel (TLS when it has a certificate).
testing::RawReply raw(const SecureDaemon& secure, bool stream, const std::string& method,
                      const std::string& bytes, const std::string& authorization) {
  const auto channel = secure.daemon->channel(secure.certificate.cert_pem);
  return stream ? testing::raw_stream(channel, method, bytes, authorization)
                : testing::raw_unary(channel, method, bytes, authorization);
}

grpc::Status patch_with(const SecureDaemon& secure, const std::string& authorization) {
  auto stub = secure.daemon->stub(secure.certificate.cert_pem);
  grpc::ClientContext context;
  if (!authorization.empty()) context.AddMetadata("authorization", authorization);
  return testing::call_patch(*stub, testing::patch_request("plane"), &context).status;
}

TEST(Security, GrpcCallsWithoutTheTokenAreUnauthenticated) {
  SecureDaemon secure;
  for (const std::string& header : {std::string(), std::string("Bearer wrong"),
                                    std::string("Basic ") + kToken, std::string(kToken)}) {
    const grpc::Status status = patch_with(secure, header);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED) << header;
  }
  EXPECT_TRUE(patch_with(secure, std::string("Bearer ") + kToken).ok());
  EXPECT_EQ(secure.daemon->daemon().stats().succeeded, 1u);  // nothing else ran
}

// Every service the gRPC server has needs the token, with TLS and in plaintext on loopback
// (issue 33, P5: without TLS, health and reflection used to answer anyone).
TEST(Security, EveryGrpcServiceNeedsTheToken) {
  for (const bool tls : {true, false}) {
    SCOPED_TRACE(tls ? "TLS" : "plaintext");
    SecureDaemon secure(tls);
    const std::string bearer = std::string("Bearer ") + kToken;
    for (const std::string& header : {std::string(), std::string("Bearer wrong"), bearer}) {
      SCOPED_TRACE(header);
      const auto expected =
          header == bearer ? grpc::StatusCode::OK : grpc::StatusCode::UNAUTHENTICATED;
      // Health/Check with an empty request (the whole server).
      const auto health = raw(secure, false, "/grpc.health.v1.Health/Check", "", header);
      EXPECT_EQ(health.status.error_code(), expected);
      if (header == bearer) {
        EXPECT_EQ(health.messages, std::vector<std::string>{std::string("\x08\x01", 2)});
      }
      // Reflection: list_services (field 7, empty string), a bidirectional stream.
      EXPECT_EQ(raw(secure, true, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
                    std::string("\x3a\x00", 2), header)
                    .status.error_code(),
                expected);
      // Our own service: Examples, an empty request.
      EXPECT_EQ(
          raw(secure, true, "/gridshell.v1.Gridshell/Examples", "", header).status.error_code(),
          expected);
    }
    if (!tls) {  // the plaintext port answers a client with the token (stub, not raw bytes)
      auto stub = secure.daemon->stub();
      grpc::ClientContext context;
      context.AddMetadata("authorization", bearer);
      EXPECT_TRUE(
          testing::call_patch(*stub, testing::patch_request("plane"), &context).status.ok());
    }
  }
}

// Bytes that are no protocol buffer get INVALID_ARGUMENT with a message (gRPC's own parser
// answered them with a bare status), once the token has been checked.
TEST(Security, MalformedGrpcBytesAreInvalidArgument) {
  SecureDaemon secure(false);
  const std::string bearer = std::string("Bearer ") + kToken;
  for (const char* method : {"Design", "Patch", "Simulate", "Fabricate"}) {
    SCOPED_TRACE(method);
    const std::string path = std::string("/gridshell.v1.Gridshell/") + method;
    // A length-delimited field whose length runs past the end, and a truncated varint.
    for (const std::string& bytes : {std::string("\x0a\x7f\x01", 3), std::string("\x08\xff")}) {
      const grpc::Status status = raw(secure, true, path, bytes, bearer).status;
      EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
      EXPECT_NE(status.error_message().find("malformed protocol buffer"), std::string::npos)
          << status.error_message();
    }
    EXPECT_EQ(raw(secure, true, path, "\xff", "").status.error_code(),
              grpc::StatusCode::UNAUTHENTICATED);
  }
  EXPECT_EQ(secure.daemon->daemon().stats().succeeded, 0u);
}

TEST(Security, ATokenWithoutTlsIsRefusedOffLoopback) {
  auto options = testing::test_options();
  options.listen = "0.0.0.0:0";
  options.insecure = true;
  options.token_file = testing::write_text(testing::temp_dir(), "token", "abc\n");
  try {
    server::Daemon daemon(options);
    FAIL() << "accepted a token without TLS on 0.0.0.0";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), "--listen");
    EXPECT_NE(std::string(e.what()).find("TLS"), std::string::npos) << e.what();
  }
}

TEST(Security, PlaintextClientCannotTalkToTheTlsPort) {
  SecureDaemon secure;
  auto stub = secure.daemon->stub();  // no TLS
  grpc::ClientContext context;
  context.AddMetadata("authorization", std::string("Bearer ") + kToken);
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  const auto status = testing::call_patch(*stub, testing::patch_request("plane"), &context).status;
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(secure.daemon->daemon().stats().succeeded, 0u);
}

TEST(Security, HttpsCallsWithoutTheTokenAre401) {
  SecureDaemon secure;
  const int port = secure.daemon->http_port();
  const std::string& ca = secure.certificate.cert_pem;
  const std::string body = to_json(testing::patch_request("plane"), false);
  auto reply = testing::http_request(port, "POST", "/v1/patch", body, {}, ca);
  EXPECT_EQ(reply.status, 401) << reply.body;
  EXPECT_EQ(reply.headers["www-authenticate"], "Bearer realm=\"gridshelld\"");
  EXPECT_EQ(nlohmann::json::parse(reply.body)["error"]["status"], "UNAUTHENTICATED");
  reply = testing::http_request(port, "POST", "/v1/patch", body, {{"Authorization", "Bearer nope"}},
                                ca);
  EXPECT_EQ(reply.status, 401);
  EXPECT_EQ(testing::http_request(port, "GET", "/healthz", "", {}, ca).status, 401);
  reply = testing::http_request(port, "POST", "/v1/patch", body,
                                {{"Authorization", std::string("Bearer ") + kToken}}, ca);
  EXPECT_EQ(reply.status, 200) << reply.body;
  EXPECT_EQ(testing::http_request(port, "GET", "/healthz", "",
                                  {{"Authorization", std::string("Bearer ") + kToken}}, ca)
                .status,
            200);
}

TEST(Security, NonLoopbackAddressesNeedTlsAndATokenOrInsecure) {
  for (const char* address : {"0.0.0.0:0", "192.168.1.20:50051", "[::]:0", "example.org:1"}) {
    auto options = testing::test_options();
    options.listen = address;
    try {
      server::Daemon daemon(options);
      ADD_FAILURE() << address << " was accepted";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("--insecure"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("--tls-cert"), std::string::npos) << e.what();
    }
    options.insecure = true;
    EXPECT_NO_THROW(server::Daemon{options}) << address;  // constructed, never started
  }
  auto options = testing::test_options();
  options.http = "0.0.0.0:8080";
  EXPECT_THROW(server::Daemon{options}, InvalidInput);
  options.tls_cert = "/nonexistent/cert.pem";
  options.tls_key = "/nonexistent/key.pem";
  options.token_file = "/nonexistent/token";
  EXPECT_THROW(server::Daemon{options}, InvalidInput);  // unreadable files
}

// TLS files are checked when the daemon is configured: an empty or wrong file must neither
// mean "no TLS" (the token would then travel in plain text) nor fail later as "cannot listen".
TEST(Security, TlsFilesMustHoldACertificateAndItsKey) {
  const testing::Certificate good = testing::make_self_signed_certificate();
  const testing::Certificate other = testing::make_self_signed_certificate();
  const std::string dir = testing::temp_dir();
  struct Case {
    std::string cert, key, field, says;
  };
  const std::vector<Case> cases = {
      {"", "", "--tls-cert", "no PEM certificate"},
      {"root:x:0:0:root:/root:/bin/bash\n", good.key_pem, "--tls-cert", "no PEM certificate"},
      {good.cert_pem, "", "--tls-key", "no unencrypted PEM private key"},
      {good.cert_pem, good.cert_pem, "--tls-key", "no unencrypted PEM private key"},
      {good.cert_pem, other.key_pem, "--tls-key", "does not belong"},
  };
  for (const Case& c : cases) {
    auto options = testing::test_options();
    options.listen = "0.0.0.0:0";  // needs TLS and a token
    options.tls_cert = testing::write_text(dir, "cert.pem", c.cert);
    options.tls_key = testing::write_text(dir, "key.pem", c.key);
    options.token_file = testing::write_text(dir, "token", std::string(kToken) + "\n");
    try {
      server::Daemon daemon(options);
      ADD_FAILURE() << c.field << " / " << c.says << ": accepted";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(std::string(e.what()).rfind(c.field, 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
    }
  }
  auto options = testing::test_options();
  options.tls_cert = testing::write_text(dir, "cert.pem", good.cert_pem);
  options.tls_key = testing::write_text(dir, "key.pem", good.key_pem);
  EXPECT_NO_THROW(server::Daemon{options});
}

// gRPC would share a port between processes (SO_REUSEPORT) and split the connections.
TEST(Security, ASecondDaemonCannotTakeTheSamePort) {
  TestDaemon first;
  auto options = testing::test_options();
  options.listen = first.grpc_address();
  server::Daemon second(options);
  try {
    second.start();
    ADD_FAILURE() << "second daemon started on " << options.listen;
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("--listen"), std::string::npos) << e.what();
    // The operating system's reason, from gRPC's error.
    EXPECT_NE(std::string(e.what()).find("Address already in use"), std::string::npos) << e.what();
  }
  second.shutdown();
}

TEST(Security, LoopbackAddresses) {
  for (const char* address : {"127.0.0.1:1", "127.10.0.3:80", "localhost:50051", "[::1]:50051"})
    EXPECT_TRUE(server::is_loopback_address(address)) << address;
  for (const char* address : {"0.0.0.0:1", "10.0.0.1:80", "[::]:1", "128.0.0.1:1", "127.0.0.1x:1",
                              "localhost.example.org:1", "1.2.3.4:5"})
    EXPECT_FALSE(server::is_loopback_address(address)) << address;
}

}  // namespace
}  // namespace gridshell
