// SPDX-License-Identifier: GPL-3.0-or-later
// A layout's patches designed and simulated, then measured together (see
// gridshell/application/layout.h, docs/multi-patch.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gridshell/application/convert.h"
#include "gridshell/application/convert_deployment.h"
#include "gridshell/application/deployment_job.h"
#include "gridshell/application/layout.h"
#include "gridshell/application/patch_cache.h"
#include "gridshell/design/members.h"
#include "gridshell/fabrication/layout_kit.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"
#include "gridshell/simulation/deployment_export.h"
#include "gridshell/simulation/layout_deployment.h"

namespace gridshell {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// A Progress that reports as `progress` does, each stage prefixed with the patch's name.
Progress patch_progress(const Progress& progress, const std::string& name) {
  return Progress(
      [progress, name](std::string_view stage, double fraction) {
        progress.report(name + ": " + std::string(stage), fraction);
      },
      progress.cancel_flag());
}

double max_normal_stress(const DeploymentRun& run) {
  double most = 0;
  for (const SimulatedLamella& l : run.lamellas) most = std::max(most, l.max_normal_stress);
  return most;
}

/// The whole in one equilibrium (docs/multi-patch.md, "Simulation of the whole").
struct JoinedWhole {
  std::vector<int> part_of;  ///< per patch: its part in the joined runs, -1 if none
  int anchors = 0;           ///< the anchors that hold the whole
  /// When no anchor lies on an outer side (a closed surface): the patch the whole stands on.
  std::string held_by;
  std::optional<JoinedDeploymentRun> without_notches, with_notches;
  std::string problem;  ///< why joining failed ("" if it did not)
};

/// Joins every patch that deployed, with the seam bolts between them and the anchors that hold
/// the whole, in the modes its patches ran (side by side when both did and threads allow).
/// Nothing to join (no seam between two built patches): no run.
JoinedWhole join_patches(const LayoutResult& cut, const std::vector<std::optional<Design>>& designs,
                         const std::vector<std::optional<DeploymentJob>>& jobs,
                         const std::vector<SeamJoints>& joints,
                         const v1::SimulationOptions& requested, const Progress& progress,
                         int threads) {
  JoinedWhole out;
  out.part_of.assign(cut.patches.size(), -1);
  std::vector<DeploymentPart> parts;
  std::vector<const TriangleMesh*> targets;
  const Design* first = nullptr;
  // The anchors that hold the whole (a closed one stands on its lowest patch), as the kit's
  // supports are.
  std::vector<const std::vector<Anchor>*> patch_anchors(cut.patches.size(), nullptr);
  std::vector<const Grid*> grids(cut.patches.size(), nullptr);
  for (size_t j = 0; j < cut.patches.size(); ++j)
    if (designs[j] && jobs[j]) patch_anchors[j] = &jobs[j]->anchors, grids[j] = &designs[j]->grid;
  const WholeAnchors held = whole_anchors(patch_anchors, grids, seam_members(joints));
  if (held.held_by >= 0) out.held_by = cut.patches[held.held_by].name;
  for (size_t j = 0; j < cut.patches.size(); ++j) {
    if (!designs[j] || !jobs[j]) continue;
    out.part_of[j] = static_cast<int>(parts.size());
    parts.push_back({&designs[j]->grid, held.patches[j]});
    out.anchors += static_cast<int>(parts.back().anchors.size());
    targets.push_back(&designs[j]->target.patch.mesh);
    if (!first) first = &*designs[j];
  }
  const std::vector<PartBolt> bolts = seam_bolts(joints, out.part_of);
  if (bolts.empty() || !first) return out;
  const v1::SimulationOptions options = resolve_simulation_options(requested);
  const bool without = options.notches() != "on", with = options.notches() != "off";
  const TriangleMesh target = merge_meshes(targets);
  const Progress whole_progress = patch_progress(progress, "whole");
  const int available = resolve_threads(threads);
  auto join = [&](bool notches, int run_threads) {
    SimulationOptions o = kernel_simulation_options(options, notches);
    o.threads = run_threads;
    std::vector<DeploymentPart> started = parts;
    for (size_t j = 0; j < cut.patches.size(); ++j)
      if (out.part_of[j] >= 0) {
        DeploymentPart& part = started[out.part_of[j]];
        const std::optional<DeploymentRun>& run =
            notches ? jobs[j]->with_notches : jobs[j]->without_notches;
        part.start = run ? &*run : nullptr;
        // Each patch deploys, its connections are tightened, then the seams are bolted: with
        // the sliders free the joined run of pillow_1 (16 patches) had not converged after 300 s,
        // locked it took 27 iterations, 16 s (docs/multi-patch.md).
        part.lock_connections = true;
      }
    return simulate_joined(started, bolts, target, first->lamella_width, first->lamella_thickness,
                           o, whole_progress);
  };
  try {
    if (without && with && available >= 2) {
      ParallelOptions parallel;
      parallel.threads = 2;
      parallel_for(
          2,
          [&](std::size_t run, const Progress&) {
            if (run == 0)
              out.without_notches = join(false, std::max(1, available / 2));
            else
              out.with_notches = join(true, std::max(1, available / 2));
          },
          progress, parallel);
    } else {
      if (without) out.without_notches = join(false, available);
      if (with) out.with_notches = join(true, available);
    }
  } catch (const Cancelled&) {
    throw;
  } catch (const std::exception& e) {
    // Reported with the patches alone: nothing they computed is lost.
    out.without_notches.reset();
    out.with_notches.reset();
    out.problem = std::string("joining the patches failed: ") + e.what();
  }
  return out;
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
  // Each patch's own design choices (Layout.Patch.alpha, members_u, members_v), checked too.
  for (int j = 0; j < request.layout().patches_size(); ++j) {
    DesignOptions scratch = in.options;
    v1::DesignOptions record = in.record;
    apply_patch_design(request.layout().patches(j), "layout.patches[" + std::to_string(j) + "]",
                       scratch, record);
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
  // One cross-section for the whole: the seams bolt two patches' lamellas together, the joined
  // simulation has one section, and a kit is cut from one stock. An automatic width is the
  // thinnest a patch would get alone (1 % of its longest side), so that every patch keeps the
  // clearance between its members that it would have alone; the thickness follows it.
  if (options.members.lamella_width == 0 && !built.empty()) {
    double width = std::numeric_limits<double>::infinity();
    for (size_t j : built)
      width = std::min(width, lamella_size(cut.patches[j].target->patch, options.members).width);
    options.members.lamella_width = width;
  }
  parallel_for(
      built.size(),
      [&](std::size_t k, const Progress& inner) {
        const size_t j = built[k];
        const LayoutPatch& patch = cut.patches[j];
        // One patch alone reports its own stages; side by side, parallel_for reports patches.
        const Progress step = parallel.threads == 1 ? patch_progress(progress, patch.name) : inner;
        try {
          const auto design_start = std::chrono::steady_clock::now();
          // Each patch's work (its maps from the layout's planar-angle check) is kept in the
          // daemon's cache: a redesign of this patch alone (Design with layout_patch) skips the
          // cut and the maps.
          PatchWork work = prepare_patch_work(*patch.target, options, step);
          if (settings.patch_cache) work.members = member_memo_for(work);
          auto shared = std::make_shared<const PatchWork>(std::move(work));
          // The patch's own choices over the common options.
          DesignOptions own = options;
          v1::DesignOptions record = in.record;
          if (static_cast<int>(j) < request.layout().patches_size())
            apply_patch_design(request.layout().patches(static_cast<int>(j)),
                               "layout.patches[" + std::to_string(j) + "]", own, record);
          designs[j] = design_on_patch(*shared, own, step);
          if (settings.patch_cache)
            settings.patch_cache->put(
                layout_patch_key(in.mesh, cut.layout, static_cast<int>(j), in.options), shared);
          design_results[j] = design_result(*designs[j], record, input + " " + patch.name,
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
      m.add_lamellas(layout_part_name(cut.patches[l.patch].name, l.family, l.member));
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
        b.add_members(layout_part_name(cut.patches[patch].name, family, member));
      ++bolts;
    }
  }
  whole_design.set_seam_bolts(bolts);

  // The whole deployment: each patch alone, then the whole joined in one equilibrium.
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
  }
  const bool any = std::any_of(main.begin(), main.end(), [](auto* r) { return r != nullptr; });
  const bool main_with = std::any_of(with.begin(), with.end(), [](auto* r) { return r; });
  const JoinedWhole joined =
      join_patches(cut, designs, jobs, joints, simulation, progress, threads);
  const JoinedDeploymentRun* main_joined =
      joined.with_notches ? &*joined.with_notches
                          : (joined.without_notches ? &*joined.without_notches : nullptr);

  for (size_t j = 0; j < count; ++j) {
    if (!jobs[j]) continue;
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
    if (main_joined && joined.part_of[j] >= 0) {
      const DeploymentRun& part = main_joined->parts[joined.part_of[j]];
      p.set_joined_rms(part.rms);
      p.set_joined_max_normal_stress(max_normal_stress(part));
    }
  }
  bool converged = any;
  for (const v1::LayoutDeployment::PatchDeployment& p : whole.patches())
    converged = converged && p.converged();
  for (const auto* run : {&joined.without_notches, &joined.with_notches})
    if (*run) converged = converged && (*run)->whole.converged;
  if (!joined.problem.empty()) converged = false;
  whole.set_converged(converged);
  const DeploymentRun alone = combine_runs(main);
  if (any) whole.set_rms_before_joining(alone.rms);
  if (joined.with_notches)
    whole.set_rms_with_notches(joined.with_notches->whole.rms);
  else if (main_with)
    whole.set_rms_with_notches(combine_runs(with).rms);
  if (joined.without_notches)
    whole.set_rms_without_notches(joined.without_notches->whole.rms);
  else if (std::any_of(without.begin(), without.end(), [](auto* r) { return r != nullptr; }))
    whole.set_rms_without_notches(combine_runs(without).rms);
  whole.set_grid_vertices(alone.grid_vertices);
  whole.set_seams_joined(main_joined != nullptr);
  for (const auto& [run, field] :
       {std::pair{&joined.without_notches, whole.mutable_joined_without_notches()},
        std::pair{&joined.with_notches, whole.mutable_joined_with_notches()}}) {
    if (!*run) continue;
    const DeploymentRun& w = (*run)->whole;
    field->set_notches(w.notches);
    field->set_rms(w.rms);
    field->set_max_deviation(w.max_deviation);
    field->set_converged(w.converged);
    field->set_iterations(w.iterations);
    field->set_termination(w.termination);
    field->set_gradient_norm(w.gradient_norm);
    field->set_anchors(joined.anchors);
    field->set_held_by(joined.held_by);
    field->set_max_normal_stress(max_normal_stress(w));
    if (simulation.bending_strength() > 0)
      field->set_bending_utilization(field->max_normal_stress() / simulation.bending_strength());
    for (const auto& [term, energy] : w.energies) (*field->mutable_energies())[term] = energy;
    field->set_energy_unit(w.energy_unit);
    field->set_seconds(w.seconds);
  }
  if (!joined.without_notches) whole.clear_joined_without_notches();
  if (!joined.with_notches) whole.clear_joined_with_notches();
  if (!joined.problem.empty()) {
    // Joining failed: the patches alone are still the answer, said so.
    v1::JoinedRun& failed =
        main_with ? *whole.mutable_joined_with_notches() : *whole.mutable_joined_without_notches();
    failed.set_notches(main_with);
    failed.set_converged(false);
    failed.set_termination(joined.problem);
  }
  // Stresses: of the whole joined when it was, else of the patches alone.
  for (const v1::LayoutDeployment::PatchDeployment& p : whole.patches()) {
    whole.set_max_normal_stress(
        std::max(whole.max_normal_stress(),
                 main_joined ? p.joined_max_normal_stress() : p.max_normal_stress()));
  }
  if (simulation.bending_strength() > 0 && any)
    whole.set_bending_utilization(whole.max_normal_stress() / simulation.bending_strength());
  if (main_joined) {
    whole.set_force_unit(main_joined->force_unit);
    // The joined whole's lamellas, for `compare`: each part's, named by its patch.
    for (size_t j = 0; j < count; ++j) {
      if (joined.part_of[j] < 0) continue;
      const DeploymentRun& part = main_joined->parts[joined.part_of[j]];
      fill_lamellas(part, whole.mutable_rods());
      for (size_t k = 0; k < part.lamellas.size(); ++k) whole.add_rod_patches(cut.patches[j].name);
    }
  }

  // Seams: before joining on the patches alone, after joining on the main joined run (its bolts
  // are the seams' joints in order, seam_bolts).
  const std::vector<SeamGaps> before = seam_gaps(joints, main);
  size_t bolt = 0;
  for (const SeamJoints& seam : joints) {
    const LayoutSeam& s = cut.seams[seam.seam];
    const SeamGaps* gaps = nullptr;
    for (const SeamGaps& g : before)
      if (g.seam == seam.seam) gaps = &g;
    const bool bolted = main_joined && joined.part_of[seam.lamellas[0].patch] >= 0 &&
                        joined.part_of[seam.lamellas[1].patch] >= 0;
    if (!gaps && !bolted) continue;
    v1::SeamDeployment& m = *whole.add_seams();
    m.add_corners(s.corners[0]);
    m.add_corners(s.corners[1]);
    for (const auto& [j, k] : s.uses) m.add_patches(cut.patches[j].name);
    if (gaps) {
      for (double g : gaps->gaps) m.add_gaps_before_joining(g);
      m.set_max_gap_before_joining(gaps->max_gap);
      whole.set_max_seam_gap_before_joining(
          std::max(whole.max_seam_gap_before_joining(), gaps->max_gap));
    }
    double squares = 0;
    if (bolted) {
      for (size_t k = 0; k < seam.joints.size() && bolt < main_joined->bolts.size(); ++k, ++bolt) {
        const BoltState& b = main_joined->bolts[bolt];
        m.add_gaps(b.gap);
        m.add_forces(b.force);
        m.set_max_gap(std::max(m.max_gap(), b.gap));
        m.set_max_force(std::max(m.max_force(), b.force));
        squares += b.gap * b.gap;
      }
      whole.set_max_bolt_force(std::max(whole.max_bolt_force(), m.max_force()));
    } else {
      for (double g : gaps->gaps) m.add_gaps(g), squares += g * g;
      m.set_max_gap(gaps->max_gap);
    }
    m.set_rms_gap(m.gaps_size() > 0 ? std::sqrt(squares / m.gaps_size()) : 0);
    whole.set_max_seam_gap(std::max(whole.max_seam_gap(), m.max_gap()));
  }

  // The whole's views: every patch's lamellas ("P1-g0" ...) and deviations on one colour scale,
  // of the whole joined when it was.
  if (any) {
    std::vector<std::pair<std::string, std::string>> parts;
    for (size_t j = 0; j < count; ++j) {
      if (!main[j]) continue;
      if (main_joined && joined.part_of[j] >= 0)
        parts.emplace_back(cut.patches[j].name,
                           deployed_obj(main_joined->parts[joined.part_of[j]],
                                        designs[j]->lamella_width, designs[j]->lamella_thickness));
      else
        parts.emplace_back(cut.patches[j].name, jobs[j]->deployed_obj);
    }
    v1::File& obj = *out.add_views();
    obj.set_name("deployed.obj");
    obj.set_content(merge_obj("gridshell deployed lamellas of " + input + ", " +
                                  std::to_string(parts.size()) + " patches" +
                                  (main_joined ? ", joined" : ""),
                              parts));
    v1::File& ply = *out.add_views();
    ply.set_name("deviation.ply");
    ply.set_content(deviation_ply(main_joined ? main_joined->whole : alone));
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
