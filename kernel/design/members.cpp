// SPDX-License-Identifier: GPL-3.0-or-later
// Member placement along a cladding function (paper Section 4.4).
//
// 1. The cladding polyline F (from (0,0) to (1,1) in the (u1,u2) square) is parameterized by
//    its arc length in that square, normalized to s in [0,1]. C(s) is the bilinear interpolation
//    of the surface distance map D at (u1(s), u2(s)) (entry (i,j) at (i/(R-1), j/(R-1))).
// 2. C is resampled on N = max(4R, 200) + 1 uniform samples of s and smoothed by a local
//    quadratic regression with Gaussian weights (sigma = two map grid steps, 2/(R-1) in s; the
//    fit is one-sided near the ends, so it is unbiased there and creates no spurious end
//    features). The fit gives C, C' and C'' at each sample. Bilinear interpolation (and the
//    cladding polyline's vertices on cell edges) make C only C0 at the map's cell lines; the
//    smoothing removes those kinks, which are below the map's resolution anyway.
// 3. Curvature of C is taken in units where both axes are normalized lengths: Ĉ = C / L with L
//    the mean length of the family's two boundaries, so moving ds along F moves a member by about
//    L·ds along the boundaries and changes its length by L·dĈ: κ = Ĉ'' / (1 + Ĉ'^2)^{3/2}.
// 4. Features: pass 1 takes the interior local extrema of C whose topographic prominence is at
//    least feature_threshold × (max C - min C) (LengthExtremum), pass 2 the interior local
//    extrema of κ with prominence at least feature_threshold × max|κ| (CurvatureExtremum).
//    Positions are refined by a parabola through the three samples around the extremum. Each
//    pass is sorted by |κ| (descending; ties by s) and accepted greedily if it keeps the spacing
//    rule to every accepted member (boundary members included) and is at least one map grid
//    step from every accepted member (features closer than the map resolution are the same
//    feature). Priority = (pass, |κ|): length extrema before curvature extrema.
// 5. Spacing rule (in the planar patch, where members and boundaries are straight): a member
//    meets boundary b at angle θ_b (β on the first, γ on the second); two lamellas of width w
//    don't overlap on b if their parameters differ by at least
//      w (1 + clearance) / (min(sin θ_b of the two) · L_b)
//    with L_b the boundary's length (side_lengths(patch)). Boundary members (0,0), (1,1) count.
// 6. Too dense (more features than max_members or count): drop the lowest-priority features.
//    Too sparse: the features (and the two boundary members) are fixed; the gaps between
//    consecutive fixed members receive k_i added members each, evenly spaced in s (the closed
//    form minimizer of the sum of squared s-distances between neighbours with the fixed ones
//    fixed). One member at a time is added to the interval holding the widest gap
//    (max of Δu1, Δu2), until the count reaches min_members (or count) and, in automatic mode,
//    no gap exceeds max_spacing on either boundary (or max_members is reached). An interval
//    whose even placement would break the spacing rule is full. If min_members (or count)
//    cannot be reached, the lowest-priority feature is dropped and the fill restarts; with no
//    features left, Infeasible. max_spacing is a target, not a constraint: a gap that the
//    spacing rule does not let us split stays (e.g. next to a steep stretch of F).
// The lamella thickness is validated but does not enter the placement. An invalid cladding
// function (cladding.valid == false) is Infeasible.
// Everything is sorted with explicit tie-breaks: the result is a pure function of the input.
#include "gridshell/design/members.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>

#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

const char* family_letter(Family family) { return family == Family::G ? "g" : "h"; }

