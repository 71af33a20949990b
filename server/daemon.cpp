// SPDX-License-Identifier: GPL-3.0-or-later
#include "daemon.h"

#include <grpc/support/log.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <sys/resource.h>

#include <atomic>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "auth.h"
#include "gridshell/application/patch_cache.h"
#include "gridshell/foundation/errors.h"
#include "grpc_service.h"
#include "http_gateway.h"
#include "methods.h"

namespace gridshell::server {
namespace {

// gRPC's own log lines (a failed bind, a malformed connection) go into the daemon's JSON log
// as {"event": "grpc", ...} instead of raw text between its lines; the last error is kept per
// thread to name the reason when the listening port cannot be opened.
std::mutex grpc_log_mutex;
/// The started daemons' log functions (guarded by grpc_log_mutex); gRPC's lines go to the most
/// recently started one still running.
std::vector<std::pair<const void*, std::function<void(nlohmann::json)>>> grpc_log_sinks;
thread_local std::string last_grpc_error;

void route_grpc_log(gpr_log_func_args* args) {
  const bool error = args->severity == GPR_LOG_SEVERITY_ERROR;
  if (error) last_grpc_error = args->message ? args->message : "";
  std::lock_guard lock(grpc_log_mutex);
  if (grpc_log_sinks.empty()) return;
  grpc_log_sinks.back().second(
      {{"event", "grpc"},
       {"severity", error ? "error" : (args->severity == GPR_LOG_SEVERITY_INFO ? "info" : "debug")},
       {"message", args->message ? args->message : ""},
       {"source", std::string(args->file ? args->file : "") + ":" + std::to_string(args->line)}});
}

/// The operating system's reason in a gRPC error text (`os_error:"Address already in use"`).
std::string os_error_in(const std::string& text) {
  const std::string key = "os_error:\"";
  const std::size_t at = text.find(key);
  if (at == std::string::npos) return {};
  const std::size_t end = text.find('"', at + key.size());
  return end == std::string::npos ? std::string{}
                                  : text.substr(at + key.size(), end - at - key.size());
}

constexpr const char* kServiceName = "gridshell.v1.Gridshell";

std::string host_of(const std::string& address) {
  const auto colon = address.rfind(':');
  std::string host = colon == std::string::npos ? address : address.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  return host;
}

void check_address(const std::string& address, const char* option) {
  const auto colon = address.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == address.size())
    throw InvalidInput(option, "expected HOST:PORT, got '" + address + "'");
  const std::string port = address.substr(colon + 1);
  if (port.find_first_not_of("0123456789") != std::string::npos || port.size() > 5 ||
      std::stoi(port) > 65535)
    throw InvalidInput(option, "'" + port + "' is not a port number");
}

/// Checks that `cert_pem` holds a PEM certificate chain and `key_pem` the private key of its
/// first certificate, so that the daemon never starts with TLS it cannot use (an empty or
/// wrong file must not silently mean "no TLS", nor fail later as "cannot listen").
/// The first PEM object of type T in `text` (read by `read`, owned with `free`), or null; the
/// OpenSSL error queue is left empty either way.
template <class T, class Read, class Free>
std::unique_ptr<T, Free> read_pem(const std::string& text, Read read, Free free) {
  const std::unique_ptr<BIO, decltype(&BIO_free)> bio(
      BIO_new_mem_buf(text.data(), static_cast<int>(text.size())), &BIO_free);
  std::unique_ptr<T, Free> object(bio ? read(bio.get(), nullptr, nullptr, nullptr) : nullptr, free);
  ERR_clear_error();
  return object;
}

void check_tls_pair(const std::string& cert_pem, const std::string& key_pem) {
  const auto cert = read_pem<X509>(cert_pem, PEM_read_bio_X509, X509_free);
  if (!cert)
    throw InvalidInput("--tls-cert",
                       "no PEM certificate in the file (expected -----BEGIN CERTIFICATE-----)");
  const auto key = read_pem<EVP_PKEY>(key_pem, PEM_read_bio_PrivateKey, EVP_PKEY_free);
  if (!key)
    throw InvalidInput(
        "--tls-key",
        "no unencrypted PEM private key in the file (expected -----BEGIN ... PRIVATE "
        "KEY-----)");
  const bool match = X509_check_private_key(cert.get(), key.get()) == 1;
  ERR_clear_error();
  if (!match)
    throw InvalidInput("--tls-key",
                       "the key does not belong to the first certificate of --tls-cert");
}

}  // namespace

