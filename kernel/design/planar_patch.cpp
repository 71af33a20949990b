// SPDX-License-Identifier: GPL-3.0-or-later
// The planar patch P̄(ᾱ) (paper Sections 3.2, 4.2): the convex four-bar configuration with the
// surface patch's side lengths and angle ᾱ at c0, and its planar distance maps D̄_u, D̄_v.
//
// Why the convex ᾱ-range is one interval (used by convex_alpha_interval):
//   Let Q(ᾱ) be the quadrilateral with c2 on the far side of the diagonal c1c3 from c0 (the only
//   candidate that can be convex: in a convex quadrilateral a diagonal separates the other two
//   corners). Its angles at c0 (= ᾱ) and c2 are < pi by construction; it is convex iff the angles
//   β1 at c1 and β3 at c3 are < pi as well. Take two convex configurations with ᾱ' > ᾱ. If β1 did
//   not decrease, the open convex chain c3-c0-c1-c2 would have both its inner angles (ᾱ, β1)
//   not decreased, one strictly increased, and by Cauchy's arm lemma its end distance |c3c2| = L2
//   would strictly increase -- impossible. So on every connected piece of the convex set, β1 and
//   β3 are strictly decreasing in ᾱ (and γ at c2 increasing). Hence no piece can end on the right
//   by β1 or β3 rising to pi: every piece ends on the right where the linkage stops closing
//   (the diagonal |c1c3| reaches L1+L2, i.e. γ -> pi) or at ᾱ = pi. That right end is the same
//   for all pieces, so there is at most one piece: the set is an open interval (lo, hi), where
//   lo is where β1 or β3 reaches pi or the linkage stops closing (|c1c3| = |L1-L2|) or 0.
//
//   The implementation locates the ends from the analytic break points (the ᾱ values where
//   |c1c3| = L1+L2 or |L1-L2|, β1 = pi or β3 = pi), decides feasibility between consecutive break
//   points with make_planar_patch itself, and refines each end by bisection on
//   make_planar_patch to 1e-13, so the interval agrees with make_planar_patch to rounding. If
//   rounding ever produced several feasible runs, the longest is returned.
#include "gridshell/design/planar_patch.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

void check_lengths(const std::array<double, 4>& L) {
  for (int i = 0; i < 4; ++i) {
    if (!std::isfinite(L[i]) || !(L[i] > 0)) {
      std::ostringstream message;
      message << L[i] << " (must be finite and positive)";
      throw InvalidInput("side_lengths[" + std::to_string(i) + "]", message.str());
    }
  }
}

double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// All four turns of c0->c1->c2->c3->c0 strictly to the left. With four vertices this means a
/// strictly convex, counter-clockwise, simple quadrilateral (exterior angles in (0,pi) sum to 2pi).
bool strictly_convex_ccw(const std::array<Vec2, 4>& c) {
  for (int i = 0; i < 4; ++i) {
    const Vec2& prev = c[(i + 3) % 4];
    const Vec2& at = c[i];
    const Vec2& next = c[(i + 1) % 4];
    if (!(cross(at - prev, next - at) > 0)) return false;
  }
  return true;
}

/// ᾱ in [0, pi] with cos ᾱ = value, or NaN if |value| > 1.
double angle_from_cos(double value) {
  if (!(value >= -1.0 && value <= 1.0)) return std::nan("");
  return std::acos(value);
}

bool feasible(const std::array<double, 4>& L, double alpha) {
  return make_planar_patch(L, alpha).has_value();
}

/// Moves from a feasible ᾱ `inside` towards `outside` (infeasible) until the bracket is below
/// 1e-13; returns the infeasible end, so every ᾱ strictly between it and `inside` at distance
/// > 1e-13 from it is feasible.
double bisect_end(const std::array<double, 4>& L, double inside, double outside) {
  for (int iteration = 0; iteration < 200 && std::abs(outside - inside) > 1e-13; ++iteration) {
    const double middle = 0.5 * (inside + outside);
    if (middle == inside || middle == outside) break;
    if (feasible(L, middle)) {
      inside = middle;
    } else {
      outside = middle;
    }
  }
  return outside;
}

