// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/deployment_job.h"

#include <cmath>
#include <cstdlib>
#include <exception>
#include <optional>

#include "gridshell/convert.h"
#include "gridshell/convert_deployment.h"
#include "gridshell/files.h"
#include "gridshell/mesh/errors.h"
#include "gridshell/mesh/parallel.h"
#include "gridshell/simulation/auto_anchors.h"
#include "gridshell/simulation/deployment_export.h"

namespace gridshell {
namespace {

/// The fields are those of a SimulationOptions message (the caller names where it came from).
void require(bool ok, const std::string& field, const std::string& problem) {
  if (!ok) throw InvalidInput(field, problem);
}

bool positive(double v) { return std::isfinite(v) && v > 0; }

/// lo <= value <= hi (false for NaN).
bool within(double value, double lo, double hi) { return value >= lo && value <= hi; }

/// SimulationOptions.anchor_goal when it is not given: 0.25 % of the patch diagonal, half the
/// accuracy bar of issue 18 (0.5 %); the paper's built models reached 0.22-0.55 % (Table 1 RMS2
/// over their patch diagonals). docs/decisions.md, "--interior-anchors auto".
constexpr double kDefaultAnchorGoalPercent = 0.25;

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
  const SimulationOptions defaults;
  if (o.notches().empty()) o.set_notches("both");
  if (o.solver().empty()) o.set_solver("newton");
  require(o.solver() == "newton" || o.solver() == "ceres", "solver",
          "expected newton or ceres, got '" + o.solver() + "'");
  require(o.notches() == "on" || o.notches() == "off" || o.notches() == "both", "notches",
          "expected on, off or both, got '" + o.notches() + "'");
  // Material: a preset by name (default lime wood); explicit moduli override its values (without
  // a name the material is then "custom"). "custom" by name needs both moduli.
  if (o.material() != "custom") {
    const bool overridden = o.young_modulus() != 0 || o.shear_modulus() != 0;
    Material preset;
    try {
      preset = material_by_name(o.material().empty() ? defaults.material.name : o.material());
    } catch (const Error& e) {
      rethrow_within(e, "material");
    }
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
  require(within(o.young_modulus(), 1e3, 1e13), "young_modulus",
          "must be a number of pascals between 1e3 and 1e13");
  require(within(o.shear_modulus(), 1e3, 1e13), "shear_modulus",
          "must be a number of pascals between 1e3 and 1e13; give it with the Young's modulus or "
          "pick a material");
  for (const auto& [value, name] : {std::pair{o.bending_strength(), "bending_strength"},
                                    std::pair{o.shear_strength(), "shear_strength"}})
    require(value == 0 || within(value, 1e3, 1e11), name,
            "must be a number of pascals between 1e3 and 1e11 (or 0: unknown)");
  auto fill = [](double value, double fallback) { return value == 0 ? fallback : value; };
  o.set_friction_mu(fill(o.friction_mu(), defaults.friction_mu));
  o.set_friction_epsilon(fill(o.friction_epsilon(), defaults.friction_epsilon));
  o.set_notch_limit_weight(fill(o.notch_limit_weight(), defaults.notch_limit_weight));
  o.set_connection_position_weight(
      fill(o.connection_position_weight(), defaults.connection_position_weight));
  o.set_connection_direction_weight(
      fill(o.connection_direction_weight(), defaults.connection_direction_weight));
  o.set_anchor_position_weight(fill(o.anchor_position_weight(), defaults.anchor_position_weight));
  o.set_anchor_direction_weight(
      fill(o.anchor_direction_weight(), defaults.anchor_direction_weight));
  o.set_edges_per_interval(fill(o.edges_per_interval(), defaults.edges_per_interval));
  o.set_reference_extent(fill(o.reference_extent(), defaults.reference_extent));
  o.set_gradient_tolerance(fill(o.gradient_tolerance(), defaults.gradient_tolerance));
  if (o.max_iterations() == 0) o.set_max_iterations(defaults.max_iterations);
  require(positive(o.friction_mu()) && o.friction_mu() <= 100, "friction_mu",
          "must be a positive number up to 100 (the paper's is 0.1)");
  require(positive(o.friction_epsilon()) && o.friction_epsilon() < 0.5, "friction_epsilon",
          "must be in (0, 0.5)");
  for (const auto& [value, name] :
       {std::pair{o.connection_position_weight(), "connection_position_weight"},
        {o.connection_direction_weight(), "connection_direction_weight"},
        {o.anchor_position_weight(), "anchor_position_weight"},
        {o.anchor_direction_weight(), "anchor_direction_weight"},
        {o.notch_limit_weight(), "notch_limit_weight"}})
    require(positive(value) && value <= 1e6, name, "must be a positive number up to 1e6");
  require(within(o.reference_extent(), 1e-3, 1e6), "reference_extent",
          "must be between 1e-3 and 1e6");
  require(positive(o.gradient_tolerance()) && o.gradient_tolerance() <= 1, "gradient_tolerance",
          "must be in (0, 1]");
  require(std::isfinite(o.edges_per_interval()) && o.edges_per_interval() >= 1 &&
              o.edges_per_interval() <= 64,
          "edges_per_interval", "must be between 1 and 64");
  require(o.max_iterations() >= 1 && o.max_iterations() <= 1000000, "max_iterations",
          "must be between 1 and 1000000");
  require(o.interior_anchors().empty() || o.interior_anchors() == "auto", "interior_anchors",
          "expected auto or nothing (the design's anchors), got '" + o.interior_anchors() + "'");
  if (o.has_anchor_goal()) {
    require(o.interior_anchors() == "auto", "anchor_goal",
            "applies to interior_anchors auto only (the search stops there)");
    require(within(o.anchor_goal(), 0, 100), "anchor_goal",
            "must be a percentage of the patch diagonal between 0 and 100");
  } else if (o.interior_anchors() == "auto") {
    o.set_anchor_goal(kDefaultAnchorGoalPercent);
  }
  if (o.unit_in_meters() == 0) o.set_unit_in_meters(parse_length_unit(o.unit()));
  require(o.unit_in_meters() == 0 || within(o.unit_in_meters(), 1e-9, 1e6), "unit_in_meters",
          "must be between 1e-9 and 1e6 metres (or 0 for unknown)");
  return o;
}

SimulationOptions kernel_simulation_options(const v1::SimulationOptions& o, bool notches) {
  SimulationOptions k;
  k.material = {o.material(), o.young_modulus(), o.shear_modulus(), o.bending_strength(),
                o.shear_strength()};
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
  // The lamella's cross-section comes from the design's options: its errors name them there.
  const auto in_design_options = [](auto&& run) {
    try {
      return run();
    } catch (const InvalidInput& e) {
      if (e.field() == "lamella_width" || e.field() == "lamella_thickness")
        throw InvalidInput("design.options." + e.field(), e.message());
      throw;
    }
  };
  auto simulate = [&](const SimulationOptions& o) {
    return in_design_options([&] {
      return simulate_deployment(design.grid, design.anchors, target, design.lamella_width,
                                 design.lamella_thickness, o, progress);
    });
  };
  std::optional<AutoAnchorResult> found;
  AutoAnchorOptions auto_options;
  const size_t design_anchors = design.anchors.size();
  if (options.interior_anchors() == "auto") {
    // The search simulates the main run (with notches if it is asked for) once per trial
    // anchor; the other run then holds the anchors found.
    const SimulationOptions& search = with ? with_options : without_options;
    auto_options.goal_rms = options.anchor_goal() / 100 * bounding_box_size(target).norm();
    found = in_design_options([&] {
      return auto_interior_anchors(design.grid, design.anchors, target, design.lamella_width,
                                   design.lamella_thickness, search, auto_options, progress);
    });
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
