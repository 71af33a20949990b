// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — can the patch be covered by shortest geodesics? (paper Section 3.3)
//
// Shortest geodesics from one boundary leave gaps behind peaks of positive Gaussian curvature
// (the cut locus). The injectivity bound pi/sqrt(Kmax) (Rauch comparison, eq. 1) is a quick
// sufficient check; the gap factor eta measures how large the gap behind the curvature peak
// is, and cotangent-Laplacian smoothing with a fixed boundary shrinks it until eta <= eta_max.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "gridshell/design/distance_map_copy.h"
#include "gridshell/design/patch.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/geodesic/geodesic.h"

namespace gridshell {

struct CoverabilityOptions {
  double eta_max = 1.0015;            // paper's empirical threshold
  int max_smoothing_iterations = 60;  // cap; exceeding it is Infeasible (exit 3)
  /// Implicit smoothing time step per iteration, in units of the squared mean edge length.
  double smoothing_step = 0.5;
  /// Sources per side when searching the longest boundary-to-boundary distance.
  int member_distance_samples = 9;
  /// Worker threads for those sources' solves; 0 = hardware concurrency (the result does not
  /// depend on it).
  int threads = 0;
  /// A patch with more vertices than this has its longest member distance measured on a copy
  /// simplified to about this many vertices (distance_map_copy.h, the one its distance maps can
  /// then use); the gap factor stays exact. 0 = never. Default 4000.
  int max_vertices = kDefaultMapVertices;
};

/// The gap factor (paper 3.3) for one curvature peak.
struct GapFactor {
  double eta = 1.0;  ///< (d(p1,pmax) + d(pmax,q1)) / d(p1,q1) >= 1
  int peak = -1;     ///< p_max: vertex of maximal Gaussian curvature
  int p1 = -1;       ///< boundary vertex closest (geodesically) to the peak
  int q1 = -1;       ///< vertex on the opposite side minimizing d(p1,pmax)+d(pmax,q)-d(p1,q)
};

struct CoverabilityReport {
  double gaussian_curvature_max = 0;  ///< max over interior vertices (discrete, angle defect/area)
  int gaussian_curvature_max_vertex = -1;
  double injectivity_bound = 0;        ///< pi/sqrt(Kmax), +inf when Kmax <= 0
  double longest_member_distance = 0;  ///< max geodesic distance between opposite sides (sampled)
  bool injectivity_ok = true;          ///< longest_member_distance < injectivity_bound
  GapFactor gap;
  /// Vertices of the mesh the longest member distance was measured on: the patch's own count,
  /// or that of its simplified copy (`map_copy`, kept for the distance maps).
  int longest_member_vertices = 0;
  std::shared_ptr<const MapCopy> map_copy;
};

/// The gap factor at the vertex of maximal Gaussian curvature. With the paper's notation:
/// p1 = closest boundary vertex to p_max, q ranges over the side opposite p1 (both opposite
/// sides if p1 is a corner; the larger eta is returned). Cancellable through `progress`.
GapFactor gap_factor(const Patch& patch, const GeodesicSolver& solver,
                     const std::vector<double>& gaussian_curvature, const Progress& progress = {});

/// Curvature, injectivity bound, longest member distance and gap factor of the patch, with
/// geodesics computed as `geodesic` says.
CoverabilityReport analyze_coverability(const Patch& patch, const GeodesicOptions& geodesic = {},
                                        const CoverabilityOptions& options = {},
                                        const Progress& progress = {});

/// One implicit cotangent-Laplacian fairing step (Desbrun et al. 1999): solves
/// (M + h L) x' = M x for the free vertices, h = step * (mean edge length)^2; `fixed` vertices
/// stay where they are. Returns the largest vertex displacement.
double laplacian_smoothing_step(TriangleMesh& mesh, const std::vector<char>& fixed, double step);

struct SmoothingResult {
  int iterations = 0;  ///< smoothing steps, over all rounds
  double eta_before = 1.0;
  double eta_after = 1.0;
  double max_displacement = 0;  ///< largest vertex movement from the input surface
  int recuts = 0;  ///< times the patch was re-cut along the smoothed surface's boundary geodesics
};

/// Relative excess of each side over the exact shortest geodesic between its corners on the
/// patch itself: (polyline length of sides[i] - d(c_i, c_i+1)) / polyline length; 0 when the
/// side is a shortest geodesic of the patch (rounding aside). Four exact solves, each pruned to
/// the paths no longer than its side (which is itself a path between the corners), on `threads`
/// workers (0 = all cores).
std::array<double, 4> boundary_geodesic_excess(const Patch& patch,
                                               const GeodesicOptions& geodesic = {},
                                               const Progress& progress = {}, int threads = 0);

/// A side counts as a shortest geodesic of the patch when its excess is at most this.
constexpr double kBoundaryGeodesicTolerance = 1e-9;

/// Smooths the patch interior (boundary fixed) until eta <= eta_max, then makes the boundary
/// exact again (paper 3.2 needs the four sides to be shortest geodesics of the patch the grid
/// is designed on, and smoothing moves the surface under them): the boundary geodesics between
/// the same corners are recomputed on the smoothed surface and the patch is re-cut along them;
/// if the re-cut patch has eta > eta_max again, it is smoothed and re-cut again. Ends when both
/// hold. Throws Infeasible (field "corners") with eta and the boundary excess when the
/// iteration cap (CoverabilityOptions::max_smoothing_iterations, over all rounds) or
/// kMaxRecuts re-cuts are reached first. `eta`: the gap factor of `patch` as given, if the caller
/// has measured it already (else it is measured here). `recut` false (a layout's shared
/// sides): a side that is no longer a shortest geodesic after smoothing is Infeasible instead
/// of re-cut.
SmoothingResult smooth_until_coverable(Patch& patch, const GeodesicOptions& geodesic = {},
                                       const CoverabilityOptions& options = {},
                                       const Progress& progress = {},
                                       std::optional<double> eta = std::nullopt, bool recut = true);

/// Re-cuts in one smoothing run, at most.
constexpr int kMaxRecuts = 12;

}  // namespace gridshell
