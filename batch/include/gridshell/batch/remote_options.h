// SPDX-License-Identifier: GPL-3.0-or-later
// How a client reaches gridshelld: the CLI's remote runs (--server, --tls, ...) and the rows of a
// sweep, whose `gridshell run` gets the same flags. Plain data; the gRPC client is the CLI's.
#pragma once

#include <string>

namespace gridshell {

struct RemoteOptions {
  std::string server;      ///< HOST:PORT of gridshelld; empty = run in-process
  bool tls = false;        ///< TLS, verifying the daemon against the system's roots
  std::string tls_ca;      ///< PEM file of the CA (or the self-signed certificate); implies TLS
  std::string token_file;  ///< file holding the bearer token
  double timeout = 0;      ///< deadline in seconds, 0 = none
  bool remote() const { return !server.empty(); }
};

}  // namespace gridshell