Vec2 lerp(const Vec2& a, const Vec2& b, double t) { return (1.0 - t) * a + t * b; }

}  // namespace

std::optional<PlanarPatch> make_planar_patch(const std::array<double, 4>& side_lengths,
                                             double alpha_bar) {
  check_lengths(side_lengths);
  if (!std::isfinite(alpha_bar) || !(alpha_bar > 0) || !(alpha_bar < kPi)) return std::nullopt;
  const auto& L = side_lengths;
  const Vec2 c0(0, 0);
  const Vec2 c1(L[0], 0);
  const Vec2 c3(L[3] * std::cos(alpha_bar), L[3] * std::sin(alpha_bar));

  // c2 on circle(c1, L1) and circle(c3, L2), |c1c3| = d. The closure quantities are formed
  // from half-angle terms so they keep full relative precision when the linkage is nearly
  // stretched or folded (d close to L1 + L2 or |L1 - L2|), where d*d - (...)^2 would cancel:
  //   d^2             = (L0 - L3)^2 + 4 L0 L3 sin^2(ᾱ/2)
  //   (L1+L2)^2 - d^2 = (L1 + L2 - L0 - L3)(L1 + L2 + L0 + L3) + 4 L0 L3 cos^2(ᾱ/2)
  //   d^2 - (L1-L2)^2 = (L0 - L3 - L1 + L2)(L0 - L3 + L1 - L2) + 4 L0 L3 sin^2(ᾱ/2)
  //   h^2 = (distance of c2 from the line c1c3)^2 = [(L1+L2)^2 - d^2][d^2 - (L1-L2)^2] / (4 d^2)
  const double r1 = L[1], r2 = L[2];
  const double s = std::sin(0.5 * alpha_bar), co = std::cos(0.5 * alpha_bar);
  const double four_l0l3 = 4 * L[0] * L[3];
  const double d2 = (L[0] - L[3]) * (L[0] - L[3]) + four_l0l3 * s * s;
  const double outer = (r1 + r2 - L[0] - L[3]) * (r1 + r2 + L[0] + L[3]) + four_l0l3 * co * co;
  const double inner = (L[0] - L[3] - r1 + r2) * (L[0] - L[3] + r1 - r2) + four_l0l3 * s * s;
  if (!(d2 > 0) || !(outer > 0) || !(inner > 0)) return std::nullopt;  // no or tangent circles
  // c3 - c1 without the cancellation in L3 cos ᾱ - L0 for small ᾱ.
  const Vec2 diagonal(L[3] - L[0] - 2 * L[3] * s * s, 2 * L[3] * s * co);
  const double d = std::sqrt(d2);
  const double a = (d2 + (r1 - r2) * (r1 + r2)) / (2 * d);  // along the diagonal from c1
  const double h = std::sqrt(outer * inner) / (2 * d);
  if (!(h > 0)) return std::nullopt;
  const Vec2 direction = diagonal / d;
  const Vec2 right(direction.y(), -direction.x());  // c0 is to the left of c1->c3
  const Vec2 foot = c1 + a * direction;

  // The far side of c1c3 from c0 is the only possibly convex solution; the near side is tried
  // too so the choice never rests on that argument alone.
  for (const double side : {1.0, -1.0}) {
    PlanarPatch planar;
    planar.alpha_bar = alpha_bar;
    planar.side_lengths = side_lengths;
    planar.corners = {c0, c1, foot + side * h * right, c3};
    if (strictly_convex_ccw(planar.corners)) return planar;
  }
  return std::nullopt;
}

