// SPDX-License-Identifier: GPL-3.0-or-later
// Cladding functions and the feasible range of the planar angle ᾱ (paper Section 4.3).
//
// Cladding function (cladding_function):
//   Δ = D − D̄ on the R x R grid, entry (i,j) at (u1,u2) = (i,j)/(R-1). F is the zero set of the
//   piecewise-linear interpolant of Δ, extracted by marching squares and traced as one path:
//   - Signs: a value < 0 is "negative", everything else (including exact zeros) "positive"
//     (symbolic perturbation: 0 counts as +ε). Every cell then has 0, 2 or 4 sign changes on its
//     edges, and the traced path is a simple curve even where Δ vanishes at grid vertices.
//   - Crossing points: linear interpolation on the edge, always from its lower-index vertex, so
//     the two cells sharing an edge produce bit-identical points. A zero vertex yields a crossing
//     exactly at the vertex. A point within 1e-6 grid steps of the previous one is dropped
//     (rounding-level zig-zags where Δ vanishes along grid vertices); (1,1) is kept exact.
//   - Saddle cells (signs + - + -): the pairing is decided by the sign of the cell-centre average
//     (the same rule in every cell, so the decomposition is consistent). A saddle cell on the
//     path means two zero curves meet there (or pass within one grid cell): the zero set
//     branches, which branch F follows is an accident of rounding, and F is invalid.
//   - The corners (0,0) and (1,1) are zeros by construction (boundary members: same length in
//     both patches). Their Δ is forced to exactly 0 when |Δ| <= kCornerTolerance · scale (scale =
//     the largest of D's four corner values); a larger difference means the two maps don't
//     describe the same side lengths and makes F invalid. With the corner exactly 0 (= +),
//     the path leaves (0,0) through the unique edge of cell (0,0) at the corner that changes
//     sign; if both or neither do, D − D̄ has one sign next to the corner inside the square and
//     no curve starts there. The path is followed cell by cell until it reaches the square's
//     boundary; it is a cladding function only if it arrives exactly at (1,1).
//   - Slopes: every segment must have Δu2/Δu1 in (k_min, k_max); a vertical segment
//     (|Δu1| <= 1e-12) gets the paper's slope vertical_c · Δu2; a segment with Δu1 < 0 runs
//     backwards and is invalid. `problem` names the worst segment.
//   Only the grid cells along the path are visited, so a trace costs O(R) once Δ is known.
//
// Feasible range of ᾱ (feasible_alpha_range), problem (3) of the paper:
//   Feasible(ᾱ) = the convex planar patch exists AND the diagonal condition (eq. 2) holds AND
//   both cladding functions are valid. The paper minimises / maximises ᾱ by SQP with numerical
//   gradients. That is fragile here: the constraints are segment slopes of a polyline whose
//   segments appear, vanish and change cells as ᾱ moves, so they are piecewise and
//   discontinuous in ᾱ, and the feasible set is decided by a yes/no indicator; finite-difference
//   gradients of it are zero or meaningless and SQP can stall or report a local answer.
//   Instead we bracket and bisect, which is deterministic and globally robust on one variable:
//   0. The search interval [a, b] is the part of the open convex interval of
//      convex_alpha_interval where every planar inner angle lies in [m, pi - m], m =
//      CladdingOptions::min_planar_angle (a designer bound on P̄, paper 4.3; default 30 degrees).
//      Without it ᾱ_min is ~0 on most of the paper's examples: a collapsed linkage that the
//      cladding criteria accept but on which no lamella fits. The bounds are monotone in ᾱ, so
//      [a, b] is one interval; its ends are found by sampling and bisection to 1e-12.
//   1. ᾱ_k = a + k (b - a) / N, k = 0..N, N = 128.
//   2. Maximal runs of consecutive feasible samples. On every example we tried, the feasible set
//      is two windows, one on each side of the surface angle α (near ᾱ = α, D - D̄ is a small
//      difference dominated by the surface's non-developable part and F degenerates; on a
//      developable patch D = D̄ at ᾱ = α exactly). AlphaRange holds one window: the FIRST run
//      (smallest ᾱ, the paper's compact choice: "we choose ᾱ_min") among the runs at least half
//      as long as the longest one, so a short run caused by grid noise cannot win. Every ᾱ
//      sampled inside the returned range is feasible.
//   3. Each end of the run is refined by bisection between the last infeasible and the first
//      feasible sample to a bracket below 1e-6 rad (a or b themselves if they are feasible); the
//      feasible end of the bracket is returned, so cladding_function is valid at exactly
//      AlphaRange::min and ::max.
//   A feasible window narrower than the sample step (b - a)/N <= 1.4 degrees can be missed;
//   if no sample at all is feasible, a second pass with 8x finer sampling is tried before
//   giving up.
//   Each evaluation needs the planar boundary points (2R) and the two traces; the planar
//   distances are computed only at the vertices of visited cells, with the same arithmetic as
//   planar_distance_map, so the internal evaluation agrees bit for bit with cladding_function
//   on planar_distance_map.
//   If nothing is feasible, Infeasible names the constraint: the diagonal condition with the
//   ranges of e, f, ē, f̄ if it fails everywhere; otherwise the problems of the cladding
//   functions (and the diagonal condition) at the sampled ᾱ that came closest (fewest failed
//   constraints, then smallest violation).
#include "gridshell/design/cladding.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <utility>

