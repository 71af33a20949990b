// SPDX-License-Identifier: GPL-3.0-or-later
// Patch layouts: cut each patch, check the layout whole (see gridshell/design/layout.h).
#include "gridshell/design/layout.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "gridshell/design/cladding.h"
#include "gridshell/design/distance_map.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"
#include "gridshell/mesh/surface_distance.h"

namespace gridshell {
namespace {

std::string corner_field(size_t patch, int k) {
  return "layout.patches[" + std::to_string(patch) + "].corners[" + std::to_string(k) + "]";
}

/// Distance from p to segment ab.
double point_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

/// Largest distance from a point of `from` to the polyline `to`.
double one_sided(const std::vector<Vec3>& from, const std::vector<Vec3>& to) {
  double worst = 0;
  for (const Vec3& p : from) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k + 1 < to.size(); ++k)
      best = std::min(best, point_segment(p, to[k], to[k + 1]));
    if (to.size() == 1) best = (p - to[0]).norm();
    worst = std::max(worst, best);
  }
  return worst;
}

/// The side of a cut patch that runs between the positions `a` and `b` (either direction), as
/// points from a to b; empty if none does.
std::vector<Vec3> side_between(const Patch& patch, const Vec3& a, const Vec3& b, double tolerance) {
  for (const std::vector<int>& side : patch.sides) {
    if (side.size() < 2) continue;
    const Vec3& p = patch.mesh.vertices()[side.front()];
    const Vec3& q = patch.mesh.vertices()[side.back()];
    std::vector<Vec3> points;
    for (int v : side) points.push_back(patch.mesh.vertices()[v]);
    if ((p - a).norm() <= tolerance && (q - b).norm() <= tolerance) return points;
    if ((p - b).norm() <= tolerance && (q - a).norm() <= tolerance) {
      std::reverse(points.begin(), points.end());
      return points;
    }
  }
  return {};
}

double polyline_length(const std::vector<Vec3>& points) {
  double length = 0;
  for (size_t k = 0; k + 1 < points.size(); ++k) length += (points[k + 1] - points[k]).norm();
  return length;
}

}  // namespace