// Arc-length parameterization of the cladding polyline.
class Curve {
 public:
  explicit Curve(const std::vector<Vec2>& points) : points_(points) {
    cumulative_.resize(points.size(), 0.0);
    for (size_t i = 1; i < points.size(); ++i)
      cumulative_[i] = cumulative_[i - 1] + (points[i] - points[i - 1]).norm();
  }
  double length() const { return cumulative_.back(); }
  Vec2 at(double s) const {
    const double target = std::clamp(s, 0.0, 1.0) * length();
    if (target <= 0) return points_.front();
    if (target >= length()) return points_.back();
    const size_t k = static_cast<size_t>(
        std::upper_bound(cumulative_.begin(), cumulative_.end(), target) - cumulative_.begin());
    const size_t i = k - 1;  // cumulative_[i] <= target < cumulative_[k]
    const double seg = cumulative_[k] - cumulative_[i];
    const double t = seg > 0 ? (target - cumulative_[i]) / seg : 0.0;
    return points_[i] + t * (points_[k] - points_[i]);
  }

 private:
  const std::vector<Vec2>& points_;
  std::vector<double> cumulative_;
};

double bilinear(const Eigen::MatrixXd& d, double u1, double u2) {
  const int r = static_cast<int>(d.rows());
  const double x = std::clamp(u1, 0.0, 1.0) * (r - 1), y = std::clamp(u2, 0.0, 1.0) * (r - 1);
  const int i = std::min(static_cast<int>(x), r - 2), j = std::min(static_cast<int>(y), r - 2);
  const double fx = x - i, fy = y - j;
  return (1 - fx) * (1 - fy) * d(i, j) + fx * (1 - fy) * d(i + 1, j) + (1 - fx) * fy * d(i, j + 1) +
         fx * fy * d(i + 1, j + 1);
}

struct Smoothed {
  std::vector<double> value, first, second;
};

// Local quadratic regression with Gaussian weights (sigma in samples), truncated at 3 sigma and
// at the ends of the signal. Returns the fitted value and first and second derivatives (per unit
// of `h`, the sample spacing).
Smoothed local_quadratic(const std::vector<double>& f, double sigma, double h) {
  const int n = static_cast<int>(f.size());
  const int radius = std::max(2, static_cast<int>(std::ceil(3 * sigma)));
  Smoothed out;
  out.value.resize(n);
  out.first.resize(n);
  out.second.resize(n);
  for (int k = 0; k < n; ++k) {
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (int m = std::max(0, k - radius); m <= std::min(n - 1, k + radius); ++m) {
      const double x = m - k;
      const double w = std::exp(-0.5 * x * x / (sigma * sigma));
      const Eigen::Vector3d phi(1.0, x, x * x);
      a += w * phi * phi.transpose();
      b += w * f[m] * phi;
    }
    const Eigen::Vector3d c = a.ldlt().solve(b);
    out.value[k] = c[0];
    out.first[k] = c[1] / h;
    out.second[k] = 2 * c[2] / (h * h);
  }
  return out;
}

struct Extremum {
  int index = 0;
  double prominence = 0;
};

// Interior local maxima of f (plateaus count once, at their middle sample) with their
// topographic prominence: height above the higher of the lowest points between the peak and
// the nearest higher sample (or the end) on either side.
std::vector<Extremum> interior_maxima(const std::vector<double>& f) {
  const int n = static_cast<int>(f.size());
  std::vector<Extremum> out;
  int i = 1;
  while (i < n - 1) {
    if (!(f[i] > f[i - 1])) {
      ++i;
      continue;
    }
    int j = i;  // end of the plateau starting at i
    while (j + 1 < n && f[j + 1] == f[i]) ++j;
    if (j + 1 < n && f[j + 1] < f[i]) {
      double left_min = f[i];
      for (int m = i - 1; m >= 0 && f[m] <= f[i]; --m) left_min = std::min(left_min, f[m]);
      double right_min = f[i];
      for (int m = j + 1; m < n && f[m] <= f[i]; ++m) right_min = std::min(right_min, f[m]);
      out.push_back({(i + j) / 2, f[i] - std::max(left_min, right_min)});
    }
    i = j + 1;
  }
  return out;
}