#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;
/// |Δ| at the corners (0,0), (1,1) below this fraction of the map's scale is rounding.
constexpr double kCornerTolerance = 1e-9;
/// Consecutive points closer than this fraction of a grid step (in both coordinates) are merged:
/// where Δ vanishes at vertices up to rounding (e.g. a rectangle against a parallelogram, whose
/// diagonal members have equal lengths for every ᾱ), rounding creates zig-zags of length
/// ~1e-16 whose slopes are meaningless.
constexpr double kMergeFraction = 1e-6;
/// |Δu1| below this makes a segment vertical.
constexpr double kVertical = 1e-12;
constexpr int kSamples = 128;
constexpr int kFineSamples = 8 * kSamples;
constexpr double kBisectionTolerance = 1e-6;
constexpr double kRunFraction = 0.5;  // chosen run: the first at least this fraction of the longest
constexpr int kShapeSamples = 256;
constexpr double kShapeTolerance = 1e-12;
constexpr const char* kStage = "cladding: feasible angle";

const char* curve_name(Family family) { return family == Family::G ? "F_u" : "F_v"; }
const char* coordinate_names(Family family) { return family == Family::G ? "(u1,u2)" : "(v1,v2)"; }
const char* difference_name(Family family) {
  return family == Family::G ? "D_u - D̄_u" : "D_v - D̄_v";
}

std::string where(Family family, const Vec2& p) {
  std::ostringstream out;
  out << coordinate_names(family) << "=(" << std::fixed << std::setprecision(2) << p.x() << ","
      << p.y() << ")";
  return out.str();
}

std::string number(double value, int digits = 3) {
  std::ostringstream out;
  out << std::setprecision(digits) << value;
  return out.str();
}

std::string degrees(double radians) { return number(radians * 180.0 / kPi, 4) + "°"; }

void check_options(const CladdingOptions& o) {
  if (!(o.k_min > 0) || !(o.k_max > o.k_min) || !std::isfinite(o.k_max)) {
    throw InvalidInput("options.k_min",
                       "slope bounds must satisfy 0 < k_min < k_max < inf, got k_min " +
                           number(o.k_min) + ", k_max " + number(o.k_max));
  }
  if (!(o.vertical_c > 0) || !std::isfinite(o.vertical_c)) {
    throw InvalidInput("options.vertical_c",
                       "must be positive and finite, got " + number(o.vertical_c));
  }
  if (!(o.min_planar_angle >= 0 && o.min_planar_angle < kPi / 2)) {
    throw InvalidInput("options.min_planar_angle",
                       "must be in [0, pi/2) radians, got " + number(o.min_planar_angle));
  }
}

void check_map(const Eigen::MatrixXd& map, const char* what) {  // `what`: the field
  if (map.rows() < 2 || map.rows() != map.cols()) {
    throw InvalidInput(what, "must be an R x R matrix with R >= 2, got " +
                                 std::to_string(map.rows()) + " x " + std::to_string(map.cols()));
  }
  if (!map.allFinite()) {
    throw InvalidInput(what, "has non-finite entries");
  }
}

/// Result of assessing one cladding function; `badness` orders invalid ones (0 if valid).
struct Assessment {
  CladdingFunction function;
  double badness = 0;
};

