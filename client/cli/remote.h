// SPDX-License-Identifier: GPL-3.0-or-later
// The CLI as a client of gridshelld: `--server HOST:PORT` runs a command remotely. The requests
// are the ones the in-process runs use (gridshell/requests.h), the results the same messages,
// so both write the same files. No gRPC types here: only remote.cpp includes gRPC.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

#include "gridshell/batch/remote_options.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/v1/fabrication.pb.h"
#include "gridshell/v1/layout.pb.h"
#include "gridshell/v1/requests.pb.h"

// CLI11 is heavy (4 s of compile time per file that includes it): declared here, included only
// by the files that build the command line.
namespace CLI {
class App;
}  // namespace CLI

namespace gridshell::cli {

/// The daemon could not be reached or refused the call for a reason that is not the input's
/// fault (unavailable, busy, unauthenticated, deadline exceeded); exit code 1.
class RemoteError : public std::runtime_error {
 public:
  explicit RemoteError(const std::string& message);
};

/// Adds --server, --tls, --tls-ca, --token-file and --timeout to a subcommand.
void add_remote_options(CLI::App* command, RemoteOptions& options);

/// One channel to a daemon, reused for every call. Calls stream progress into `progress` and
/// honour its cancellation flag (the call is cancelled on the server too). Status codes become
/// the kernel's errors: INVALID_ARGUMENT -> InvalidInput, FAILED_PRECONDITION -> Infeasible,
/// CANCELLED -> Cancelled; anything else throws std::runtime_error naming the code.
class RemoteClient {
 public:
  explicit RemoteClient(const RemoteOptions& options);
  ~RemoteClient();
  RemoteClient(const RemoteClient&) = delete;
  RemoteClient& operator=(const RemoteClient&) = delete;

  v1::PatchResult patch(const v1::PatchRequest& request, const Progress& progress = {});
  v1::DesignResult design(const v1::DesignRequest& request, const Progress& progress = {});
  v1::SimulateResult simulate(const v1::SimulateRequest& request, const Progress& progress = {});
  v1::GeodesicResult geodesic(const v1::GeodesicRequest& request, const Progress& progress = {});
  v1::FabricateResult fabricate(const v1::FabricateRequest& request, const Progress& progress = {});
  v1::LayoutResult layout(const v1::LayoutRequest& request, const Progress& progress = {});
  v1::LayoutRunResult run_layout(const v1::LayoutRunRequest& request,
                                 const Progress& progress = {});
  /// grpc.health.v1 Check of `service` ("" = the whole daemon): "SERVING", "NOT_SERVING", ...
  std::string health(const std::string& service = "");

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gridshell::cli
