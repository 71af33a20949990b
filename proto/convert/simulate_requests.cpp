// Simulate and Run requests -> kernel -> results (see gridshell/requests.h).
#include <string>
#include <utility>

#include "gridshell/deployment_job.h"
#include "gridshell/mesh/errors.h"
#include "gridshell/requests.h"

namespace gridshell {
namespace {

/// resolve_simulation_options names bare fields ("notches: ..."); API callers see the request
/// path, CLI users the flag.
std::string name_option(const std::string& message, FieldNames names, const std::string& prefix) {
  if (names == FieldNames::Request) return prefix + message;
  static const std::pair<std::string, std::string> kFlags[] = {
      {"notches", "--notches"},
      {"solver", "--solver"},
      {"material", "--material"},
      {"young_modulus", "--young"},
      {"shear_modulus", "--shear"},
      {"friction_mu", "--mu"},
      {"edges_per_interval", "--edges-per-interval"},
      {"max_iterations", "--max-iterations"},
      {"unit_in_meters", "--unit"},
      {"unit", "--unit"}};
  for (const auto& [field, flag] : kFlags)
    if (message.rfind(field + ":", 0) == 0) return flag + message.substr(field.size());
  return message;
}

v1::SimulateResult simulate(const v1::Design& design, const v1::SimulationOptions& options,
                            const std::string& name, const Progress& progress, int threads) {
  DeploymentJob job = run_deployment_job(design, options, name, progress, threads);
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
  return out;
}

}  // namespace

v1::SimulationOptions prepare_simulation_options(const v1::SimulationOptions& options,
                                                 FieldNames names, const std::string& prefix) {
  try {
    return resolve_simulation_options(options);
  } catch (const InvalidInput& e) {
    throw InvalidInput(name_option(e.what(), names, prefix));
  }
}

v1::SimulateResult run_simulate(const v1::SimulateRequest& request, const Progress& progress,
                                const RunSettings& settings) {
  const v1::SimulationOptions options =
      prepare_simulation_options(request.options(), settings.names);
  const std::string name = request.design_name().empty() ? "design.json" : request.design_name();
  return simulate(request.design(), options, name, progress, settings.threads);
}

v1::RunResult run_run(const v1::RunRequest& request, const Progress& progress,
                      const RunSettings& settings) {
  // Check the simulation options before the (longer) design runs.
  const v1::SimulationOptions options =
      prepare_simulation_options(request.simulation(), settings.names, "simulation.");
  v1::RunResult out;
  try {
    *out.mutable_design() = run_design(request.design(), progress, settings);
  } catch (const InvalidInput& e) {
    if (settings.names == FieldNames::CommandLine) throw;
    throw InvalidInput(std::string("design.") + e.what());  // the DesignRequest inside
  }
  *out.mutable_simulation() =
      simulate(out.design().design(), options, "design.json", progress, settings.threads);
  return out;
}

}  // namespace gridshell