LayoutResult cut_layout(const TriangleMesh& mesh, const PatchLayout& layout,
                        const TargetPatchOptions& options, const Progress& progress,
                        LayoutChecks checks) {
  LayoutResult out;
  out.layout = layout;
  const int corner_count = static_cast<int>(layout.corners.size());
  if (layout.patches.empty()) throw InvalidInput("layout.patches", "a layout needs a patch");
  for (int i = 0; i < corner_count; ++i) {
    const LayoutCorner& c = layout.corners[i];
    const std::string field = "layout.corners[" + std::to_string(i) + "]";
    if (c.vertex >= mesh.vertex_count())
      throw InvalidInput(field, "vertex index " + std::to_string(c.vertex) +
                                    " is out of range (the mesh has " +
                                    std::to_string(mesh.vertex_count()) + " vertices)");
    if (c.vertex < 0 && !c.point.allFinite()) throw InvalidInput(field, "not a finite point");
  }
  // Names and corners of each patch.
  std::set<std::string> names;
  for (size_t j = 0; j < layout.patches.size(); ++j) {
    PatchLayout::Quad& quad = out.layout.patches[j];
    if (quad.name.empty()) quad.name = "P" + std::to_string(j + 1);
    if (!names.insert(quad.name).second)
      throw InvalidInput("layout.patches[" + std::to_string(j) + "].name",
                         "'" + quad.name + "' names two patches");
    for (int k = 0; k < 4; ++k) {
      if (quad.corners[k] < 0 || quad.corners[k] >= corner_count)
        throw InvalidInput(corner_field(j, k), "corner " + std::to_string(quad.corners[k]) +
                                                   " is out of range (the layout has " +
                                                   std::to_string(corner_count) + " corners)");
      for (int m = 0; m < k; ++m)
        if (quad.corners[m] == quad.corners[k])
          throw InvalidInput(corner_field(j, k), "corner " + std::to_string(quad.corners[k]) +
                                                     " is in the patch twice");
    }
  }
  // Sides: each joins two corners and belongs to at most two patches.
  std::map<std::pair<int, int>, LayoutSeam> sides;
  for (size_t j = 0; j < out.layout.patches.size(); ++j)
    for (int k = 0; k < 4; ++k) {
      const int a = out.layout.patches[j].corners[k],
                b = out.layout.patches[j].corners[(k + 1) % 4];
      LayoutSeam& seam = sides[{std::min(a, b), std::max(a, b)}];
      seam.corners = {std::min(a, b), std::max(a, b)};
      seam.uses.emplace_back(static_cast<int>(j), k);
      if (seam.uses.size() > 2)
        throw InvalidInput("layout.patches[" + std::to_string(j) + "]",
                           "the side between corners " + std::to_string(seam.corners[0]) + " and " +
                               std::to_string(seam.corners[1]) +
                               " is a side of three patches; a seam joins two");
    }

  // Every corner a vertex of one mesh, every side one exact shortest geodesic on it, computed
  // once: two patches that share a side are cut along the same points.
  progress.report("layout: corners", 0);
  std::vector<SurfacePoint> points(corner_count);
  {
    std::optional<SurfaceDistance> closest;
    for (int i = 0; i < corner_count; ++i) {
      const LayoutCorner& c = layout.corners[i];
      if (c.vertex >= 0) {
        points[i] = SurfacePoint::at_vertex(mesh, c.vertex);
        continue;
      }
      if (c.point.cwiseAbs().maxCoeff() > kMaxCoordinate)
        throw InvalidInput("layout.corners[" + std::to_string(i) + "]",
                           "a coordinate is not within +-1e15");
      if (!closest) closest.emplace(mesh);
      points[i] = closest->closest(c.point);
    }
  }
  const MeshWithCorners cornered = insert_corners(mesh, points, "layout.corners", options.cut);
  for (int v : cornered.corners) out.corners.push_back(cornered.mesh.vertices()[v]);
  const GeodesicSolver solver(cornered.mesh, options.geodesic);
  std::map<std::pair<int, int>, std::vector<SurfacePoint>> side_paths;  // from .first to .second
  std::map<std::pair<int, int>, Error> side_errors;
  size_t solved = 0;
  for (auto& [key, seam] : sides) {
    progress.report("layout: sides", static_cast<double>(solved++) / sides.size());
    try {
      side_paths[key] = side_geodesic(solver, cornered.mesh, cornered.corners[key.first],
                                      cornered.corners[key.second], progress.checker());
    } catch (const Cancelled&) {
      throw;
    } catch (const Error& e) {
      side_errors.emplace(key, Error(e.code(), "corners",
                                     "corners " + std::to_string(key.first) + " and " +
                                         std::to_string(key.second) + ": " + e.message()));
    }
  }

  // Each patch cut along its sides and checked as a single patch is. Smoothing moves a patch's
  // interior only (its sides, shared with neighbours, stay fixed) and never re-cuts a side: a
  // patch whose sides stop being shortest geodesics fails. The patches are independent: cut and
  // checked side by side, each on a share of the threads (the result does not depend on them).
  const size_t count = out.layout.patches.size();
  ParallelOptions parallel;
  parallel.threads = static_cast<int>(
      std::min<size_t>(static_cast<size_t>(resolve_threads(options.coverability.threads)), count));
  parallel.stage = "layout: patches";
  TargetPatchOptions patch_options = options;
  patch_options.fixed_sides = true;
  patch_options.coverability.threads =
      std::max(1, resolve_threads(options.coverability.threads) / std::max(1, parallel.threads));
  out.input_area = surface_area(mesh);
  out.patches.resize(count);
  parallel_for(
      count,
      [&](std::size_t j, const Progress& inner) {
        const PatchLayout::Quad& quad = out.layout.patches[j];
        const std::string field = "layout.patches[" + std::to_string(j) + "]";
        LayoutPatch& result = out.patches[j];
        result.name = quad.name;
        try {
          std::array<int, 4> corners{};
          std::array<std::vector<SurfacePoint>, 4> patch_sides;
          std::array<SurfacePoint, 4> input_corners;
          for (int k = 0; k < 4; ++k) {
            const int a = quad.corners[k], b = quad.corners[(k + 1) % 4];
            const std::pair<int, int> key{std::min(a, b), std::max(a, b)};
            if (side_errors.count(key)) throw side_errors.at(key);
            patch_sides[k] = side_paths.at(key);
            if (a != key.first) std::reverse(patch_sides[k].begin(), patch_sides[k].end());
            corners[k] = cornered.corners[a];
            input_corners[k] = points[a];
          }
          Patch cut = cut_patch_along(cornered.mesh, corners, patch_sides, mesh.vertex_count(),
                                      options.cut, inner);
          if (checks == LayoutChecks::CutOnly) {
            check_convex_corners(cut);
            TargetPatch& t = result.target.emplace();
            t.input_corners = input_corners;
            t.corner_angles = corner_angles(cut);
            t.boundary_lengths = side_lengths(cut);
            t.area = surface_area(cut.mesh);
            t.patch = std::move(cut);
            return;
          }
          result.target =
              target_patch_from_cut(std::move(cut), input_corners, patch_options, inner);
          TargetPatch& t = *result.target;
          // As for a single patch, an eta above eta_max is left where the injectivity bound holds
          // (smooth_until_coverable runs otherwise): only without smoothing does it fail.
          if (!patch_options.smooth && t.smoothing.eta_after > patch_options.coverability.eta_max) {
            std::ostringstream msg;
            msg << "gap factor eta " << t.smoothing.eta_after << " is above eta_max "
                << patch_options.coverability.eta_max << " and smoothing is off";
            result.problem = Infeasible(field, msg.str());
          } else {
            for (int k = 0; k < 4; ++k)
              if (t.boundary_excess[k] > kBoundaryGeodesicTolerance) {
                std::ostringstream msg;
                msg << "side " << k << " is " << t.boundary_excess[k]
                    << " (relative) longer than the shortest geodesic between its corners";
                result.problem = Infeasible(field, msg.str());
                break;
              }
          }
          // A patch is only covered if it can be designed: a feasible planar angle on its
          // distance maps (the design's, as the automatic corners' search checks it). The maps
          // stay with the patch for its design.
          if (!result.problem) {
            const GeodesicSolver solver(t.patch.mesh, patch_options.geodesic);
            auto maps = std::make_shared<DistanceMaps>(compute_distance_maps(
                t.patch, solver, patch_options.auto_corners.maps, inner.checker()));
            const AlphaRange range = feasible_alpha_range(
                *maps, side_lengths(t.patch), patch_options.auto_corners.cladding, inner.checker());
            result.alpha_range = std::array<double, 2>{range.min, range.max};
            t.maps = std::move(maps);
            t.maps_options = patch_options.auto_corners.maps;
          }
        } catch (const Cancelled&) {
          throw;
        } catch (const Error& e) {
          result.problem = Error(e.code(), join_field(field, e.field()), e.message(), e.reason());
        }
      },
      progress, parallel);
  for (const LayoutPatch& p : out.patches)
    if (p.target && !p.problem) out.covered_area += p.target->area;

  // Seams: two patches on opposite sides, cut along the same curve.
  const double scale = std::max(1.0, bounding_box_size(mesh).norm());
  for (auto& [key, seam] : sides) {
    if (seam.shared()) {
      const auto [j1, k1] = seam.uses[0];
      const auto [j2, k2] = seam.uses[1];
      // The side runs corners[k] -> corners[k+1] in each patch's own order: neighbours on either
      // side of it run it in opposite directions.
      const bool forward1 = out.layout.patches[j1].corners[k1] == seam.corners[0];
      const bool forward2 = out.layout.patches[j2].corners[k2] == seam.corners[0];
      if (forward1 == forward2)
        throw Infeasible("layout.patches[" + std::to_string(j2) + "]",
                         "patches " + out.layout.patches[j1].name + " and " +
                             out.layout.patches[j2].name + " run the side between corners " +
                             std::to_string(seam.corners[0]) + " and " +
                             std::to_string(seam.corners[1]) +
                             " in the same direction: give both patches' corners in the same "
                             "turning sense, so that they lie on either side of it");
    }
    // Each cut patch's side along the seam, from its first corner to its second.
    std::vector<std::vector<Vec3>> polylines;
    for (const auto& [j, k] : seam.uses) {
      if (!out.patches[j].target) continue;
      const TargetPatch& target = *out.patches[j].target;
      const std::array<int, 4>& quad = out.layout.patches[j].corners;
      const Vec3 a = cornered.mesh.vertices()[cornered.corners[quad[k]]];
      const Vec3 b = cornered.mesh.vertices()[cornered.corners[quad[(k + 1) % 4]]];
      std::vector<Vec3> side = side_between(target.patch, a, b, 1e-9 * scale);
      if (out.layout.patches[j].corners[k] != seam.corners[0])
        std::reverse(side.begin(), side.end());
      polylines.push_back(std::move(side));
    }
    if (!polylines.empty() && !polylines[0].empty()) {
      seam.length = polyline_length(polylines[0]);
      seam.points = polylines[0];
    }
    if (polylines.size() == 2 && !polylines[0].empty() && !polylines[1].empty())
      seam.mismatch =
          std::max(one_sided(polylines[0], polylines[1]), one_sided(polylines[1], polylines[0]));
    out.seams.push_back(seam);
  }
  progress.report("layout", 1.0);
  return out;
}