/// Traces and checks F for one family. `delta(i,j)` = D(i,j) − D̄(i,j); `scale` is the size of the
/// distances (for the corner tolerance).
template <class Delta>
Assessment assess(int R, const Delta& delta, double scale, Family family, double alpha_bar,
                  const CladdingOptions& options) {
  Assessment result;
  CladdingFunction& F = result.function;
  F.family = family;
  F.alpha_bar = alpha_bar;
  const std::string name = curve_name(family);
  const auto fail = [&](std::string problem, double badness) {
    F.valid = false;
    F.problem = std::move(problem);
    result.badness = badness;
    return result;
  };

  // Corners: zeros by construction.
  const int n = R - 1;
  const double tolerance = kCornerTolerance * scale;
  for (const int c : {0, n}) {
    const double value = delta(c, c);
    if (!(std::abs(value) <= tolerance)) {
      const Vec2 corner = Vec2::Constant(c == 0 ? 0.0 : 1.0);
      return fail(name + ": " + difference_name(family) + " = " + number(value) + " at " +
                      where(family, corner) +
                      " is not zero (the boundary member must have the same length on the "
                      "surface and in the plane)",
                  200);
    }
  }
  const double merge = kMergeFraction / n;
  const auto value = [&](int i, int j) {
    if ((i == 0 && j == 0) || (i == n && j == n)) return 0.0;
    return delta(i, j);
  };

  // Cell (i,j) has corners k = 0 (i,j), 1 (i+1,j), 2 (i+1,j+1), 3 (i,j+1) and edges
  // s = 0 bottom (corner 0-1), 1 right (1-2), 2 top (2-3), 3 left (3-0).
  static constexpr int kCornerDi[4] = {0, 1, 1, 0};
  static constexpr int kCornerDj[4] = {0, 0, 1, 1};
  const auto crossing = [&](int i, int j, int side) {
    // Lower-index vertex a and the other one b of the edge.
    int ai = i, aj = j, bi = i, bj = j;
    switch (side) {
      case 0:
        bi = i + 1;
        break;
      case 1:
        ai = bi = i + 1;
        bj = j + 1;
        break;
      case 2:
        aj = bj = j + 1;
        bi = i + 1;
        break;
      default:
        bj = j + 1;
        break;
    }
    const double va = value(ai, aj), vb = value(bi, bj);
    const double t = va / (va - vb);
    return Vec2((ai + t * (bi - ai)) / n, (aj + t * (bj - aj)) / n);
  };

  // Start at (0,0): the corner's value is 0 (+); an edge of cell (0,0) at the corner crosses iff
  // its other vertex is negative.
  const bool bottom = value(1, 0) < 0, left = value(0, 1) < 0;
  if (bottom == left) {
    // To first order, D - D̄ along the two sides at the corner changes like the cosines of the
    // surface vs planar corner angles at the member's ends (c0, c3 for F_u; c1, c0 for F_v).
    const char* corners = family == Family::G ? "c0 and c3" : "c1 and c0";
    return fail(name + " does not enter the square at " + where(family, Vec2(0, 0)) + ": " +
                    difference_name(family) +
                    " has the same sign on both sides of the corner (the planar angles at " +
                    corners + " must deviate from the surface angles in opposite directions)",
                150);
  }
  F.points.push_back(Vec2(0, 0));
  int i = 0, j = 0, entry = bottom ? 0 : 3;
  bool reached = false;
  Vec2 exit_point(0, 0);
  std::optional<Vec2> branch;  // centre of the first saddle cell on the path
  for (long step = 0; step < 4L * R * R; ++step) {
    bool negative[4];
    double sum = 0;
    for (int k = 0; k < 4; ++k) {
      const double v = value(i + kCornerDi[k], j + kCornerDj[k]);
      negative[k] = v < 0;
      sum += v;
    }
    bool crosses[4];
    int count = 0;
    for (int s = 0; s < 4; ++s) {
      crosses[s] = negative[s] != negative[(s + 1) % 4];
      if (crosses[s]) ++count;
    }
    int exit = -1;
    if (count == 4) {
      if (!branch) branch = Vec2((i + 0.5) / n, (j + 0.5) / n);
      // Centre with the sign of corners 0 and 2: they are connected, corners 1 and 3 are cut off
      // (edge pairs 0-1 and 2-3); otherwise corners 0 and 2 are cut off (pairs 3-0 and 1-2).
      static constexpr int kConnected02[4] = {1, 0, 3, 2};
      static constexpr int kCut02[4] = {3, 2, 1, 0};
      exit = (sum < 0) == negative[0] ? kConnected02[entry] : kCut02[entry];
    } else {
      for (int s = 0; s < 4; ++s)
        if (s != entry && crosses[s]) exit = s;
    }
    if (exit < 0) break;  // cannot happen: the entry edge crosses, so another one does
    const Vec2 p = crossing(i, j, exit);
    const bool end = p.x() == 1.0 && p.y() == 1.0;
    if ((p - F.points.back()).cwiseAbs().maxCoeff() > merge) {
      F.points.push_back(p);
    } else if (end && F.points.size() > 1) {
      F.points.back() = p;  // keep (1,1) exact
    }
    static constexpr int kDi[4] = {0, 1, 0, -1};
    static constexpr int kDj[4] = {-1, 0, 1, 0};
    const int ni = i + kDi[exit], nj = j + kDj[exit];
    if (ni < 0 || nj < 0 || ni >= n || nj >= n) {
      exit_point = p;
      reached = end;
      break;
    }
    i = ni;
    j = nj;
    entry = (exit + 2) % 4;
  }
  if (!reached) F.points.clear();
  if (branch) {
    // Two zero curves meet (or pass within one grid cell): which one F follows is decided by
    // rounding, so F is not well defined there.
    return fail(name + " branches at " + where(family, *branch) + ": the zero set of " +
                    difference_name(family) + " crosses itself there" +
                    (reached ? ""
                             : " (the branch followed leaves the domain at " +
                                   where(family, exit_point) + ")"),
                90);
  }
  if (!reached) {
    return fail(name + " leaves the domain at " + where(family, exit_point) +
                    " instead of reaching " + where(family, Vec2(1, 1)),
                100);
  }

  // Slopes. Only the worst violation is described: an infeasible angle has many, and formatting
  // each one's message was a third of the time of an infeasible design's suggestions.
  enum class Violation { Backwards, BelowMin, AboveMax };
  double worst = 0, worst_slope = 0;
  int worst_segment = -1;
  Violation worst_kind = Violation::Backwards;
  for (size_t k = 0; k + 1 < F.points.size(); ++k) {
    const Vec2 d = F.points[k + 1] - F.points[k];
    double slope = 0, violation = 0;
    Violation kind = Violation::Backwards;
    if (d.x() < -kVertical) {
      violation = 40 + std::atan(-d.x() / std::max(d.norm(), 1e-300));
    } else {
      const bool vertical = d.x() <= kVertical;
      slope = vertical ? options.vertical_c * d.y() : d.y() / d.x();
      if (!(slope > options.k_min)) {
        violation = slope > 0 ? 1e-9 + std::log(options.k_min / slope) : 30 + std::atan(-slope);
        kind = Violation::BelowMin;
      } else if (!(slope < options.k_max)) {
        violation = 1e-9 + std::log(slope / options.k_max);
        kind = Violation::AboveMax;
      }
    }
    if (violation > worst) {
      worst = violation;
      worst_segment = static_cast<int>(k);
      worst_kind = kind;
      worst_slope = slope;
    }
  }
  std::string worst_problem;
  if (worst_segment >= 0) {
    const size_t k = static_cast<size_t>(worst_segment);
    const Vec2 mid = 0.5 * (F.points[k] + F.points[k + 1]);
    const std::string note =
        F.points[k + 1].x() - F.points[k].x() <= kVertical && worst_kind != Violation::Backwards
            ? " (vertical segment)"
            : "";
    if (worst_kind == Violation::Backwards) {
      worst_problem = name + " runs backwards (" + std::string(family == Family::G ? "u1" : "v1") +
                      " decreases) at " + where(family, mid);
    } else if (worst_kind == Violation::BelowMin) {
      const char* relation = worst_slope == options.k_min ? " = k_min " : " < k_min ";
      worst_problem = name + " slope " + number(worst_slope) + note + relation +
                      number(options.k_min) + " at " + where(family, mid);
    } else {
      const char* relation = worst_slope == options.k_max ? " = k_max " : " > k_max ";
      worst_problem = name + " slope " + number(worst_slope) + note + relation +
                      number(options.k_max) + " at " + where(family, mid);
    }
  }
  if (worst_segment >= 0) return fail(worst_problem, worst);
  F.valid = true;
  return result;
}

