// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell geodesic MESH --source V [--method ..] [--compare cgal] [--repeat N] [--json]`:
// one single-source distance field, timed, optionally compared with a reference engine.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/requests.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/v1/reports.pb.h"
#include "remote.h"

namespace gridshell::cli {
namespace {

struct GeodesicArguments {
  std::string mesh;
  int source = 0;
  std::string method = "fast";
  std::string compare;
  int repeat = 1;
  bool json = false;
  std::string distances_out;
  RemoteOptions remote;
};

int run_geodesic(const GeodesicArguments& args) {
  const InputMesh input = load_input(args.mesh);
  v1::GeodesicRequest request;
  *request.mutable_mesh() = request_mesh(input);
  // The mesh goes out as loaded; the source is checked against the file's numbering here and
  // sent as an index into the loaded mesh.
  request.set_source(mesh_vertex(input, args.source, "--source"));
  request.set_method(args.method);
  request.set_compare(args.compare);
  if (args.repeat < 1) throw InvalidInput("--repeat", "must be at least 1");
  request.set_repeat(args.repeat);
  request.set_distances(!args.distances_out.empty());
  const Progress progress = make_progress(true);
  v1::GeodesicResult result;
  if (args.remote.remote()) {
    prepare_geodesic(request);  // bad flags fail here, before a remote call
    result = RemoteClient(args.remote).geodesic(request, progress);
  } else {
    result = gridshell::run_geodesic(request, progress, {});
  }
  v1::GeodesicReport report = result.report();
  report.set_input(std::filesystem::path(args.mesh).filename().string());
  report.set_source(args.source);
  if (!args.distances_out.empty()) {
    std::string text;
    char line[64];
    for (double d : result.distances()) {
      std::snprintf(line, sizeof line, "%.17g\n", d);
      text += line;
    }
    write_file_atomically(args.distances_out, text);
  }
  if (args.json) {
    std::cout << to_json(report, false) << "\n";
  } else {
    std::printf("%s: %d vertices, source %d, %s: %.3f ms per source (median of %d)%s\n",
                args.mesh.c_str(), report.vertices(), args.source, report.method().c_str(),
                report.ms_per_source(), report.repeats(),
                args.remote.remote() ? (" on " + args.remote.server).c_str() : "");
    if (!report.reference().empty())
      std::printf(
          "reference %s: %.3f ms per source (%.1fx), max abs diff %.3g, max rel diff %.3g\n",
          report.reference().c_str(), report.reference_ms_per_source(), report.speedup(),
          report.max_abs_diff(), report.max_rel_diff());
  }
  return 0;
}

}  // namespace

Command add_geodesic_command(CLI::App& app) {
  auto args = std::make_shared<GeodesicArguments>();
  CLI::App* sub =
      app.add_subcommand("geodesic", "Exact geodesic distances from one source vertex, timed");
  sub->add_option("MESH", args->mesh, "input mesh or example:NAME")->required();
  sub->add_option("--source", args->source, "source vertex (file order, from 0)")->required();
  sub->add_option("--method", args->method, "fast | cgal | heat")->capture_default_str();
  sub->add_option("--compare", args->compare, "reference method to compare with (e.g. cgal)");
  sub->add_option("--repeat", args->repeat, "repeats; the median time is reported")
      ->capture_default_str();
  sub->add_flag("--json", args->json, "print one JSON object");
  sub->add_option("--distances", args->distances_out, "write the distances, one per line");
  add_remote_options(sub, args->remote);
  return [args] { return run_geodesic(*args); };
}

}  // namespace gridshell::cli