std::array<double, 2> convex_alpha_interval(const std::array<double, 4>& side_lengths) {
  check_lengths(side_lengths);
  const auto& L = side_lengths;

  // Analytic break points (see the comment at the top of the file).
  std::vector<double> breaks = {0.0, kPi};
  const auto add = [&breaks](double alpha) {
    if (std::isfinite(alpha) && alpha > 0 && alpha < kPi) breaks.push_back(alpha);
  };
  // |c1c3|^2 = L0^2 + L3^2 - 2 L0 L3 cos ᾱ equal to (L1 ± L2)^2.
  for (const double diagonal : {L[1] + L[2], std::abs(L[1] - L[2])}) {
    add(angle_from_cos((L[0] * L[0] + L[3] * L[3] - diagonal * diagonal) / (2 * L[0] * L[3])));
  }
  // β1 = pi: c2 = (L0 + L1, 0) and |c2c3| = L2.
  {
    const double x = L[0] + L[1];
    add(angle_from_cos((x * x + L[3] * L[3] - L[2] * L[2]) / (2 * x * L[3])));
  }
  // β3 = pi: c2 = (L3 + L2)(cos ᾱ, sin ᾱ) and |c1c2| = L1.
  {
    const double x = L[3] + L[2];
    add(angle_from_cos((L[0] * L[0] + x * x - L[1] * L[1]) / (2 * L[0] * x)));
  }
  std::sort(breaks.begin(), breaks.end());
  breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());

  // Feasibility is constant between consecutive break points (up to rounding right at them);
  // also sample each gap a little so a misplaced break point cannot hide a feasible run.
  struct Sample {
    double alpha;
    bool ok;
  };
  std::vector<Sample> samples;
  samples.push_back({0.0, false});
  for (size_t k = 0; k + 1 < breaks.size(); ++k) {
    const double a = breaks[k], b = breaks[k + 1];
    constexpr int kPerGap = 16;
    for (int s = 0; s < kPerGap; ++s) {
      const double alpha = a + (b - a) * (s + 0.5) / kPerGap;
      samples.push_back({alpha, feasible(L, alpha)});
    }
    if (k + 2 < breaks.size()) samples.push_back({b, feasible(L, b)});
  }
  samples.push_back({kPi, false});

  // Longest run of feasible samples, refined at both ends.
  std::array<double, 2> best{0.0, 0.0};
  for (size_t i = 1; i + 1 < samples.size();) {
    if (!samples[i].ok) {
      ++i;
      continue;
    }
    size_t j = i;
    while (samples[j + 1].ok) ++j;
    const double lo = bisect_end(L, samples[i].alpha, samples[i - 1].alpha);
    const double hi = bisect_end(L, samples[j].alpha, samples[j + 1].alpha);
    if (hi - lo > best[1] - best[0]) best = {lo, hi};
    i = j + 1;
  }
  return best;
}

std::array<double, 4> planar_corner_angles(const PlanarPatch& planar) {
  std::array<double, 4> angles{};
  const auto& c = planar.corners;
  for (int i = 0; i < 4; ++i) {
    const Vec2 a = c[(i + 3) % 4] - c[i];
    const Vec2 b = c[(i + 1) % 4] - c[i];
    angles[i] = std::atan2(std::abs(cross(a, b)), a.dot(b));
  }
  return angles;
}

Vec2 planar_boundary_point(const PlanarPatch& planar, Family family, int end, double t) {
  if (!(t >= 0.0 && t <= 1.0)) {
    throw InvalidInput("t", std::to_string(t) + " is outside [0,1]");
  }
  if (end != 0 && end != 1) {
    throw InvalidInput("end", "must be 0 or 1, got " + std::to_string(end));
  }
  const auto& c = planar.corners;
  if (family == Family::G) {
    return end == 0 ? lerp(c[0], c[1], t) : lerp(c[3], c[2], t);
  }
  return end == 0 ? lerp(c[1], c[2], t) : lerp(c[0], c[3], t);
}

Eigen::MatrixXd planar_distance_map(const PlanarPatch& planar, Family family, int resolution) {
  if (resolution < 2) {
    throw InvalidInput("resolution", "must be at least 2, got " + std::to_string(resolution));
  }
  const int R = resolution;
  std::vector<Vec2> first(R), second(R);
  for (int i = 0; i < R; ++i) {
    const double t = static_cast<double>(i) / (R - 1);
    first[i] = planar_boundary_point(planar, family, 0, t);
    second[i] = planar_boundary_point(planar, family, 1, t);
  }
  Eigen::MatrixXd distances(R, R);
  for (int j = 0; j < R; ++j) {
    for (int i = 0; i < R; ++i) distances(i, j) = (first[i] - second[j]).norm();
  }
  return distances;
}

}  // namespace gridshell