double map_scale(const Eigen::MatrixXd& D) {
  const int n = static_cast<int>(D.rows()) - 1;
  return std::max({std::abs(D(0, 0)), std::abs(D(n, n)), std::abs(D(0, n)), std::abs(D(n, 0))});
}

/// Planar diagonals ē = |c0c2|, f̄ = |c1c3|.
std::array<double, 2> planar_diagonals(const PlanarPatch& planar) {
  const auto& c = planar.corners;
  return {(c[2] - c[0]).norm(), (c[3] - c[1]).norm()};
}

/// Eq. (2) without input checks: e = D_u(0,1) = d(c0,c2), f = D_u(1,0) = d(c1,c3).
bool diagonals_cross(const Eigen::MatrixXd& D_u, const PlanarPatch& planar) {
  const Eigen::Index n = D_u.rows() - 1;
  const double e = D_u(0, n), f = D_u(n, 0);
  const auto [e_bar, f_bar] = planar_diagonals(planar);
  return (e - e_bar) * (f - f_bar) < 0;
}

/// One evaluated ᾱ.
struct Sample {
  double alpha = 0;
  bool planar = false;  // the convex planar patch exists
  bool diagonal = false;
  double e_bar = 0, f_bar = 0;
  std::optional<Assessment> g, h;
  bool feasible = false;
  double badness = std::numeric_limits<double>::infinity();
};

