// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell compare SCAN --design DIR --out DIR2`: a scan of the built grid registered to its
// simulated deployment (DIR/design.json + DIR/deployment.json, as `gridshell run` writes them),
// with distances to the deployment and to the target patch: compare.json and compare.ply.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/compare_job.h"
#include "gridshell/application/files.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::cli {
namespace {

struct CompareArguments {
  std::string scan;
  std::string design;
  std::string deployment;
  std::string out;
  bool quiet = false;
  int threads = 0;
  int icp_points = 10000;
};

/// A JSON file of `message`'s type; InvalidInput naming the file.
template <typename Message>
void read_message_file(const std::string& path, Message& message, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidInput(path, "cannot open " + what);
  std::stringstream text;
  text << in.rdbuf();
  try {
    from_json(text.str(), message);
  } catch (const InvalidInput& e) {
    throw InvalidInput(path, "not " + what + ": " + std::string(e.what()));
  }
}

v1::Deployment read_deployment_file(const std::string& path) {
  v1::Deployment deployment;
  read_message_file(path, deployment, "a gridshell deployment file");
  return deployment;
}

int run_compare(const CompareArguments& args) {
  namespace fs = std::filesystem;
  const auto started = std::chrono::steady_clock::now();
  const fs::path folder(args.design);
  const std::string design_path =
      fs::is_directory(folder) ? (folder / "design.json").string() : args.design;
  const std::string deployment_path =
      !args.deployment.empty() ? args.deployment
                               : (fs::path(design_path).parent_path() / "deployment.json").string();
  // A layout run's folder: its joined whole against the union of its patches.
  const std::optional<LayoutDesignFiles> layout = read_layout_design_file(design_path);
  v1::Design design;
  v1::Deployment deployment;
  v1::LayoutDeployment whole;
  if (layout) {
    read_message_file(deployment_path, whole, "a layout run's deployment file");
  } else {
    design = read_design_file(design_path);
    deployment = read_deployment_file(deployment_path);
  }
  if (!(args.icp_points >= 100 && args.icp_points <= 10000000))
    throw InvalidInput("--icp-points", "must be between 100 and 10000000");
  const std::vector<Vec3> scan = read_point_cloud(args.scan);
  check_point_cloud(scan, args.scan);
  prepare_output_folder(args.out);
  const Progress progress = make_progress(args.quiet);
  field_context().design = design_path;
  CompareOptions options;
  options.threads = args.threads;
  options.icp_points = args.icp_points;
  CompareJob job = layout ? run_compare_layout_job(scan, layout->patches, whole, options, progress)
                          : run_compare_job(scan, design, deployment, options, progress);
  finish_progress();
  v1::CompareReport& r = job.report;
  r.set_scan(fs::path(args.scan).filename().string());
  r.set_design(design_path);
  r.set_unit(layout ? whole.options().unit() : deployment.options().unit());
  r.set_seconds(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
  write_files({{"compare.json", to_json(r) + "\n"}, {"compare.ply", job.ply}}, args.out);
  std::printf("compare %s -> %s\n", args.scan.c_str(), args.out.c_str());
  std::printf("  points          %d read, %d used, %d rejected (farther than %.4g)\n",
              r.points_read(), r.points_used(), r.points_rejected(), r.rejection_distance());
  std::printf("  registration    %s; %d ICP iterations\n", r.coarse().c_str(), r.icp_iterations());
  const v1::Registration& g = r.registration();
  std::printf("  motion          rotation %.4g degrees, translation %.4g; residual %.3g",
              g.rotation_degrees(), g.translation(), g.residual());
  if (g.runner_up_transform_size() > 0)
    std::printf(", the next pose %.3g (ratio %.3g)\n", g.runner_up(), g.ambiguity());
  else
    std::printf(", no other pose left\n");
  if (g.ambiguity() > 0.9)
    std::printf(
        "  AMBIGUOUS       the scan fits another pose as well (registration.runner_up_transform\n"
        "                  in compare.json): the shape is symmetric where the scan sees it; scan\n"
        "                  more of it, or mark which end is which\n");
  for (const v1::DistanceStatistics* s : {&r.deployment(), &r.target()})
    std::printf("  %-15s RMS %.4g  mean %.4g  sd %.4g  p95 %.4g  max %.4g\n",
                s->reference() == "deployment" ? "to deployment" : "to target", s->rms(), s->mean(),
                s->standard_deviation(), s->p95(), s->max());
  std::printf("  wrote           compare.json compare.ply  (%.2f s)\n", r.seconds());
  return 0;
}

}  // namespace

Command add_compare_command(CLI::App& app) {
  auto args = std::make_shared<CompareArguments>();
  CLI::App* sub = app.add_subcommand(
      "compare", "Register a scan of the built grid to its simulation and measure deviations");
  sub->add_option("SCAN", args->scan, "point cloud: .ply (ASCII/binary), .xyz/.txt, .obj, .off")
      ->required();
  sub->add_option("--design", args->design,
                  "folder with design.json and deployment.json (gridshell run, also with --layout: "
                  "the whole), "
                  "or a design.json")
      ->required();
  sub->add_option("--deployment", args->deployment, "deployment.json (default: beside the design)");
  sub->add_option("--out", args->out, "output folder")->required();
  sub->add_option("--icp-points", args->icp_points, "scan points used for registration")
      ->capture_default_str();
  sub->add_option("--threads", args->threads, "threads for the distances (0 = all cores)");
  sub->add_flag("--quiet", args->quiet, "no progress line");
  return [args] { return run_compare(*args); };
}

}  // namespace gridshell::cli
