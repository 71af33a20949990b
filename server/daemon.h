// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld — the daemon as an object: the job queue, the gRPC service (with health checking and
// reflection) and the HTTP/JSON gateway, started and stopped together. main.cpp runs one; the
// tests run one in-process on ephemeral loopback ports.
#pragma once

#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "http_budgets.h"
#include "job_queue.h"

namespace gridshell::server {

struct DaemonOptions {
  std::string listen = "127.0.0.1:50051";  ///< gRPC HOST:PORT; port 0 picks a free one
  std::string http = "127.0.0.1:8080";     ///< HTTP HOST:PORT; empty = no gateway
  int workers = 0;                         ///< concurrent requests; 0 = one per hardware thread
  int queue = 16;                          ///< requests that may wait for a worker
  /// Kernel threads inside one request. 1: the pool already keeps every core busy with
  /// concurrent requests, and more would oversubscribe them. Results do not depend on it.
  int request_threads = 1;
  /// Kernel threads of a redesign on a cached patch (ᾱ or member counts changed: the grid stage
  /// only, a client waiting for it while a slider moves); 0 = all cores. Short bursts, so they
  /// may take the cores of the pool for a moment. Results do not depend on it.
  int redesign_threads = 0;
  int progress_interval_ms = 100;  ///< progress events per request and stage at most this often
  int max_message_mib = 256;       ///< largest gRPC message, either direction
  /// Largest HTTP request body. 32 MiB holds a 250k-triangle mesh as an ASCII OBJ sent as file
  /// bytes (about 13 MB, 17 MB in base64) or as packed arrays in JSON (about 13 MB), with room.
  int http_body_limit_mib = 32;
  HttpBudgets http_budgets;               ///< the gateway's budgets (http_budgets.h)
  int cache_mib = 512;                    ///< per-patch design work kept for redesigns; 0 = none
  std::vector<std::string> cors_origins;  ///< origins allowed to call /v1/* from their pages
  std::string static_dir;                 ///< served by the gateway for GET; empty = none
  std::string tls_cert, tls_key;          ///< PEM files: TLS on both ports
  std::string token_file;                 ///< bearer token required on every call
  bool insecure = false;                  ///< allow a non-loopback address without TLS and token
  double shutdown_grace_seconds = 10;     ///< running work may finish for this long on shutdown
  std::ostream* log = nullptr;            ///< JSON lines; null = none
};

/// True for 127.0.0.0/8, ::1 and "localhost" (the host part of HOST:PORT).
bool is_loopback_address(const std::string& address);

class Daemon {
 public:
  /// Checks the options, including the security rule: a non-loopback address needs TLS and a
  /// token unless `insecure`. Reads the certificate, key and token files. Throws InvalidInput.
  explicit Daemon(DaemonOptions options);
  ~Daemon();  ///< shutdown()

  /// Binds both ports and starts serving. Throws InvalidInput if an address cannot be used.
  void start();
  int grpc_port() const;
  int http_port() const;  ///< 0 without gateway

  /// Health NOT_SERVING, new calls refused (UNAVAILABLE), running work finishes for up to the
  /// grace period and is cancelled after it, then both servers stop. Idempotent.
  void shutdown();

  bool serving() const;
  JobQueue::Stats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gridshell::server
