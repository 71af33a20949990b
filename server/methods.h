// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld — the RPC table. One RPC is one entry here: its name and its request -> kernel ->
// result function. Queueing, streaming, cancellation, deadlines, logging and the HTTP route are
// generic (job_queue.h, grpc_service.cpp, http_gateway.cpp) and need nothing per method.
//
// To implement Simulate or Run: write `v1::SimulateResult run_simulate(const v1::SimulateRequest&,
// const Progress&, const RunSettings&)` next to run_design in application/requests.cpp and set
// `methods.simulate.run` to it in make_methods (methods.cpp). That is all.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <utility>

#include "gridshell/application/fabricate.h"
#include "gridshell/application/files.h"
#include "gridshell/application/layout.h"
#include "gridshell/application/options.h"
#include "gridshell/application/requests.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/v1/layout.pb.h"
#include "gridshell/v1/requests.pb.h"
#include "job_queue.h"

namespace gridshell::server {

template <class RequestMessage, class ResultMessage>
struct Method {
  using Request = RequestMessage;
  using Result = ResultMessage;
  std::string name;  ///< gRPC method name ("Design"); the HTTP route is /v1/ + lower case
  /// Request -> kernel -> result; throws the kernel's errors (InvalidInput, Infeasible,
  /// Cancelled). Empty: the method answers UNIMPLEMENTED with `unimplemented` as its message.
  std::function<Result(const Request&, const Progress&)> run;
  std::string unimplemented;
  /// Answered from tables without kernel work (Examples): runs in the queue's light lane, never
  /// behind design jobs (JobRequest::light).
  bool light = false;
};

struct Methods {
  Method<v1::PatchRequest, v1::PatchResult> patch;
  Method<v1::DesignRequest, v1::DesignResult> design;
  Method<v1::SimulateRequest, v1::SimulateResult> simulate;
  Method<v1::RunRequest, v1::RunResult> run;
  Method<v1::GeodesicRequest, v1::GeodesicResult> geodesic;
  Method<v1::LoadRequest, v1::LoadResult> load;
  Method<v1::ExamplesRequest, v1::ExamplesResult> examples;
  Method<v1::FabricateRequest, v1::FabricateResult> fabricate;
  Method<v1::OptionsRequest, v1::OptionsResult> options;
  Method<v1::LayoutRequest, v1::LayoutResult> layout;
  Method<v1::LayoutRunRequest, v1::LayoutRunResult> run_layout;
};

/// The table; `settings` (kernel threads per request) applies to every method.
Methods make_methods(const RunSettings& settings);

/// Vertices and faces of the first gridshell.v1.Mesh in a request (searched through nested
/// messages), for the log line; {0, 0} if it has none.
std::pair<int, int> mesh_size(const google::protobuf::Message& request);

/// The longest text any string field of a request may hold, in bytes (names, labels, options;
/// file contents are `bytes` fields, limited by the message size only), and the most entries a
/// repeated string field may have. Text given to the daemon is copied into results and logs, so
/// one long name must not multiply into a response (issue 33, P4).
inline constexpr std::size_t kMaxTextBytes = 1024;
inline constexpr int kMaxTextEntries = 1000;

/// Throws InvalidInput naming the first string field of `request` (path like "mesh.name" or
/// "mesh.warnings[3]") that is longer than kMaxTextBytes, or a repeated string field with more
/// than kMaxTextEntries entries. Does not look inside google.protobuf.* values.
void check_text_limits(const google::protobuf::Message& request);

/// The job body for a request the transport holds (gRPC: valid until the call is finished, which
/// happens only after the job finished).
template <class M>
auto job_function(const M& method, const typename M::Request* request) {
  return [&method, request](const Progress& progress,
                            JobInfo& info) -> std::unique_ptr<google::protobuf::Message> {
    check_text_limits(*request);
    const auto [vertices, faces] = mesh_size(*request);
    info.vertices = vertices;
    info.faces = faces;
    return std::make_unique<typename M::Result>(method.run(*request, progress));
  };
}

/// The job body for a request in protobuf's JSON mapping (HTTP): parsed on the worker, so a large
/// body does not hold up the gateway. Read strictly (from_json): unknown fields, wrong JSON
/// types, malformed JSON and nesting deeper than kJsonMaxDepth are INVALID_ARGUMENT naming the
/// field.
template <class M>
auto job_function_from_json(const M& method, std::shared_ptr<const std::string> body) {
  return [&method, body](const Progress& progress,
                         JobInfo& info) -> std::unique_ptr<google::protobuf::Message> {
    typename M::Request request;
    // Strict (gridshell/files.h), and an over-long string is refused before protobuf copies it.
    from_json(*body, request, kJsonMaxDepth, UnknownFields::Refuse, kMaxTextBytes);
    progress.check();
    check_text_limits(request);
    const auto [vertices, faces] = mesh_size(request);
    info.vertices = vertices;
    info.faces = faces;
    return std::make_unique<typename M::Result>(method.run(request, progress));
  };
}

}  // namespace gridshell::server
