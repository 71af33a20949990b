// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell health --server HOST:PORT`: asks a daemon whether it is serving (gRPC health check).
#include <CLI/CLI.hpp>
#include <cstdio>

#include "commands.h"
#include "gridshell/foundation/errors.h"
#include "remote.h"

namespace gridshell::cli {

Command add_health_command(CLI::App& app) {
  struct Arguments {
    RemoteOptions remote;
  };
  auto args = std::make_shared<Arguments>();
  CLI::App* sub = app.add_subcommand(
      "health", "Ask gridshelld whether it is serving (exit 0 if it is, 1 otherwise)");
  add_remote_options(sub, args->remote);
  return [args] {
    if (!args->remote.remote())
      throw InvalidInput("--server", "required (HOST:PORT of gridshelld)");
    RemoteClient client(args->remote);
    const std::string overall = client.health();
    const std::string service = client.health("gridshell.v1.Gridshell");
    std::printf("%s: %s (gridshell.v1.Gridshell: %s)\n", args->remote.server.c_str(),
                overall.c_str(), service.c_str());
    return overall == "SERVING" && service == "SERVING" ? 0 : 1;
  };
}

}  // namespace gridshell::cli
