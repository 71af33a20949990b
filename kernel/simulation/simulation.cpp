// SPDX-License-Identifier: GPL-3.0-or-later
// Deployment simulation (paper Section 5) with Ceres.
//
// Unknowns: every rod vertex (3), every rod edge's twist angle (1), and for each end of a
// sliding connection its barycentric coordinate on its current edge (1). Without notches the
// coordinates are constants at the planar arc lengths s̄.
//
// The solve is an outer loop around Ceres' Levenberg-Marquardt (damped Gauss-Newton, sparse
// normal Cholesky): solve with the current reference frames and connection edges; then update
// the reference frames by time-parallel transport (d1 transported from the old tangent to the
// new one; the material frame, and so the energy, is unchanged at the current point) and move
// every sliding connection that left its edge (barycentric coordinate outside [0, 1]) to the
// neighbouring edge at the same rest arc length. The problem is rebuilt for the next solve.
// It ends when a solve converges on the gradient and no connection moved.
#include "gridshell/simulation/simulation.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <thread>
#include <tuple>

#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"
#include "gridshell/mesh/surface_distance.h"
#include "newton_solver.h"
#include "rod_derivatives.h"
#include "rod_terms.h"

namespace gridshell {

namespace {

using rod_terms::EdgeReference;

/// A sliding connection is held at a rod vertex at most this many times (released in between
/// when its one-sided derivatives showed it was not a minimum there).
constexpr int kMaxHolds = 3;
/// ... after crossing back and forth over the same vertex this many times in a row. Three
/// happen on the way down to an equilibrium (triple-vault): held and released at the end, that
/// cost 19 iterations. A one-sided derivative check when a connection is held cannot tell
/// early: it is exact only once the rest of the grid is in equilibrium.
constexpr int kFlipsToHold = 6;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool finite(const Vec3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

/// Point at arc length s along a polyline (clamped to its ends).
Vec3 point_at(const std::vector<Vec3>& polyline, const std::vector<double>& cumulative, double s) {
  if (s <= 0) return polyline.front();
  if (s >= cumulative.back()) return polyline.back();
  const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), s);
  const size_t k = static_cast<size_t>(it - cumulative.begin()) - 1;
  const double span = cumulative[k + 1] - cumulative[k];
  const double t = span > 0 ? (s - cumulative[k]) / span : 0.0;
  return (1 - t) * polyline[k] + t * polyline[k + 1];
}

struct Rod {
  Family family = Family::G;
  int index = 0;
  bool boundary = false;
  double rest_length = 0;  // scaled
  double h = 0;            // rest edge length, scaled
  int n = 0;               // edges
  std::vector<Vec3> x;     // n + 1 vertices (Ceres parameter blocks)
  std::vector<double> theta;
  std::vector<EdgeReference> ref;
  std::vector<double> reference_twist;  // per interior vertex k (index k - 1), unwrapped
};

/// One end of a connection, on one rod.
struct Slider {
  int rod = 0;
  int edge = 0;
  double beta = 0;  // Ceres parameter block (constant unless sliding)
  bool sliding = false;
  double lo = 0, hi = 0;        // notch interval in rest arc length (scaled) when sliding
  double s_bar = 0, notch = 0;  // scaled
  int side = 0;                 // neighbouring edge used for the normal's blending (+1 / -1)
  // Held at a rod vertex (edge = the vertex, beta = 0, constant): a kink minimum, see
  // Deployment::reproject and release_held.
  bool held = false;
  int holds = 0;                             // times it was held
  int last_vertex = -1, last_direction = 0;  // the last rod vertex it crossed, and which way
  int flips = 0;  // times in a row it crossed back over the vertex it crossed before
  double sigma(const Rod& r) const { return (edge + beta) * r.h; }
};

struct Joint {
  int g = 0, h = 0;  // member indices in the part's families (a crossing)
  Slider end[2];     // [0] on member g, [1] on member h (a bolt: the lower, the upper lamella)
  int anchor = -1;
  int part = 0;       // the part whose crossing it is
  int bolt = -1;      // >= 0: a bolt between parts (index into the bolts given), not a crossing
  double offset = 1;  // end 1 lies this many thicknesses above end 0 (a crossing: h on g)
};

struct AnchorTarget {
  Vec3 position = Vec3::Zero();  // scaled
  Vec3 normal = Vec3::UnitZ();
  /// Per lamella (g, h): the unit direction in the tangent plane across the lamella, n x t_a
  /// (t_a its direction at the start, which lies on the target's geodesics).
  Vec3 across[2] = {Vec3::UnitY(), Vec3::UnitX()};
};

struct Stiffness {
  double EA = 0, EI_weak = 0, EI_strong = 0, GJ = 0;
};

/// Torsion constant of a solid w x t rectangle, w >= t (Roark).
double torsion_constant(double w, double t) {
  const double a = std::max(w, t), b = std::min(w, t);
  const double r = b / a;
  return a * b * b * b * (1.0 / 3.0 - 0.21 * r * (1 - std::pow(r, 4) / 12));
}

class ProgressCallback : public ceres::IterationCallback {
 public:
  ProgressCallback(const Progress& progress, std::string stage, double tolerance)
      : progress_(progress), stage_(std::move(stage)), tolerance_(tolerance) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (progress_.cancelled()) {
      cancelled_ = true;
      return ceres::SOLVER_ABORT;
    }
    if (first_ <= 0) first_ = std::max(summary.gradient_max_norm, tolerance_ * 10);
    // Fraction of the way from the first gradient norm to the tolerance, on a log scale.
    const double g = std::max(summary.gradient_max_norm, tolerance_);
    double fraction = std::log(first_ / g) / std::log(first_ / tolerance_);
    fraction = std::clamp(fraction, 0.0, 0.99);
    best_ = std::max(best_, fraction);
    try {
      progress_.report(stage_, best_);
    } catch (const Cancelled&) {
      cancelled_ = true;
      return ceres::SOLVER_ABORT;
    }
    return ceres::SOLVER_CONTINUE;
  }
  bool cancelled() const { return cancelled_; }

 private:
  const Progress& progress_;
  std::string stage_;
  double tolerance_;
  double first_ = -1, best_ = 0;
  bool cancelled_ = false;
};

/// The inputs simulate_deployment documents as invalid (before any work is done).
void check_inputs(const Grid& grid, double width, double thickness,
                  const SimulationOptions& options) {
  if (!(width > 0) || !std::isfinite(width))
    throw InvalidInput("lamella_width", "must be a positive number");
  if (!(thickness > 0) || !std::isfinite(thickness))
    throw InvalidInput("lamella_thickness", "must be a positive number");
  if (grid.g.size() < 2 || grid.h.size() < 2)
    throw InvalidInput("design.members", "each family needs at least its two boundary members");
  const Material& mat = options.material;
  if (!(mat.young_modulus > 0) || !(mat.shear_modulus > 0) || !std::isfinite(mat.young_modulus) ||
      !std::isfinite(mat.shear_modulus))
    throw InvalidInput("options.young_modulus",
                       "Young's and shear moduli must be positive numbers");
  if (!(options.friction_mu >= 0) || !(options.friction_epsilon > 0))
    throw InvalidInput("options.friction_mu", "mu must be >= 0 and epsilon > 0");
  if (!(options.edges_per_interval >= 1) || options.edges_per_interval > 64)
    throw InvalidInput("options.edges_per_interval", "must be between 1 and 64");
  if (options.max_iterations < 1)
    throw InvalidInput("options.max_iterations", "must be at least 1");
  if (!(options.compression_stiffness >= 0 && options.compression_stiffness <= 1))
    throw InvalidInput("options.compression_stiffness", "must be between 0 and 1");
  int list_index = 0;  // design.members lists g then h
  for (const auto* family : {&grid.g, &grid.h})
    for (const Member& m : *family) {
      const std::string field = "design.members[" + std::to_string(list_index++) + "]";
      const std::string name =
          std::string(m.family == Family::G ? "g" : "h") + std::to_string(m.index);
      if (m.surface.size() < 2)
        throw InvalidInput(field, "member " + name + " has fewer than 2 surface points");
      for (const Vec3& p : m.surface)
        if (!finite(p)) throw InvalidInput(field, "member " + name + " has a non-finite point");
      if (!(m.planar_length > 0) || !std::isfinite(m.planar_length))
        throw InvalidInput(field, "member " + name + " has no positive planar length");
    }
  const int ng = static_cast<int>(grid.g.size()), nh = static_cast<int>(grid.h.size());
  for (size_t k = 0; k < grid.crossings.size(); ++k) {
    const Crossing& c = grid.crossings[k];
    if (c.g < 0 || c.g >= ng || c.h < 0 || c.h >= nh)
      throw InvalidInput("design.crossings[" + std::to_string(k) + "]",
                         "crossing (" + std::to_string(c.g) + ", " + std::to_string(c.h) +
                             ") names a member that does not exist");
  }
}

