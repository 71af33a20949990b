// SPDX-License-Identifier: GPL-3.0-or-later
// Simulate and Run requests -> kernel -> results (see gridshell/requests.h).
#include <string>
#include <utility>

#include "gridshell/application/deployment_job.h"
#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

v1::SimulateResult simulate(const v1::Design& design, const v1::SimulationOptions& options,
                            const std::string& name, const Progress& progress, int threads,
                            bool files = false) {
  v1::SimulateResult out =
      simulate_result(run_deployment_job(design, options, name, progress, threads));
  if (files) {
    // Made before it is added: the bundle would take the new, empty view for the file.
    std::string json = simulate_files(out).at("deployment.json");
    v1::File* view = out.add_views();
    view->set_name("deployment.json");
    view->set_content(std::move(json));
  }
  return out;
}

}  // namespace

v1::SimulateResult simulate_result(DeploymentJob job) {
  v1::SimulateResult out;
  *out.mutable_deployment() = std::move(job.deployment);
  auto add_view = [&](const char* file, std::string content) {
    if (content.empty()) return;
    v1::File* view = out.add_views();
    view->set_name(file);
    view->set_content(std::move(content));
  };
  add_view("deployed.obj", std::move(job.deployed_obj));
  add_view("deviation.ply", std::move(job.deviation_ply));
  add_view("deployed_without_notches.obj", std::move(job.deployed_without_notches_obj));
  add_view("deviation_without_notches.ply", std::move(job.deviation_without_notches_ply));
  add_view("design-anchored.json", std::move(job.anchored_design));
  return out;
}

v1::SimulationOptions prepare_simulation_options(const v1::SimulationOptions& options,
                                                 const std::string& prefix) {
  try {
    return resolve_simulation_options(options);
  } catch (const Error& e) {
    rethrow_within(e, prefix);
  }
}

v1::SimulateResult run_simulate(const v1::SimulateRequest& request, const Progress& progress,
                                const RunSettings& settings) {
  const v1::SimulationOptions options = prepare_simulation_options(request.options(), "options");
  const std::string name = request.design_name().empty() ? "design.json" : request.design_name();
  return simulate(request.design(), options, name, progress, settings.threads, request.files());
}

v1::RunResult run_run(const v1::RunRequest& request, const Progress& progress,
                      const RunSettings& settings) {
  // Check the simulation options before the (longer) design runs.
  const v1::SimulationOptions options =
      prepare_simulation_options(request.simulation(), "simulation");
  v1::RunResult out;
  try {
    *out.mutable_design() = run_design(request.design(), progress, settings);
  } catch (const Error& e) {
    rethrow_within(e, "design");  // the DesignRequest inside
  }
  *out.mutable_simulation() =
      simulate(out.design().design(), options, "design.json", progress, settings.threads);
  return out;
}

}  // namespace gridshell
