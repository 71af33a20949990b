// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld as a child process of a benchmark (bench service, interactive, abuse): started from
// next to this executable on ephemeral loopback ports, its log in a file, stopped with SIGTERM.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace gridshell::cli {

/// The whole file, "" if it cannot be read.
std::string read_all(const std::string& path);

class ChildDaemon {
 public:
  /// Runs `gridshelld --listen 127.0.0.1:0 ARGS...` (add "--http", "127.0.0.1:0" for the gateway)
  /// and waits until it logs its ports. Throws if it does not start.
  ChildDaemon(const std::string& log_path, const std::vector<std::string>& args);
  ~ChildDaemon();  ///< SIGTERM, then waits for it
  ChildDaemon(const ChildDaemon&) = delete;
  ChildDaemon& operator=(const ChildDaemon&) = delete;

  const std::string& address() const { return address_; }  ///< gRPC HOST:PORT
  int http_port() const { return http_port_; }             ///< 0 without the gateway
  pid_t pid() const { return pid_; }
  /// VmRSS, and VmHWM (the peak so far), in MiB.
  double resident_mib() const;
  double peak_resident_mib() const;
  std::string log() const { return read_all(log_path_); }
  /// CPU time of the daemon so far (all its threads, exited ones included), in s; 10 ms ticks.
  double cpu_seconds() const;
  bool running() const;      ///< not exited (a crash would show here)
  int open_sockets() const;  ///< sockets among its file descriptors

 private:
  double status_mib(const char* key) const;
  std::string log_path_;
  std::string address_;
  int http_port_ = 0;
  pid_t pid_ = -1;
};

}  // namespace gridshell::cli