class Deployment {
 public:
  /// Several parts, each a grid with its anchors, and bolts between their lamellas (one part and
  /// no bolts: a single patch's deployment).
  Deployment(const std::vector<DeploymentPart>& parts, const std::vector<PartBolt>& bolts,
             const TriangleMesh& target, double width, double thickness,
             const SimulationOptions& options);
  DeploymentRun solve(const Progress& progress);
  /// After solve(): each part's lamellas and connections with its RMS (results of that part).
  std::vector<DeploymentRun> part_results();
  /// After solve(): every bolt's gap and force, and the force's unit.
  std::vector<BoltState> bolt_states(std::string* unit);

 private:
  // The steps of the constructor, in order.
  /// The model's scale (largest extent -> options.reference_extent) and the stiffnesses.
  void set_scale(const TriangleMesh& target, double width, double thickness);
  /// One discrete elastic rod per member, on its geodesic offset by half the thickness.
  void build_rods(const Grid& grid, double thickness);
  /// A joint per crossing: two sliders (fixed, or sliding within the notch).
  void build_connections(const Grid& grid, int part);
  /// Pins the anchored joints of a part to the target.
  void bind_anchors(const std::vector<Anchor>& anchors, int part);
  /// The mean rest edge length over all rods and the connection and anchor weights from it.
  void finish_rods();
  /// Puts a part's rods and sliders where its own deployment `run` left them (DeploymentPart).
  void start_from(int part, const DeploymentRun& run, bool lock);
  /// A joint per bolt between parts: two fixed sliders.
  void build_bolts(const std::vector<PartBolt>& bolts);
  /// The rod of a part's member (checked).
  int rod_of(int part, Family family, int member) const;
  /// Results of the rods [first, last) and of the joints that `take` accepts.
  DeploymentRun results_of(int first_rod, int last_rod,
                           const std::function<bool(const Joint&)>& take);

  struct Terms {
    std::vector<std::unique_ptr<ceres::CostFunction>> owned;
    std::vector<NewtonSolver::Term> terms;
    std::vector<std::pair<double*, int>> blocks;  // free parameter blocks
    std::vector<double*> constant;                // fixed connection coordinates
  };
  Terms build_terms();
  void fill_problem(const Terms& terms, ceres::Problem& problem) const;
  bool move_sliders();
  void solve_newton(const Progress& progress, const std::string& stage, DeploymentRun& run);
  /// Where the largest remaining force of an unconverged run acts: a rod vertex, an edge's
  /// twist or a sliding connection, named by lamella (and part when there are several).
  std::string largest_force(const NewtonSolver& newton) const;
  void solve_ceres(const Progress& progress, const std::string& stage, DeploymentRun& run);
  void update_frames();
  void update_reference_twist(Rod& rod);
  bool reproject(Slider& slider);
  /// Releases the held sliders whose one-sided derivatives do not both point uphill (the
  /// energy must rise to both sides of the vertex); true if any was released.
  bool release_held();
  int held_count() const;
  void notch_edges(const Slider& s, int* lo_edge, double* lo_beta, int* hi_edge,
                   double* hi_beta) const;
  struct Binding {
    std::vector<double*> parameters;
    rod_terms::MemberEdge edge;
  };
  Binding bind(Slider& s);
  /// E_a of the anchored joint whose two members are bound as `g` and `h`.
  rod_terms::AnchorResidual anchor_residual(const Joint& joint, const Binding& g,
                                            const Binding& h) const;
  bool sides_changed() const;
  bool is_twist(const double* block) const {
    for (const Rod& rod : rods_)
      if (!rod.theta.empty() && block >= rod.theta.data() && block < rod.theta.data() + rod.n)
        return true;
    return false;
  }
  DeploymentRun results();

  const SimulationOptions& options_;
  SurfaceDistance distance_;
  double scale_ = 1;                  // scaled = model * scale_
  double width_ = 0, thickness_ = 0;  // scaled
  Stiffness k_;
  double force_reference_ = 1;
  double h_mean_ = 1;  // mean rest edge length, scaled
  double w_position_ = 0, w_direction_ = 0, w_anchor_position_ = 0, w_anchor_direction_ = 0;
  std::vector<Rod> rods_;
  std::vector<int> first_rod_;        // per part: its first rod (g members, then h)
  std::vector<int> part_g_, part_h_;  // per part: members per family
  std::vector<Joint> joints_;
  std::vector<AnchorTarget> anchors_;
  int moves_ = 0;
  /// Scale of compressed edges' geometric stiffness in the Newton model: 1 except in the
  /// Gauss-Newton phase of solve_newton (SimulationOptions::compression_stiffness).
  double compression_scale_ = 1;
};

Deployment::Deployment(const std::vector<DeploymentPart>& parts, const std::vector<PartBolt>& bolts,
                       const TriangleMesh& target, double width, double thickness,
                       const SimulationOptions& options)
    : options_(options), distance_(target) {
  // A single patch's fields are its own; a part's carry "parts[i]." before them.
  const bool single = parts.size() == 1 && bolts.empty();
  auto within = [&](size_t p, auto&& step) {
    try {
      step();
    } catch (const InvalidInput& e) {
      if (single) throw;
      rethrow_within(e, "parts[" + std::to_string(p) + "]");
    }
  };
  if (parts.empty()) throw InvalidInput("parts", "no grid to simulate");
  for (size_t p = 0; p < parts.size(); ++p)
    within(p, [&] {
      if (!parts[p].grid) throw InvalidInput("design", "no grid");
      check_inputs(*parts[p].grid, width, thickness, options);
    });
  set_scale(target, width, thickness);
  for (size_t p = 0; p < parts.size(); ++p)
    within(p, [&] {
      first_rod_.push_back(static_cast<int>(rods_.size()));
      part_g_.push_back(static_cast<int>(parts[p].grid->g.size()));
      part_h_.push_back(static_cast<int>(parts[p].grid->h.size()));
      build_rods(*parts[p].grid, thickness);
    });
  finish_rods();
  for (size_t p = 0; p < parts.size(); ++p)
    within(p, [&] {
      build_connections(*parts[p].grid, static_cast<int>(p));
      bind_anchors(parts[p].anchors, static_cast<int>(p));
      if (parts[p].start)
        start_from(static_cast<int>(p), *parts[p].start, parts[p].lock_connections);
    });
  build_bolts(bolts);
}

void Deployment::set_scale(const TriangleMesh& target, double width, double thickness) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec3& v : target.vertices()) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double extent = (hi - lo).maxCoeff();
  if (!(extent > 0) || !std::isfinite(extent))
    throw InvalidInput("design.patch", "the target surface has no extent");
  for (const auto& [value, name] :
       {std::pair{width, "lamella_width"}, std::pair{thickness, "lamella_thickness"}})
    if (!(value >= 1e-6 * extent && value <= 0.5 * extent)) {
      char message[200];
      std::snprintf(message, sizeof message, "%g is outside [1e-6, 0.5] x the target's extent (%g)",
                    value, extent);
      throw InvalidInput(name, message);
    }
  scale_ = options_.reference_extent / extent;
  width_ = width * scale_;
  thickness_ = thickness * scale_;
  const double E = options_.material.young_modulus, G = options_.material.shear_modulus;
  k_.EA = E * width_ * thickness_;
  k_.EI_weak = E * width_ * std::pow(thickness_, 3) / 12;
  k_.EI_strong = E * thickness_ * std::pow(width_, 3) / 12;
  k_.GJ = G * torsion_constant(width_, thickness_);
  force_reference_ = k_.EI_weak;  // EI_weak / (1 scaled unit)^2
}

