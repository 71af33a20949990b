// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — deployment simulation (paper Section 5): every lamella a discrete elastic rod
// (Bergou et al. 2008/2010) with anisotropic rectangular cross-section, rotating and sliding
// connections with the lamellas' thickness offset, anchors pinned to the target, notch limits
// and pseudo-friction. The equilibrium is found by a damped Newton method (Gauss-Newton Hessian
// plus the hand-derived geometric stiffness and barrier curvature, block sparse Cholesky;
// kernel/simulation/newton_solver.h) on the terms' Ceres cost functions; Ceres' own
// Levenberg-Marquardt is kept as the reference (SimulationSolver::Ceres).
//
// Units. Lengths are in the design's (mesh) units. Internally the model is scaled so that its
// largest extent is `SimulationOptions::reference_extent` (100, the size of the paper's models)
// and elastic energies use the material's moduli in pascal on that scale: this is the regime in
// which the paper's dimensionless notch terms (E_n with weight 1/10, E_p with mu = 0.1,
// eps = 1e-4) act as described (docs/decisions.md, "Deployment simulation"). The equilibrium
// shape depends only on the ratio of the moduli, the cross-section and these terms, not on the
// model's physical size.
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "gridshell/design/anchors.h"
#include "gridshell/design/grid.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/mesh/mesh.h"