class Evaluator {
 public:
  Evaluator(const DistanceMaps& maps, const std::array<double, 4>& lengths,
            const CladdingOptions& options)
      : maps_(maps), lengths_(lengths), options_(options) {}

  Sample operator()(double alpha) const {
    Sample s;
    s.alpha = alpha;
    const std::optional<PlanarPatch> planar = make_planar_patch(lengths_, alpha);
    if (!planar) return s;
    s.planar = true;
    const auto diagonals = planar_diagonals(*planar);
    s.e_bar = diagonals[0];
    s.f_bar = diagonals[1];
    s.diagonal = diagonals_cross(maps_.g.distances, *planar);
    s.g = assess_family(maps_.g, *planar);
    s.h = assess_family(maps_.h, *planar);
    // Only validity and problems are kept for the diagnostics.
    std::vector<Vec2>().swap(s.g->function.points);
    std::vector<Vec2>().swap(s.h->function.points);
    const int failed = !s.diagonal + !s.g->function.valid + !s.h->function.valid;
    s.feasible = failed == 0;
    s.badness = 1000.0 * failed + s.g->badness + s.h->badness;
    return s;
  }

 private:
  Assessment assess_family(const DistanceMap& map, const PlanarPatch& planar) const {
    const int R = map.resolution();
    std::vector<Vec2>& first = first_[static_cast<int>(map.family)];
    std::vector<Vec2>& second = second_[static_cast<int>(map.family)];
    first.resize(R);
    second.resize(R);
    for (int i = 0; i < R; ++i) {
      const double t = static_cast<double>(i) / (R - 1);  // as planar_distance_map
      first[i] = planar_boundary_point(planar, map.family, 0, t);
      second[i] = planar_boundary_point(planar, map.family, 1, t);
    }
    const Eigen::MatrixXd& D = map.distances;
    const auto delta = [&](int i, int j) { return D(i, j) - (first[i] - second[j]).norm(); };
    return assess(R, delta, map_scale(D), map.family, planar.alpha_bar, options_);
  }

  const DistanceMaps& maps_;
  const std::array<double, 4>& lengths_;
  const CladdingOptions& options_;
  mutable std::array<std::vector<Vec2>, 2> first_, second_;
};

/// Maximal runs of nonzero entries as {first, last}, in order. The first and last entries must
/// be zero (sentinels).
std::vector<std::pair<int, int>> runs(const std::vector<char>& ok) {
  std::vector<std::pair<int, int>> result;
  for (int k = 0; k < static_cast<int>(ok.size());) {
    if (!ok[k]) {
      ++k;
      continue;
    }
    int last = k;
    while (last + 1 < static_cast<int>(ok.size()) && ok[last + 1]) ++last;
    result.push_back({k, last});
    k = last + 1;
  }
  return result;
}

/// The first run at least `fraction` as long as the longest one; {-1, -1} if there is none.
std::pair<int, int> chosen_run(const std::vector<char>& ok, double fraction) {
  const auto all = runs(ok);
  int longest = 0;
  for (const auto& [first, last] : all) longest = std::max(longest, last - first + 1);
  for (const auto& [first, last] : all)
    if (last - first + 1 >= fraction * longest) return {first, last};
  return {-1, -1};
}