// Interior extrema (maxima and minima) of f with prominence >= min_prominence (and > 0).
std::vector<int> interior_extrema(const std::vector<double>& f, double min_prominence) {
  std::vector<int> out;
  for (const Extremum& e : interior_maxima(f))
    if (e.prominence > 0 && e.prominence >= min_prominence) out.push_back(e.index);
  std::vector<double> negated(f.size());
  for (size_t i = 0; i < f.size(); ++i) negated[i] = -f[i];
  for (const Extremum& e : interior_maxima(negated))
    if (e.prominence > 0 && e.prominence >= min_prominence) out.push_back(e.index);
  std::sort(out.begin(), out.end());
  return out;
}

// Sub-sample position (in samples) of the extremum at sample k: the vertex of the parabola
// through k-1, k, k+1, clamped to half a sample.
double refine(const std::vector<double>& f, int k) {
  const double a = f[k - 1], b = f[k], c = f[k + 1];
  const double denom = a - 2 * b + c;
  if (denom == 0) return k;
  return k + std::clamp(0.5 * (a - c) / denom, -0.5, 0.5);
}

struct Placement {
  double s = 0;
  double u1 = 0, u2 = 0;
  std::array<double, 2> sine{};  // sin of the angle with the first / second boundary
  MemberPosition::Reason reason = MemberPosition::Reason::GapFill;
  double curvature = 0;  // |κ| at s (priority within a pass)
};

class Placer {
 public:
  Placer(const CladdingFunction& cladding, const PlanarPatch& planar,
         const std::array<double, 2>& boundary_lengths, double min_distance)
      : curve_(cladding.points),
        planar_(planar),
        family_(cladding.family),
        lengths_(boundary_lengths),
        min_distance_(min_distance) {
    for (int end = 0; end < 2; ++end)
      direction_[end] = planar_boundary_point(planar, family_, end, 1.0) -
                        planar_boundary_point(planar, family_, end, 0.0);
  }

  Placement at(double s) const {
    Placement p;
    p.s = s;
    const Vec2 u = s <= 0 ? Vec2(0, 0) : s >= 1 ? Vec2(1, 1) : curve_.at(s);
    p.u1 = u.x();
    p.u2 = u.y();
    const Vec2 a = planar_boundary_point(planar_, family_, 0, p.u1);
    const Vec2 b = planar_boundary_point(planar_, family_, 1, p.u2);
    const Vec2 m = b - a;
    for (int end = 0; end < 2; ++end) {
      const Vec2& t = direction_[end];
      const double denom = m.norm() * t.norm();
      p.sine[end] = denom > 0 ? std::abs(m.x() * t.y() - m.y() * t.x()) / denom : 0.0;
    }
    return p;
  }

  // The spacing rule between two members (either order) on both boundaries.
  bool spaced(const Placement& a, const Placement& b) const {
    const std::array<double, 2> ta{a.u1, a.u2}, tb{b.u1, b.u2};
    for (int end = 0; end < 2; ++end) {
      const double sine = std::min(a.sine[end], b.sine[end]);
      if (!(sine > 0)) return false;
      const double needed = min_distance_ / sine;
      if (std::abs(ta[end] - tb[end]) * lengths_[end] < needed * (1 - 1e-12)) return false;
    }
    return true;
  }

 private:
  Curve curve_;
  const PlanarPatch& planar_;
  Family family_;
  std::array<double, 2> lengths_;
  double min_distance_;  // w (1 + clearance)
  std::array<Vec2, 2> direction_;
};

double widest_gap(const Placement& a, const Placement& b) {
  return std::max(std::abs(b.u1 - a.u1), std::abs(b.u2 - a.u2));
}

struct FillResult {
  std::vector<Placement> members;  // fixed and added, sorted by s, boundary members included
  int inner = 0;
};

