// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — CGAL oracle for exact geodesics (GeodesicMethod::Cgal).
//
// CGAL::Surface_mesh_shortest_path (Xin-Wang's improved Chen-Han algorithm) on a
// CGAL::Surface_mesh<Epick::Point_3> that mirrors the TriangleMesh index for index (vertex i is
// the i-th vertex added, face i the i-th face). It is slow (exact-predicate kernel, pointer-based
// cone tree) and serves as the reference for the fast engine.
//
// Barycentric coordinates: CGAL orders a face's coordinates along its halfedge cycle starting at
// source(halfedge(f)), which need not be faces[f][0]. `rotation_[f]` is the index r such that
// faces[f][r] == source(halfedge(f)); CGAL coordinate k belongs to faces[f][(r + k) % 3].
//
// Known CGAL 5.5 problems worked around / documented here: points exactly on an edge are
// mirrored along the edge (see CgalData::to_cgal), and on the exactly developable example
// cylinder (a grid of planar rectangles) CGAL's distances exceed the exact unrolled distance by
// up to ~5e-5 relative; the fast engine is tested against the closed form there.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_shortest_path.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "geodesic_fast.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::geodesic_detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using Traits = CGAL::Surface_mesh_shortest_path_traits<Kernel, CgalMesh>;
using ShortestPath = CGAL::Surface_mesh_shortest_path<Traits>;
using VertexIndex = CgalMesh::Vertex_index;
using FaceIndex = CgalMesh::Face_index;
using HalfedgeIndex = CgalMesh::Halfedge_index;
using Barycentric = Traits::Barycentric_coordinates;

struct CgalData {
  TriangleMesh mesh;
  CgalMesh cgal;
  std::vector<int> rotation;  ///< per face, see the file comment

  Barycentric to_cgal(const SurfacePoint& point) const {
    SurfacePoint p = point;
    int zeros = 0, zero = -1;
    for (int i = 0; i < 3; ++i)
      if (p.barycentric[i] == 0.0) ++zeros, zero = i;
    if (zeros == 1) {
      // CGAL 5.5 mirrors locations exactly on an edge (Surface_mesh_shortest_path::expand_root
      // passes the weight of the edge's source vertex to face_location(he, t), which takes the
      // weight of its target), so edge points are moved 1e-11 (relative) into the face.
      const int big = p.barycentric[(zero + 1) % 3] > p.barycentric[(zero + 2) % 3]
                          ? (zero + 1) % 3
                          : (zero + 2) % 3;
      p.barycentric[zero] = 1e-11;
      p.barycentric[big] -= 1e-11;
    }
    const int r = rotation[p.face];
    return Barycentric{{p.barycentric[r], p.barycentric[(r + 1) % 3], p.barycentric[(r + 2) % 3]}};
  }
  SurfacePoint from_cgal(FaceIndex f, const Barycentric& b) const {
    SurfacePoint p;
    p.face = static_cast<int>(f.idx());
    const int r = rotation[p.face];
    for (int k = 0; k < 3; ++k) p.barycentric[(r + k) % 3] = b[k];
    return p;
  }
  SurfacePoint vertex_point(VertexIndex v) const {
    return SurfacePoint::at_vertex(mesh, static_cast<int>(v.idx()));
  }
  /// The point (1 - t) * source(h) + t * target(h), as a point of the face of h (or its twin).
  SurfacePoint edge_point(HalfedgeIndex h, double t) const {
    if (cgal.is_border(h)) h = cgal.opposite(h);
    if (t <= 0) return vertex_point(cgal.source(h));
    if (t >= 1) return vertex_point(cgal.target(h));
    const int f = static_cast<int>(cgal.face(h).idx());
    const int a = static_cast<int>(cgal.source(h).idx()),
              b = static_cast<int>(cgal.target(h).idx());
    SurfacePoint p;
    p.face = f;
    p.barycentric = Vec3::Zero();
    for (int i = 0; i < 3; ++i) {
      if (mesh.faces()[f][i] == a) p.barycentric[i] = 1.0 - t;
      if (mesh.faces()[f][i] == b) p.barycentric[i] = t;
    }
    return p;
  }
};