void Deployment::build_rods(const Grid& grid, double thickness) {
  const int ng = static_cast<int>(grid.g.size()), nh = static_cast<int>(grid.h.size());
  const size_t first = rods_.size();
  std::vector<int> crossings_per_rod(ng + nh, 0);
  for (const Crossing& c : grid.crossings) {
    ++crossings_per_rod[c.g];
    ++crossings_per_rod[ng + c.h];
  }
  for (const auto* family : {&grid.g, &grid.h})
    for (const Member& m : *family) {
      Rod rod;
      rod.family = m.family;
      rod.index = m.index;
      rod.boundary = m.boundary;
      rod.rest_length = m.planar_length * scale_;
      const int count = crossings_per_rod[rods_.size() - first];
      rod.n = std::max(
          4,
          static_cast<int>(std::ceil(options_.edges_per_interval * std::max(1, count - 1) - 1e-9)));
      rod.h = rod.rest_length / rod.n;
      std::vector<double> cumulative{0.0};
      for (size_t k = 1; k < m.surface.size(); ++k)
        cumulative.push_back(cumulative.back() + (m.surface[k] - m.surface[k - 1]).norm());
      const double surface_length = cumulative.back();
      if (!(surface_length > 0))
        throw InvalidInput(
            "design.members[" +
                std::to_string(m.family == Family::G ? m.index : grid.g.size() + m.index) + "]",
            std::string("member ") + (m.family == Family::G ? "g" : "h") + std::to_string(m.index) +
                ": its surface polyline has zero length");
      // Start on the geodesic, offset by half the thickness: g below the surface, h above it
      // (the connection puts h on the material-normal side of g).
      const double side = m.family == Family::G ? -0.5 : 0.5;
      for (int k = 0; k <= rod.n; ++k) {
        const Vec3 p = point_at(m.surface, cumulative, surface_length * k / rod.n);
        const Vec3 n = distance_.normal_at_closest(p);
        rod.x.push_back((p + side * thickness * n) * scale_);
      }
      for (int k = 0; k < rod.n; ++k) {
        const Vec3 mid = 0.5 * (rod.x[k] + rod.x[k + 1]) / scale_;
        const Vec3 t = (rod.x[k + 1] - rod.x[k]).normalized();
        Vec3 d1 = distance_.normal_at_closest(mid);
        d1 = (d1 - d1.dot(t) * t);
        if (d1.norm() < 1e-9) d1 = t.unitOrthogonal();
        EdgeReference ref;
        ref.tangent = t;
        ref.d1 = d1.normalized();
        rod.ref.push_back(ref);
        rod.theta.push_back(0.0);
      }
      update_reference_twist(rod);
      rods_.push_back(std::move(rod));
    }
}

void Deployment::finish_rods() {
  double h_sum = 0;
  for (const Rod& rod : rods_) h_sum += rod.h;
  const double h_mean = h_sum / rods_.size();
  h_mean_ = h_mean;
  w_position_ = options_.connection_position_weight * k_.EA / h_mean;
  w_direction_ = options_.connection_direction_weight * k_.EI_strong / h_mean;
  w_anchor_position_ = options_.anchor_position_weight * k_.EA / h_mean;
  w_anchor_direction_ = options_.anchor_direction_weight * k_.EI_strong / h_mean;
}

void Deployment::build_connections(const Grid& grid, int part) {
  const int first = first_rod_[part], ng = part_g_[part];
  auto make_slider = [&](int rod_index, double s, double s_bar, bool may_slide) {
    const Rod& rod = rods_[rod_index];
    const double surface_to_rest = 1.0;  // criterion (i): surface length == planar length
    Slider slider;
    slider.rod = rod_index;
    slider.s_bar = std::clamp(s_bar * scale_, 0.0, rod.rest_length);
    const double s_rest = std::clamp(s * scale_ * surface_to_rest, 0.0, rod.rest_length);
    slider.notch = s_rest - slider.s_bar;
    double sigma = slider.s_bar;
    // A notch shorter than a hundredth of an edge is not worth a slider.
    if (may_slide && std::abs(slider.notch) > 0.01 * rod.h) {
      slider.sliding = true;
      slider.lo = std::min(slider.s_bar, s_rest);
      slider.hi = std::max(slider.s_bar, s_rest);
      // Start at the geodesic crossing (the notch's far end), where the grid laid on the
      // geodesics closes every connection, or at s̄; just inside, as the notch limits are log
      // barriers.
      const double inset = std::min(1e-3 * rod.h, 0.1 * std::abs(slider.notch));
      const double direction = slider.notch > 0 ? 1.0 : -1.0;
      sigma = options_.notch_start == SimulationOptions::NotchStart::Planar
                  ? slider.s_bar + direction * inset
                  : s_rest - direction * inset;
    }
    slider.edge = std::clamp(static_cast<int>(std::floor(sigma / rod.h)), 0, rod.n - 1);
    slider.beta = sigma / rod.h - slider.edge;
    return slider;
  };
  for (const Crossing& c : grid.crossings) {
    Joint joint;
    joint.g = c.g;
    joint.h = c.h;
    joint.part = part;
    const bool may_slide = options_.notches && !c.on_boundary;
    joint.end[0] = make_slider(first + c.g, c.s_g, c.s_bar_g, may_slide);
    joint.end[1] = make_slider(first + ng + c.h, c.s_h, c.s_bar_h, may_slide);
    joints_.push_back(joint);
  }
}

void Deployment::start_from(int part, const DeploymentRun& run, bool lock) {
  const int first = first_rod_[part], count = part_g_[part] + part_h_[part];
  if (static_cast<int>(run.lamellas.size()) != count)
    throw InvalidInput("start", "has " + std::to_string(run.lamellas.size()) +
                                    " lamellas, the grid " + std::to_string(count));
  for (int i = 0; i < count; ++i) {
    Rod& rod = rods_[first + i];
    const SimulatedLamella& l = run.lamellas[i];
    if (l.family != rod.family || l.index != rod.index ||
        static_cast<int>(l.centerline.size()) != rod.n + 1 ||
        static_cast<int>(l.edge_normals.size()) != rod.n)
      throw InvalidInput("start.lamellas[" + std::to_string(i) + "]",
                         "is not this grid's rod (another member or resolution)");
    for (int k = 0; k <= rod.n; ++k) rod.x[k] = l.centerline[k] * scale_;
    // The material frames become the reference frames, with no twist on top.
    for (int k = 0; k < rod.n; ++k) {
      const Vec3 t = (rod.x[k + 1] - rod.x[k]).normalized();
      Vec3 d1 = l.edge_normals[k] - l.edge_normals[k].dot(t) * t;
      if (d1.norm() < 1e-9) d1 = t.unitOrthogonal();
      rod.ref[k].tangent = t;
      rod.ref[k].d1 = d1.normalized();
      rod.theta[k] = 0;
    }
    rod.reference_twist.clear();
    update_reference_twist(rod);
  }
  std::vector<Joint*> crossings;
  for (Joint& joint : joints_)
    if (joint.part == part && joint.bolt < 0) crossings.push_back(&joint);
  if (run.connections.size() != crossings.size())
    throw InvalidInput("start", "has " + std::to_string(run.connections.size()) +
                                    " connections, the grid " + std::to_string(crossings.size()));
  for (size_t i = 0; i < crossings.size(); ++i) {
    const SimulatedConnection& c = run.connections[i];
    for (int end = 0; end < 2; ++end) {
      Slider& s = crossings[i]->end[end];
      if (!s.sliding) continue;
      const Rod& rod = rods_[s.rod];
      double sigma = s.s_bar + (end == 0 ? c.slide_g : c.slide_h) * scale_;
      if (lock) {
        s.sliding = false;
      } else {
        // Strictly inside the notch, as every slider starts.
        const double inset = std::min(1e-3 * rod.h, 0.1 * std::abs(s.notch));
        sigma = std::clamp(sigma, s.lo + inset, s.hi - inset);
      }
      sigma = std::clamp(sigma, 0.0, rod.rest_length);
      s.edge = std::clamp(static_cast<int>(std::floor(sigma / rod.h)), 0, rod.n - 1);
      s.beta = sigma / rod.h - s.edge;
    }
  }
}

int Deployment::rod_of(int part, Family family, int member) const {
  if (part < 0 || part >= static_cast<int>(first_rod_.size())) return -1;
  const int count = family == Family::G ? part_g_[part] : part_h_[part];
  if (member < 0 || member >= count) return -1;
  return first_rod_[part] + (family == Family::G ? 0 : part_g_[part]) + member;
}