bool is_loopback_address(const std::string& address) {
  const std::string host = host_of(address);
  if (host == "localhost" || host == "::1") return true;
  // 127.0.0.0/8, written as four decimal numbers.
  int parts[4], used = 0;
  if (std::sscanf(host.c_str(), "%d.%d.%d.%d%n", &parts[0], &parts[1], &parts[2], &parts[3],
                  &used) == 4 &&
      used == static_cast<int>(host.size()))
    return parts[0] == 127 && parts[1] >= 0 && parts[1] <= 255 && parts[2] >= 0 &&
           parts[2] <= 255 && parts[3] >= 0 && parts[3] <= 255;
  return false;
}

struct Daemon::Impl {
  DaemonOptions options;
  std::string token, cert_pem, key_pem;
  std::unique_ptr<JobQueue> queue;
  Methods methods;
  std::unique_ptr<GridshellService> service;
  std::unique_ptr<grpc::Server> server;
  std::unique_ptr<HttpGateway> gateway;
  std::unique_ptr<PatchCache> patch_cache;
  int grpc_port = 0;
  std::atomic<bool> serving{false};
  std::mutex shutdown_mutex;
  bool started = false, stopped = false;

  void log(nlohmann::json line) {
    if (!options.log) return;
    line["time"] = utc_timestamp();
    const std::string text = line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    if (queue)
      queue->write_log(text);
    else
      *options.log << text << '\n' << std::flush;
  }
};

Daemon::Daemon(DaemonOptions options) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.options = std::move(options);
  const DaemonOptions& o = d.options;
  check_address(o.listen, "--listen");
  if (!o.http.empty()) check_address(o.http, "--http");
  if (o.tls_cert.empty() != o.tls_key.empty())
    throw InvalidInput("--tls-cert and --tls-key", "give both (certificate chain and its key)");
  const bool tls = !o.tls_cert.empty();
  for (const auto& [address, option] : {std::pair{o.listen, "--listen"}, {o.http, "--http"}}) {
    if (address.empty() || is_loopback_address(address) || o.insecure) continue;
    if (!tls || o.token_file.empty())
      throw InvalidInput(option,
                         "" + address +
                             " is not a loopback address; serving it needs TLS and a token "
                             "(--tls-cert, --tls-key, --token-file), or --insecure to serve it "
                             "without them");
  }
  // A bearer token in clear text can be read by anyone on the network path, and gRPC can check
  // it before every service (health and reflection included) only on TLS or on loopback.
  if (!o.token_file.empty() && !tls)
    for (const auto& [address, option] : {std::pair{o.listen, "--listen"}, {o.http, "--http"}})
      if (!address.empty() && !is_loopback_address(address))
        throw InvalidInput(option, "" + address +
                                       " is not a loopback address; a token (--token-file) is "
                                       "only sent there over TLS (--tls-cert, --tls-key)");
  if (o.workers < 0 || o.workers > 1024) throw InvalidInput("--workers", "must be 0..1024");
  if (o.queue < 0 || o.queue > 100000) throw InvalidInput("--queue", "must be 0..100000");
  if (o.request_threads < 0 || o.request_threads > 1024)
    throw InvalidInput("--request-threads", "must be 0..1024");
  if (o.redesign_threads < 0 || o.redesign_threads > 1024)
    throw InvalidInput("--redesign-threads", "must be 0..1024");
  if (o.progress_interval_ms < 0 || o.progress_interval_ms > 60000)
    throw InvalidInput("--progress-interval-ms", "must be 0..60000");
  if (o.max_message_mib < 1 || o.max_message_mib > 2047)
    throw InvalidInput("--max-message-mib", "must be 1..2047");
  if (o.cache_mib < 0 || o.cache_mib > 1 << 20)
    throw InvalidInput("--cache-mib", "must be 0 (no cache) to 1048576");
  for (const std::string& origin : o.cors_origins)
    if (origin.rfind("http://", 0) != 0 && origin.rfind("https://", 0) != 0)
      throw InvalidInput("--cors-origin",
                         "expected an origin like https://example.org:8443, got '" + origin + "'");
  if (o.http_body_limit_mib < 1 || o.http_body_limit_mib > 4096)
    throw InvalidInput("--http-body-limit-mib", "must be 1..4096");
  if (o.http_budgets.max_connections < 2 || o.http_budgets.max_connections > 100000)
    throw InvalidInput("--http-max-connections", "must be 2..100000");
  if (rlimit files{}; !o.http.empty() && getrlimit(RLIMIT_NOFILE, &files) == 0 &&
                      files.rlim_cur != RLIM_INFINITY &&
                      static_cast<rlim_t>(o.http_budgets.max_connections) + 128 > files.rlim_cur)
    throw InvalidInput("--http-max-connections",
                       std::to_string(o.http_budgets.max_connections) + " connections need about " +
                           std::to_string(o.http_budgets.max_connections + 128) +
                           " file descriptors; the limit is " + std::to_string(files.rlim_cur) +
                           " (ulimit -n)");
  if (o.http_budgets.max_client_connections < 1 ||
      o.http_budgets.max_client_connections > o.http_budgets.max_connections)
    throw InvalidInput("--http-max-client-connections", "must be 1..--http-max-connections");
  if (o.http_budgets.body_budget_mib < o.http_body_limit_mib ||
      o.http_budgets.body_budget_mib > 65536)
    throw InvalidInput("--http-body-budget-mib", "must be at least --http-body-limit-mib (" +
                                                     std::to_string(o.http_body_limit_mib) +
                                                     ") and at most 65536");
  if (!(o.http_budgets.stall_timeout_seconds >= 0.1 &&
        o.http_budgets.stall_timeout_seconds <= 3600))
    throw InvalidInput("--http-stall-timeout", "must be 0.1..3600 seconds");
  if (o.http_budgets.min_rate_kib < 1 || o.http_budgets.min_rate_kib > 1 << 20)
    throw InvalidInput("--http-min-rate-kib", "must be 1..1048576");
  if (!(o.shutdown_grace_seconds >= 0)) throw InvalidInput("--shutdown-grace", "must be >= 0");
  if (tls) {
    d.cert_pem = read_secret_file(o.tls_cert, "--tls-cert");
    d.key_pem = read_secret_file(o.tls_key, "--tls-key");
    check_tls_pair(d.cert_pem, d.key_pem);
  }
  if (!o.token_file.empty()) d.token = read_token_file(o.token_file);
}

