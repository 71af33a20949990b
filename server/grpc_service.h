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

class GridshellService final : public v1::Gridshell::CallbackService {
 public:
  /// `token`: required bearer token, empty = none.
  GridshellService(JobQueue& queue, const Methods& methods, std::string token);

  grpc::ServerWriteReactor<v1::PatchEvent>* Patch(grpc::CallbackServerContext* context,
                                                  const v1::PatchRequest* request) override;
  grpc::ServerWriteReactor<v1::DesignEvent>* Design(grpc::CallbackServerContext* context,
                                                    const v1::DesignRequest* request) override;
  grpc::ServerWriteReactor<v1::SimulateEvent>* Simulate(
      grpc::CallbackServerContext* context, const v1::SimulateRequest* request) override;
  grpc::ServerWriteReactor<v1::RunEvent>* Run(grpc::CallbackServerContext* context,
                                              const v1::RunRequest* request) override;
  grpc::ServerWriteReactor<v1::GeodesicEvent>* Geodesic(
      grpc::CallbackServerContext* context, const v1::GeodesicRequest* request) override;
  grpc::ServerWriteReactor<v1::LoadEvent>* Load(grpc::CallbackServerContext* context,
                                                const v1::LoadRequest* request) override;
  grpc::ServerWriteReactor<v1::ExamplesEvent>* Examples(
      grpc::CallbackServerContext* context, const v1::ExamplesRequest* request) override;
  grpc::ServerWriteReactor<v1::FabricateEvent>* Fabricate(
      grpc::CallbackServerContext* context, const v1::FabricateRequest* request) override;

 private:
  template <class Event, class M>
  grpc::ServerWriteReactor<Event>* serve(grpc::CallbackServerContext* context,
                                         const typename M::Request* request, const M& method);

  JobQueue& queue_;
  const Methods& methods_;
  std::string token_;
};

/// Checks the bearer token of every call on a TLS port, the health and reflection services
/// included; `on_refused` is told the peer of each refused call (for the log).
std::shared_ptr<grpc::AuthMetadataProcessor> make_token_processor(
    std::string token, std::function<void(const std::string& method)> on_refused);

}  // namespace gridshell::server
