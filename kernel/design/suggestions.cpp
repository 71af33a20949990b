// SPDX-License-Identifier: GPL-3.0-or-later
// Feasible suggestions for an infeasible design (suggestions.h; issue 18 item 4).
#include "gridshell/design/suggestions.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include "gridshell/design/distance_map_copy.h"
#include "gridshell/foundation/parallel.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

std::string degrees_text(const AlphaRange& range) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1) << range.min * 180 / kPi << ".."
      << range.max * 180 / kPi << " deg";
  return out.str();
}

std::string number(double value) {
  std::ostringstream out;
  out << std::setprecision(3) << value;
  return out.str();
}

/// `value` rounded to 3 significant digits, up or down.
double round3(double value, bool up) {
  const double scale = std::pow(10.0, 2 - std::floor(std::log10(value)));
  return (up ? std::ceil(value * scale - 1e-9) : std::floor(value * scale + 1e-9)) / scale;
}

/// The feasible planar angles on `maps` (and the patch's side lengths); false if there are none.
bool alpha_feasible(const DistanceMaps& maps, const std::array<double, 4>& sides,
                    const CladdingOptions& cladding, AlphaRange* range, const Progress& progress) {
  try {
    *range = feasible_alpha_range(maps, sides, cladding, progress.checker());
    return true;
  } catch (const Infeasible&) {
    return false;
  }
}

/// `map` resampled to `samples` x `samples` by bilinear interpolation (as the cladding functions
/// read it), corners exact.
DistanceMap resampled(const DistanceMap& map, int samples) {
  const int n = map.resolution() - 1;
  DistanceMap out;
  out.family = map.family;
  out.distances.resize(samples, samples);
  for (int i = 0; i < samples; ++i)
    for (int j = 0; j < samples; ++j) {
      const double x = static_cast<double>(i) * n / (samples - 1),
                   y = static_cast<double>(j) * n / (samples - 1);
      const int i0 = std::min(static_cast<int>(x), n - 1),
                j0 = std::min(static_cast<int>(y), n - 1);
      const double a = x - i0, b = y - j0;
      const Eigen::MatrixXd& D = map.distances;
      out.distances(i, j) = (1 - a) * (1 - b) * D(i0, j0) + a * (1 - b) * D(i0 + 1, j0) +
                            (1 - a) * b * D(i0, j0 + 1) + a * b * D(i0 + 1, j0 + 1);
    }
  return out;
}

/// The design with `options` on `work`; false (and nothing else) if it is infeasible.
bool design_ok(const PatchWork& work, const DesignOptions& options, AlphaRange* range,
               const Progress& progress) {
  try {
    const Design design = design_on_patch(work, options, progress.checker());
    *range = design.alpha_range;
    return true;
  } catch (const Infeasible&) {
    return false;
  } catch (const InvalidInput&) {
    return false;
  }
}

struct Search {
  const TriangleMesh& mesh;
  const PatchWork& work;
  const DesignOptions& options;
  const SuggestionOptions& limits;
  const Progress& progress;
  std::vector<DesignSuggestion> found;
  int designs = 0;
  int screens = 0;

  bool budget() const { return designs < limits.max_designs; }