Daemon::~Daemon() { shutdown(); }

void Daemon::start() {
  Impl& d = *impl_;
  const DaemonOptions& o = d.options;
  d.started = true;
  d.queue = std::make_unique<JobQueue>(
      JobQueue::Options{o.workers, o.queue, o.log, o.progress_interval_ms});
  d.patch_cache = std::make_unique<PatchCache>(static_cast<std::size_t>(o.cache_mib) << 20);
  RunSettings settings;
  settings.patch_cache = o.cache_mib > 0 ? d.patch_cache.get() : nullptr;
  settings.threads = o.request_threads;
  settings.redesign_threads = o.redesign_threads;
  d.methods = make_methods(settings);
  d.service = std::make_unique<GridshellService>(*d.queue, d.methods, d.token);

  static std::once_flag plugins;
  std::call_once(plugins, [] {
    grpc::EnableDefaultHealthCheckService(true);
    grpc::reflection::InitProtoReflectionServerBuilderPlugin();
    gpr_set_log_function(route_grpc_log);
  });
  {
    std::lock_guard lock(grpc_log_mutex);
    grpc_log_sinks.emplace_back(&d, [&d](nlohmann::json line) { d.log(std::move(line)); });
  }
  // The token is checked by an AuthMetadataProcessor before any service sees a call, so it
  // guards every service the server has: ours, health and reflection. gRPC runs processors only
  // on secure credentials: TLS, or, without TLS, its local credentials (plaintext HTTP/2 that
  // only accepts loopback peers; the Daemon constructor refuses a token without TLS elsewhere).
  std::shared_ptr<grpc::ServerCredentials> credentials;
  if (!o.tls_cert.empty()) {
    grpc::SslServerCredentialsOptions ssl;
    ssl.pem_key_cert_pairs.push_back({d.key_pem, d.cert_pem});
    credentials = grpc::SslServerCredentials(ssl);
  } else if (!d.token.empty()) {
    credentials = grpc::experimental::LocalServerCredentials(LOCAL_TCP);
  } else {
    credentials = grpc::InsecureServerCredentials();
  }
  if (!d.token.empty())
    credentials->SetAuthMetadataProcessor(
        make_token_processor(d.token, [&d](const std::string& method) {
          d.log({{"method", method},
                 {"transport", "grpc"},
                 {"status", "UNAUTHENTICATED"},
                 {"message", "missing or wrong bearer token"}});
        }));
  grpc::ServerBuilder builder;
  // gRPC sets SO_REUSEPORT by default: a second daemon on the same port would start and take
  // half of the connections. One daemon per port.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.AddListeningPort(o.listen, credentials, &d.grpc_port);
  const int max_message = o.max_message_mib * (1 << 20);
  builder.SetMaxReceiveMessageSize(max_message);
  builder.SetMaxSendMessageSize(max_message);
  builder.RegisterService(d.service.get());
  last_grpc_error.clear();
  d.server = builder.BuildAndStart();
  if (!d.server || d.grpc_port == 0) {
    const std::string reason = os_error_in(last_grpc_error);
    throw InvalidInput("--listen", "cannot listen on " + o.listen + ": " +
                                       (reason.empty() ? "the address cannot be bound" : reason));
  }

  if (!o.http.empty()) {
    HttpOptions http;
    http.address = o.http;
    http.body_limit = static_cast<std::size_t>(o.http_body_limit_mib) << 20;
    http.budgets = o.http_budgets;
    http.static_dir = o.static_dir;
    http.cors_origins = o.cors_origins;
    http.token = d.token;
    http.tls_cert_pem = d.cert_pem;
    http.tls_key_pem = d.key_pem;
    d.gateway =
        std::make_unique<HttpGateway>(http, *d.queue, d.methods, [&d] { return d.serving.load(); });
    try {
      d.gateway->start();
    } catch (...) {
      d.server->Shutdown();
      throw;
    }
  }
  auto* health = d.server->GetHealthCheckService();
  health->SetServingStatus(true);
  health->SetServingStatus(kServiceName, true);
  d.serving = true;
  d.log({{"event", "listening"},
         {"grpc", host_of(o.listen) + ":" + std::to_string(d.grpc_port)},
         {"http",
          o.http.empty() ? std::string() : host_of(o.http) + ":" + std::to_string(http_port())},
         {"tls", !d.cert_pem.empty()},
         {"token", !d.token.empty()},
         {"workers", d.queue->stats().workers},
         {"queue", o.queue},
         {"request_threads", o.request_threads},
         {"redesign_threads", o.redesign_threads},
         {"cache_mib", o.cache_mib}});
}

