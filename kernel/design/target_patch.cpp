// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/design/target_patch.h"

#include <chrono>

#include "gridshell/mesh/errors.h"
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
    case CornerSpec::Kind::Auto: {
      const auto corners = auto_corners(mesh);
      for (int i = 0; i < 4; ++i)
        result.input_corners[i] = SurfacePoint::at_vertex(mesh, corners[i]);
      break;
    }
  }
  result.patch = cut_patch(mesh, result.input_corners, options.geodesic, options.cut, progress);
  check_convex_corners(result.patch);
  result.stage_seconds["cut"] = seconds_since(start);

  start = std::chrono::steady_clock::now();
  result.coverability =
      analyze_coverability(result.patch, options.geodesic, options.coverability, progress);
  result.stage_seconds["coverability"] = seconds_since(start);

  start = std::chrono::steady_clock::now();
  // Paper 3.3: a patch whose longest member is shorter than the injectivity bound pi/sqrt(Kmax)
  // is covered by shortest geodesics as it is; only otherwise is the gap measured by eta and
  // smoothed away.
  if (options.smooth && !result.coverability.injectivity_ok) {
    result.smoothing =
        smooth_until_coverable(result.patch, options.geodesic, options.coverability, progress);
  } else {
    result.smoothing.eta_before = result.smoothing.eta_after = result.coverability.gap.eta;
  }
  result.stage_seconds["smoothing"] = seconds_since(start);

  result.corner_angles = corner_angles(result.patch);
  check_convex_corners(result.patch);
  result.boundary_lengths = side_lengths(result.patch);
  result.area = surface_area(result.patch.mesh);
  return result;
}

}  // namespace gridshell
