// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/simulation/auto_anchors.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "gridshell/mesh/surface_distance.h"

namespace gridshell {
namespace {

/// Deviation of the deployed crossing (g, h) from the target: the larger of the two lamellas'
/// deviations at their rod vertices nearest the connection (rod vertices are uniform in rest
/// length; the connection sits at s̄ plus its slide).
double crossing_deviation(const Grid& grid, const DeploymentRun& run, const Crossing& crossing,
                          const SimulatedConnection& c) {
  double worst = 0;
  for (const bool on_g : {true, false}) {
    const Member& member = on_g ? grid.g[c.g] : grid.h[c.h];
    const SimulatedLamella& rod = run.lamellas[on_g ? c.g : static_cast<int>(grid.g.size()) + c.h];
    const int edges = static_cast<int>(rod.centerline.size()) - 1;
    if (edges < 1 || !(member.planar_length > 0) || rod.deviation.empty()) continue;
    const double s = (on_g ? crossing.s_bar_g : crossing.s_bar_h) + (on_g ? c.slide_g : c.slide_h);
    const int k =
        std::clamp(static_cast<int>(std::lround(s / (member.planar_length / edges))), 0, edges);
    worst = std::max(worst, rod.deviation[static_cast<size_t>(k)]);
  }
  return worst;
}

}  // namespace

AutoAnchorResult auto_interior_anchors(const Grid& grid, std::vector<Anchor> anchors,
                                       const TriangleMesh& target, double lamella_width,
                                       double lamella_thickness, const SimulationOptions& options,
                                       const AutoAnchorOptions& auto_options,
                                       const Progress& progress) {
  const int ng = static_cast<int>(grid.g.size()), nh = static_cast<int>(grid.h.size());
  const int trials = std::max(0, auto_options.max_anchors) + 1;
  int trial = 0;
  auto simulate = [&](const std::vector<Anchor>& with) {
    const Progress inner(
        [&, trial](std::string_view, double fraction) {
          progress.report("simulating (automatic inner anchors)", (trial + fraction) / trials);
        },
        progress.cancel_flag());
    return simulate_deployment(grid, with, target, lamella_width, lamella_thickness, options,
                               inner);
  };
  AutoAnchorResult result;
  result.run = simulate(anchors);
  result.rms_trials.push_back(result.run.rms);
  const bool complete = static_cast<int>(grid.crossings.size()) == ng * nh;
  const SurfaceDistance surface(target);
  const auto reached = [&] {
    return auto_options.goal_rms > 0 && result.run.rms <= auto_options.goal_rms;
  };
  while (complete && result.added < auto_options.max_anchors && !reached()) {
    // The farthest inner crossing not yet anchored.
    const SimulatedConnection* worst = nullptr;
    double worst_deviation = -1;
    for (const SimulatedConnection& c : result.run.connections) {
      if (c.g <= 0 || c.g >= ng - 1 || c.h <= 0 || c.h >= nh - 1) continue;
      if (std::any_of(anchors.begin(), anchors.end(),
                      [&](const Anchor& a) { return a.g == c.g && a.h == c.h; }))
        continue;
      const Crossing& crossing = grid.crossings[static_cast<size_t>(c.g) * nh + c.h];
      const double d = crossing_deviation(grid, result.run, crossing, c);
      if (d > worst_deviation) worst_deviation = d, worst = &c;
    }
    if (!worst) break;
    Anchor a;
    a.g = worst->g, a.h = worst->h;
    a.side = -1;
    a.position = grid.crossings[static_cast<size_t>(a.g) * nh + a.h].surface_point;
    a.normal = surface.normal_at_closest(a.position);
    std::vector<Anchor> with = anchors;
    with.push_back(a);
    ++trial;
    DeploymentRun run = simulate(with);
    result.rms_trials.push_back(run.rms);
    if (!(run.rms <= (1 - auto_options.min_improvement) * result.run.rms)) break;
    anchors = std::move(with);
    result.run = std::move(run);
    ++result.added;
  }
  result.anchors = std::move(anchors);
  progress.report("simulating (automatic inner anchors)", 1.0);
  return result;
}

}  // namespace gridshell