void Deployment::build_bolts(const std::vector<PartBolt>& bolts) {
  for (size_t k = 0; k < bolts.size(); ++k) {
    const PartBolt& b = bolts[k];
    const std::string field = "bolts[" + std::to_string(k) + "]";
    Joint joint;
    joint.part = -1;
    joint.bolt = static_cast<int>(k);
    joint.offset = b.offset;
    for (int end = 0; end < 2; ++end) {
      const int rod_index = rod_of(b.part[end], b.family[end], b.member[end]);
      if (rod_index < 0)
        throw InvalidInput(field, "end " + std::to_string(end) + " names part " +
                                      std::to_string(b.part[end]) + " member " +
                                      (b.family[end] == Family::G ? "g" : "h") +
                                      std::to_string(b.member[end]) + ", which does not exist");
      const Rod& rod = rods_[rod_index];
      const double s = b.s[end] * scale_;
      // Rounding of the arc lengths along a seam: a hundredth of an edge past an end is the end.
      if (!std::isfinite(s) || s < -0.01 * rod.h || s > rod.rest_length + 0.01 * rod.h)
        throw InvalidInput(field, "end " + std::to_string(end) + ": arc length " +
                                      std::to_string(b.s[end]) + " is outside its lamella (0 to " +
                                      std::to_string(rod.rest_length / scale_) + ")");
      Slider& slider = joint.end[end];
      slider.rod = rod_index;
      slider.s_bar = std::clamp(s, 0.0, rod.rest_length);
      slider.edge = std::clamp(static_cast<int>(std::floor(slider.s_bar / rod.h)), 0, rod.n - 1);
      slider.beta = slider.s_bar / rod.h - slider.edge;
    }
    joints_.push_back(joint);
  }
}

void Deployment::bind_anchors(const std::vector<Anchor>& anchors, int part) {
  for (size_t k = 0; k < anchors.size(); ++k) {
    const Anchor& a = anchors[k];
    const std::string field = "design.anchors[" + std::to_string(k) + "]";
    if (!finite(a.position) || !finite(a.normal) || !(a.normal.norm() > 0))
      throw InvalidInput(field, "anchor at crossing (" + std::to_string(a.g) + ", " +
                                    std::to_string(a.h) + ") has a non-finite position or normal");
    int found = -1;
    for (size_t j = 0; j < joints_.size(); ++j)
      if (joints_[j].part == part && joints_[j].g == a.g && joints_[j].h == a.h)
        found = static_cast<int>(j);
    if (found < 0)
      throw InvalidInput(field, "anchor at (" + std::to_string(a.g) + ", " + std::to_string(a.h) +
                                    ") is not a crossing of the grid");
    if (joints_[found].anchor >= 0) continue;  // the same crossing anchored twice
    joints_[found].anchor = static_cast<int>(anchors_.size());
    AnchorTarget target{a.position * scale_, a.normal.normalized()};
    // The lamellas start on their geodesics: the edges' directions there are the target's
    // (their components in the tangent plane; AnchorTangent holds only the turn about n).
    for (int end = 0; end < 2; ++end) {
      const Slider& s = joints_[found].end[end];
      const Rod& rod = rods_[s.rod];
      const Vec3 t = (rod.x[s.edge + 1] - rod.x[s.edge]).normalized();
      target.across[end] = target.normal.cross(t).normalized();
    }
    anchors_.push_back(target);
  }
}

void Deployment::notch_edges(const Slider& s, int* lo_edge, double* lo_beta, int* hi_edge,
                             double* hi_beta) const {
  const Rod& rod = rods_[s.rod];
  // The lower bound's edge holds it with beta in [0, 1), the upper bound's with beta in (0, 1].
  *lo_edge = std::clamp(static_cast<int>(std::floor(s.lo / rod.h)), 0, rod.n - 1);
  *lo_beta = s.lo / rod.h - *lo_edge;
  *hi_edge = std::clamp(static_cast<int>(std::ceil(s.hi / rod.h)) - 1, 0, rod.n - 1);
  *hi_beta = s.hi / rod.h - *hi_edge;
}

Deployment::Binding Deployment::bind(Slider& s) {
  Rod& rod = rods_[s.rod];
  Binding b;
  b.parameters = {rod.x[s.edge].data(), rod.x[s.edge + 1].data(), &rod.theta[s.edge], &s.beta};
  b.edge.ref = &rod.ref[s.edge];
  s.side = s.beta >= 0.5 ? 1 : -1;
  const int neighbour = s.edge + s.side;
  // Only a sliding connection crosses vertices and needs the continuous (blended) normal; a
  // fixed one keeps its edge's own material normal.
  if (s.sliding && neighbour >= 0 && neighbour < rod.n) {
    b.edge.neighbour = &rod.ref[neighbour];
    b.edge.side = s.side;
    b.parameters.push_back(s.side > 0 ? rod.x[s.edge + 2].data() : rod.x[s.edge - 1].data());
    b.parameters.push_back(&rod.theta[neighbour]);
  }
  return b;
}

rod_terms::AnchorResidual Deployment::anchor_residual(const Joint& joint, const Binding& g,
                                                      const Binding& h) const {
  const AnchorTarget& target = anchors_[joint.anchor];
  rod_terms::AnchorResidual anchor;
  anchor.g = g.edge;
  anchor.h = h.edge;
  anchor.position = target.position;
  anchor.normal = target.normal;
  anchor.thickness = thickness_;
  anchor.sqrt_position = std::sqrt(2 * w_anchor_position_);
  anchor.sqrt_direction = std::sqrt(2 * w_anchor_direction_);
  return anchor;
}

bool Deployment::sides_changed() const {
  for (const Joint& joint : joints_)
    for (const Slider& s : joint.end)
      if (s.sliding && (s.beta >= 0.5 ? 1 : -1) != s.side) return true;
  return false;
}

/// The connection or anchor term with its hand-derived Jacobian (rod_derivatives.h).
template <typename Residual>
ceres::CostFunction* pair_cost(const Residual& residual) {
  return new rod_terms::PairCost<Residual>(residual);
}

constexpr double kInf = std::numeric_limits<double>::infinity();