  // Slope bounds: the smallest relaxation (k_max up, k_min down, or both by one factor) that
  // gives a feasible planar angle, searched on the maps resampled to 33 x 33 (a ninth of the
  // work of each check), then confirmed on the design's maps (the factor stepped up by 2 % while
  // they disagree, down by 0.5 % while they agree on less) and by a complete design.
  void slope_bounds() {
    const CladdingOptions& base = options.cladding;
    const double ladder[] = {1.02, 1.05, 1.1, 1.2, 1.35, 1.5, 2, 3, 5};
    struct Variant {
      bool raise_max, lower_min;
    };
    auto relaxed = [&](const Variant& v, double f) {
      CladdingOptions c = base;
      if (v.raise_max) c.k_max = base.k_max * f;
      if (v.lower_min) c.k_min = base.k_min / f;
      return c;
    };
    auto rounded = [&](const Variant& v, double f) {
      CladdingOptions c = relaxed(v, f);
      if (v.raise_max) c.k_max = round3(c.k_max, true);
      if (v.lower_min) c.k_min = round3(c.k_min, false);
      return c;
    };
    const std::array<double, 4> sides = side_lengths(work.target.patch);
    DistanceMaps coarse;
    const int samples = std::min(33, work.maps.g.resolution());
    coarse.g = resampled(work.maps.g, samples);
    coarse.h = resampled(work.maps.h, samples);
    bool any = false;
    for (const Variant& v : {Variant{true, false}, Variant{false, true}, Variant{true, true}}) {
      if (v.raise_max && v.lower_min && any) break;  // both only when neither alone works
      if (!budget()) return;
      progress.check();
      double lo = 1, hi = 0;
      AlphaRange range;
      for (double f : ladder) {
        if (alpha_feasible(coarse, sides, relaxed(v, f), &range, progress)) {
          hi = f;
          break;
        }
        lo = f;
      }
      if (hi == 0) continue;
      for (int k = 0; k < 6; ++k) {  // the smallest factor, to 1.5 % of the bracket's ratio
        const double mid = std::sqrt(lo * hi);
        if (alpha_feasible(coarse, sides, relaxed(v, mid), &range, progress))
          hi = mid;
        else
          lo = mid;
      }
      bool confirmed = alpha_feasible(work.maps, sides, rounded(v, hi), &range, progress);
      for (int step = 1; step < 10 && !confirmed; ++step) {
        hi *= 1.02;
        confirmed = alpha_feasible(work.maps, sides, rounded(v, hi), &range, progress);
      }
      if (!confirmed) continue;
      // The coarse maps may also ask for more than the design's: step down while they agree.
      for (int step = 0; step < 4 && hi / 1.005 > lo; ++step) {
        AlphaRange lower;
        if (!alpha_feasible(work.maps, sides, rounded(v, hi / 1.005), &lower, progress)) break;
        hi /= 1.005;
        range = lower;
      }
      const CladdingOptions c = rounded(v, hi);
      DesignOptions changed = options;
      changed.cladding = c;
      ++designs;
      if (!design_ok(work, changed, &range, progress)) continue;
      DesignSuggestion s;
      s.kind = DesignSuggestion::Kind::SlopeBounds;
      s.k_min = c.k_min;
      s.k_max = c.k_max;
      s.alpha = range;
      s.change = std::max(c.k_max / base.k_max, base.k_min / c.k_min) - 1;
      std::ostringstream text;
      text << "slope bounds";
      if (v.lower_min)
        text << " k_min " << number(c.k_min) << " (from " << number(base.k_min) << ")";
      if (v.raise_max)
        text << " k_max " << number(c.k_max) << " (from " << number(base.k_max) << ")";
      text << ": feasible planar angles " << degrees_text(range);
      s.description = text.str();
      found.push_back(s);
      any = true;
    }
  }

