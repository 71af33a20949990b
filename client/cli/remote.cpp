// SPDX-License-Identifier: GPL-3.0-or-later
// The gRPC client behind `--server`. Built only with GRIDSHELL_BUILD_SERVER (the default); without
// it the options still parse and a remote run explains why it cannot happen.
#include "remote.h"

#include <CLI/CLI.hpp>
#include <cmath>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include "gridshell/application/patch_routing_key.h"
#include "gridshell/application/requests.h"
#include "gridshell/foundation/errors.h"

#ifdef GRIDSHELL_HAVE_GRPC
#include <grpcpp/grpcpp.h>

#include "gridshell/v1/service.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#endif

namespace gridshell::cli {

void add_remote_options(CLI::App* command, RemoteOptions& options) {
  const char* group = "Remote (gridshelld)";
  command->add_option("--server", options.server, "run on gridshelld at HOST:PORT")->group(group);
  command->add_flag("--tls", options.tls, "connect with TLS (system CA roots)")->group(group);
  command
      ->add_option("--tls-ca", options.tls_ca,
                   "PEM CA or self-signed certificate that verifies the daemon (implies --tls)")
      ->group(group);
  command->add_option("--token-file", options.token_file, "file holding the bearer token")
      ->group(group);
  command->add_option("--timeout", options.timeout, "deadline in seconds (0 = none)")->group(group);
}

RemoteError::RemoteError(const std::string& message) : std::runtime_error(message) {}

#ifdef GRIDSHELL_HAVE_GRPC

namespace {

std::string read_whole_file(const std::string& path, const char* option) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidInput(option, "cannot read " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string trimmed(std::string text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  const auto last = text.find_last_not_of(" \t\r\n");
  return first == std::string::npos ? "" : text.substr(first, last - first + 1);
}

}  // namespace

struct RemoteClient::Impl {
  RemoteOptions options;
  std::string token;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::Gridshell::Stub> stub;

  void prepare(grpc::ClientContext& context, double default_timeout = 0) const {
    if (!token.empty()) context.AddMetadata("authorization", "Bearer " + token);
    const double timeout = options.timeout > 0 ? options.timeout : default_timeout;
    if (timeout > 0)
      context.set_deadline(std::chrono::system_clock::now() +
                           std::chrono::microseconds(static_cast<long long>(timeout * 1e6)));
  }

  [[noreturn]] void fail(const grpc::Status& status) const {
    const std::string& message = status.error_message();
    const std::string where = "gridshelld at " + options.server + ": ";
    // The error as data (field and plain message) when the daemon sent it, so that the field
    // is shown in the CLI's terms as for a local run.
    v1::ErrorDetail detail;
    const bool structured =
        !status.error_details().empty() && detail.ParseFromString(status.error_details());
    const std::string field = structured ? detail.field() : "";
    const std::string text = structured ? detail.message() : message;
    switch (status.error_code()) {
      case grpc::StatusCode::INVALID_ARGUMENT:
        throw InvalidInput(field, text);
      case grpc::StatusCode::FAILED_PRECONDITION:
        if (structured && detail.suggestions_size() > 0)
          throw InfeasibleWithSuggestions(
              field, text, {detail.suggestions().begin(), detail.suggestions().end()});
        throw Infeasible(field, text);
      case grpc::StatusCode::CANCELLED:
        throw Cancelled();
      case grpc::StatusCode::DEADLINE_EXCEEDED:
        throw RemoteError(where + "deadline exceeded (--timeout " +
                          std::to_string(options.timeout) + " s)");
      case grpc::StatusCode::UNAUTHENTICATED:
        throw RemoteError(where + "unauthenticated: " + message + " (see --token-file)");
      case grpc::StatusCode::RESOURCE_EXHAUSTED:
        throw RemoteError(where + "busy: " + message + "; retry later");
      case grpc::StatusCode::UNAVAILABLE:
        throw RemoteError(where + "unavailable: " + message);
      case grpc::StatusCode::UNIMPLEMENTED:
        throw RemoteError(where + "not implemented: " + message);
      default:
        throw RemoteError(where + "status " + std::to_string(status.error_code()) + ": " + message);
    }
  }

