// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld — the gRPC transport: service gridshell.v1.Gridshell on the callback API. Every
// method is one line that hands its entry of the RPC table (methods.h) to the generic `serve`,
// which checks the token, queues the job, streams its progress, turns client cancellation and
// deadlines into the kernel's cancellation flag and finishes the call with the job's status.
#pragma once

#include <grpcpp/grpcpp.h>

#include <functional>
#include <memory>
#include <string>

#include "gridshell/v1/service.grpc.pb.h"
#include "job_queue.h"
#include "methods.h"

namespace gridshell::server {

/// Every method takes and sends raw bytes: the service parses the request itself, so that
/// malformed bytes get INVALID_ARGUMENT with a message (gRPC's own parser answers them with a
/// bare status), and serializes the events itself.
using RawService = v1::Gridshell::WithRawCallbackMethod_Patch<
    v1::Gridshell::WithRawCallbackMethod_Design<v1::Gridshell::WithRawCallbackMethod_Simulate<
        v1::Gridshell::WithRawCallbackMethod_Run<v1::Gridshell::WithRawCallbackMethod_Geodesic<
            v1::Gridshell::WithRawCallbackMethod_Load<v1::Gridshell::WithRawCallbackMethod_Examples<
                v1::Gridshell::WithRawCallbackMethod_Fabricate<
                    v1::Gridshell::WithRawCallbackMethod_Options<
                        v1::Gridshell::WithRawCallbackMethod_Layout<
                            v1::Gridshell::WithRawCallbackMethod_RunLayout<
                                v1::Gridshell::Service>>>>>>>>>>>;

class GridshellService final : public RawService {
 public:
  /// `token`: required bearer token, empty = none.
  GridshellService(JobQueue& queue, const Methods& methods, std::string token);

  using Reactor = grpc::ServerWriteReactor<grpc::ByteBuffer>;
  using Context = grpc::CallbackServerContext;
  Reactor* Patch(Context* context, const grpc::ByteBuffer* request) override;
  Reactor* Design(Context* context, const grpc::ByteBuffer* request) override;
  Reactor* Simulate(Context* context, const grpc::ByteBuffer* request) override;
  Reactor* Run(Context* context, const grpc::ByteBuffer* request) override;
  Reactor* Geodesic(Context* context, const grpc::ByteBuffer* request) override;
  Reactor* Load(Context* context, const grpc::ByteBuffer* request) override;
  Reactor* Examples(Context* context, const grpc::ByteBuffer* request) override;
  Reactor* Options(Context* context, const grpc::ByteBuffer* request) override;
  Reactor* Layout(Context* context, const grpc::ByteBuffer* request) override;
  Reactor* RunLayout(Context* context, const grpc::ByteBuffer* request) override;
  Reactor* Fabricate(Context* context, const grpc::ByteBuffer* request) override;

 private:
  template <class Event, class M>
  Reactor* serve(Context* context, const grpc::ByteBuffer* request, const M& method);

  JobQueue& queue_;
  const Methods& methods_;
  std::string token_;
};

/// Checks the bearer token of every call on a TLS port, the health and reflection services
/// included; `on_refused` is told the peer of each refused call (for the log).
std::shared_ptr<grpc::AuthMetadataProcessor> make_token_processor(
    std::string token, std::function<void(const std::string& method)> on_refused);

}  // namespace gridshell::server
