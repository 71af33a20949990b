// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/design/target_patch.h"

#include <chrono>
#include <sstream>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/surface_distance.h"

namespace gridshell {
namespace {
double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

TargetPatch make_target_patch(const TriangleMesh& mesh, const CornerSpec& spec,
                              const TargetPatchOptions& options, const Progress& progress) {
  TargetPatch result;
  auto start = std::chrono::steady_clock::now();
  switch (spec.kind) {
    case CornerSpec::Kind::Vertices:
      for (int i = 0; i < 4; ++i) {
        if (spec.vertices[i] < 0 || spec.vertices[i] >= mesh.vertex_count())
          throw InvalidInput("corners.vertices[" + std::to_string(i) + "]",
                             "vertex index " + std::to_string(spec.vertices[i]) +
                                 " is out of range (the mesh has " +
                                 std::to_string(mesh.vertex_count()) + " vertices)");
        if (mesh.topology().vertex_faces[spec.vertices[i]].empty())
          throw InvalidInput(
              "corners.vertices[" + std::to_string(i) + "]",
              "vertex " + std::to_string(spec.vertices[i]) + " is isolated (no face uses it)");
        result.input_corners[i] = SurfacePoint::at_vertex(mesh, spec.vertices[i]);
      }
      break;
    case CornerSpec::Kind::Points: {
      for (int i = 0; i < 4; ++i)
        if (!spec.points[i].allFinite() || spec.points[i].cwiseAbs().maxCoeff() > kMaxCoordinate)
          throw InvalidInput("corners.points[" + std::to_string(i) + "]",
                             "a coordinate is not a finite number within +-1e15");
      const SurfaceDistance closest(mesh);
      for (int i = 0; i < 4; ++i) result.input_corners[i] = closest.closest(spec.points[i]);
      break;
    }
    case CornerSpec::Kind::Auto:
      return search_auto_corners(mesh, options, progress);
  }
  const double resolve_seconds = seconds_since(start);
  TargetPatch out = target_patch_at(mesh, result.input_corners, options, progress);
  out.stage_seconds["cut"] += resolve_seconds;
  return out;
}

TargetPatch target_patch_at(const TriangleMesh& mesh, const std::array<SurfacePoint, 4>& corners,
                            const TargetPatchOptions& options, const Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  Patch patch = cut_patch(mesh, corners, options.geodesic, options.cut, progress);
  const double cut_seconds = seconds_since(start);
  TargetPatch result = target_patch_from_cut(std::move(patch), corners, options, progress);
  result.stage_seconds["cut"] = cut_seconds;
  return result;
}

TargetPatch target_patch_from_cut(Patch patch, const std::array<SurfacePoint, 4>& corners,
                                  const TargetPatchOptions& options, const Progress& progress) {
  TargetPatch result;
  result.input_corners = corners;
  result.patch = std::move(patch);
  check_convex_corners(result.patch);
  auto start = std::chrono::steady_clock::now();
  result.coverability =
      analyze_coverability(result.patch, options.geodesic, options.coverability, progress);
  result.stage_seconds["coverability"] = seconds_since(start);

  start = std::chrono::steady_clock::now();
  // Paper 3.3: a patch whose longest member is shorter than the injectivity bound pi/sqrt(Kmax)
  // is covered by shortest geodesics as it is; only otherwise is the gap measured by eta and
  // smoothed away (and the boundary re-cut on the smoothed surface, smooth_until_coverable).
  if (options.smooth && !result.coverability.injectivity_ok) {
    result.smoothing =
        smooth_until_coverable(result.patch, options.geodesic, options.coverability, progress,
                               result.coverability.gap.eta, !options.fixed_sides);
  } else {
    result.smoothing.eta_before = result.smoothing.eta_after = result.coverability.gap.eta;
  }
  result.stage_seconds["smoothing"] = seconds_since(start);
  // Never a silent eta above eta_max (issue 18): say why it was left.
  const double eta_max = options.coverability.eta_max;
  if (result.smoothing.eta_after > eta_max) {
    std::ostringstream msg;
    msg << "gap factor eta " << result.smoothing.eta_after << " > eta_max " << eta_max << ": ";
    if (!options.smooth)
      msg << "smoothing is off, so the patch may have gaps no shortest geodesic covers";
    else
      msg << "not smoothed because the injectivity bound holds (longest member "
          << result.coverability.longest_member_distance << " < pi/sqrt(Kmax) "
          << result.coverability.injectivity_bound
          << "), the paper's sufficient condition for coverage by shortest geodesics (3.3); "
             "eta is measured at the Gaussian curvature maximum K = "
          << result.coverability.gaussian_curvature_max;
    result.warnings.push_back(msg.str());
  }
  // The four sides must be shortest geodesics of the final patch: measured, not assumed.
  start = std::chrono::steady_clock::now();
  result.boundary_excess = boundary_geodesic_excess(result.patch, options.geodesic, progress,
                                                    options.coverability.threads);
  result.stage_seconds["boundary_check"] = seconds_since(start);
  for (int i = 0; i < 4; ++i)
    if (result.boundary_excess[i] > kBoundaryGeodesicTolerance) {
      std::ostringstream msg;
      msg << "side c" << i << "-c" << (i + 1) % 4 << " is " << result.boundary_excess[i]
          << " (relative) longer than the shortest geodesic between its corners on the patch";
      result.warnings.push_back(msg.str());
    }

  result.corner_angles = corner_angles(result.patch);
  check_convex_corners(result.patch);
  result.boundary_lengths = side_lengths(result.patch);
  result.area = surface_area(result.patch.mesh);
  return result;
}

}  // namespace gridshell
