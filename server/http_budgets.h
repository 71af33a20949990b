// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld — the HTTP gateway's budgets, in the units of their flags; defined here once, read by
// the daemon's options (DaemonOptions::http_budgets, main.cpp's flags) and by the gateway
// (HttpOptions::budgets). What each one does: docs/api.md, "Budgets of the HTTP gateway".
#pragma once

#include <chrono>
#include <cmath>
#include <cstddef>

namespace gridshell::server {

struct HttpBudgets {
  /// Open connections in all, and from one client address. A new connection beyond either
  /// makes the least recently active connection that waits for a request (idle, or its header
  /// or body arriving) give way: of the same address first, then of the address that has the
  /// most. Only when every connection is busy with an answer is the new one refused (503).
  int max_connections = 512;         ///< --http-max-connections
  int max_client_connections = 128;  ///< --http-max-client-connections
  /// Request bodies held at once (being received, or waiting for their answer): a body reserves
  /// its Content-Length when its header arrives (a chunked one the body limit). A request that
  /// does not fit makes bodies stalled for a second or more give way, or gets 503 Retry-After.
  int body_budget_mib = 128;  ///< --http-body-budget-mib
  /// Once a request's first byte arrives its header must be complete within this time; a body
  /// or an answer must move at least this often, and after this grace average min_rate_kib.
  double stall_timeout_seconds = 10;  ///< --http-stall-timeout
  int min_rate_kib = 64;              ///< --http-min-rate-kib, both directions

  std::size_t body_budget_bytes() const { return static_cast<std::size_t>(body_budget_mib) << 20; }
  std::chrono::milliseconds stall_timeout() const {
    return std::chrono::milliseconds(std::lround(stall_timeout_seconds * 1000));
  }
  std::size_t min_rate_bytes() const { return static_cast<std::size_t>(min_rate_kib) << 10; }
};

}  // namespace gridshell::server
