// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — approximate geodesic distances by the heat method (GeodesicMethod::Heat).
//
// CGAL::Heat_method_3::Surface_mesh_geodesic_distances_3 (Crane, Weischedel, Wardetzky, "Geodesics
// in heat", ACM TOG 2013) with the intrinsic Delaunay triangulation variant, which is much more
// accurate on meshes with obtuse triangles. The Laplacian and its factorisations are built once
// per solver; solves share that object behind a mutex (the CGAL object stores the source set),
// so concurrent heat solves are serialised.
//
// Sources: vertices only. A source strictly inside a face or an edge throws InvalidInput (the
// heat method's distance is defined from a source set of vertices; snapping to a vertex would
// silently move the source). distance_to interpolates the vertex distances barycentrically;
// path_to throws InvalidInput: the heat method gives distances only.
#define CGAL_EIGEN3_ENABLED 1  // the heat method needs CGAL's Eigen solvers
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Heat_method_3/Surface_mesh_geodesic_distances_3.h>
#include <CGAL/Surface_mesh.h>

#include <limits>
#include <mutex>

#include "geodesic_fast.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::geodesic_detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using VertexIndex = CgalMesh::Vertex_index;
using HeatMethod =
    CGAL::Heat_method_3::Surface_mesh_geodesic_distances_3<CgalMesh,
                                                           CGAL::Heat_method_3::Intrinsic_Delaunay>;

/// Writable property map vertex -> distance into a std::vector (the heat method only writes it).
struct DistanceMap {
  using key_type = VertexIndex;
  using value_type = double;
  using reference = void;
  using category = boost::writable_property_map_tag;
  std::vector<double>* values;
  friend void put(const DistanceMap& map, key_type v, double d) { (*map.values)[v.idx()] = d; }
};

class HeatField final : public DistanceField::Impl {
 public:
  std::shared_ptr<const TriangleMesh> mesh;

  double distance_to(const SurfacePoint& target) const override {
    const SurfacePoint q = normalize_surface_point(*mesh, target, "target");
    const Face& f = mesh->faces()[q.face];
    double d = 0;
    for (int i = 0; i < 3; ++i)
      if (q.barycentric[i] != 0.0) d += q.barycentric[i] * distances[f[i]];
    return d;
  }

  std::vector<SurfacePoint> path_to(const SurfacePoint&) const override {
    throw InvalidInput("", "the heat method gives distances only, no paths");
  }
};

class HeatSolver final : public GeodesicSolver::Impl {
 public:
  explicit HeatSolver(const TriangleMesh& input) {
    mesh = input;
    shared_mesh_ = std::make_shared<const TriangleMesh>(input);
    for (const Vec3& p : input.vertices()) cgal_.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z()));
    for (int f = 0; f < input.face_count(); ++f) {
      const Face& t = input.faces()[f];
      if (cgal_.add_face(VertexIndex(t[0]), VertexIndex(t[1]), VertexIndex(t[2])) ==
          CgalMesh::null_face())
        throw std::logic_error("heat geodesics: face " + std::to_string(f) +
                               " cannot be added to a CGAL surface mesh (non-manifold)");
    }
    heat_ = std::make_unique<HeatMethod>(cgal_);
  }

  DistanceField solve(const SurfacePoint& source, const SolveOptions& options,
                      const Progress& progress) const override {
    const int v = source.vertex(mesh);
    if (v < 0)
      throw InvalidInput(
          "source",
          "the heat geodesic method supports vertex sources only (the source lies inside a face "
          "or on an edge)");
    progress.report("geodesic distances (heat)", 0.0);
    auto field = std::make_shared<HeatField>();
    field->mesh = shared_mesh_;
    field->source = source;
    field->distances.assign(mesh.vertex_count(), std::numeric_limits<double>::infinity());
    {
      std::lock_guard lock(mutex_);
      heat_->clear_sources();
      heat_->add_source(VertexIndex(v));
      heat_->estimate_geodesic_distances(DistanceMap{&field->distances});
    }
    for (const SurfacePoint& t : options.targets)
      field->target_distances.push_back(field->distance_to(t));
    progress.report("geodesic distances (heat)", 1.0);
    return DistanceField(std::move(field));
  }

 private:
  std::shared_ptr<const TriangleMesh> shared_mesh_;
  CgalMesh cgal_;
  mutable std::mutex mutex_;
  std::unique_ptr<HeatMethod> heat_;  // mutable state (source set) guarded by mutex_
};

}  // namespace

std::unique_ptr<GeodesicSolver::Impl> make_heat_solver(const TriangleMesh& mesh) {
  return std::make_unique<HeatSolver>(mesh);
}

}  // namespace gridshell::geodesic_detail
