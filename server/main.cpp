// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld — the gridshell daemon: gRPC service gridshell.v1.Gridshell (with health checking
// and reflection) and its HTTP/JSON gateway, both on loopback unless told otherwise.
//
//   gridshelld [--listen HOST:PORT] [--http HOST:PORT] [--workers N] [--queue N] ...
//
// Logs one JSON line per request on stderr. SIGTERM or SIGINT: stop accepting, let running work
// finish for --shutdown-grace seconds, cancel the rest, exit 0. Exit 2 for bad options.
#include <pthread.h>
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <filesystem>
#include <iostream>

#include "daemon.h"
#include "gridshell/application/options.h"
#include "gridshell/foundation/errors.h"

int main(int argc, char** argv) {
  using namespace gridshell;
  server::DaemonOptions options;
  options.log = &std::cerr;
  bool no_http = false;
  CLI::App app{"gridshelld: the gridshell daemon (gRPC service and HTTP/JSON gateway)"};
  app.set_version_flag("--version", "gridshelld 0.1.0");
  app.add_option("--listen", options.listen, "gRPC address HOST:PORT (port 0: any free port)")
      ->capture_default_str();
  app.add_option("--http", options.http, "HTTP/JSON gateway address HOST:PORT")
      ->capture_default_str();
  app.add_flag("--no-http", no_http, "no HTTP/JSON gateway");
  app.add_option("--workers", options.workers, "concurrent requests (0 = one per core)")
      ->capture_default_str();
  app.add_option("--queue", options.queue, "requests that may wait; one more is refused")
      ->capture_default_str();
  app.add_option("--request-threads", options.request_threads,
                 "kernel threads per request (0 = all cores)")
      ->capture_default_str();
  app.add_option("--redesign-threads", options.redesign_threads,
                 "kernel threads of a redesign on a cached patch (0 = all cores)")
      ->capture_default_str();
  app.add_option("--progress-interval-ms", options.progress_interval_ms,
                 "progress events per request and stage at most this often (0 = all)")
      ->capture_default_str();
  app.add_option("--max-message-mib", options.max_message_mib, "largest gRPC message, MiB")
      ->capture_default_str();
  app.add_option("--http-body-limit-mib", options.http_body_limit_mib,
                 "largest HTTP request body, MiB")
      ->capture_default_str();
  app.add_option("--http-max-connections", options.http_budgets.max_connections,
                 "HTTP connections in all; beyond, the least recently active waiting one closes")
      ->capture_default_str();
  app.add_option("--http-max-client-connections", options.http_budgets.max_client_connections,
                 "HTTP connections from one client address (the same rule within it)")
      ->capture_default_str();
  app.add_option("--http-body-budget-mib", options.http_budgets.body_budget_mib,
                 "HTTP request bodies held at once, MiB; beyond, stalled ones give way or 503")
      ->capture_default_str();
  app.add_option("--http-stall-timeout", options.http_budgets.stall_timeout_seconds,
                 "seconds an HTTP header may take, and a body or answer may stand still")
      ->capture_default_str();
  app.add_option("--http-min-rate-kib", options.http_budgets.min_rate_kib,
                 "KiB/s an HTTP body or answer must average after the stall timeout")
      ->capture_default_str();
  // The web page, served at / when it is built (scripts/build.sh); --static elsewhere, or
  // --no-static for none.
  options.static_dir = GRIDSHELL_WEB_DIR;
  bool no_static = false;
  app.add_option("--static", options.static_dir,
                 "folder of static files served over HTTP (default: the built web page)")
      ->capture_default_str();
  app.add_flag("--no-static", no_static, "serve no static files (the HTTP API only)");
  app.add_option("--cache-mib", options.cache_mib,
                 "memory for per-patch design work kept for redesigns, MiB (0 = none)")
      ->capture_default_str();
  app.add_option("--cors-origin", options.cors_origins,
                 "an origin (https://host:port) whose pages may call the API; repeatable");
  app.add_option("--tls-cert", options.tls_cert, "PEM certificate chain (TLS on both ports)");
  app.add_option("--tls-key", options.tls_key, "PEM private key of the certificate");
  app.add_option("--token-file", options.token_file,
                 "file holding the bearer token every call must carry");
  app.add_flag("--insecure", options.insecure,
               "allow a non-loopback address without TLS and token");
  app.add_option("--shutdown-grace", options.shutdown_grace_seconds,
                 "seconds running work may finish on SIGTERM before it is cancelled")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "error: " << e.what() << "\n(run 'gridshelld --help' for usage)\n";
    return 2;
  }
  // The default folder only when the page was built; an explicit --static must exist.
  if (no_static ||
      (app.count("--static") == 0 && !std::filesystem::is_directory(GRIDSHELL_WEB_DIR)))
    options.static_dir.clear();
  if (no_http) options.http.clear();

  // Every connection is a file descriptor: take what the system allows (the soft limit is often
  // 1024, the hard one much higher); the Daemon checks its connection budget against it.
  rlimit files{};
  if (getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur < files.rlim_max) {
    files.rlim_cur = files.rlim_max;
    setrlimit(RLIMIT_NOFILE, &files);
  }

  // Signals are taken by sigwait below only: block them before any thread starts.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);

  try {
    load_site_materials();  // GRIDSHELL_MATERIALS, before the description is answered
    server::Daemon daemon(options);
    daemon.start();
    int signal = 0;
    sigwait(&signals, &signal);
    daemon.shutdown();
    return 0;
  } catch (const InvalidInput& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "error: internal: " << e.what() << "\n";
    return 1;
  }
}