  // Corners: each corner moved along either of its patch sides by a fraction of that side.
  void corners() {
    const Patch& patch = work.target.patch;
    const TriangleMesh& pm = patch.mesh;
    // The input vertex nearest a patch point.
    auto nearest_input = [&](const Vec3& p) {
      int best = -1;
      double best_d = std::numeric_limits<double>::infinity();
      for (int v = 0; v < mesh.vertex_count(); ++v) {
        if (mesh.topology().vertex_faces[v].empty()) continue;
        const double d = (mesh.vertices()[v] - p).squaredNorm();
        if (d < best_d) best_d = d, best = v;
      }
      return best;
    };
    // The point at fraction t of a side's length from its start (or end).
    auto along = [&](const std::vector<int>& side, double t, bool from_end) {
      std::vector<Vec3> points;
      for (int v : side) points.push_back(pm.vertices()[v]);
      if (from_end) std::reverse(points.begin(), points.end());
      double total = 0;
      for (size_t k = 1; k < points.size(); ++k) total += (points[k] - points[k - 1]).norm();
      double left = t * total;
      for (size_t k = 1; k < points.size(); ++k) {
        const double l = (points[k] - points[k - 1]).norm();
        if (left <= l && l > 0)
          return Vec3(points[k - 1] + (left / l) * (points[k] - points[k - 1]));
        left -= l;
      }
      return points.back();
    };
    std::array<int, 4> base{};
    for (int i = 0; i < 4; ++i) base[i] = nearest_input(pm.vertices()[patch.corners[i]]);
    // The moves, in the order they are tried: 5 % then 10 %, each corner along either side.
    struct Move {
      double t = 0;
      int corner = 0;
      bool forward = true;
      std::array<int, 4> corners{};
      std::optional<TargetPatch> target;  // the moved patch, if its screen passed
    };
    std::vector<Move> moves;
    for (double t : {0.05, 0.1})
      for (int i = 0; i < 4; ++i)
        for (bool forward : {true, false}) {
          if (static_cast<int>(moves.size()) >= limits.max_corner_screens) break;
          // Along side i (towards corner i+1) or side i-1 (towards corner i-1).
          const Vec3 p =
              forward ? along(patch.sides[i], t, false) : along(patch.sides[(i + 3) % 4], t, true);
          std::array<int, 4> moved = base;
          moved[i] = nearest_input(p);
          if (moved[i] == base[i]) continue;
          moves.push_back({t, i, forward, moved, std::nullopt});
        }
    // Each move screened on coarse maps (R = 32, a third of the solves): the new patch cut and
    // smoothed, its maps and its feasible planar angles. The screens are independent, so they
    // run side by side (one thread each); only a move that passes gets the design's maps and a
    // complete design, in the order above, so the suggestions do not depend on the threads.
    // On a large input the screens cut their patches out of a copy simplified to 4000 vertices
    // that keeps every corner (the maps' edge collapse); a move that passes is cut again out of
    // the input before its design.
    std::optional<SimplifiedMesh> copy;
    if (mesh.vertex_count() > kSimplifiedSearchAbove && !moves.empty()) {
      std::vector<int> keep;
      for (const Move& move : moves)
        keep.insert(keep.end(), move.corners.begin(), move.corners.end());
      try {
        copy = simplify_mesh(mesh, kDefaultMapVertices, keep, progress);
      } catch (const InvalidInput&) {
        // A surface CGAL cannot simplify is screened on itself, as a small one is.
      }
    }
    std::vector<char> passed(moves.size(), 0);
    parallel_for(moves.size(),
                 [&](size_t m, const Progress& inner) {
                   try {
                     std::array<int, 4> corners = moves[m].corners;
                     if (copy)
                       for (int& v : corners) v = copy->of_input[v];
                     TargetPatch target = make_target_patch(
                         copy ? copy->mesh : mesh, CornerSpec::at_vertices(corners),
                         patch_options(options), inner.checker());
                     const GeodesicSolver solver(target.patch.mesh, options.patch.geodesic);
                     DistanceMapOptions coarse = options.maps;
                     coarse.resolution =
                         std::min(32, options.maps.resolution > 0 ? options.maps.resolution : 32);
                     coarse.threads = 1;
                     const DistanceMaps maps =
                         compute_distance_maps(target.patch, solver, coarse, inner.checker());
                     AlphaRange coarse_range;
                     if (alpha_feasible(maps, side_lengths(target.patch), options.cladding,
                                        &coarse_range, inner)) {
                       passed[m] = 1;
                       if (!copy) moves[m].target = std::move(target);
                     }
                   } catch (const Infeasible&) {
                   } catch (const InvalidInput&) {
                   }
                 },
                 progress, {options.maps.threads, "suggestions", 0.3, 0.8});
    for (Move& move : moves) {
      if (!budget() || static_cast<int>(found.size()) >= 2 * limits.count) return;
      progress.check();
      ++screens;
      if (!passed[&move - moves.data()]) continue;
      // The moves come in order of their change: once `count` suggestions change no more than
      // this one, no later one can be among the best (ranked by change, earlier first), so its
      // complete design is not needed.
      const auto no_larger = std::count_if(found.begin(), found.end(),
                                           [&](const auto& f) { return f.change <= move.t; });
      if (no_larger >= limits.count) return;
      try {
        ++designs;
        if (!move.target)
          move.target = make_target_patch(mesh, CornerSpec::at_vertices(move.corners),
                                          patch_options(options), progress.checker());
        const PatchWork other =
            prepare_patch_work(std::move(*move.target), options, progress.checker());
        AlphaRange range;
        if (!design_ok(other, options, &range, progress)) continue;
        DesignSuggestion s;
        s.kind = DesignSuggestion::Kind::Corners;
        s.corners = move.corners;
        s.alpha = range;
        s.change = move.t;
        const int i = move.corner;
        std::ostringstream text;
        text << "move corner c" << i << " " << static_cast<int>(std::lround(100 * move.t))
             << "% along side "
             << (move.forward ? "c" + std::to_string(i) + "-c" + std::to_string((i + 1) % 4)
                              : "c" + std::to_string(i) + "-c" + std::to_string((i + 3) % 4))
             << " (to input vertex " << move.corners[i] << "): feasible planar angles "
             << degrees_text(range);
        s.description = text.str();
        found.push_back(s);
      } catch (const Infeasible&) {
      } catch (const InvalidInput&) {
      }
    }
  }