Deployment::Terms Deployment::build_terms() {
  using ceres::AutoDiffCostFunction;
  Terms out;
  auto add = [&](ceres::CostFunction* cost, std::vector<double*> parameters,
                 std::function<void(const double*, Eigen::MatrixXd&)> curvature = nullptr,
                 double lower = -kInf, double upper = kInf) {
    out.owned.emplace_back(cost);
    const bool numeric = !curvature;  // bending-twisting, connections, anchors
    out.terms.push_back({cost, std::move(parameters), std::move(curvature), numeric, lower, upper});
  };
  for (Rod& rod : rods_) {
    for (Vec3& x : rod.x) out.blocks.emplace_back(x.data(), 3);
    for (double& theta : rod.theta) out.blocks.emplace_back(&theta, 1);
    const double stretch = std::sqrt(k_.EA / rod.h);
    for (int k = 0; k < rod.n; ++k) {
      double* xa = rod.x[k].data();
      double* xb = rod.x[k + 1].data();
      const rod_terms::Stretch term{stretch, rod.h};
      // Geometric stiffness of the edge: r Hess(r) = (T / |e|) (I - t t^T) on (x_a, x_b), with
      // the axial force T = sqrt(EA / l̄) r.
      // Compressive forces' share as the solver's phase asks (compression_scale_).
      auto curvature = [xa, xb, term, this](const double* r, Eigen::MatrixXd& H) {
        rod_terms::add_stretch_curvature(term, xa, xb, r, H, compression_scale_);
      };
      add(new rod_terms::StretchCost(term), {xa, xb}, curvature);
    }
    // Uniform edges: the Voronoi length of every interior vertex is h.
    const double weak = std::sqrt(k_.EI_weak / rod.h), strong = std::sqrt(k_.EI_strong / rod.h),
                 twist = std::sqrt(k_.GJ / rod.h);
    for (int k = 1; k < rod.n; ++k)
      add(new rod_terms::BendTwistCost(rod_terms::BendTwist{
              &rod.ref[k - 1], &rod.ref[k], weak, strong, twist, &rod.reference_twist[k - 1]}),
          {rod.x[k - 1].data(), rod.x[k].data(), rod.x[k + 1].data(), &rod.theta[k - 1],
           &rod.theta[k]});
  }
  const double position = std::sqrt(2 * w_position_), direction = std::sqrt(2 * w_direction_);
  const double mu = options_.friction_mu, epsilon = options_.friction_epsilon;
  for (Joint& joint : joints_) {
    Slider& a = joint.end[0];
    Slider& b = joint.end[1];
    for (Slider* s : {&a, &b}) {
      if (!s->sliding || s->held) {
        out.constant.push_back(&s->beta);
        continue;
      }
      out.blocks.emplace_back(&s->beta, 1);
      double* beta = &s->beta;
      // r Hess(r) of sqrt(2) mu log(eps + b) and sqrt(2) mu log(eps + 1 - b).
      const rod_terms::Friction friction{mu, epsilon};
      add(
          new AutoDiffCostFunction<rod_terms::Friction, 2, 1>(new rod_terms::Friction(friction)),
          {beta},
          [beta, friction](const double* r, Eigen::MatrixXd& H) {
            rod_terms::add_friction_curvature(friction, beta, r, H);
          },
          -epsilon, 1 + epsilon);
      int lo_edge, hi_edge;
      double lo_beta, hi_beta;
      notch_edges(*s, &lo_edge, &lo_beta, &hi_edge, &hi_beta);
      const double w = options_.notch_limit_weight;
      for (const auto& [on_edge, bound, upper] : {std::tuple{s->edge == lo_edge, lo_beta, false},
                                                  std::tuple{s->edge == hi_edge, hi_beta, true}}) {
        if (!on_edge) continue;
        const rod_terms::NotchLimit limit{bound, upper, w};
        add(
            new AutoDiffCostFunction<rod_terms::NotchLimit, 1, 1>(new rod_terms::NotchLimit(limit)),
            {beta},
            [beta, limit](const double* r, Eigen::MatrixXd& H) {
              rod_terms::add_notch_limit_curvature(limit, beta, r, H);
            },
            upper ? -kInf : bound, upper ? bound : kInf);
      }
    }
    const Binding bg = bind(a), bh = bind(b);
    std::vector<double*> parameters = bg.parameters;
    parameters.insert(parameters.end(), bh.parameters.begin(), bh.parameters.end());
    // A sliding end whose slide crosses the middle of its edge blends with the edge on the other
    // side: a rebuild then reads that edge instead (see bind()).
    std::vector<double*> may_read;
    for (const Slider* s : {&a, &b}) {
      if (!s->sliding || s->held) continue;
      Rod& rod = rods_[s->rod];
      const int other = s->edge - s->side;  // the neighbour bind() did not take
      if (other < 0 || other >= rod.n) continue;
      may_read.push_back(rod.x[s->side > 0 ? s->edge - 1 : s->edge + 2].data());
      may_read.push_back(&rod.theta[other]);
    }
    rod_terms::ConnectionResidual connection{bg.edge, bh.edge, joint.offset * thickness_, position,
                                             direction};
    add(pair_cost(connection), parameters);
    out.terms.back().may_read = may_read;
    if (joint.anchor >= 0) {
      add(pair_cost(anchor_residual(joint, bg, bh)), parameters);
      out.terms.back().may_read = may_read;
      if (options_.anchor_tangents)
        for (int end = 0; end < 2; ++end) {
          const rod_terms::AnchorTangent tangent{anchors_[joint.anchor].across[end],
                                                 std::sqrt(2 * w_anchor_direction_)};
          const Binding& b = end == 0 ? bg : bh;
          add(new rod_terms::AnchorTangentCost(tangent), {b.parameters[0], b.parameters[1]});
        }
    }
  }
  return out;
}

void Deployment::fill_problem(const Terms& terms, ceres::Problem& problem) const {
  for (const auto& [pointer, size] : terms.blocks) problem.AddParameterBlock(pointer, size);
  for (double* constant : terms.constant) {
    problem.AddParameterBlock(constant, 1);
    problem.SetParameterBlockConstant(constant);
  }
  for (const NewtonSolver::Term& term : terms.terms)
    problem.AddResidualBlock(const_cast<ceres::CostFunction*>(term.cost), nullptr, term.parameters);
}

void Deployment::update_frames() {
  for (Rod& rod : rods_) {
    for (int k = 0; k < rod.n; ++k) {
      EdgeReference& ref = rod.ref[k];
      const Vec3 t = (rod.x[k + 1] - rod.x[k]).normalized();
      const Vec3 d1 = rod_terms::transport<double>(ref.tangent, t, ref.d1);
      ref.tangent = t;
      ref.d1 = (d1 - d1.dot(t) * t).normalized();
    }
    update_reference_twist(rod);
  }
}

void Deployment::update_reference_twist(Rod& rod) {
  const bool first = rod.reference_twist.empty();
  rod.reference_twist.resize(std::max(0, rod.n - 1), 0.0);
  for (int k = 1; k < rod.n; ++k) {
    const auto f0 = rod_terms::edge_frame(rod.x[k - 1].data(), rod.x[k].data(), &rod.theta[k - 1],
                                          rod.ref[k - 1]);
    const auto f1 =
        rod_terms::edge_frame(rod.x[k].data(), rod.x[k + 1].data(), &rod.theta[k], rod.ref[k]);
    const double raw = rod_terms::raw_reference_twist(f0, f1);
    double& previous = rod.reference_twist[k - 1];
    previous =
        first ? raw
              : raw - 2 * std::numbers::pi * std::round((raw - previous) / (2 * std::numbers::pi));
  }
}

bool Deployment::reproject(Slider& s) {
  if (!s.sliding || s.held) return false;
  const Rod& rod = rods_[s.rod];
  bool moved = false;
  int vertex = -1, direction = 0;  // the last vertex crossed (vertex k joins edges k-1 and k)
  while (s.beta > 1 && s.edge < rod.n - 1) {
    s.beta -= 1;
    ++s.edge;
    moved = true;
    vertex = s.edge;
    direction = 1;
  }
  while (s.beta < 0 && s.edge > 0) {
    s.beta += 1;
    --s.edge;
    moved = true;
    vertex = s.edge + 1;
    direction = -1;
  }
  if (moved) {
    // Back and forth over the same vertex, again and again: along the member the energy has a
    // kink at the vertex that pulls the connection into it from both sides (the nearest point
    // of a bent polyline to its partner is the vertex), stronger than E_p's push away from
    // edge ends; no smooth equilibrium exists and the steps would cycle over the vertex
    // forever. Hold it there (checked and, if it does not hold, released by release_held).
    const double at = vertex * rod.h;
    s.flips = vertex == s.last_vertex && direction == -s.last_direction ? s.flips + 1 : 0;
    if (s.flips >= kFlipsToHold && s.holds < kMaxHolds && at > s.lo + 1e-6 * rod.h &&
        at < s.hi - 1e-6 * rod.h) {
      s.held = true;
      ++s.holds;
      s.edge = vertex;
      s.beta = 0;
      s.last_vertex = -1;
      s.last_direction = 0;
      s.flips = 0;
      return true;
    }
    s.last_vertex = vertex;
    s.last_direction = direction;
  }
  s.beta = std::clamp(s.beta, 0.0, 1.0);
  // Stay strictly inside the notch (the limit terms are undefined on and beyond its ends).
  const double margin = 1e-9 * rod.h;
  double sigma = s.sigma(rod);
  if (sigma <= s.lo + margin || sigma >= s.hi - margin) {
    sigma = std::clamp(sigma, s.lo + 2 * margin, s.hi - 2 * margin);
    s.edge = std::clamp(static_cast<int>(std::floor(sigma / rod.h)), 0, rod.n - 1);
    s.beta = sigma / rod.h - s.edge;
  }
  return moved;
}

int Deployment::held_count() const {
  int count = 0;
  for (const Joint& joint : joints_)
    for (const Slider& s : joint.end) count += s.held;
  return count;
}

