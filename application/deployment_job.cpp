// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/application/deployment_job.h"

#include <cmath>
#include <cstdlib>
#include <exception>
#include <optional>

#include "gridshell/application/convert.h"
#include "gridshell/application/convert_deployment.h"
#include "gridshell/application/files.h"
#include "gridshell/application/options.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"
#include "gridshell/simulation/auto_anchors.h"
#include "gridshell/simulation/deployment_export.h"

namespace gridshell {
namespace {

bool positive(double v) { return std::isfinite(v) && v > 0; }

}  // namespace

double parse_length_unit(const std::string& unit, const std::string& field) {
  if (unit.empty()) return 0;
  if (unit == "mm") return 1e-3;
  if (unit == "cm") return 1e-2;
  if (unit == "m") return 1;
  if (unit == "in") return 0.0254;
  if (unit == "ft") return 0.3048;
  char* end = nullptr;
  const double v = std::strtod(unit.c_str(), &end);
  if (end && *end == '\0' && positive(v)) return v;
  throw InvalidInput(
      field, "expected mm, cm, m, in, ft or a positive number of metres, got '" + unit + "'");
}

v1::SimulationOptions resolve_simulation_options(v1::SimulationOptions o) {
  // Each option against its description (options.cpp); fields as in SimulationOptions (the
  // caller names where the message came from).
  const auto check = [](const char* name, double value) {
    return check_option(option_spec("simulation", name), value, name);
  };
  const auto choose = [](const char* name, const std::string& value) {
    return check_option(option_spec("simulation", name), value, name);
  };
  const auto fill = [](const char* name, double value) {
    return value == 0 ? std::strtod(option_spec("simulation", name).default_value.c_str(), nullptr)
                      : value;
  };
  o.set_notches(choose("notches", o.notches().empty() ? "both" : o.notches()));
  o.set_solver(choose("solver", o.solver().empty() ? "newton" : o.solver()));
  // Material: a preset by name (default lime wood); explicit moduli override its values (without
  // a name the material is then "custom"). "custom" by name needs both moduli.
  if (o.material() != "custom") {
    const bool overridden = o.young_modulus() != 0 || o.shear_modulus() != 0;
    const std::string& name = choose(
        "material",
        o.material().empty() ? option_spec("simulation", "material").default_value : o.material());
    const Material preset = material_by_name(name);
    if (o.young_modulus() == 0) o.set_young_modulus(preset.young_modulus);
    if (o.shear_modulus() == 0) o.set_shear_modulus(preset.shear_modulus);
    // A preset's strengths go with its name: moduli given without a name make a custom
    // material, whose strengths are unknown unless given too.
    if (!(o.material().empty() && overridden)) {
      if (o.bending_strength() == 0) o.set_bending_strength(preset.bending_strength);
      if (o.shear_strength() == 0) o.set_shear_strength(preset.shear_strength);
    }
    o.set_material(o.material().empty() && overridden ? "custom" : preset.name);
  }
  // 1 kPa (soft foam) to 10 TPa (beyond diamond): outside, energies and stresses overflow.
  if (o.young_modulus() == 0)
    throw InvalidInput("young_modulus", "a custom material needs its Young's modulus");
  if (o.shear_modulus() == 0)
    throw InvalidInput("shear_modulus",
                       "a custom material needs its shear modulus; give it with the Young's "
                       "modulus or pick a material");
  for (const char* name : {"young_modulus", "shear_modulus", "bending_strength", "shear_strength"})
    check(name, o.GetReflection()->GetDouble(o, o.GetDescriptor()->FindFieldByName(name)));
  o.set_friction_mu(check("friction_mu", fill("friction_mu", o.friction_mu())));
  o.set_friction_epsilon(check("friction_epsilon", fill("friction_epsilon", o.friction_epsilon())));
  o.set_notch_limit_weight(
      check("notch_limit_weight", fill("notch_limit_weight", o.notch_limit_weight())));
  o.set_connection_position_weight(
      check("connection_position_weight",
            fill("connection_position_weight", o.connection_position_weight())));
  o.set_connection_direction_weight(
      check("connection_direction_weight",
            fill("connection_direction_weight", o.connection_direction_weight())));
  o.set_anchor_position_weight(
      check("anchor_position_weight", fill("anchor_position_weight", o.anchor_position_weight())));
  o.set_anchor_direction_weight(check(
      "anchor_direction_weight", fill("anchor_direction_weight", o.anchor_direction_weight())));
  o.set_edges_per_interval(
      check("edges_per_interval", fill("edges_per_interval", o.edges_per_interval())));
  o.set_reference_extent(check("reference_extent", fill("reference_extent", o.reference_extent())));
  o.set_gradient_tolerance(
      check("gradient_tolerance", fill("gradient_tolerance", o.gradient_tolerance())));
  o.set_max_iterations(
      static_cast<int>(check("max_iterations", fill("max_iterations", o.max_iterations()))));
  choose("interior_anchors", o.interior_anchors());
  if (o.has_anchor_goal()) {
    if (o.interior_anchors() != "auto")
      throw InvalidInput("anchor_goal",
                         "applies to interior_anchors auto only (the search stops there)");
    check("anchor_goal", o.anchor_goal());
  } else if (o.interior_anchors() == "auto") {
    o.set_anchor_goal(
        std::strtod(option_spec("simulation", "anchor_goal").default_value.c_str(), nullptr));
  }
  if (o.unit_in_meters() == 0) o.set_unit_in_meters(parse_length_unit(o.unit()));
  check("unit_in_meters", o.unit_in_meters());
  return o;
}

SimulationOptions kernel_simulation_options(const v1::SimulationOptions& o, bool notches) {
  SimulationOptions k;
  k.material.name = o.material();
  k.material.young_modulus = o.young_modulus();
  k.material.shear_modulus = o.shear_modulus();
  k.material.bending_strength = o.bending_strength();
  k.material.shear_strength = o.shear_strength();
  k.notches = notches;
  k.solver = o.solver() == "ceres" ? SimulationSolver::Ceres : SimulationSolver::Newton;
  k.friction_mu = o.friction_mu();
  k.friction_epsilon = o.friction_epsilon();
  k.notch_limit_weight = o.notch_limit_weight();
  k.connection_position_weight = o.connection_position_weight();
  k.connection_direction_weight = o.connection_direction_weight();
  k.anchor_position_weight = o.anchor_position_weight();
  k.anchor_direction_weight = o.anchor_direction_weight();
  k.edges_per_interval = o.edges_per_interval();
  k.reference_extent = o.reference_extent();
  k.gradient_tolerance = o.gradient_tolerance();
  k.max_iterations = o.max_iterations();
  k.unit_in_meters = o.unit_in_meters();
  return k;
}

DeploymentJob run_deployment_job(const v1::Design& design_message,
                                 const v1::SimulationOptions& requested,
                                 const std::string& design_name, const Progress& progress,
                                 int threads) {
  v1::SimulationOptions options;
  Design design;
  try {
    options = resolve_simulation_options(requested);
  } catch (const Error& e) {
    rethrow_within(e, "options");
  }
  try {
    design = design_from_proto(design_message);
  } catch (const Error& e) {
    rethrow_within(e, "design");
  }
  options.set_lamella_width(design.lamella_width);
  options.set_lamella_thickness(design.lamella_thickness);
  DeploymentJob job;
  const bool without = options.notches() != "on", with = options.notches() != "off";
  const TriangleMesh& target = design.target.patch.mesh;
  SimulationOptions without_options = kernel_simulation_options(options, false),
                    with_options = kernel_simulation_options(options, true);
  without_options.threads = with_options.threads = threads;
  // Both runs are independent: with two or more threads they run side by side, half the threads
  // each (results do not depend on the thread count).
  const int available = resolve_threads(threads);
  // The lamella's cross-section was checked with the design (design_from_proto names
  // design.options.lamella_width), so the kernel's own check of it cannot fail here.
  auto simulate = [&](const SimulationOptions& o) {
    return simulate_deployment(design.grid, design.anchors, target, design.lamella_width,
                               design.lamella_thickness, o, progress);
  };
  std::optional<AutoAnchorResult> found;
  AutoAnchorOptions auto_options;
  const size_t design_anchors = design.anchors.size();
  if (options.interior_anchors() == "auto") {
    // The search simulates the main run (with notches if it is asked for) once per trial
    // anchor; the other run then holds the anchors found.
    const SimulationOptions& search = with ? with_options : without_options;
    auto_options.goal_rms = options.anchor_goal() / 100 * bounding_box_size(target).norm();
    found = auto_interior_anchors(design.grid, design.anchors, target, design.lamella_width,
                                  design.lamella_thickness, search, auto_options, progress);
    design.anchors = found->anchors;
    (with ? job.with_notches : job.without_notches) = std::move(found->run);
    if (with && without) job.without_notches = simulate(without_options);
  } else if (without && with && available >= 2) {
    without_options.threads = with_options.threads = std::max(1, available / 2);
    ParallelOptions parallel;
    parallel.threads = 2;
    // Each run reports its own stages through `progress` (thread-safe) and polls its flag.
    parallel_for(
        2,
        [&](std::size_t run, const Progress&) {
          if (run == 0)
            job.without_notches = simulate(without_options);
          else
            job.with_notches = simulate(with_options);
        },
        progress, parallel);
  } else {
    if (without) job.without_notches = simulate(without_options);
    if (with) job.with_notches = simulate(with_options);
  }
  job.anchors = design.anchors;
  job.deployment = to_proto(job.without_notches ? &*job.without_notches : nullptr,
                            job.with_notches ? &*job.with_notches : nullptr, options, design_name);
  if (found) {
    v1::Design anchored = design_message;  // the design as simulated: for supports, re-runs
    for (size_t k = design_anchors; k < design.anchors.size(); ++k) {
      to_proto(design.anchors[k], job.deployment.add_added_anchors());
      to_proto(design.anchors[k], anchored.add_anchors());
    }
    for (double rms : found->rms_trials) job.deployment.add_anchor_trial_rms(rms);
    job.deployment.set_anchor_goal_rms(auto_options.goal_rms);
    job.anchored_design = to_json(anchored) + "\n";
  }
  // One colour scale for both runs so the two PLY files compare at a glance.
  double top = 0;
  for (const auto* run : {&job.without_notches, &job.with_notches})
    if (*run) top = std::max(top, (*run)->max_deviation);
  const DeploymentRun& main = job.with_notches ? *job.with_notches : *job.without_notches;
  job.deployed_obj = deployed_obj(main, design.lamella_width, design.lamella_thickness);
  job.deviation_ply = deviation_ply(main, top);
  if (job.with_notches && job.without_notches) {
    job.deployed_without_notches_obj =
        deployed_obj(*job.without_notches, design.lamella_width, design.lamella_thickness);
    job.deviation_without_notches_ply = deviation_ply(*job.without_notches, top);
  }
  return job;
}

}  // namespace gridshell