  // Members: narrower lamellas, or fewer explicit members.
  void members(const Error& failure) {
    const bool width = failure.reason() == Reason::LamellasTooWide;
    const bool g = failure.reason() == Reason::GMembersDoNotFit,
               h = failure.reason() == Reason::HMembersDoNotFit;
    if (!width && !g && !h) return;
    const LamellaSize size = lamella_size(work.target.patch, options.members);
    for (double f : {0.8, 0.6, 0.4, 0.25, 0.15, 0.1}) {
      if (!budget()) return;
      progress.check();
      DesignOptions changed = options;
      changed.members.lamella_width = size.width * f;
      changed.members.lamella_thickness = size.thickness;
      AlphaRange range;
      ++designs;
      if (!design_ok(work, changed, &range, progress)) continue;
      DesignSuggestion s;
      s.kind = DesignSuggestion::Kind::LamellaWidth;
      s.lamella_width = changed.members.lamella_width;
      s.alpha = range;
      s.change = 1 - f;
      s.description = "lamella width " + number(s.lamella_width) + " (from " + number(size.width) +
                      "): feasible planar angles " + degrees_text(range);
      found.push_back(s);
      break;
    }
    const int base_g = options.members_g > 0 ? options.members_g : options.members.min_members;
    const int base_h = options.members_h > 0 ? options.members_h : options.members.min_members;
    for (int fewer = 1; fewer <= 2; ++fewer) {
      if (!budget()) return;
      progress.check();
      DesignOptions changed = options;
      if (width || g) changed.members_g = std::max(1, base_g - fewer);
      if (width || h) changed.members_h = std::max(1, base_h - fewer);
      AlphaRange range;
      ++designs;
      if (!design_ok(work, changed, &range, progress)) continue;
      DesignSuggestion s;
      s.kind = DesignSuggestion::Kind::Members;
      s.members_g = changed.members_g;
      s.members_h = changed.members_h;
      s.alpha = range;
      s.change = static_cast<double>(fewer) / std::max(base_g, base_h);
      std::ostringstream text;
      text << "members";
      if (changed.members_g) text << " u " << changed.members_g;
      if (changed.members_h) text << " v " << changed.members_h;
      text << ": feasible planar angles " << degrees_text(range);
      s.description = text.str();
      found.push_back(s);
      break;
    }
  }
};

}  // namespace

const char* to_string(DesignSuggestion::Kind kind) {
  switch (kind) {
    case DesignSuggestion::Kind::SlopeBounds:
      return "slope_bounds";
    case DesignSuggestion::Kind::Corners:
      return "corners";
    case DesignSuggestion::Kind::Members:
      return "members";
    case DesignSuggestion::Kind::LamellaWidth:
      return "lamella_width";
  }
  return "";
}

std::vector<DesignSuggestion> suggest_feasible_designs(
    const TriangleMesh& mesh, const PatchWork& work, const DesignOptions& options,
    const Error& failure, const SuggestionOptions& limits, const Progress& progress) {
  Search search{mesh, work, options, limits, progress, {}, 0};
  if (limits.count <= 0 || failure.code() != ErrorCode::Infeasible) return {};
  progress.report("suggestions", 0.0);
  const bool members = failure.reason() == Reason::LamellasTooWide ||
                       failure.reason() == Reason::GMembersDoNotFit ||
                       failure.reason() == Reason::HMembersDoNotFit;
  if (members) {
    search.members(failure);
  } else {
    search.slope_bounds();
    progress.report("suggestions", 0.3);
    search.corners();
  }
  std::stable_sort(
      search.found.begin(), search.found.end(),
      [](const DesignSuggestion& a, const DesignSuggestion& b) { return a.change < b.change; });
  if (static_cast<int>(search.found.size()) > limits.count) search.found.resize(limits.count);
  progress.report("suggestions", 1.0);
  return search.found;
}

}  // namespace gridshell