bool Deployment::release_held() {
  std::vector<Slider*> held;
  for (Joint& joint : joints_)
    for (Slider& s : joint.end)
      if (s.held) held.push_back(&s);
  if (held.empty()) return false;
  // The partial derivative of the energy in beta on the edge after the vertex (at beta = 0:
  // to the right) and on the edge before it (at beta = 1: to the left), with every held slider
  // free and everything else as it is; each slider's beta enters only its own terms.
  auto derivatives = [&](bool right) {
    for (Slider* s : held) {
      s->held = false;
      if (!right) {
        s->edge -= 1;
        s->beta = 1;
      }
    }
    std::vector<double> out;
    {
      Terms terms = build_terms();
      NewtonSolver check(terms.blocks, terms.terms, {});
      const bool ok = check.evaluate();
      for (Slider* s : held)
        out.push_back(ok ? check.gradient_at(&s->beta) : std::numeric_limits<double>::quiet_NaN());
    }
    for (Slider* s : held) {
      s->held = true;
      if (!right) {
        s->edge += 1;
        s->beta = 0;
      }
    }
    return out;
  };
  const std::vector<double> to_right = derivatives(true), to_left = derivatives(false);
  const double tolerance = options_.gradient_tolerance * force_reference_;
  bool released = false;
  for (size_t i = 0; i < held.size(); ++i) {
    Slider& s = *held[i];
    const bool right_uphill = to_right[i] >= -tolerance, left_uphill = to_left[i] <= tolerance;
    if (right_uphill && left_uphill) continue;  // a minimum at the vertex: stays held
    // Release it a little into the edge where the energy descends.
    s.held = false;
    const Rod& rod = rods_[s.rod];
    const double at = s.edge * rod.h;
    const double inset = std::min(1e-3, 0.25 * std::min(s.hi - at, at - s.lo) / rod.h);
    if (!right_uphill && (left_uphill || to_right[i] <= -to_left[i])) {
      s.beta = inset;
    } else {
      s.edge -= 1;
      s.beta = 1 - inset;
    }
    released = true;
  }
  return released;
}

bool Deployment::move_sliders() {
  bool moved = false;
  for (Joint& joint : joints_)
    for (Slider& s : joint.end)
      if (reproject(s)) {
        moved = true;
        ++moves_;
      }
  return moved;
}

void Deployment::solve_newton(const Progress& progress, const std::string& stage,
                              DeploymentRun& run) {
  NewtonSolver::Options newton_options;
  // One thread: evaluating the terms on two took 7% longer on this machine's 2 cores (a thread
  // start per evaluation and the per-term copies for the ordered sum cost more than half of the
  // evaluations' ~30% of a run; no gain at 2210 or 4386 rod vertices either). The threads of a
  // deployment go to running the two modes side by side instead (deployment_job.cpp).
  newton_options.threads = 1;
  newton_options.cholmod_from = options_.cholmod_from;
  newton_options.order_cache = std::make_shared<NewtonSolver::Options::OrderCache>();

  double lambda = newton_options.initial_lambda;
  std::unique_ptr<NewtonSolver> newton;
  // Each solver's statistics go into the run's profile when it is replaced or the run ends.
  const auto collect = [&run](const NewtonSolver& solver) {
    const NewtonSolver::Stats& s = solver.stats();
    SolverProfile& p = run.profile;
    p.factorization = s.factorization;
    p.unknowns = s.unknowns;
    if (s.factor_nonzeros > 0) p.factor_nonzeros = s.factor_nonzeros;
    p.analyses += s.analyses;
    p.evaluations += s.evaluations;
    p.factorizations += s.factorizations;
    p.failed_factorizations += s.failed_factorizations;
    p.cost_evaluations += s.cost_evaluations;
    p.analyze_seconds += s.analyze_seconds;
    p.evaluate_seconds += s.evaluate_seconds;
    p.factorize_seconds += s.factorize_seconds;
    p.solve_seconds += s.solve_seconds;
    p.cost_seconds += s.cost_seconds;
  };
  struct Collect {
    const std::unique_ptr<NewtonSolver>& solver;
    const decltype(collect)& add;
    ~Collect() {
      if (solver) add(*solver);
    }
  } at_end{newton, collect};
  Terms terms;
  bool rebuild = true;
  double first = -1, best = 0;
  const double tolerance = options_.gradient_tolerance;
  // Gauss-Newton plus geometric stiffness far from the equilibrium (robust, cheap); the full
  // Hessian close to it (quadratic convergence along the soft modes).
  bool exact = false;
  bool sliding = false;
  for (const Joint& joint : joints_)
    for (const Slider& s : joint.end) sliding = sliding || s.sliding;
  compression_scale_ = sliding ? 1.0 : options_.compression_stiffness;
  const double exact_below =
      sliding ? options_.exact_hessian_below : options_.exact_hessian_below_fixed;
  while (true) {
    if (rebuild) {
      if (newton) collect(*newton);
      newton.reset();
      terms = build_terms();
      newton = std::make_unique<NewtonSolver>(terms.blocks, terms.terms, newton_options);
      newton->set_lambda(lambda);
      newton->set_exact_hessian(exact);
      // Trust radii (options): a quarter of an edge per step for vertices, 2 rad for twist angles
      // (the connection coordinates keep to their barriers' domains by themselves).
      std::vector<double> limits;
      for (const auto& [pointer, size] : terms.blocks)
        limits.push_back(size == 3 ? options_.max_vertex_step * h_mean_
                                   : (is_twist(pointer) ? options_.max_twist_step : 0.0));
      newton->set_step_limits(std::move(limits));
      rebuild = false;
      ++run.outer_iterations;
    }
    if (!newton->evaluate()) {
      if (run.iterations == 0)  // the start itself: the input's fault
        throw InvalidInput(
            "design.members",
            "the grid laid on its geodesics has folded or degenerate rod edges (the "
            "energy cannot be evaluated there); check the members' surface polylines");
      throw std::runtime_error("simulation: the state left the energy's domain");
    }
    run.gradient_norm = newton->gradient_max_norm() / force_reference_;
    if (first < 0) first = std::max(run.gradient_norm, 10 * tolerance);
    const double fraction =
        std::log(first / std::max(run.gradient_norm, tolerance)) / std::log(first / tolerance);
    best = std::clamp(std::max(best, fraction), 0.0, 0.99);
    progress.report(stage, best);
    if (!exact && run.gradient_norm < exact_below) {
      exact = true;
      compression_scale_ = 1;
      newton->set_exact_hessian(true);
      if (!newton->evaluate())
        throw std::runtime_error("simulation: the state left the energy's domain");
    }
    if (run.gradient_norm <= tolerance) {
      if (release_held()) {  // not a minimum at some vertex after all: go on from there
        rebuild = true;
        continue;
      }
      run.converged = true;
      run.termination = "gradient below tolerance";
      return;
    }
    if (run.iterations >= options_.max_iterations) {
      run.termination = "iteration cap reached (" + std::to_string(options_.max_iterations) +
                        "); largest remaining force at " + largest_force(*newton);
      return;
    }
    const NewtonSolver::StepResult step = newton->step(options_.max_iterations - run.iterations);
    run.iterations += step.trials;
    lambda = newton->lambda();
    if (step.out_of_trials) {
      run.termination = "iteration cap reached (" + std::to_string(options_.max_iterations) +
                        "); largest remaining force at " + largest_force(*newton);
      return;
    }
    if (!step.accepted) {
      run.termination =
          "no step decreases the energy (damping at its maximum); largest "
          "remaining force at " +
          largest_force(*newton);
      return;
    }
    // Step criterion: a Newton step at rounding level (1e-12 relative) with the gradient close
    // to tolerance. A connection resting against a notch limit (a log barrier) has a gradient
    // whose rounding grows with the barrier's curvature, so the gradient alone cannot go
    // lower there.
    if (step.relative_step < 1e-12 && run.gradient_norm < 1e3 * tolerance) {
      if (release_held()) {
        rebuild = true;
        continue;
      }
      run.converged = true;
      run.termination = "step below tolerance (gradient at its rounding limit)";
      return;
    }
    update_frames();
    if (move_sliders() || sides_changed()) rebuild = true;
  }
}

std::string Deployment::largest_force(const NewtonSolver& newton) const {
  const auto lamella = [&](int r) {
    const Rod& rod = rods_[r];
    std::string name = std::string(rod.family == Family::G ? "g" : "h") + std::to_string(rod.index);
    if (first_rod_.size() > 1) {
      const int part = static_cast<int>(std::upper_bound(first_rod_.begin(), first_rod_.end(), r) -
                                        first_rod_.begin() - 1);
      name += " of part " + std::to_string(part + 1);
    }
    return "lamella " + name;
  };
  double best = -1;
  std::string where;
  const auto consider = [&](double g, const auto& describe) {
    if (g > best) {
      best = g;
      where = describe();
    }
  };
  for (int r = 0; r < static_cast<int>(rods_.size()); ++r) {
    const Rod& rod = rods_[r];
    for (size_t k = 0; k < rod.x.size(); ++k)
      consider(newton.gradient_norm_at(rod.x[k].data(), 3), [&] {
        return "vertex " + std::to_string(k) + " of " + std::to_string(rod.x.size()) + " of " +
               lamella(r);
      });
    for (size_t k = 0; k < rod.theta.size(); ++k)
      consider(newton.gradient_norm_at(&rod.theta[k], 1),
               [&] { return "the twist of edge " + std::to_string(k) + " of " + lamella(r); });
  }
  for (const Joint& joint : joints_)
    for (const Slider& s : joint.end)
      if (s.sliding)
        consider(newton.gradient_norm_at(&s.beta, 1), [&] {
          return "the sliding connection g" + std::to_string(joint.g) + " x h" +
                 std::to_string(joint.h) + " (its end on " + lamella(s.rod) + ")";
        });
  if (best < 0) return "";
  char force[64];
  std::snprintf(force, sizeof force, " (%.1e of the reference force)", best / force_reference_);
  return where + force;
}