/// Bisection between `inside` (ok) and `outside` (not ok) until they are within `tolerance`;
/// returns the ok end.
template <class Predicate>
double bisect(const Predicate& ok, double inside, double outside, double tolerance,
              const Progress& progress) {
  for (int iteration = 0; iteration < 200 && std::abs(outside - inside) > tolerance; ++iteration) {
    progress.check();
    const double middle = 0.5 * (inside + outside);
    if (middle == inside || middle == outside) break;
    if (ok(middle)) {
      inside = middle;
    } else {
      outside = middle;
    }
  }
  return inside;
}

void check_maps(const DistanceMaps& maps) {
  check_map(maps.g.distances, "maps.g");
  check_map(maps.h.distances, "maps.h");
  if (maps.g.family != Family::G || maps.h.family != Family::H) {
    throw InvalidInput("maps", "maps.g / maps.h must hold families G / H");
  }
}

std::string interval_text(double lo, double hi) {
  return "(" + degrees(lo) + ", " + degrees(hi) + ")";
}

[[noreturn]] void throw_infeasible(const std::vector<Sample>& samples, const DistanceMaps& maps,
                                   double lo, double hi, double min_angle) {
  const int R = maps.g.resolution();
  const double e = maps.g.distances(0, R - 1), f = maps.g.distances(R - 1, 0);
  std::ostringstream message;
  message << "no feasible planar angle ᾱ in " << (min_angle > 0 ? "the admissible" : "the convex")
          << " range " << interval_text(lo, hi) << ": ";
  const Sample* best = nullptr;
  bool any_diagonal = false;
  double e_lo = std::numeric_limits<double>::infinity(), e_hi = -e_lo, f_lo = e_lo, f_hi = -e_lo;
  for (const Sample& s : samples) {
    if (!s.planar) continue;
    any_diagonal = any_diagonal || s.diagonal;
    e_lo = std::min(e_lo, s.e_bar);
    e_hi = std::max(e_hi, s.e_bar);
    f_lo = std::min(f_lo, s.f_bar);
    f_hi = std::max(f_hi, s.f_bar);
    if (!best || s.badness < best->badness) best = &s;
  }
  if (!best) {
    message << "no sampled angle gives a convex planar patch";
    throw Infeasible("corners", message.str());
  }
  if (!any_diagonal) {
    message << "the diagonal condition (e - ē)(f - f̄) < 0 (paper eq. 2) fails for every ᾱ: "
            << "surface diagonals e = d(c0,c2) = " << number(e, 5)
            << ", f = d(c1,c3) = " << number(f, 5) << "; planar ē = |c0c2| ranges over ["
            << number(e_lo, 5) << ", " << number(e_hi, 5) << "], f̄ = |c1c3| over ["
            << number(f_lo, 5) << ", " << number(f_hi, 5) << "]";
    throw Infeasible("corners", message.str());
  }
  message << "closest at ᾱ = " << degrees(best->alpha) << " (" << number(best->alpha, 6)
          << " rad): ";
  std::vector<std::string> problems;
  if (!best->diagonal) {
    problems.push_back("diagonal condition (e - ē)(f - f̄) < 0 fails (e = " + number(e, 5) +
                       ", ē = " + number(best->e_bar, 5) + ", f = " + number(f, 5) +
                       ", f̄ = " + number(best->f_bar, 5) + ")");
  }
  for (const auto* a : {&best->g, &best->h}) {
    if (!(*a)->function.valid) problems.push_back((*a)->function.problem);
  }
  for (size_t k = 0; k < problems.size(); ++k) message << (k ? "; " : "") << problems[k];
  throw Infeasible("corners", message.str());
}

}  // namespace

CladdingFunction cladding_function(const Eigen::MatrixXd& surface_map,
                                   const Eigen::MatrixXd& planar_map, Family family,
                                   double alpha_bar, const CladdingOptions& options) {
  check_options(options);
  check_map(surface_map, "surface_map");
  check_map(planar_map, "planar_map");
  if (planar_map.rows() != surface_map.rows()) {
    throw InvalidInput("planar_map", "surface map is " + std::to_string(surface_map.rows()) +
                                         " x " + std::to_string(surface_map.rows()) +
                                         " but planar map is " + std::to_string(planar_map.rows()) +
                                         " x " + std::to_string(planar_map.rows()));
  }
  const auto delta = [&](int i, int j) { return surface_map(i, j) - planar_map(i, j); };
  return assess(static_cast<int>(surface_map.rows()), delta, map_scale(surface_map), family,
                alpha_bar, options)
      .function;
}