int Daemon::grpc_port() const { return impl_->grpc_port; }
int Daemon::http_port() const { return impl_->gateway ? impl_->gateway->port() : 0; }
bool Daemon::serving() const { return impl_->serving; }

JobQueue::Stats Daemon::stats() const {
  return impl_->queue ? impl_->queue->stats() : JobQueue::Stats{};
}

void Daemon::shutdown() {
  Impl& d = *impl_;
  std::lock_guard lock(d.shutdown_mutex);
  if (!d.started || d.stopped) return;
  d.stopped = true;
  d.serving = false;
  if (d.server) {
    auto* health = d.server->GetHealthCheckService();
    health->SetServingStatus(false);
    health->SetServingStatus(kServiceName, false);
  }
  d.log({{"event", "shutting down"},
         {"running", d.queue->stats().running},
         {"queued", d.queue->stats().queued}});
  d.queue->shutdown(
      std::chrono::milliseconds(static_cast<long long>(d.options.shutdown_grace_seconds * 1000)));
  if (d.server) d.server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  if (d.gateway) d.gateway->stop();
  {
    std::lock_guard log_lock(grpc_log_mutex);
    std::erase_if(grpc_log_sinks, [&d](const auto& sink) { return sink.first == &d; });
  }
  const JobQueue::Stats stats = d.queue->stats();
  d.log({{"event", "stopped"},
         {"succeeded", stats.succeeded},
         {"failed", stats.failed},
         {"cancelled", stats.cancelled},
         {"rejected", stats.rejected}});
}

}  // namespace gridshell::server
