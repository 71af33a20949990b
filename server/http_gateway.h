// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld — the HTTP/JSON gateway (Boost.Beast on Asio) next to the gRPC service:
//
//   POST /v1/METHOD                      request in protobuf's JSON mapping -> result as JSON
//                                        (METHOD = patch|design|simulate|run|geodesic),
//                                        or, with "Accept: text/event-stream", progress and the
//                                        result as Server-Sent Events
//   GET  /healthz                        {"status": "SERVING"} (200) or NOT_SERVING (503)
//   GET  /...                            static files from the configured folder
//
// The same job queue and RPC table as gRPC serve the calls; status codes map as in
// docs/api.md. Connections run on one I/O thread; the computing, JSON parsing of requests and
// printing of results happen on the workers.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "http_budgets.h"
#include "job_queue.h"
#include "methods.h"

namespace gridshell::server {

struct HttpOptions {
  std::string address = "127.0.0.1:8080";  ///< HOST:PORT; port 0 picks a free one
  std::size_t body_limit = 256u << 20;     ///< largest request body, bytes (413 beyond)
  HttpBudgets budgets;     ///< one client must not be able to take the gateway from the others
  std::string static_dir;  ///< folder served for GET; empty = none
  std::string token;       ///< bearer token for /v1/* and /healthz; empty = none
  /// Origins (scheme://host[:port]) whose pages may call /v1/* from another origin (CORS);
  /// empty = none: browsers only let pages served by this gateway call it.
  std::vector<std::string> cors_origins;
  std::string tls_cert_pem, tls_key_pem;  ///< both set: HTTPS
};

class HttpGateway {
 public:
  /// `serving` answers /healthz.
  HttpGateway(HttpOptions options, JobQueue& queue, const Methods& methods,
              std::function<bool()> serving);
  ~HttpGateway();

  /// Binds and starts the I/O thread. Throws InvalidInput if the address cannot be used.
  void start();
  /// The bound port.
  int port() const;
  /// Stops accepting, lets responses in progress finish (up to 3 s), closes idle connections
  /// and joins the I/O thread. Idempotent.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gridshell::server