bool diagonal_condition(const DistanceMaps& maps, const PlanarPatch& planar) {
  check_map(maps.g.distances, "maps.g");
  return diagonals_cross(maps.g.distances, planar);
}

AlphaRange feasible_alpha_range(const DistanceMaps& maps, const std::array<double, 4>& side_lengths,
                                const CladdingOptions& options, const Progress& progress) {
  check_options(options);
  check_maps(maps);
  // Named values, not a structured binding: the lambdas below capture them, which clang 14 (the
  // fuzz build) rejects for bindings.
  const std::array<double, 2> convex = convex_alpha_interval(side_lengths);  // validates them
  const double lo = convex[0], hi = convex[1];
  if (!(hi > lo)) {
    std::ostringstream message;
    message << "no convex planar quadrilateral has the side lengths " << side_lengths[0] << ", "
            << side_lengths[1] << ", " << side_lengths[2] << ", " << side_lengths[3];
    throw Infeasible("corners", message.str());
  }
  progress.report(kStage, 0.0);

  // The admissible shapes: every planar angle in [m, pi - m]. On the convex interval the angle
  // at c0 (= ᾱ) and at c2 increase with ᾱ and those at c1, c3 decrease (planar_patch.cpp), so
  // each bound holds on a sub-interval and so does their conjunction.
  const double m = options.min_planar_angle;
  const auto admissible = [&](double alpha) {
    const auto planar = make_planar_patch(side_lengths, alpha);
    if (!planar) return false;
    for (const double angle : planar_corner_angles(*planar))
      if (!(angle >= m && angle <= kPi - m)) return false;
    return true;
  };
  std::vector<char> shape_ok(kShapeSamples + 1, 0);
  for (int k = 1; k < kShapeSamples; ++k)
    shape_ok[k] = admissible(lo + (hi - lo) * k / kShapeSamples);
  const auto [shape_first, shape_last] = chosen_run(shape_ok, 1.0);  // one run (monotone)
  if (shape_first < 0) {
    throw Infeasible("options.min_planar_angle",
                     "no planar patch with these side lengths has every inner angle in [" +
                         degrees(m) + ", " + degrees(kPi - m) + "] (convex range " +
                         interval_text(lo, hi) + ", CladdingOptions::min_planar_angle)");
  }
  const auto shape_alpha = [&](int k) { return lo + (hi - lo) * k / kShapeSamples; };
  const double a = bisect(admissible, shape_alpha(shape_first), shape_alpha(shape_first - 1),
                          kShapeTolerance, progress);
  const double b = bisect(admissible, shape_alpha(shape_last), shape_alpha(shape_last + 1),
                          kShapeTolerance, progress);

  const Evaluator evaluate(maps, side_lengths, options);
  const auto feasible = [&](double alpha) { return evaluate(alpha).feasible; };
  std::vector<Sample> samples;
  for (const int N : {kSamples, kFineSamples}) {
    // samples[k + 1] at a + (b - a) k / N, k = 0..N; samples[0] and samples[N + 2] are
    // infeasible sentinels at a and b (so a feasible end sample is its own bisection result).
    samples.assign(N + 3, Sample{});
    samples[0].alpha = a;
    samples[N + 2].alpha = b;
    std::vector<char> ok(N + 3, 0);
    for (int k = 0; k <= N; ++k) {
      // One evaluation takes up to ~40 ms on a large patch: poll the flag at each one (a
      // 59k-vertex design took 0.63 s to stop here when it polled every 16), report every 16.
      progress.check();
      if (k % 16 == 0) progress.report(kStage, 0.8 * k / N);
      samples[k + 1] = evaluate(k == N ? b : a + (b - a) * k / N);
      ok[k + 1] = samples[k + 1].feasible;
    }
    const auto [first, last] = chosen_run(ok, kRunFraction);
    if (first < 0) continue;
    AlphaRange range;
    range.min = bisect(feasible, samples[first].alpha, samples[first - 1].alpha,
                       kBisectionTolerance, progress);
    progress.report(kStage, 0.9);
    range.max = bisect(feasible, samples[last].alpha, samples[last + 1].alpha, kBisectionTolerance,
                       progress);
    progress.report(kStage, 1.0);
    return range;
  }
  throw_infeasible(samples, maps, a, b, m);
}

}  // namespace gridshell
