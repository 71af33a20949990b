// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — geodesic front end: surface points, method names, path length and the dispatch
// from GeodesicSolver / DistanceField to the engines (geodesic_fast.cpp, geodesic_cgal.cpp,
// geodesic_heat.cpp).
#include "gridshell/geodesic/geodesic.h"

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <sstream>

#include "geodesic_fast.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_topology.h"

namespace gridshell {

namespace geodesic_detail {

SurfacePoint normalize_surface_point(const TriangleMesh& mesh, const SurfacePoint& point,
                                     const std::string& field) {
  if (point.face < 0 || point.face >= mesh.face_count()) {
    std::ostringstream msg;
    msg << "face " << point.face << " is out of range (the mesh has " << mesh.face_count()
        << " faces)";
    throw InvalidInput(field, msg.str());
  }
  const Vec3& w = point.barycentric;
  const double sum = w[0] + w[1] + w[2];
  if (!std::isfinite(sum) || w.minCoeff() < -1e-9 || std::abs(sum - 1.0) > 1e-9) {
    std::ostringstream msg;
    msg << "barycentric weights (" << w[0] << ", " << w[1] << ", " << w[2] << ") in face "
        << point.face << " must be non-negative and sum to 1";
    throw InvalidInput(field, msg.str());
  }
  SurfacePoint out = point;
  for (int i = 0; i < 3; ++i)
    if (out.barycentric[i] < 1e-14) out.barycentric[i] = 0.0;
  out.barycentric /= out.barycentric.sum();
  for (int i = 0; i < 3; ++i)
    if (out.barycentric[(i + 1) % 3] == 0.0 && out.barycentric[(i + 2) % 3] == 0.0)
      out.barycentric[i] = 1.0;
  return out;
}

int zero_weight_count(const SurfacePoint& point) {
  return (point.barycentric[0] == 0.0) + (point.barycentric[1] == 0.0) +
         (point.barycentric[2] == 0.0);
}

}  // namespace geodesic_detail

// ---------------------------------------------------------------------------------------------
// Method names

GeodesicMethod parse_geodesic_method(const std::string& name) {
  if (name == "fast") return GeodesicMethod::Fast;
  if (name == "cgal") return GeodesicMethod::Cgal;
  if (name == "heat") return GeodesicMethod::Heat;
  throw InvalidInput("", "unknown geodesic method '" + name + "' (expected fast, cgal or heat)");
}

std::string to_string(GeodesicMethod method) {
  switch (method) {
    case GeodesicMethod::Fast:
      return "fast";
    case GeodesicMethod::Cgal:
      return "cgal";
    case GeodesicMethod::Heat:
      return "heat";
  }
  return "unknown";
}

// ---------------------------------------------------------------------------------------------
// DistanceField

DistanceField::DistanceField(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}
DistanceField::~DistanceField() = default;
DistanceField::DistanceField(DistanceField&&) noexcept = default;
DistanceField& DistanceField::operator=(DistanceField&&) noexcept = default;

const SurfacePoint& DistanceField::source() const { return impl_->source; }
const std::vector<double>& DistanceField::vertex_distances() const { return impl_->distances; }
std::size_t DistanceField::memory_bytes() const { return impl_->memory_bytes(); }
std::size_t DistanceField::peak_memory_bytes() const { return impl_->peak_memory_bytes(); }
const std::vector<double>& DistanceField::target_distances() const {
  return impl_->target_distances;
}
double DistanceField::distance_to(const SurfacePoint& target) const {
  return impl_->distance_to(target);
}
std::vector<SurfacePoint> DistanceField::path_to(const SurfacePoint& target) const {
  return impl_->path_to(target);
}

// ---------------------------------------------------------------------------------------------
// GeodesicSolver

GeodesicSolver::GeodesicSolver(const TriangleMesh& mesh, GeodesicOptions options) {
  for (int v = 0; v < mesh.vertex_count(); ++v)
    if (!mesh.vertices()[v].allFinite())
      throw InvalidInput("mesh.vertices[" + std::to_string(v) + "]", "non-finite coordinate");
  switch (options.method) {
    case GeodesicMethod::Fast:
      impl_ = geodesic_detail::make_fast_solver(mesh);
      break;
    case GeodesicMethod::Cgal:
      impl_ = geodesic_detail::make_cgal_solver(mesh);
      break;
    case GeodesicMethod::Heat:
      impl_ = geodesic_detail::make_heat_solver(mesh);
      break;
  }
  if (!impl_) throw std::logic_error("GeodesicSolver: unknown geodesic method");
  impl_->method = options.method;
}

GeodesicSolver::~GeodesicSolver() = default;
GeodesicSolver::GeodesicSolver(GeodesicSolver&&) noexcept = default;
GeodesicSolver& GeodesicSolver::operator=(GeodesicSolver&&) noexcept = default;

const TriangleMesh& GeodesicSolver::mesh() const { return impl_->mesh; }
GeodesicMethod GeodesicSolver::method() const { return impl_->method; }

DistanceField GeodesicSolver::solve(const SurfacePoint& source, const Progress& progress) const {
  return solve(source, SolveOptions{}, progress);
}

DistanceField GeodesicSolver::solve(const SurfacePoint& source, const SolveOptions& options,
                                    const Progress& progress) const {
  const SurfacePoint s = geodesic_detail::normalize_surface_point(impl_->mesh, source, "source");
  if (options.stop_at_targets && options.targets.empty())
    throw InvalidInput("options.stop_at_targets", "needs at least one target");
  const SolveOptions::Goal& goal = options.goal;
  if (!goal.center.allFinite()) throw InvalidInput("options.goal.center", "must be a finite point");
  if (!(goal.radius >= 0) || !std::isfinite(goal.radius))
    throw InvalidInput("options.goal.radius", "must be finite and >= 0");
  if (!(goal.bound >= 0))
    throw InvalidInput("options.goal.bound", "must be >= 0 (+inf: no pruning)");
  SolveOptions checked = options;
  for (SurfacePoint& t : checked.targets)
    t = geodesic_detail::normalize_surface_point(
        impl_->mesh, t, "options.targets[" + std::to_string(&t - checked.targets.data()) + "]");
  return impl_->solve(s, checked, progress);
}

std::vector<double> GeodesicSolver::distances(const SurfacePoint& source,
                                              const Progress& progress) const {
  SolveOptions options;
  options.keep_windows = false;
  return solve(source, options, progress).vertex_distances();
}

namespace {

// The goal of a solve that needs the exact answer at `to` only (shortest_path, distance).
SolveOptions::Goal point_goal(const TriangleMesh& mesh, const SurfacePoint& from,
                              const SurfacePoint& to) {
  SolveOptions::Goal goal;
  const double bound = edge_path_bound(mesh, from, to);
  if (!std::isfinite(bound)) return goal;  // no pruning: the solve finds out what is reachable
  goal.center = to.position(mesh);
  goal.radius = 0;
  // The bound is the length of a real path; a little more keeps rounding from pruning the
  // shortest one when they are equal (a path along an edge line).
  goal.bound = bound * (1 + 1e-9) + 1e-12 * bounding_box_size(mesh).norm();
  return goal;
}

}  // namespace

std::vector<SurfacePoint> GeodesicSolver::shortest_path(const SurfacePoint& from,
                                                        const SurfacePoint& to,
                                                        const Progress& progress) const {
  const SurfacePoint a = geodesic_detail::normalize_surface_point(impl_->mesh, from, "from");
  const SurfacePoint b = geodesic_detail::normalize_surface_point(impl_->mesh, to, "to");
  SolveOptions options;
  options.goal = point_goal(impl_->mesh, a, b);
  return solve(a, options, progress).path_to(b);
}

double GeodesicSolver::distance(const SurfacePoint& from, const SurfacePoint& to,
                                const Progress& progress) const {
  const SurfacePoint a = geodesic_detail::normalize_surface_point(impl_->mesh, from, "from");
  const SurfacePoint b = geodesic_detail::normalize_surface_point(impl_->mesh, to, "to");
  SolveOptions options;
  options.keep_windows = false;
  options.targets = {b};
  options.goal = point_goal(impl_->mesh, a, b);
  return solve(a, options, progress).target_distances()[0];
}

// ---------------------------------------------------------------------------------------------

double edge_path_bound(const TriangleMesh& mesh, const SurfacePoint& from, const SurfacePoint& to) {
  const SurfacePoint a = geodesic_detail::normalize_surface_point(mesh, from, "from");
  const SurfacePoint b = geodesic_detail::normalize_surface_point(mesh, to, "to");
  const Vec3 pa = a.position(mesh), pb = b.position(mesh);
  const MeshTopology& topology = mesh.topology();
  std::vector<double> d(mesh.vertex_count(), std::numeric_limits<double>::infinity());
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  for (int v : mesh.faces()[a.face]) {
    const double start = (mesh.vertices()[v] - pa).norm();
    if (start < d[v]) queue.push({d[v] = start, v});
  }
  std::array<int, 3> goal = mesh.faces()[b.face];
  int settled_goals = 0;
  double best = a.face == b.face ? (pb - pa).norm() : std::numeric_limits<double>::infinity();
  while (!queue.empty() && settled_goals < 3) {
    const auto [dv, v] = queue.top();
    queue.pop();
    if (dv > d[v]) continue;
    if (dv >= best) break;  // no path through later vertices is shorter
    for (int g : goal)
      if (g == v) {
        ++settled_goals;
        best = std::min(best, dv + (pb - mesh.vertices()[v]).norm());
      }
    for (int f : topology.vertex_faces[v])
      for (int w : mesh.faces()[f]) {
        if (w == v) continue;
        const double dw = dv + (mesh.vertices()[w] - mesh.vertices()[v]).norm();
        if (dw < d[w]) queue.push({d[w] = dw, w});
      }
  }
  return best;
}

double path_length(const TriangleMesh& mesh, const std::vector<SurfacePoint>& path) {
  double length = 0;
  for (size_t i = 1; i < path.size(); ++i)
    length += (path[i].position(mesh) - path[i - 1].position(mesh)).norm();
  return length;
}

}  // namespace gridshell