// Fills the gaps between the fixed members (sorted by s, boundary members first and last).
FillResult fill(const Placer& placer, const std::vector<Placement>& fixed, int target_min,
                int target_max, bool fill_spacing, double max_spacing) {
  const size_t intervals = fixed.size() - 1;
  std::vector<std::vector<Placement>> added(intervals);
  std::vector<bool> full(intervals, false);
  int inner = static_cast<int>(fixed.size()) - 2;

  // Members of interval i in order, fixed ends included.
  auto chain = [&](size_t i) {
    std::vector<const Placement*> c{&fixed[i]};
    for (const Placement& p : added[i]) c.push_back(&p);
    c.push_back(&fixed[i + 1]);
    return c;
  };
  auto interval_gap = [&](size_t i) {
    const auto c = chain(i);
    double gap = 0;
    for (size_t k = 0; k + 1 < c.size(); ++k) gap = std::max(gap, widest_gap(*c[k], *c[k + 1]));
    return gap;
  };

  while (true) {
    const bool below_min = inner < target_min;
    if (!below_min && !(fill_spacing && inner < target_max)) break;
    size_t best = intervals;
    double best_gap = -1;
    for (size_t i = 0; i < intervals; ++i) {
      if (full[i]) continue;
      const double gap = interval_gap(i);
      if (!below_min && !(gap > max_spacing)) continue;
      if (gap > best_gap) {
        best_gap = gap;
        best = i;
      }
    }
    if (best == intervals) break;
    // Even placement of k + 1 members in s between the fixed ends.
    const int k = static_cast<int>(added[best].size()) + 1;
    const double s0 = fixed[best].s, s1 = fixed[best + 1].s;
    std::vector<Placement> trial;
    for (int j = 1; j <= k; ++j) trial.push_back(placer.at(s0 + (s1 - s0) * j / (k + 1)));
    bool ok = true;
    const Placement* previous = &fixed[best];
    for (const Placement& p : trial) {
      ok = ok && placer.spaced(*previous, p);
      previous = &p;
    }
    ok = ok && placer.spaced(*previous, fixed[best + 1]);
    if (!ok) {
      full[best] = true;
      continue;
    }
    added[best] = std::move(trial);
    ++inner;
  }

  FillResult result;
  result.inner = inner;
  for (size_t i = 0; i < intervals; ++i) {
    result.members.push_back(fixed[i]);
    for (const Placement& p : added[i]) result.members.push_back(p);
  }
  result.members.push_back(fixed.back());
  return result;
}

void validate(const CladdingFunction& cladding, const DistanceMap& surface_map,
              const MemberPlacementOptions& o) {
  const std::string count_field =
      cladding.family == Family::G ? "options.members_u" : "options.members_v";
  if (!(o.lamella_width >= 0) || !std::isfinite(o.lamella_width))
    throw InvalidInput("options.lamella_width", "must be positive (or 0 for automatic)");
  if (!(o.lamella_thickness >= 0) || !std::isfinite(o.lamella_thickness))
    throw InvalidInput("options.lamella_thickness", "must be positive (or 0 for automatic)");
  if (!(o.clearance >= 0) || !std::isfinite(o.clearance))
    throw InvalidInput("options.clearance", "must be >= 0");
  if (!(o.max_spacing > 0 && o.max_spacing <= 1))
    throw InvalidInput("options.max_spacing", "must be in (0, 1]");
  if (o.min_members < 0) throw InvalidInput("options.min_members", "must be >= 0");
  if (o.max_members < o.min_members) {
    std::ostringstream msg;
    msg << "must be >= min_members (" << o.min_members << "), got " << o.max_members;
    throw InvalidInput("options.max_members", msg.str());
  }
  if (o.count < 0) throw InvalidInput(count_field, "must be >= 0 (0 = automatic)");
  if (!(o.feature_threshold >= 0) || !std::isfinite(o.feature_threshold))
    throw InvalidInput("options.feature_threshold", "must be >= 0");

  const std::string f = family_letter(cladding.family);
  if (surface_map.family != cladding.family)
    throw InvalidInput("surface_map", "distance map and cladding function of different families");
  const auto& d = surface_map.distances;
  if (d.rows() < 2 || d.rows() != d.cols() || !d.allFinite())
    throw InvalidInput("surface_map",
                       "distance map of family " + f + " must be a finite R x R matrix, R >= 2");
  const auto& pts = cladding.points;
  const auto near = [](const Vec2& p, double x) {
    return std::abs(p.x() - x) < 1e-6 && std::abs(p.y() - x) < 1e-6;
  };
  if (pts.size() < 2 || !near(pts.front(), 0) || !near(pts.back(), 1))
    throw InvalidInput("cladding",
                       "cladding function of family " + f + " does not connect (0,0) to (1,1)");
  for (const Vec2& p : pts)
    if (!p.allFinite() || p.minCoeff() < -1e-6 || p.maxCoeff() > 1 + 1e-6)
      throw InvalidInput("cladding",
                         "cladding function of family " + f + " leaves the unit square");
  if (!cladding.valid)
    throw Infeasible("options.alpha",
                     "cladding function of family " + f + " is not valid" +
                         (cladding.problem.empty() ? std::string() : ": " + cladding.problem));
}

}  // namespace