void Deployment::solve_ceres(const Progress& progress, const std::string& stage,
                             DeploymentRun& run) {
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver.sparse_linear_algebra_library_type =
      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ? ceres::SUITE_SPARSE
                                                                            : ceres::EIGEN_SPARSE;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  solver.num_threads = resolve_threads(options_.threads);
  const double tolerance = options_.gradient_tolerance * force_reference_;
  solver.gradient_tolerance = tolerance;
  solver.function_tolerance = 1e-15;
  solver.parameter_tolerance = 1e-15;
  solver.max_num_consecutive_invalid_steps = 20;
  ProgressCallback callback(progress, stage, tolerance);
  solver.callbacks.push_back(&callback);
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  auto gradient_norm = [&](Terms& terms) {
    NewtonSolver check(terms.blocks, terms.terms, {});
    if (!check.evaluate()) return std::numeric_limits<double>::infinity();
    return check.gradient_max_norm() / force_reference_;
  };
  while (true) {
    progress.check();
    Terms terms = build_terms();
    ceres::Problem problem(problem_options);
    fill_problem(terms, problem);
    solver.max_num_iterations = std::max(1, options_.max_iterations - run.iterations);
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    if (callback.cancelled()) throw Cancelled();
    run.iterations += std::max(0, static_cast<int>(summary.iterations.size()) - 1);
    ++run.outer_iterations;
    run.termination = summary.message;
    if (summary.termination_type == ceres::FAILURE)
      throw std::runtime_error("simulation: the solver failed: " + summary.message);
    update_frames();
    const bool moved = move_sliders();
    if (!moved && summary.termination_type == ceres::CONVERGENCE) {
      // Confirm on the updated frames: the gradient is chart-independent at an equilibrium.
      Terms check = build_terms();
      run.gradient_norm = gradient_norm(check);
      run.converged = run.gradient_norm <= options_.gradient_tolerance;
      if (run.converged && release_held()) {
        run.converged = false;
        continue;
      }
      if (run.converged) return;
    }
    if (run.iterations >= options_.max_iterations ||
        run.outer_iterations >= options_.max_outer_iterations) {
      run.termination =
          run.iterations >= options_.max_iterations
              ? "iteration cap reached (" + std::to_string(options_.max_iterations) + ")"
              : "outer iteration cap reached";
      Terms check = build_terms();
      run.gradient_norm = gradient_norm(check);
      return;
    }
  }
}

DeploymentRun Deployment::solve(const Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  const std::string stage = options_.notches ? "simulate with notches" : "simulate without notches";
  DeploymentRun run;
  if (options_.solver == SimulationSolver::Ceres)
    solve_ceres(progress, stage, run);
  else
    solve_newton(progress, stage, run);
  DeploymentRun out = results();
  // Never hand out a result that is not a number.
  bool finite_result = std::isfinite(out.rms) && std::isfinite(run.gradient_norm);
  for (const auto& [term, value] : out.energies)
    finite_result = finite_result && std::isfinite(value);
  if (!finite_result)
    throw std::runtime_error("simulation: the result is not finite (RMS, gradient or an energy)");
  out.notches = options_.notches;
  out.iterations = run.iterations;
  out.outer_iterations = run.outer_iterations;
  out.connection_moves = moves_;
  out.connections_at_vertices = held_count();
  out.converged = run.converged;
  out.gradient_norm = run.gradient_norm;
  out.gradient_tolerance = options_.gradient_tolerance;
  out.termination = run.termination;
  out.profile = run.profile;
  if (out.connections_at_vertices > 0)
    out.termination += "; " + std::to_string(out.connections_at_vertices) +
                       " connection end(s) held at a rod vertex (energy rising to both sides)";
  out.seconds = seconds_since(start);
  progress.report(stage, 1.0);
  return out;
}

DeploymentRun Deployment::results() {
  return results_of(0, static_cast<int>(rods_.size()), [](const Joint&) { return true; });
}

std::vector<DeploymentRun> Deployment::part_results() {
  std::vector<DeploymentRun> out;
  for (size_t p = 0; p < first_rod_.size(); ++p) {
    const int last = p + 1 < first_rod_.size() ? first_rod_[p + 1] : static_cast<int>(rods_.size());
    const int part = static_cast<int>(p);
    DeploymentRun run =
        results_of(first_rod_[p], last, [part](const Joint& joint) { return joint.part == part; });
    run.energies.clear();
    out.push_back(std::move(run));
  }
  return out;
}

std::vector<BoltState> Deployment::bolt_states(std::string* unit) {
  std::vector<BoltState> out;
  const double position = std::sqrt(2 * w_position_), direction = std::sqrt(2 * w_direction_);
  // Forces are Pa x (scaled length)^2: in model units divide by scale^2, in newtons multiply by
  // the unit's length^2.
  const bool newtons = options_.unit_in_meters > 0;
  const double to_force =
      (newtons ? options_.unit_in_meters * options_.unit_in_meters : 1.0) / (scale_ * scale_);
  *unit = newtons ? "N" : "Pa*unit^2";
  for (Joint& joint : joints_) {
    if (joint.bolt < 0) continue;
    const Binding a = bind(joint.end[0]), b = bind(joint.end[1]);
    double r[rod_terms::ConnectionResidual::kResiduals];
    rod_terms::ConnectionResidual{a.edge, b.edge, joint.offset * thickness_, position, direction}
        .evaluate(const_cast<const double* const*>(a.parameters.data()),
                  const_cast<const double* const*>(b.parameters.data()), r);
    const Vec3 d1 = Vec3(r[0], r[1], r[2]) / position, d2 = Vec3(r[3], r[4], r[5]) / position;
    BoltState state;
    state.gap = d1.norm() / scale_;
    // E = w |d1|^2 + w |d2|^2 with d1 = q_0 - q_1 + o t m_0, d2 = q_1 - q_0 - o t m_1: the force on
    // q_0 is dE/dq_0 = 2 w (d1 - d2) (and its opposite on q_1).
    state.force = (2 * w_position_ * (d1 - d2)).norm() * to_force;
    out.push_back(state);
  }
  return out;
}

