// SPDX-License-Identifier: GPL-3.0-or-later
// A layout's patches designed and simulated, then measured together (see
// gridshell/application/layout.h, docs/multi-patch.md).
#include <chrono>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "gridshell/application/convert.h"
#include "gridshell/application/deployment_job.h"
#include "gridshell/application/layout.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"
#include "gridshell/simulation/deployment_export.h"
#include "gridshell/simulation/layout_deployment.h"

namespace gridshell {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// A member's part name: the patch, its family and its index ("P2-g7"), as the kit names it.
std::string part_name(const std::string& patch, Family family, int index) {
  return patch + "-" + (family == Family::G ? "g" : "h") + std::to_string(index);
}

/// A Progress that reports as `progress` does, each stage prefixed with the patch's name.
Progress patch_progress(const Progress& progress, const std::string& name) {
  return Progress(
      [progress, name](std::string_view stage, double fraction) {
        progress.report(name + ": " + std::string(stage), fraction);
      },
      progress.cancel_flag());
}

}  // namespace

v1::LayoutRunResult run_layout_run(const v1::LayoutRunRequest& request, const Progress& progress,
                                   const RunSettings& settings) {
  const auto start = std::chrono::steady_clock::now();
  // Every option is checked before any work: the simulation's, then the design's.
  const v1::SimulationOptions simulation =
      prepare_simulation_options(request.simulation(), "simulation");
  DesignInputs in;
  try {
    prepare_design_options(request.design(), in);
  } catch (const Error& e) {
    rethrow_within(e, "design");
  }
  in.mesh = to_mesh(request.mesh(), &in.load);
  in.options.maps.threads = in.options.grid.threads = settings.threads;
  in.options.patch.coverability.threads = settings.threads;
  in.record.set_corners("layout");
  const std::string input = mesh_label(request.mesh());
  const RequestedLayout requested = cut_requested_layout(
      request.layout(), request.has_automatic() ? &request.automatic() : nullptr, in.mesh, in.load,
      patch_options(in.options), progress);
  const LayoutResult& cut = requested.cut;

  v1::LayoutRunResult out;
  *out.mutable_layout() = layout_result(requested, in.mesh, input);
  v1::LayoutReport& report = *out.mutable_layout()->mutable_report();
  const size_t count = cut.patches.size();
  std::vector<std::optional<Design>> designs(count);
  std::vector<std::optional<DeploymentJob>> jobs(count);
  std::vector<v1::DesignResult> design_results(count);
  std::vector<std::optional<Error>> failures(count);
  // The patches are independent: built side by side, each on a share of the threads (a patch's
  // own stages, and its two simulations, use fewer threads than there are cores for most of their
  // time). Results do not depend on the thread count.
  std::vector<size_t> built;
  for (size_t j = 0; j < count; ++j)
    if (cut.patches[j].target && !cut.patches[j].problem) built.push_back(j);
  const int threads = resolve_threads(settings.threads);
  ParallelOptions parallel;
  parallel.threads = std::max(1, std::min(threads, static_cast<int>(built.size())));
  parallel.stage = "layout: patches designed and simulated";
  const int inner_threads = std::max(1, threads / parallel.threads);
  DesignOptions options = in.options;
  options.maps.threads = options.grid.threads = options.patch.coverability.threads = inner_threads;
  parallel_for(
      built.size(),
      [&](std::size_t k, const Progress& inner) {
        const size_t j = built[k];
        const LayoutPatch& patch = cut.patches[j];
        // One patch alone reports its own stages; side by side, parallel_for reports patches.
        const Progress step = parallel.threads == 1 ? patch_progress(progress, patch.name) : inner;
        try {
          const auto design_start = std::chrono::steady_clock::now();
          designs[j] = design_grid(*patch.target, options, step);
          design_results[j] = design_result(*designs[j], in.record, input + " " + patch.name,
                                            in.mesh.vertex_count(), seconds_since(design_start));
          jobs[j] = run_deployment_job(design_results[j].design(), simulation, "design.json", step,
                                       inner_threads);
        } catch (const Cancelled&) {
          throw;
        } catch (const Error& e) {
          designs[j].reset();
          jobs[j].reset();
          failures[j] = e;
        }
      },
      progress, parallel);
  for (size_t j = 0; j < count; ++j) {
    v1::RunResult& run = *out.add_patches();
    if (designs[j]) *run.mutable_design() = std::move(design_results[j]);
    if (!failures[j]) continue;
    // The patch is not built: it says why, and the coverage does without it.
    const Error& e = *failures[j];
    const LayoutPatch& patch = cut.patches[j];
    v1::LayoutReport::PatchSummary& s = *report.mutable_patches(static_cast<int>(j));
    s.set_ok(false);
    s.set_problem_code(to_string(e.code()));
    s.set_problem_field(join_field("layout.patches[" + std::to_string(j) + "]", e.field()));
    s.set_problem(e.message());
    v1::LayoutReport::Uncovered& u = *report.add_uncovered();
    u.set_where(patch.name);
    u.set_area(patch.target->area);
    u.set_reason("its design: " + e.message());
    report.set_covered_area(report.covered_area() - patch.target->area);
    report.set_coverage(report.input_area() > 0 ? report.covered_area() / report.input_area() : 0);
  }

  // The seams: joints on the designs, gaps on the main runs.
  std::vector<const Design*> design_pointers(count, nullptr);
  for (size_t j = 0; j < count; ++j)
    if (designs[j]) design_pointers[j] = &*designs[j];
  const std::vector<SeamJoints> joints = seam_joints(cut, design_pointers);
  v1::LayoutDesign& whole_design = *out.mutable_design();
  whole_design.set_input(input);
  *whole_design.mutable_layout() = report;
  for (size_t j = 0; j < count; ++j)
    whole_design.add_patch_designs(designs[j] ? "patches/" + cut.patches[j].name + "/design.json"
                                              : "");
  int bolts = 0;
  for (const SeamJoints& seam : joints) {
    const LayoutSeam& s = cut.seams[seam.seam];
    v1::SeamDesign& m = *whole_design.add_seams();
    m.add_corners(s.corners[0]);
    m.add_corners(s.corners[1]);
    for (const SeamLamella& l : seam.lamellas) {
      m.add_patches(cut.patches[l.patch].name);
      m.add_lamellas(part_name(cut.patches[l.patch].name, l.family, l.member));
    }
    m.set_length(s.length);
    m.set_length_difference(seam.length_difference);
    for (const SeamJoint& joint : seam.joints) {
      v1::SeamJoint& b = *m.add_joints();
      b.set_s(joint.s);
      for (int k = 0; k < 3; ++k) b.add_point(joint.point[k]);
      for (const SeamLamella& l : seam.lamellas)
        b.add_lamella_s(l.forward ? joint.s : l.length - joint.s);
      for (const auto& [patch, family, member] : joint.ends)
        b.add_members(part_name(cut.patches[patch].name, family, member));
      ++bolts;
    }
  }
  whole_design.set_seam_bolts(bolts);

  // The whole deployment: each patch's runs together, and the seams' gaps on the main run.
  v1::LayoutDeployment& whole = *out.mutable_deployment();
  whole.set_design("design.json");
  *whole.mutable_options() = simulation;
  whole.set_diagonal(bounding_box_size(in.mesh).norm());
  std::vector<const DeploymentRun*> with(count, nullptr), without(count, nullptr),
      main(count, nullptr);
  for (size_t j = 0; j < count; ++j) {
    if (!jobs[j]) continue;
    if (jobs[j]->with_notches) with[j] = &*jobs[j]->with_notches;
    if (jobs[j]->without_notches) without[j] = &*jobs[j]->without_notches;
    main[j] = with[j] ? with[j] : without[j];
    const v1::Deployment& d = jobs[j]->deployment;
    v1::LayoutDeployment::PatchDeployment& p = *whole.add_patches();
    p.set_name(cut.patches[j].name);
    p.set_deployment("patches/" + cut.patches[j].name + "/deployment.json");
    if (d.has_rms_without_notches()) p.set_rms_without_notches(d.rms_without_notches());
    if (d.has_rms_with_notches()) p.set_rms_with_notches(d.rms_with_notches());
    p.set_converged(d.converged());
    p.set_grid_vertices(d.grid_vertices());
    const v1::SimulationRun& m = with[j] ? d.with_notches() : d.without_notches();
    p.set_max_normal_stress(m.max_normal_stress());
    if (m.has_bending_utilization()) p.set_bending_utilization(m.bending_utilization());
    whole.set_max_normal_stress(std::max(whole.max_normal_stress(), m.max_normal_stress()));
    if (m.has_bending_utilization())
      whole.set_bending_utilization(std::max(whole.bending_utilization(), m.bending_utilization()));
  }
  const bool any = std::any_of(main.begin(), main.end(), [](auto* r) { return r != nullptr; });
  bool converged = any;
  for (const v1::LayoutDeployment::PatchDeployment& p : whole.patches())
    converged = converged && p.converged();
  whole.set_converged(converged);
  if (std::any_of(with.begin(), with.end(), [](auto* r) { return r != nullptr; }))
    whole.set_rms_with_notches(combine_runs(with).rms);
  if (std::any_of(without.begin(), without.end(), [](auto* r) { return r != nullptr; }))
    whole.set_rms_without_notches(combine_runs(without).rms);
  const DeploymentRun combined = combine_runs(main);
  whole.set_grid_vertices(combined.grid_vertices);
  whole.set_seams_joined(false);
  for (const SeamGaps& gaps : seam_gaps(joints, main)) {
    const LayoutSeam& s = cut.seams[gaps.seam];
    v1::SeamDeployment& m = *whole.add_seams();
    m.add_corners(s.corners[0]);
    m.add_corners(s.corners[1]);
    for (const auto& [j, k] : s.uses) m.add_patches(cut.patches[j].name);
    for (double g : gaps.gaps) m.add_gaps(g);
    m.set_max_gap(gaps.max_gap);
    m.set_rms_gap(gaps.rms_gap);
    whole.set_max_seam_gap(std::max(whole.max_seam_gap(), gaps.max_gap));
  }

  // The whole's views: every patch's lamellas ("P1-g0" ...) and deviations on one colour scale.
  if (any) {
    std::vector<std::pair<std::string, std::string>> parts;
    for (size_t j = 0; j < count; ++j)
      if (main[j]) parts.emplace_back(cut.patches[j].name, jobs[j]->deployed_obj);
    v1::File& obj = *out.add_views();
    obj.set_name("deployed.obj");
    obj.set_content(merge_obj("gridshell deployed lamellas of " + input + ", " +
                                  std::to_string(parts.size()) + " patches",
                              parts));
    v1::File& ply = *out.add_views();
    ply.set_name("deviation.ply");
    ply.set_content(deviation_ply(combined));
  }
  // The per-patch simulation answers last: they take the jobs' views.
  for (size_t j = 0; j < count; ++j)
    if (jobs[j])
      *out.mutable_patches(static_cast<int>(j))->mutable_simulation() =
          simulate_result(std::move(*jobs[j]));
  whole.set_seconds(seconds_since(start));
  return out;
}

LayoutRunFiles layout_run_files(const v1::LayoutRunResult& result) {
  LayoutRunFiles files;
  files.whole = layout_files(result.layout());
  files.whole["design.json"] = to_json(result.design()) + "\n";
  files.whole["deployment.json"] = to_json(result.deployment()) + "\n";
  for (const v1::File& view : result.views()) files.whole[view.name()] = view.content();
  const v1::LayoutReport& report = result.layout().report();
  for (int j = 0; j < result.patches_size() && j < report.layout().patches_size(); ++j) {
    const v1::RunResult& run = result.patches(j);
    if (!run.has_design()) continue;
    files.patches.emplace_back(report.layout().patches(j).name(), run_files(run));
  }
  return files;
}

}  // namespace gridshell