  /// One server-streaming call: progress events go to `progress`, the result is returned. The
  /// cancellation flag is watched while the call waits, so Ctrl-C cancels on the daemon too.
  /// `patch_key` (x-gridshell-patch-key) lets a proxy send every design on one patch to the same
  /// replica. A call that fails with UNAVAILABLE (daemon down, restarting or shutting down; no
  /// replica behind the proxy) is made again after a back-off: every method is idempotent.
  template <class Event, class Request>
  auto call(std::unique_ptr<grpc::ClientReader<Event>> (v1::Gridshell::Stub::*method)(
                grpc::ClientContext*, const Request&),
            const Request& request, const Progress& progress, const std::string& patch_key = "") {
    using Result = std::decay_t<decltype(std::declval<Event>().result())>;
    const auto deadline =
        options.timeout > 0
            ? std::chrono::system_clock::now() +
                  std::chrono::microseconds(static_cast<long long>(options.timeout * 1e6))
            : std::chrono::system_clock::time_point::max();
    for (int attempt = 1;; ++attempt) {
      Result result;
      bool have_result = false;
      const grpc::Status status =
          call_once(method, request, progress, patch_key, deadline, &result, &have_result);
      if (progress.cancelled()) throw Cancelled();
      if (status.ok()) {
        if (!have_result) throw RemoteError("gridshelld at " + options.server + ": no result");
        return result;
      }
      const double delay = retry_delay(status, attempt);
      if (delay < 0 || std::chrono::system_clock::now() +
                               std::chrono::milliseconds(static_cast<long long>(delay * 1e3)) >=
                           deadline)
        fail(status);
      // Wait, still answering Ctrl-C; the progress line says why nothing moves.
      progress.report("gridshelld unavailable, retry " + std::to_string(attempt) + " of " +
                          std::to_string(kMaxRetries),
                      0);
      const auto until = std::chrono::steady_clock::now() +
                         std::chrono::milliseconds(static_cast<long long>(delay * 1e3));
      while (std::chrono::steady_clock::now() < until) {
        progress.check();
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    }
  }

  /// Retries of a call the daemon did not answer: UNAVAILABLE (refused, reset, no replica up,
  /// shutting down), or UNKNOWN / INTERNAL without the daemon's ErrorDetail, which is how gRPC
  /// reports a stream cut under it ("Stream removed" when the replica behind haproxy died
  /// mid-call; the daemon itself never answers UNKNOWN and details its INTERNAL errors). At most
  /// kMaxRetries, waits 0.25 s doubling up to 4 s, each scaled by a random factor in [0.5, 1) so
  /// that many clients do not return in step. -1: give up now.
  static constexpr int kMaxRetries = 5;
  static double retry_delay(const grpc::Status& status, int attempt) {
    const grpc::StatusCode code = status.error_code();
    const bool cut = (code == grpc::StatusCode::UNKNOWN || code == grpc::StatusCode::INTERNAL) &&
                     status.error_details().empty();
    if ((code != grpc::StatusCode::UNAVAILABLE && !cut) || attempt > kMaxRetries) return -1;
    thread_local std::mt19937 random{std::random_device{}()};
    const double base = std::min(4.0, 0.25 * std::pow(2.0, attempt - 1));
    return base * std::uniform_real_distribution<double>(0.5, 1.0)(random);
  }

  template <class Event, class Request, class Result>
  grpc::Status call_once(std::unique_ptr<grpc::ClientReader<Event>> (v1::Gridshell::Stub::*method)(
                             grpc::ClientContext*, const Request&),
                         const Request& request, const Progress& progress,
                         const std::string& patch_key,
                         std::chrono::system_clock::time_point deadline, Result* result,
                         bool* have_result) {
    grpc::ClientContext context;
    prepare(context);
    if (deadline != std::chrono::system_clock::time_point::max()) context.set_deadline(deadline);
    if (!patch_key.empty()) context.AddMetadata("x-gridshell-patch-key", patch_key);
    std::mutex mutex;
    std::condition_variable wake;
    bool done = false;
    std::thread watcher([&] {
      std::unique_lock lock(mutex);
      while (!done) {
        if (progress.cancelled()) {
          context.TryCancel();
          return;
        }
        wake.wait_for(lock, std::chrono::milliseconds(50));
      }
    });
    auto stop_watcher = [&] {
      {
        std::lock_guard lock(mutex);
        done = true;
      }
      wake.notify_all();
      if (watcher.joinable()) watcher.join();
    };
    grpc::Status status;
    try {
      auto reader = (stub.get()->*method)(&context, request);
      Event event;
      while (reader->Read(&event)) {
        if (event.has_result()) {
          *result = std::move(*event.mutable_result());
          *have_result = true;
        } else if (event.has_progress()) {
          try {
            progress.report(event.progress().stage(), event.progress().fraction());
          } catch (const Cancelled&) {
            context.TryCancel();  // then drain the stream and finish it
          }
        }
      }
      status = reader->Finish();
    } catch (...) {
      stop_watcher();
      throw;
    }
    stop_watcher();
    return status;
  }
};

RemoteClient::RemoteClient(const RemoteOptions& options) : impl_(std::make_unique<Impl>()) {
  impl_->options = options;
  const auto colon = options.server.rfind(':');
  if (colon == std::string::npos || colon == 0)
    throw InvalidInput("--server", "expected HOST:PORT, got '" + options.server + "'");
  const std::string port = options.server.substr(colon + 1);
  const bool digits = !port.empty() && port.size() <= 5 &&
                      port.find_first_not_of("0123456789") == std::string::npos;
  if (!digits || std::stoi(port) < 1 || std::stoi(port) > 65535)
    throw InvalidInput("--server", "'" + port + "' is not a port number (1-65535)");
  // Up to a year: a deadline that gRPC's clock arithmetic does not overflow (NaN fails too).
  if (!(options.timeout >= 0 && options.timeout <= 3.2e7))
    throw InvalidInput("--timeout", "must be between 0 (none) and 3.2e7 seconds");
  if (!options.token_file.empty()) {
    impl_->token = trimmed(read_whole_file(options.token_file, "--token-file"));
    if (impl_->token.empty())
      throw InvalidInput("--token-file", "" + options.token_file + " is empty");
  }
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  if (options.tls || !options.tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    if (!options.tls_ca.empty()) ssl.pem_root_certs = read_whole_file(options.tls_ca, "--tls-ca");
    credentials = grpc::SslCredentials(ssl);
  } else {
    credentials = grpc::InsecureChannelCredentials();
  }
  grpc::ChannelArguments arguments;
  arguments.SetMaxReceiveMessageSize(-1);  // results can be large; the daemon bounds them
  arguments.SetMaxSendMessageSize(-1);
  impl_->channel = grpc::CreateCustomChannel(options.server, credentials, arguments);
  impl_->stub = v1::Gridshell::NewStub(impl_->channel);
}

RemoteClient::~RemoteClient() = default;

v1::PatchResult RemoteClient::patch(const v1::PatchRequest& request, const Progress& progress) {
  return impl_->call(&v1::Gridshell::Stub::Patch, request, progress);
}

v1::DesignResult RemoteClient::design(const v1::DesignRequest& request, const Progress& progress) {
  // The key checks and converts the request first (prepare_design): bad options fail here,
  // before any call.
  return impl_->call(&v1::Gridshell::Stub::Design, request, progress, patch_routing_key(request));
}

v1::SimulateResult RemoteClient::simulate(const v1::SimulateRequest& request,
                                          const Progress& progress) {
  return impl_->call(&v1::Gridshell::Stub::Simulate, request, progress);
}

v1::GeodesicResult RemoteClient::geodesic(const v1::GeodesicRequest& request,
                                          const Progress& progress) {
  return impl_->call(&v1::Gridshell::Stub::Geodesic, request, progress);
}

v1::FabricateResult RemoteClient::fabricate(const v1::FabricateRequest& request,
                                            const Progress& progress) {
  return impl_->call(&v1::Gridshell::Stub::Fabricate, request, progress);
}

v1::LayoutResult RemoteClient::layout(const v1::LayoutRequest& request, const Progress& progress) {
  return impl_->call(&v1::Gridshell::Stub::Layout, request, progress);
}

v1::LayoutRunResult RemoteClient::run_layout(const v1::LayoutRunRequest& request,
                                             const Progress& progress) {
  return impl_->call(&v1::Gridshell::Stub::RunLayout, request, progress);
}

std::string RemoteClient::health(const std::string& service) {
  auto stub = grpc::health::v1::Health::NewStub(impl_->channel);
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  grpc::health::v1::HealthCheckResponse response;
  grpc::ClientContext context;
  impl_->prepare(context, 10.0);
  const grpc::Status status = stub->Check(&context, request, &response);
  if (status.error_code() == grpc::StatusCode::NOT_FOUND) return "SERVICE_UNKNOWN";
  if (!status.ok()) impl_->fail(status);
  return grpc::health::v1::HealthCheckResponse::ServingStatus_Name(response.status());
}

#else  // built without gRPC

struct RemoteClient::Impl {};

RemoteClient::RemoteClient(const RemoteOptions&) {
  throw InvalidInput("--server",
                     "this gridshell was built without gRPC (GRIDSHELL_BUILD_SERVER=OFF)");
}
RemoteClient::~RemoteClient() = default;
v1::PatchResult RemoteClient::patch(const v1::PatchRequest&, const Progress&) { return {}; }
v1::DesignResult RemoteClient::design(const v1::DesignRequest&, const Progress&) { return {}; }
v1::SimulateResult RemoteClient::simulate(const v1::SimulateRequest&, const Progress&) {
  return {};
}
v1::GeodesicResult RemoteClient::geodesic(const v1::GeodesicRequest&, const Progress&) {
  return {};
}
v1::FabricateResult RemoteClient::fabricate(const v1::FabricateRequest&, const Progress&) {
  return {};
}
v1::LayoutResult RemoteClient::layout(const v1::LayoutRequest&, const Progress&) { return {}; }
v1::LayoutRunResult RemoteClient::run_layout(const v1::LayoutRunRequest&, const Progress&) {
  return {};
}
std::string RemoteClient::health(const std::string&) { return {}; }

#endif

}  // namespace gridshell::cli