/// Collects the simplices of a CGAL shortest path (target first) as surface points.
struct PathVisitor {
  const CgalData* data;
  std::vector<SurfacePoint>* out;
  void operator()(HalfedgeIndex h, Kernel::FT t) { out->push_back(data->edge_point(h, t)); }
  void operator()(VertexIndex v) { out->push_back(data->vertex_point(v)); }
  void operator()(FaceIndex f, const Barycentric& b) { out->push_back(data->from_cgal(f, b)); }
};

class CgalField final : public DistanceField::Impl {
 public:
  CgalField(std::shared_ptr<const CgalData> data, const SurfacePoint& source)
      : data_(std::move(data)), shortest_path_(data_->cgal) {
    this->source = source;
    shortest_path_.add_source_point(FaceIndex(source.face), data_->to_cgal(source));
    shortest_path_.build_sequence_tree();
    const int nv = data_->mesh.vertex_count();
    distances.assign(nv, std::numeric_limits<double>::infinity());
    for (int v = 0; v < nv; ++v) {
      if (data_->cgal.is_isolated(VertexIndex(v))) continue;
      const double d = shortest_path_.shortest_distance_to_source_points(VertexIndex(v)).first;
      if (d >= 0) distances[v] = d;
    }
  }

  double distance_to(const SurfacePoint& target) const override {
    const SurfacePoint q = normalize_surface_point(data_->mesh, target, "target");
    std::lock_guard lock(mutex_);
    const double d =
        shortest_path_.shortest_distance_to_source_points(FaceIndex(q.face), data_->to_cgal(q))
            .first;
    return d >= 0 ? d : std::numeric_limits<double>::infinity();
  }

  std::vector<SurfacePoint> path_to(const SurfacePoint& target) const override {
    const SurfacePoint q = normalize_surface_point(data_->mesh, target, "target");
    std::vector<SurfacePoint> points;
    PathVisitor visitor{data_.get(), &points};
    std::lock_guard lock(mutex_);
    const double d =
        shortest_path_
            .shortest_path_sequence_to_source_points(FaceIndex(q.face), data_->to_cgal(q), visitor)
            .first;
    if (d < 0)
      throw InvalidInput("target", "not reachable from the source (another connected piece)");
    std::reverse(points.begin(), points.end());
    if (!points.empty()) {
      points.front() = source;
      points.back() = q;
    }
    return points;
  }

 private:
  std::shared_ptr<const CgalData> data_;
  mutable std::mutex mutex_;  // CGAL's query functions are not const
  mutable ShortestPath shortest_path_;
};

class CgalSolver final : public GeodesicSolver::Impl {
 public:
  explicit CgalSolver(const TriangleMesh& input) {
    mesh = input;
    auto data = std::make_shared<CgalData>();
    data->mesh = input;
    for (const Vec3& p : input.vertices())
      data->cgal.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z()));
    data->rotation.resize(input.faces().size());
    for (int f = 0; f < input.face_count(); ++f) {
      const Face& t = input.faces()[f];
      const FaceIndex fi =
          data->cgal.add_face(VertexIndex(t[0]), VertexIndex(t[1]), VertexIndex(t[2]));
      if (fi == CgalMesh::null_face() || static_cast<int>(fi.idx()) != f)
        throw std::logic_error("cgal geodesics: face " + std::to_string(f) +
                               " cannot be added to a CGAL surface mesh (non-manifold)");
      const int s = static_cast<int>(data->cgal.source(data->cgal.halfedge(fi)).idx());
      data->rotation[f] = t[0] == s ? 0 : (t[1] == s ? 1 : 2);
    }
    data_ = std::move(data);
  }

  DistanceField solve(const SurfacePoint& source, const SolveOptions& options,
                      const Progress& progress) const override {
    progress.report("geodesic distances (cgal)", 0.0);
    auto field = std::make_shared<CgalField>(data_, source);
    for (const SurfacePoint& t : options.targets)
      field->target_distances.push_back(field->distance_to(t));
    progress.report("geodesic distances (cgal)", 1.0);
    return DistanceField(std::move(field));
  }

 private:
  std::shared_ptr<const CgalData> data_;
};

}  // namespace

std::unique_ptr<GeodesicSolver::Impl> make_cgal_solver(const TriangleMesh& mesh) {
  return std::make_unique<CgalSolver>(mesh);
}

}  // namespace gridshell::geodesic_detail