LamellaSize lamella_size(const Patch& patch, const MemberPlacementOptions& options) {
  const std::array<double, 4> sides = side_lengths(patch);
  const double longest = *std::max_element(sides.begin(), sides.end());
  LamellaSize size;
  size.width = options.lamella_width > 0 ? options.lamella_width : 0.01 * longest;
  size.thickness = options.lamella_thickness > 0 ? options.lamella_thickness : size.width / 10;
  return size;
}

std::vector<MemberPosition> place_members(const CladdingFunction& cladding,
                                          const DistanceMap& surface_map, const Patch& patch,
                                          const PlanarPatch& planar,
                                          const MemberPlacementOptions& raw_options) {
  validate(cladding, surface_map, raw_options);
  MemberPlacementOptions options = raw_options;
  const LamellaSize size = lamella_size(patch, raw_options);
  options.lamella_width = size.width;
  options.lamella_thickness = size.thickness;
  const Family family = cladding.family;
  const std::array<double, 4> sides = side_lengths(patch);
  const std::array<double, 2> lengths = family == Family::G
                                            ? std::array<double, 2>{sides[0], sides[2]}
                                            : std::array<double, 2>{sides[1], sides[3]};
  if (!(lengths[0] > 0 && lengths[1] > 0))
    throw InvalidInput("patch", "the patch boundaries of family " +
                                    std::string(family_letter(family)) + " have zero length");
  const Placer placer(cladding, planar, lengths, options.lamella_width * (1 + options.clearance));

  // C(s) on a uniform grid of s, smoothed, with derivatives and curvature.
  const int r = surface_map.resolution();
  const int n = std::max(4 * r, 200) + 1;
  const double h = 1.0 / (n - 1);
  const double l_ref = 0.5 * (lengths[0] + lengths[1]);
  const Curve curve(cladding.points);
  std::vector<double> raw(n);
  for (int k = 0; k < n; ++k) {
    const Vec2 u = curve.at(k * h);
    raw[k] = bilinear(surface_map.distances, u.x(), u.y()) / l_ref;
  }
  // Two map grid steps, in samples: with one step, the grid-scale kinks of the bilinear C (and of
  // the marching-squares cladding polyline) leave curvature noise of several % of max|κ| on the
  // example surfaces (30 spurious curvature extrema on the sphere); with two it is < 0.2%.
  const double sigma = 2.0 * (n - 1) / (r - 1);
  const Smoothed c = local_quadratic(raw, sigma, h);
  std::vector<double> kappa(n);
  for (int k = 0; k < n; ++k) kappa[k] = c.second[k] / std::pow(1 + c.first[k] * c.first[k], 1.5);
  auto kappa_at = [&](double position) {  // linear interpolation, position in samples
    const int k = std::clamp(static_cast<int>(position), 0, n - 2);
    const double t = position - k;
    return (1 - t) * kappa[k] + t * kappa[k + 1];
  };

  // Feature candidates, per pass sorted by |κ| (descending), ties by s.
  const auto [c_min, c_max] = std::minmax_element(c.value.begin(), c.value.end());
  double kappa_max = 0;
  for (double v : kappa) kappa_max = std::max(kappa_max, std::abs(v));
  const double c_scale = std::max(std::abs(*c_min), std::abs(*c_max));
  struct Candidate {
    Placement p;
    int pass;
  };
  std::vector<Candidate> candidates;
  const std::array<const std::vector<double>*, 2> signals{&c.value, &kappa};
  const std::array<double, 2> thresholds{
      std::max(options.feature_threshold * (*c_max - *c_min), 1e-12 * c_scale),
      std::max(options.feature_threshold * kappa_max, 1e-12)};
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<Candidate> list;
    for (int k : interior_extrema(*signals[pass], thresholds[pass])) {
      const double position = refine(*signals[pass], k);
      Candidate cand{placer.at(position * h), pass};
      cand.p.reason = pass == 0 ? MemberPosition::Reason::LengthExtremum
                                : MemberPosition::Reason::CurvatureExtremum;
      cand.p.curvature = std::abs(kappa_at(position));
      list.push_back(cand);
    }
    std::sort(list.begin(), list.end(), [](const Candidate& a, const Candidate& b) {
      if (a.p.curvature != b.p.curvature) return a.p.curvature > b.p.curvature;
      return a.p.s < b.p.s;
    });
    candidates.insert(candidates.end(), list.begin(), list.end());
  }

  // Greedy acceptance in priority order.
  const Placement start = placer.at(0), end = placer.at(1);
  const double resolution_step = 1.0 / (r - 1);
  std::vector<Placement> features;  // in priority order
  for (const Candidate& cand : candidates) {
    bool ok = placer.spaced(start, cand.p) && placer.spaced(cand.p, end);
    for (const Placement& f : features)
      ok = ok && placer.spaced(f, cand.p) && std::abs(f.s - cand.p.s) >= resolution_step;
    if (ok) features.push_back(cand.p);
  }

  const bool automatic = options.count == 0;
  const int target_min = automatic ? options.min_members : options.count;
  const int target_max = automatic ? options.max_members : options.count;
  if (static_cast<int>(features.size()) > target_max) features.resize(target_max);

  FillResult best;
  best.inner = -1;
  while (true) {
    std::vector<Placement> fixed{start};
    fixed.insert(fixed.end(), features.begin(), features.end());
    fixed.push_back(end);
    std::sort(fixed.begin() + 1, fixed.end() - 1,
              [](const Placement& a, const Placement& b) { return a.s < b.s; });
    FillResult result = fill(placer, fixed, target_min, target_max, automatic, options.max_spacing);
    if (result.inner >= target_min) {
      best = std::move(result);
      break;
    }
    if (result.inner > best.inner) best = std::move(result);
    if (features.empty()) {
      std::ostringstream msg;
      msg << "only " << best.inner << " " << family_letter(family)
          << "-members fit with lamella width " << options.lamella_width << " ("
          << (automatic ? "min " : "asked for ") << target_min << ")";
      // Where lamellas need the room: the smallest angle between member and boundary.
      double sine = 1;
      for (int k = 0; k <= 100; ++k) {
        const Placement p = placer.at(k / 100.0);
        sine = std::min({sine, p.sine[0], p.sine[1]});
      }
      msg << "; members meet the boundaries at angles down to " << std::fixed
          << std::setprecision(1) << std::asin(sine) * 180 / std::numbers::pi << " deg";
      const Reason reason = automatic             ? Reason::LamellasTooWide
                            : family == Family::G ? Reason::GMembersDoNotFit
                                                  : Reason::HMembersDoNotFit;
      throw Infeasible(automatic             ? "options.lamella_width"
                       : family == Family::G ? "options.members_u"
                                             : "options.members_v",
                       msg.str(), reason);
    }
    features.pop_back();  // lowest priority
  }

  std::vector<MemberPosition> out;
  for (size_t i = 1; i + 1 < best.members.size(); ++i) {
    const Placement& p = best.members[i];
    MemberPosition m;
    m.u1 = p.u1;
    m.u2 = p.u2;
    m.s = p.s;
    m.reason = p.reason;
    out.push_back(m);
  }
  return out;
}

}  // namespace gridshell
