// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/mesh/surface_distance.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <vector>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/normals.h"

namespace gridshell {
namespace {
using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point to_point(const Vec3& v) { return Point(v.x(), v.y(), v.z()); }
}  // namespace

struct SurfaceDistance::Impl {
  TriangleMesh mesh;
  std::vector<Triangle> triangles;
  std::vector<Vec3> normals;
  Tree tree;
};

SurfaceDistance::SurfaceDistance(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  if (mesh.faces().empty()) throw InvalidInput("", "the surface has no faces");
  impl_->mesh = mesh;
  impl_->triangles.reserve(mesh.faces().size());
  for (const Face& f : mesh.faces())
    impl_->triangles.emplace_back(to_point(mesh.vertices()[f[0]]), to_point(mesh.vertices()[f[1]]),
                                  to_point(mesh.vertices()[f[2]]));
  impl_->normals = vertex_normals(mesh);
  impl_->tree.insert(impl_->triangles.begin(), impl_->triangles.end());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
}

SurfaceDistance::~SurfaceDistance() = default;
SurfaceDistance::SurfaceDistance(SurfaceDistance&&) noexcept = default;
SurfaceDistance& SurfaceDistance::operator=(SurfaceDistance&&) noexcept = default;

double SurfaceDistance::distance(const Vec3& point) const {
  return std::sqrt(impl_->tree.squared_distance(to_point(point)));
}

SurfacePoint SurfaceDistance::closest(const Vec3& point) const {
  const auto [closest, primitive] = impl_->tree.closest_point_and_primitive(to_point(point));
  SurfacePoint result;
  result.face = static_cast<int>(primitive - impl_->triangles.cbegin());
  const Face& f = impl_->mesh.faces()[result.face];
  const Vec3 a = impl_->mesh.vertices()[f[0]], b = impl_->mesh.vertices()[f[1]],
             c = impl_->mesh.vertices()[f[2]];
  const Vec3 p(closest.x(), closest.y(), closest.z());
  // Barycentric weights of p in abc (p lies in the triangle up to rounding).
  const Vec3 v0 = b - a, v1 = c - a, v2 = p - a;
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0),
               d21 = v2.dot(v1);
  const double denominator = d00 * d11 - d01 * d01;
  double wb = 0, wc = 0;
  if (denominator > 0) {
    wb = (d11 * d20 - d01 * d21) / denominator;
    wc = (d00 * d21 - d01 * d20) / denominator;
  }
  Vec3 w(1 - wb - wc, wb, wc);
  w = w.cwiseMax(0.0);
  const double sum = w.sum();
  result.barycentric = sum > 0 ? Vec3(w / sum) : Vec3(1, 0, 0);
  return result;
}

std::optional<Vec3> SurfaceDistance::first_hit(const Vec3& origin, const Vec3& direction) const {
  const Kernel::Ray_3 ray(to_point(origin),
                          Kernel::Vector_3(direction.x(), direction.y(), direction.z()));
  const auto hit = impl_->tree.first_intersection(ray);
  if (!hit) return std::nullopt;
  // A point, or a segment where the ray runs within a face: its end nearest the origin.
  Point at;
  if (const Point* p = boost::get<Point>(&hit->first)) {
    at = *p;
  } else if (const Kernel::Segment_3* s = boost::get<Kernel::Segment_3>(&hit->first)) {
    at = CGAL::squared_distance(s->source(), ray.source()) <=
                 CGAL::squared_distance(s->target(), ray.source())
             ? s->source()
             : s->target();
  } else {
    return std::nullopt;
  }
  return Vec3(at.x(), at.y(), at.z());
}

Vec3 SurfaceDistance::normal_at_closest(const Vec3& point) const {
  const SurfacePoint p = closest(point);
  const Face& f = impl_->mesh.faces()[p.face];
  Vec3 n = Vec3::Zero();
  for (int i = 0; i < 3; ++i) n += p.barycentric[i] * impl_->normals[f[i]];
  if (n.norm() == 0) {
    const Vec3 a = impl_->mesh.vertices()[f[0]];
    n = (impl_->mesh.vertices()[f[1]] - a).cross(impl_->mesh.vertices()[f[2]] - a);
  }
  return n.normalized();
}

SurfacePoint closest_surface_point(const TriangleMesh& mesh, const Vec3& point) {
  return SurfaceDistance(mesh).closest(point);
}

}  // namespace gridshell