DeploymentRun Deployment::results_of(int first_rod, int last_rod,
                                     const std::function<bool(const Joint&)>& take) {
  DeploymentRun run;
  const double E = options_.material.young_modulus, G = options_.material.shear_modulus;
  double sum_sq = 0;
  int count = 0;
  std::map<std::string, double> energy{{"stretch", 0},     {"bend_weak", 0},  {"bend_strong", 0},
                                       {"twist", 0},       {"connection", 0}, {"anchor", 0},
                                       {"notch_limit", 0}, {"friction", 0}};
  const bool bolts = std::any_of(joints_.begin(), joints_.end(), [&](const Joint& joint) {
    return joint.bolt >= 0 && take(joint);
  });
  if (bolts) energy["bolts"] = 0;
  for (int rod_index = first_rod; rod_index < last_rod; ++rod_index) {
    const Rod& rod = rods_[rod_index];
    SimulatedLamella lamella;
    lamella.family = rod.family;
    lamella.index = rod.index;
    lamella.boundary = rod.boundary;
    lamella.rest_length = rod.rest_length / scale_;
    std::vector<rod_terms::EdgeFrame<double>> frames;
    for (int k = 0; k < rod.n; ++k)
      frames.push_back(
          rod_terms::edge_frame(rod.x[k].data(), rod.x[k + 1].data(), &rod.theta[k], rod.ref[k]));
    for (int v = 0; v <= rod.n; ++v) {
      const Vec3 p = rod.x[v] / scale_;
      lamella.centerline.push_back(p);
      Vec3 m1 = Vec3::Zero(), m2 = Vec3::Zero();
      if (v > 0) m1 += frames[v - 1].m1, m2 += frames[v - 1].m2;
      if (v < rod.n) m1 += frames[v].m1, m2 += frames[v].m2;
      // Averages of the two edges' frames, made orthonormal again (the average of two
      // orthonormal frames is orthogonal only to second order in the angle between them).
      m1.normalize();
      lamella.normals.push_back(m1);
      lamella.widths.push_back((m2 - m2.dot(m1) * m1).normalized());
      if (v < rod.n) lamella.edge_normals.push_back(frames[v].m1);
      const double d = distance_.distance(p);
      lamella.deviation.push_back(d);
      sum_sq += d * d;
      ++count;
      run.max_deviation = std::max(run.max_deviation, d);
    }
    const double stretch = std::sqrt(k_.EA / rod.h);
    for (int k = 0; k < rod.n; ++k) {
      double r = 0;
      rod_terms::Stretch{stretch, rod.h}(rod.x[k].data(), rod.x[k + 1].data(), &r);
      energy["stretch"] += 0.5 * r * r;
    }
    for (int k = 1; k < rod.n; ++k) {
      double r[3] = {0, 0, 0};
      rod_terms::BendTwist{&rod.ref[k - 1], &rod.ref[k], 1, 1, 1, &rod.reference_twist[k - 1]}(
          rod.x[k - 1].data(), rod.x[k].data(), rod.x[k + 1].data(), &rod.theta[k - 1],
          &rod.theta[k], r);
      // r holds the integrated curvatures and twist; pointwise values divide by h.
      const double k_weak = std::abs(r[0]) / rod.h, k_strong = std::abs(r[1]) / rod.h,
                   twist_rate = std::abs(r[2]) / rod.h;
      energy["bend_weak"] += 0.5 * k_.EI_weak * r[0] * r[0] / rod.h;
      energy["bend_strong"] += 0.5 * k_.EI_strong * r[1] * r[1] / rod.h;
      energy["twist"] += 0.5 * k_.GJ * r[2] * r[2] / rod.h;
      lamella.max_weak_curvature = std::max(lamella.max_weak_curvature, k_weak * scale_);
      lamella.max_strong_curvature = std::max(lamella.max_strong_curvature, k_strong * scale_);
      lamella.max_twist_rate = std::max(lamella.max_twist_rate, twist_rate * scale_);
      // kappa t and theta' t are scale-free: stresses in Pa from the moduli alone.
      lamella.max_bending_stress =
          std::max(lamella.max_bending_stress, E * k_weak * thickness_ / 2);
      lamella.max_strong_bending_stress =
          std::max(lamella.max_strong_bending_stress, E * k_strong * width_ / 2);
      lamella.max_torsion_stress =
          std::max(lamella.max_torsion_stress, G * twist_rate * thickness_);
      lamella.max_normal_stress =
          std::max(lamella.max_normal_stress, E * (k_weak * thickness_ + k_strong * width_) / 2);
    }
    run.lamellas.push_back(std::move(lamella));
    run.grid_vertices += rod.n + 1;
  }
  run.rms = count > 0 ? std::sqrt(sum_sq / count) : 0.0;
  const double position = std::sqrt(2 * w_position_), direction = std::sqrt(2 * w_direction_);
  for (Joint& joint : joints_) {
    if (!take(joint)) continue;
    Slider& a = joint.end[0];
    Slider& b = joint.end[1];
    const Rod& ra = rods_[a.rod];
    const Rod& rb = rods_[b.rod];
    double r[rod_terms::AnchorResidual::kResiduals];
    const Binding bg = bind(a), bh = bind(b);
    rod_terms::ConnectionResidual{bg.edge, bh.edge, joint.offset * thickness_, position, direction}
        .evaluate(const_cast<const double* const*>(bg.parameters.data()),
                  const_cast<const double* const*>(bh.parameters.data()), r);
    double& connection_energy = energy[joint.bolt >= 0 ? "bolts" : "connection"];
    for (int i = 0; i < rod_terms::ConnectionResidual::kResiduals; ++i)
      connection_energy += 0.5 * r[i] * r[i];
    if (joint.bolt >= 0) continue;  // fixed: no anchor, notch or friction terms
    SimulatedConnection c;
    c.g = joint.g;
    c.h = joint.h;
    c.sliding_g = a.sliding;
    c.sliding_h = b.sliding;
    c.slide_g = (a.sigma(ra) - a.s_bar) / scale_;
    c.slide_h = (b.sigma(rb) - b.s_bar) / scale_;
    c.notch_g = a.notch / scale_;
    c.notch_h = b.notch / scale_;
    c.gap = Eigen::Vector3d(r[0], r[1], r[2]).norm() / position / scale_;
    c.at_vertex_g = a.held;
    c.at_vertex_h = b.held;
    run.connections.push_back(c);
    if (joint.anchor >= 0) {
      anchor_residual(joint, bg, bh)
          .evaluate(const_cast<const double* const*>(bg.parameters.data()),
                    const_cast<const double* const*>(bh.parameters.data()), r);
      for (double v : r) energy["anchor"] += 0.5 * v * v;
      if (options_.anchor_tangents)
        for (const Slider* s : {&a, &b}) {
          const Rod& rod = rods_[s->rod];
          rod_terms::AnchorTangent{anchors_[joint.anchor].across[s == &a ? 0 : 1],
                                   std::sqrt(2 * w_anchor_direction_)}(
              rod.x[s->edge].data(), rod.x[s->edge + 1].data(), r);
          energy["anchor"] += 0.5 * r[0] * r[0];
        }
    }
    for (const Slider* s : {&a, &b}) {
      if (!s->sliding) continue;
      double f[2];
      if (rod_terms::Friction{options_.friction_mu, options_.friction_epsilon}(&s->beta, f))
        energy["friction"] += 0.5 * (f[0] * f[0] + f[1] * f[1]);
      int lo_edge, hi_edge;
      double lo_beta, hi_beta, n;
      notch_edges(*s, &lo_edge, &lo_beta, &hi_edge, &hi_beta);
      if (s->edge == lo_edge &&
          rod_terms::NotchLimit{lo_beta, false, options_.notch_limit_weight}(&s->beta, &n))
        energy["notch_limit"] += 0.5 * n * n;
      if (s->edge == hi_edge &&
          rod_terms::NotchLimit{hi_beta, true, options_.notch_limit_weight}(&s->beta, &n))
        energy["notch_limit"] += 0.5 * n * n;
    }
  }
  // Energies are E[Pa] x (scaled length)^3; in model units divide by scale^3, in joules
  // multiply by the unit's length^3.
  const double to_model = 1.0 / (scale_ * scale_ * scale_);
  const bool joules = options_.unit_in_meters > 0;
  const double unit3 = std::pow(options_.unit_in_meters, 3);
  // The paper's dimensionless notch terms are part of the same objective, so they are counted
  // in the same unit.
  for (const auto& [term, value] : energy)
    run.energies[term] = joules ? value * to_model * unit3 : value;
  run.energy_unit = joules ? "J" : "scaled";
  return run;
}

}  // namespace

DeploymentRun simulate_deployment(const Grid& grid, const std::vector<Anchor>& anchors,
                                  const TriangleMesh& target, double lamella_width,
                                  double lamella_thickness, const SimulationOptions& options,
                                  const Progress& progress) {
  Deployment deployment({DeploymentPart{&grid, anchors}}, {}, target, lamella_width,
                        lamella_thickness, options);
  return deployment.solve(progress);
}

JoinedDeploymentRun simulate_joined(const std::vector<DeploymentPart>& parts,
                                    const std::vector<PartBolt>& bolts, const TriangleMesh& target,
                                    double lamella_width, double lamella_thickness,
                                    const SimulationOptions& options, const Progress& progress) {
  Deployment deployment(parts, bolts, target, lamella_width, lamella_thickness, options);
  JoinedDeploymentRun out;
  out.whole = deployment.solve(progress);
  out.parts = deployment.part_results();
  for (DeploymentRun& part : out.parts) {
    part.notches = out.whole.notches;
    part.iterations = out.whole.iterations;
    part.outer_iterations = out.whole.outer_iterations;
    part.converged = out.whole.converged;
    part.gradient_norm = out.whole.gradient_norm;
    part.gradient_tolerance = out.whole.gradient_tolerance;
    part.termination = out.whole.termination;
    part.seconds = out.whole.seconds;
    part.energy_unit = out.whole.energy_unit;
  }
  out.bolts = deployment.bolt_states(&out.force_unit);
  return out;
}

}  // namespace gridshell
