// SPDX-License-Identifier: GPL-3.0-or-later
// Helpers for the daemon tests: an in-process gridshelld on ephemeral loopback ports, gRPC and
// HTTP clients, requests built from the example surfaces, the bad-input set, throwaway TLS
// certificates. Nothing here needs a network beyond loopback.
#pragma once

#include <grpcpp/grpcpp.h>

#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "daemon.h"
#include "gridshell/v1/service.grpc.pb.h"

namespace gridshell::testing {

/// A daemon on 127.0.0.1, both ports chosen by the system. Stopped by the destructor.
class TestDaemon {
 public:
  explicit TestDaemon(server::DaemonOptions options = {});
  ~TestDaemon();
  server::Daemon& daemon() { return *daemon_; }
  std::string grpc_address() const;
  std::string http_address() const;
  int http_port() const { return daemon_->http_port(); }
  /// A channel (TLS if `ca_pem` is set, verifying against it).
  std::shared_ptr<grpc::Channel> channel(const std::string& ca_pem = "") const;
  std::unique_ptr<v1::Gridshell::Stub> stub(const std::string& ca_pem = "") const;
  /// Log lines written so far.
  std::string log() const;
  /// Waits up to `seconds` until `condition(stats)` holds.
  bool wait_for(const std::function<bool(const server::JobQueue::Stats&)>& condition,
                double seconds = 20) const;

 private:
  struct Log;
  std::shared_ptr<Log> log_;
  std::unique_ptr<server::Daemon> daemon_;
};

/// Options for tests: ephemeral ports, a log, `workers` and `queue` as given.
server::DaemonOptions test_options(int workers = 2, int queue = 16);

/// Requests on an example surface with its corners.
v1::PatchRequest patch_request(const std::string& example);
v1::DesignRequest design_request(const std::string& example, int resolution = 0);

/// The outcome of a streaming call.
template <class Result>
struct CallResult {
  grpc::Status status;
  std::optional<Result> result;
  std::vector<v1::Progress> progress;
};

CallResult<v1::PatchResult> call_patch(v1::Gridshell::Stub& stub, const v1::PatchRequest& request,
                                       grpc::ClientContext* context = nullptr);
CallResult<v1::DesignResult> call_design(v1::Gridshell::Stub& stub,
                                         const v1::DesignRequest& request,
                                         grpc::ClientContext* context = nullptr);
CallResult<v1::SimulateResult> call_simulate(v1::Gridshell::Stub& stub,
                                             const v1::SimulateRequest& request,
                                             grpc::ClientContext* context = nullptr);
CallResult<v1::GeodesicResult> call_geodesic(v1::Gridshell::Stub& stub,
                                             const v1::GeodesicRequest& request,
                                             grpc::ClientContext* context = nullptr);
CallResult<v1::RunResult> call_run(v1::Gridshell::Stub& stub, const v1::RunRequest& request,
                                   grpc::ClientContext* context = nullptr);

/// A call by method path with raw request bytes, for services without a stub here (health,
/// reflection) and for bytes that are no message: its status and the messages it answered.
struct RawReply {
  grpc::Status status;
  std::vector<std::string> messages;
};
RawReply raw_unary(const std::shared_ptr<grpc::Channel>& channel, const std::string& method,
                   const std::string& bytes, const std::string& authorization = "");
/// The same for a streaming method: `bytes` as its (only) request, every answer read.
RawReply raw_stream(const std::shared_ptr<grpc::Channel>& channel, const std::string& method,
                    const std::string& bytes, const std::string& authorization = "");

/// A small design (plane, resolution 16) to simulate, made in process once.
const v1::Design& small_design();

/// A plain HTTP/1.1 exchange with the gateway (TLS if `ca_pem` is set).
struct HttpReply {
  int status = 0;
  std::map<std::string, std::string> headers;  ///< lower-case names
  std::string body;
};
HttpReply http_request(int port, const std::string& method, const std::string& target,
                       const std::string& body = "",
                       const std::map<std::string, std::string>& headers = {},
                       const std::string& ca_pem = "");

/// One entry of the bad-input set (issue 2's rejected inputs, plus corners and options): a
/// request the daemon must answer with INVALID_ARGUMENT / 400, and a part of the message.
struct BadInput {
  std::string name;
  std::string method;    ///< "Patch", "Design", "Simulate", "Run" or "Geodesic"
  std::string json;      ///< the request in JSON (what the HTTP gateway receives)
  std::string expected;  ///< must appear in the error message
};
std::vector<BadInput> bad_inputs();

/// A self-signed certificate for 127.0.0.1 and localhost (EC P-256), made in memory.
struct Certificate {
  std::string cert_pem, key_pem;
};
Certificate make_self_signed_certificate();

/// deployment.json without its timings (the totals, each run's seconds and the seconds of its
/// solver profile), to compare a remote run with an in-process one.
nlohmann::json deployment_without_timings(const std::string& text);

}  // namespace gridshell::testing