namespace {

std::string svg_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

/// Eight colours that tell neighbours apart (Okabe-Ito), light enough for black text.
const char* patch_colour(size_t k) {
  static const char* colours[] = {"#e69f00", "#56b4e9", "#009e73", "#f0e442",
                                  "#0072b2", "#d55e00", "#cc79a7", "#999999"};
  return colours[k % 8];
}

}  // namespace

std::string layout_svg(const TriangleMesh& mesh, const LayoutResult& layout) {
  // The plan: the input's centroid and its two largest principal directions.
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : mesh.vertices()) centre += p;
  centre /= std::max<size_t>(1, mesh.vertices().size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : mesh.vertices()) covariance += (p - centre) * (p - centre).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  // Signs fixed so that a direction's largest coordinate is positive (the plan of a surface over
  // the xy plane keeps x to the right and y up).
  const auto signed_axis = [](Vec3 axis) {
    Eigen::Index largest = 0;
    axis.cwiseAbs().maxCoeff(&largest);
    return axis[largest] < 0 ? Vec3(-axis) : axis;
  };
  const Vec3 ex = signed_axis(eigen.eigenvectors().col(2)),
             ey = signed_axis(eigen.eigenvectors().col(1));
  const auto plan = [&](const Vec3& p) { return Vec2((p - centre).dot(ex), (p - centre).dot(ey)); };
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec3& p : mesh.vertices()) lo = lo.cwiseMin(plan(p)), hi = hi.cwiseMax(plan(p));
  if (mesh.vertices().empty()) lo = hi = Vec2::Zero();
  const double margin = 0.05 * std::max(1e-9, (hi - lo).maxCoeff());
  lo.array() -= margin;
  hi.array() += margin;
  const Vec2 size = hi - lo;
  const double stroke = 0.003 * size.maxCoeff();
  const auto point = [&](const Vec3& p) {
    const Vec2 q = plan(p);
    return svg_number(q.x() - lo.x()) + "," + svg_number(hi.y() - q.y());
  };
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << svg_number(size.x()) << " "
      << svg_number(size.y()) << "\">\n<title>gridshell layout: " << layout.patches.size()
      << " patches, coverage " << svg_number(100 * layout.coverage())
      << " %; plan on the input's two largest principal directions</title>\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  // The input's boundary loops, dashed.
  for (const std::vector<int>& loop : mesh.topology().boundary_loops) {
    svg << "<polygon fill=\"none\" stroke=\"#555\" stroke-dasharray=\"" << svg_number(4 * stroke)
        << "\" stroke-width=\"" << svg_number(stroke) << "\" points=\"";
    for (int v : loop) svg << point(mesh.vertices()[v]) << " ";
    svg << "\"/>\n";
  }
  // Each cut patch: its boundary (the four sides in order), filled; its name at its centre.
  for (size_t j = 0; j < layout.patches.size(); ++j) {
    const LayoutPatch& p = layout.patches[j];
    if (!p.target) continue;
    const Patch& patch = p.target->patch;
    svg << "<polygon fill=\"" << patch_colour(j) << "\" fill-opacity=\""
        << (p.problem ? "0.2" : "0.55") << "\" stroke=\"black\" stroke-width=\""
        << svg_number(stroke) << "\" points=\"";
    Vec3 sum = Vec3::Zero();
    int count = 0;
    for (const std::vector<int>& side : patch.sides)
      for (size_t k = 0; k + 1 < side.size(); ++k) {
        svg << point(patch.mesh.vertices()[side[k]]) << " ";
        sum += patch.mesh.vertices()[side[k]];
        ++count;
      }
    svg << "\"/>\n";
    const Vec3 middle = sum / std::max(1, count);
    const std::string at = point(middle);
    svg << "<text x=\"" << at.substr(0, at.find(',')) << "\" y=\"" << at.substr(at.find(',') + 1)
        << "\" font-size=\"" << svg_number(0.035 * size.maxCoeff())
        << "\" text-anchor=\"middle\" font-family=\"sans-serif\">" << p.name
        << (p.problem ? " (fails)" : "") << "</text>\n";
  }
  // Shared seams thick; corners as dots with their layout index.
  for (const LayoutSeam& seam : layout.seams) {
    if (!seam.shared() || seam.points.size() < 2) continue;
    svg << "<polyline fill=\"none\" stroke=\"black\" stroke-width=\"" << svg_number(3 * stroke)
        << "\" points=\"";
    for (const Vec3& p : seam.points) svg << point(p) << " ";
    svg << "\"/>\n";
  }
  for (size_t i = 0; i < layout.corners.size(); ++i) {
    const std::string at = point(layout.corners[i]);
    const std::string x = at.substr(0, at.find(',')), y = at.substr(at.find(',') + 1);
    svg << "<circle cx=\"" << x << "\" cy=\"" << y << "\" r=\"" << svg_number(2.5 * stroke)
        << "\" fill=\"black\"/><text x=\"" << x << "\" y=\"" << y << "\" dx=\""
        << svg_number(3 * stroke) << "\" font-size=\"" << svg_number(0.025 * size.maxCoeff())
        << "\" font-family=\"sans-serif\">" << i << "</text>\n";
  }
  svg << "</svg>\n";
  return svg.str();
}

}  // namespace gridshell