namespace gridshell {

/// An isotropic-enough lamella material: Young's modulus along the lamella and shear modulus,
/// both in pascal, and the stresses it bears (0 = unknown): the bending strength (wood: the
/// modulus of rupture along the grain; metals and plastics: the yield stress) and the shear
/// strength (wood: along the grain; metals: the shear yield stress). Reference values, not
/// design values: no safety factor (docs/decisions.md).
struct Material {
  std::string name;
  double young_modulus = 0;     ///< E, Pa
  double shear_modulus = 0;     ///< G, Pa
  double bending_strength = 0;  ///< f_m, Pa (0 = unknown)
  double shear_strength = 0;    ///< f_v, Pa (0 = unknown)
  std::string label;            ///< "lime wood": for forms and bills of materials
  std::string source;           ///< where the values come from
  bool site = false;            ///< added by add_material_presets, not built in
};

/// The materials: the built-in ones (reference values; kernel/simulation/materials.cpp, the one
/// place they are listed), "lime-wood" first (the paper's models are lime wood lamellas), then
/// those a site added.
const std::vector<Material>& material_presets();
/// Adds a site's own materials after the built-in ones (gridshell.v1.MaterialLibrary, read by
/// the application layer). Call before any thread runs. Throws InvalidInput naming
/// "materials[i].<field>" for an empty or taken name or moduli outside 1e3..1e13 Pa.
void add_material_presets(const std::vector<Material>& materials);
/// A preset by name; throws InvalidInput listing the known names.
Material material_by_name(const std::string& name);

/// The minimizer. Both minimize the same energy built from the same Ceres residual blocks.
enum class SimulationSolver {
  /// Damped Newton: the Gauss-Newton Hessian plus the geometric stiffness of the rod edges and
  /// the exact curvature of the notch terms, Levenberg-Marquardt damping, sparse Cholesky
  /// (kernel/simulation/newton_solver.h explains why). Default.
  Newton,
  /// Ceres' Levenberg-Marquardt with sparse normal Cholesky (SuiteSparse): the reference.
  Ceres,
};

struct SimulationOptions {
  SimulationSolver solver = SimulationSolver::Newton;
  Material material = material_presets().front();  // lime wood
  bool notches = true;  // sliding connections within [s̄, s] at inner crossings
  /// Where sliding connections start: at the geodesic crossing s (default: the grid laid on
  /// the target's geodesics closes every connection), or at the planar arc length s̄.
  enum class NotchStart { Geodesic, Planar } notch_start = NotchStart::Geodesic;
  /// Pseudo-friction E_p (paper Section 5): weight mu and how far past an edge end a connection
  /// may move within one solve.
  double friction_mu = 0.1;
  double friction_epsilon = 1e-4;
  double notch_limit_weight = 0.1;  // the paper's 1/10 in E_n
  /// Connection and anchor weights, relative to the stiffness of a rod edge in stretching
  /// (position terms, EA / l̄) and in strong-axis bending (direction terms, EI_strong / l̄).
  /// Anchors are supports, rigid against the grid: their direction terms 100 x a rod edge's
  /// stiffness (at 1 the lamella turned at its support about as readily as along one edge
  /// of itself, and the sphere deployed 0.84 from its target instead of 0.62; from 10 up the
  /// result changes by less than 1%, docs/decisions.md, issue 18).
  double connection_position_weight = 1;
  double connection_direction_weight = 1;
  double anchor_position_weight = 1;
  double anchor_direction_weight = 100;
  /// Anchors hold each lamella's direction about the surface normal too (its geodesic direction
  /// on the target, the start's), not only position and normal: the paper's supports
  /// "provide correct orientation for the lamellas by inclined contact areas" (Section 6.1).
  /// Without it each anchored lamella may turn about the normal at its support and doubly
  /// curved grids sag between their anchors (sphere 1.035 -> 0.617 with it). Default true.
  bool anchor_tangents = true;
  /// Rod resolution: edges per interval between consecutive crossings along a member (on
  /// average; every rod has uniform edges). Default 2.
  double edges_per_interval = 2;
  double reference_extent = 100;  // model scale of the energy (see Units above)
  /// Convergence: max-norm of the energy gradient (scaled model) below this, times the
  /// reference force EI_weak / (1 unit)^2 of the scaled model. Default 1e-9.
  double gradient_tolerance = 1e-9;
  int max_iterations = 2000;  // Levenberg-Marquardt iterations in all, the cap
  /// Newton solver: switch from the Gauss-Newton-plus-geometric-stiffness Hessian to the full
  /// Hessian once the relative gradient norm is below this: 1e-3 when connections slide (with
  /// notches), 3e-2 when none does (without notches); measured in docs/decisions.md.
  double exact_hessian_below = 1e-3;
  double exact_hessian_below_fixed = 3e-2;
  /// Newton solver, runs where no connection slides (without notches), before the switch to
  /// the full Hessian: the geometric stiffness of compressed rod edges (negative, the softening
  /// that buckles them) enters the model scaled by this, in [0, 1]; tension's enters whole, and
  /// the full Hessian (from the switch on) is exact. With all of it (1) the model turned
  /// indefinite every few steps on the way through a snap-through, and each time the damping
  /// doubled up from ~1e-8 through failed factorizations to a step along a nearly singular
  /// mode; 0.75 keeps a margin: 24% fewer iterations on the seven examples, equal or lower
  /// energies at the end. With sliding connections it stays 1 (no gain measured there; the
  /// notched runs keep their path). See docs/decisions.md.
  double compression_stiffness = 0.75;
  /// Newton solver trust radii per step: vertex moves in rest edge lengths, twist changes in
  /// radians (0 = unlimited). They keep the iterates on the deployment's branch.
  double max_vertex_step = 0.25;
  double max_twist_step = 2.0;
  int max_outer_iterations = 200;  // frame updates / connection re-projections
  /// Newton solver: systems of at least this many unknowns are factorized by CHOLMOD
  /// (supernodal, nested dissection of the parameter blocks), smaller ones by the block kernel
  /// (0: always the block kernel). Both cost the same per factorization near 34k unknowns on
  /// this machine (a 44 x 44-member grid): the block kernel 10% faster at 28k, CHOLMOD 1.28x
  /// at 40k, 1.31-1.35x at 61k, 2.5x at 165k (docs/solver.md).
  /// Every example is far below it.
  int cholmod_from = 34000;
  /// Jacobian evaluation threads of the Ceres solver, 0 = hardware concurrency (the Newton
  /// solver evaluates on one; see solve_newton).
  int threads = 0;
  /// The model's length unit in metres (0 = unknown): energies are then reported in joules.
  double unit_in_meters = 0;
};

/// One deployed lamella.
struct SimulatedLamella {
  Family family = Family::G;
  int index = 0;
  bool boundary = false;
  double rest_length = 0;
  std::vector<Vec3> centerline;          ///< deployed vertices, start first
  std::vector<Vec3> normals;             ///< unit material normal (thickness direction) per vertex
  std::vector<Vec3> widths;              ///< unit width direction per vertex (tangent x normal)
  std::vector<Vec3> edge_normals;        ///< unit material normal per rod edge (a start's frames)
  std::vector<double> deviation;         ///< distance of each vertex to the target patch
  double max_weak_curvature = 0;         ///< 1/length, bending out of the lamella's plane
  double max_strong_curvature = 0;       ///< 1/length, bending in the lamella's plane
  double max_twist_rate = 0;             ///< rad/length
  double max_bending_stress = 0;         ///< Pa: E kappa_weak t / 2
  double max_strong_bending_stress = 0;  ///< Pa: E kappa_strong w / 2
  double max_torsion_stress = 0;         ///< Pa: G theta' t (thin rectangle)
  /// Pa: the largest normal stress at a corner of the cross-section, where both bending
  /// stresses add up: E (kappa_weak t / 2 + kappa_strong w / 2) at one rod vertex.
  double max_normal_stress = 0;
};

/// Final state of one crossing's connection.
struct SimulatedConnection {
  int g = 0, h = 0;
  bool sliding_g = false, sliding_h = false;  ///< had a notch on that member
  double slide_g = 0, slide_h = 0;  ///< final rest arc length minus s̄ (0 without notches)
  double notch_g = 0, notch_h = 0;  ///< s - s̄ (the notch's length and direction)
  double gap = 0;  ///< |q_g - q_h + t m_g|: how far the connection is from being closed
  /// Held at a vertex of that member's rod: a minimum where the energy has a kink along the
  /// member (see docs/decisions.md, "Connections held at rod vertices").
  bool at_vertex_g = false, at_vertex_h = false;
};

/// Where a simulation's time went, summed over the Newton solver's rebuilds (each connection
/// move starts a new one: one more analysis, unless a CHOLMOD system keeps its pattern).
/// docs/solver.md.
struct SolverProfile {
  std::string factorization;  ///< "block" (the block kernel), "cholmod" (supernodal), or ""
  long unknowns = 0;          ///< of the last system
  long factor_nonzeros = 0;   ///< of the last factorization
  int analyses = 0, evaluations = 0, factorizations = 0, failed_factorizations = 0,
      cost_evaluations = 0;
  double analyze_seconds = 0, evaluate_seconds = 0, factorize_seconds = 0, solve_seconds = 0,
         cost_seconds = 0;
};

struct DeploymentRun {
  bool notches = false;
  std::vector<SimulatedLamella> lamellas;  ///< g members first, then h, by index
  std::vector<SimulatedConnection> connections;
  int grid_vertices = 0;  ///< |G_V|: rod vertices in all
  double rms = 0;         ///< RMS distance of all rod vertices to the target patch
  double max_deviation = 0;
  /// Energy per term: stretch, bend_weak, bend_strong, twist, connection, anchor, notch_limit,
  /// friction. In joules when the unit is known, else in the scaled model's units.
  std::map<std::string, double> energies;
  std::string energy_unit;   ///< "J" or "scaled"
  int iterations = 0;        ///< Levenberg-Marquardt iterations in all
  int outer_iterations = 0;  ///< frame updates / re-projections
  int connection_moves = 0;  ///< times a sliding connection moved to a neighbouring edge
  /// Sliding connection ends held at a rod vertex at the end (a kink minimum: the energy rises
  /// to both sides along the member, checked by its one-sided derivatives).
  int connections_at_vertices = 0;
  bool converged = false;    ///< gradient below tolerance and no connection moved at the end
  double gradient_norm = 0;  ///< final max-norm, relative to the reference force
  double gradient_tolerance = 0;
  std::string termination;  ///< why the solver stopped
  double seconds = 0;
  SolverProfile profile;  ///< Newton solver only
};

/// Simulates the deployed grid. `target` is the target patch (distances are measured to it and
/// the rods start on its geodesics: each member's `surface` polyline, resampled); `grid` and
/// `anchors` as designed; lamella width and thickness in mesh units. Throws InvalidInput for an
/// inconsistent grid (empty members, crossings or anchors naming missing members, non-finite
/// values), Cancelled when cancelled.
DeploymentRun simulate_deployment(const Grid& grid, const std::vector<Anchor>& anchors,
                                  const TriangleMesh& target, double lamella_width,
                                  double lamella_thickness, const SimulationOptions& options = {},
                                  const Progress& progress = {});

/// One grid of a structure simulated as a whole (several patches joined at seams): its grid and
/// its anchors, as simulate_deployment takes them.
struct DeploymentPart {
  const Grid* grid = nullptr;
  std::vector<Anchor> anchors;
  /// Optional: the part's own deployment (simulate_deployment of this grid with the same
  /// options but for the anchors) to start from instead of the geodesics: its rod vertices,
  /// material frames and connections' slides.
  const DeploymentRun* start = nullptr;
  /// With a start: its sliding connections are held where they slid to (tightened after the
  /// part deployed), not sliding any more.
  bool lock_connections = false;
};

/// A bolt joining a lamella of one part to a lamella of another at a fixed point of each (it
/// does not slide): end 1's lamella lies `offset` thicknesses above end 0's along end 0's
/// material normal (as a crossing's h lies one thickness on g); the two may turn about their
/// common normal.
struct PartBolt {
  std::array<int, 2> part{};  ///< index into the parts
  std::array<Family, 2> family{Family::G, Family::G};
  std::array<int, 2> member{};  ///< index in its part's family
  std::array<double, 2> s{};    ///< arc length from the member's start (surface = rest length)
  /// End 1 lies this many thicknesses above end 0, along end 0's material normal: 1 as h on g
  /// at a crossing; a seam's two lamellas keep their own patch's heights (layout_deployment.h).
  double offset = 1;
};

/// A bolt's state at the joined equilibrium.
struct BoltState {
  /// |q_0 - q_1 + offset t m_0|: how far the bolt is from closed (the penalty's gap), in mesh
  /// units.
  double gap = 0;
  /// The force the bolt carries: |dE/dq_0| of its position terms, in newtons when the unit is
  /// known (SimulationOptions::unit_in_meters), else in Pa x (mesh unit)^2.
  double force = 0;
};

struct JoinedDeploymentRun {
  /// Everything together: the lamellas and crossings' connections of every part in part order,
  /// the RMS over all rod vertices to the target, the solver's counts, the energies (the
  /// bolts' under "bolts").
  DeploymentRun whole;
  /// Per part: its lamellas and connections, the RMS and largest deviation over its rod
  /// vertices (to the whole target), the stresses; the solver's fields are the whole's; no
  /// energies.
  std::vector<DeploymentRun> parts;
  std::vector<BoltState> bolts;  ///< in the order of the bolts given
  std::string force_unit;        ///< "N" or "Pa*unit^2"
};

/// Simulates several grids as one structure: each part's rods, crossings and anchors as
/// simulate_deployment builds them, and the bolts between parts' lamellas, in one equilibrium,
/// found from each part's start (its own deployment) or from the geodesics of the target (every
/// connection and bolt closed). `target` is the whole surface (distances and normals). Throws
/// InvalidInput as simulate_deployment does, with "parts[i]." before a part's fields ("start"
/// for a start that is not this grid's deployment), and naming "bolts[k]" for a bolt whose part
/// or member does not exist or whose arc length is outside its lamella.
JoinedDeploymentRun simulate_joined(const std::vector<DeploymentPart>& parts,
                                    const std::vector<PartBolt>& bolts, const TriangleMesh& target,
                                    double lamella_width, double lamella_thickness,
                                    const SimulationOptions& options = {},
                                    const Progress& progress = {});

}  // namespace gridshell
