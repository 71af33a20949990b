// SPDX-License-Identifier: GPL-3.0-or-later
// A coarser copy of a large patch for its distance maps (issue 17; see distance_map_copy.h).
//
// 1. The sample points of the maps (point_on_chain at u = i/(samples-1) on the four family
//    boundary chains) become vertices: a point inside a boundary edge splits the edge's face
//    (a fan from the opposite corner, or from a new centre vertex when points lie on two edges
//    of one face). A point within 1e-9 of an edge's length from one of its ends is that end.
// 2. CGAL's edge collapse (Lindstrom-Turk cost and placement) simplifies the mesh until about
//    `max_vertices` are left, under three rules that keep the boundary: a sample vertex never
//    moves (an edge between two samples is not collapsed; one with a sample collapses onto it),
//    a boundary vertex only collapses along the boundary (onto a boundary neighbour's position),
//    and an inner edge joining two boundary vertices is never collapsed (it would pinch the
//    patch). So the copy's boundary is the chain of sample points (plus a few original boundary
//    vertices the cost kept), and its interior approximates the patch's surface.
// 3. The surviving vertices are numbered in CGAL's order (deterministic for a given input); the
//    samples are found through a label each vertex carries through the collapses.
#include "gridshell/design/distance_map_copy.h"

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Edge_collapse_visitor_base.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_cost.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_placement.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>

#include "gridshell/design/distance_map.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"

namespace gridshell {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using VertexIndex = CgalMesh::Vertex_index;
namespace SMS = CGAL::Surface_mesh_simplification;

constexpr const char* kStage = "distance maps: copy";
constexpr double kSnap = 1e-9;  // fraction of an edge within which a sample is the edge's end

// Placement that keeps the boundary (rules in the file comment), around Lindstrom-Turk's.
struct KeepBoundaryPlacement : SMS::LindstromTurk_placement<CgalMesh> {
  const CgalMesh::Property_map<VertexIndex, int>* label = nullptr;

  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(const Profile& profile) const {
    const CgalMesh& mesh = profile.surface_mesh();
    const VertexIndex v0 = profile.v0(), v1 = profile.v1();
    const bool fixed0 = (*label)[v0] >= 0, fixed1 = (*label)[v1] >= 0;
    if (fixed0 && fixed1) return boost::none;
    const bool border0 = mesh.is_border(v0, true), border1 = mesh.is_border(v1, true);
    if (border0 && border1 && !mesh.is_border(mesh.edge(profile.v0_v1()))) return boost::none;
    if (fixed0 || (border0 && !fixed1)) return mesh.point(v0);
    if (fixed1 || border1) return mesh.point(v1);
    return SMS::LindstromTurk_placement<CgalMesh>::operator()(profile);
  }
};

// Carries sample labels through collapses, counts vertices, polls cancellation.
struct CopyVisitor : SMS::Edge_collapse_visitor_base<CgalMesh> {
  CgalMesh::Property_map<VertexIndex, int>* label = nullptr;
  std::size_t* vertices = nullptr;
  const Progress* progress = nullptr;
  std::size_t calls = 0;

  void poll() {
    if ((++calls & 511) == 0) progress->check();
  }
  void OnCollected(const Profile&, const boost::optional<FT>&) { poll(); }
  void OnSelected(const Profile&, const boost::optional<FT>&, size_type, size_type) { poll(); }
  void OnCollapsed(const Profile& profile, const VertexIndex& kept) {
    const int l0 = (*label)[profile.v0()], l1 = (*label)[profile.v1()];
    (*label)[kept] = l0 >= 0 ? l0 : l1;
    --*vertices;
  }
};

// Stops once the mesh has `target` vertices left.
struct VertexCountStop {
  const std::size_t* vertices = nullptr;
  std::size_t target = 0;
  template <typename F, typename Profile>
  bool operator()(const F&, const Profile&, std::size_t, std::size_t) const {
    return *vertices <= target;
  }
};

// A point on a face edge that becomes a vertex: its parameter from faces[f][k] to
// faces[f][(k+1)%3] and the new vertex.
struct EdgePoint {
  double t = 0;
  int vertex = -1;
};

// The surviving surface of a collapse: vertices (isolated ones dropped) in CGAL's order, faces,
// and the copy vertex of each label.
struct Collapsed {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
  std::map<int, int> of_label;
};

// Collapses edges of `cgal` until `max_vertices` of its `remaining` vertices are left, under the
// rules of the file comment (vertices with a label >= 0 never move), and extracts the result.
Collapsed collapse(CgalMesh& cgal, CgalMesh::Property_map<VertexIndex, int>& label,
                   std::size_t remaining, int max_vertices, const Progress& progress) {
  CopyVisitor visitor;
  visitor.label = &label;
  visitor.vertices = &remaining;
  visitor.progress = &progress;
  KeepBoundaryPlacement placement;
  placement.label = &label;
  VertexCountStop stop{&remaining, static_cast<std::size_t>(max_vertices)};
  if (remaining > stop.target)
    SMS::edge_collapse(cgal, stop,
                       CGAL::parameters::get_cost(SMS::LindstromTurk_cost<CgalMesh>())
                           .get_placement(placement)
                           .visitor(visitor));
  Collapsed out;
  std::vector<int> index(cgal.number_of_vertices() + cgal.number_of_removed_vertices(), -1);
  out.vertices.reserve(cgal.number_of_vertices());
  for (VertexIndex v : cgal.vertices()) {
    if (cgal.is_isolated(v)) continue;
    index[v] = static_cast<int>(out.vertices.size());
    const auto& p = cgal.point(v);
    out.vertices.emplace_back(p.x(), p.y(), p.z());
    if (label[v] >= 0) out.of_label[label[v]] = index[v];
  }
  out.faces.reserve(cgal.number_of_faces());
  for (auto f : cgal.faces()) {
    Face t{};
    int k = 0;
    for (VertexIndex v : CGAL::vertices_around_face(cgal.halfedge(f), cgal)) t[k++] = index[v];
    out.faces.push_back(t);
  }
  return out;
}

}  // namespace

std::size_t MapCopy::memory_bytes() const {
  std::size_t bytes = sizeof(MapCopy);
  const TriangleMesh& mesh = patch.mesh;
  bytes += mesh.vertices().capacity() * sizeof(Vec3) + mesh.faces().capacity() * sizeof(Face);
  const MeshTopology& topology = mesh.topology();
  bytes += topology.face_neighbors.capacity() * sizeof(std::array<int, 3>) +
           topology.is_boundary_vertex.capacity();
  for (const auto& faces : topology.vertex_faces) bytes += 32 + faces.capacity() * sizeof(int);
  for (const auto& loop : topology.boundary_loops) bytes += loop.capacity() * sizeof(int);
  for (const auto& chain : chains) bytes += chain.capacity() * sizeof(int);
  for (const auto& side : patch.sides) bytes += side.capacity() * sizeof(int);
  return bytes;
}

MapCopy make_map_copy(const Patch& patch, int max_vertices, int samples, const Progress& progress) {
  if (samples < 2)
    throw InvalidInput("samples", "must be at least 2, got " + std::to_string(samples));
  if (max_vertices < 1)
    throw InvalidInput("max_vertices", "must be at least 1, got " + std::to_string(max_vertices));
  const TriangleMesh& mesh = patch.mesh;
  progress.report(kStage, 0.0);

  // 1. Sample points as vertices.
  std::vector<Vec3> vertices = mesh.vertices();
  std::map<std::pair<int, int>, std::vector<EdgePoint>> on_edge;  // (face, local edge) -> points
  std::array<std::vector<int>, 4> sample_vertex;                  // chain -> split-mesh vertex
  const std::array<std::vector<int>, 4> chain{
      family_boundary(patch, Family::G, 0), family_boundary(patch, Family::H, 0),
      family_boundary(patch, Family::G, 1), family_boundary(patch, Family::H, 1)};
  for (int c = 0; c < 4; ++c) {
    sample_vertex[c].resize(samples);
    for (int i = 0; i < samples; ++i) {
      const SurfacePoint q = point_on_chain(mesh, chain[c], static_cast<double>(i) / (samples - 1));
      const Face& f = mesh.faces()[q.face];
      int zero = -1, zeros = 0;
      for (int k = 0; k < 3; ++k)
        if (q.barycentric[k] == 0.0) zero = k, ++zeros;
      int vertex = -1;
      if (zeros >= 2) {
        for (int k = 0; k < 3; ++k)
          if (q.barycentric[k] != 0.0) vertex = f[k];
      } else {
        // On the edge opposite corner `zero`: from f[zero+1] to f[zero+2].
        const int k = (zero + 1) % 3;
        const double t = q.barycentric[(zero + 2) % 3];
        if (t < kSnap) {
          vertex = f[k];
        } else if (t > 1 - kSnap) {
          vertex = f[(k + 1) % 3];
        } else {
          auto& points = on_edge[{q.face, k}];
          const auto same = std::find_if(points.begin(), points.end(),
                                         [&](const EdgePoint& p) { return p.t == t; });
          if (same != points.end()) {
            vertex = same->vertex;
          } else {
            vertex = static_cast<int>(vertices.size());
            vertices.push_back(q.position(mesh));
            points.push_back({t, vertex});
          }
        }
      }
      sample_vertex[c][i] = vertex;
    }
  }
  std::vector<Face> faces;
  faces.reserve(mesh.faces().size() + 2 * on_edge.size() + 8 * samples);
  for (int f = 0; f < mesh.face_count(); ++f) {
    const Face& face = mesh.faces()[f];
    std::array<std::vector<EdgePoint>*, 3> points{};
    int edges_with_points = 0, edge = -1;
    for (int k = 0; k < 3; ++k) {
      const auto it = on_edge.find({f, k});
      if (it == on_edge.end()) continue;
      std::sort(it->second.begin(), it->second.end(),
                [](const EdgePoint& a, const EdgePoint& b) { return a.t < b.t; });
      points[k] = &it->second;
      ++edges_with_points, edge = k;
    }
    if (edges_with_points == 0) {
      faces.push_back(face);
    } else if (edges_with_points == 1) {  // fan from the corner opposite the edge
      const int apex = face[(edge + 2) % 3];
      int previous = face[edge];
      for (const EdgePoint& p : *points[edge]) {
        faces.push_back({previous, p.vertex, apex});
        previous = p.vertex;
      }
      faces.push_back({previous, face[(edge + 1) % 3], apex});
    } else {  // fan from a new vertex at the centre
      std::vector<int> polygon;
      for (int k = 0; k < 3; ++k) {
        polygon.push_back(face[k]);
        if (points[k])
          for (const EdgePoint& p : *points[k]) polygon.push_back(p.vertex);
      }
      const int centre = static_cast<int>(vertices.size());
      vertices.push_back(
          (mesh.vertices()[face[0]] + mesh.vertices()[face[1]] + mesh.vertices()[face[2]]) / 3.0);
      for (std::size_t k = 0; k < polygon.size(); ++k)
        faces.push_back({polygon[k], polygon[(k + 1) % polygon.size()], centre});
    }
  }

  // 2. The collapse.
  CgalMesh cgal;
  cgal.reserve(vertices.size(), 3 * faces.size() / 2 + 1, faces.size());
  std::vector<VertexIndex> handle;
  handle.reserve(vertices.size());
  for (const Vec3& p : vertices) handle.push_back(cgal.add_vertex({p.x(), p.y(), p.z()}));
  for (const Face& f : faces)
    if (cgal.add_face(handle[f[0]], handle[f[1]], handle[f[2]]) == CgalMesh::null_face())
      throw std::logic_error("map copy: the split patch is not a manifold surface");
  auto label = cgal.add_property_map<VertexIndex, int>("v:sample", -1).first;
  for (const auto& vs : sample_vertex)
    for (int v : vs) label[handle[v]] = v;
  Collapsed collapsed = collapse(cgal, label, vertices.size(), max_vertices, progress);
  progress.report(kStage, 0.9);

  // 3. The copy as a patch.
  const std::map<int, int>& of_label = collapsed.of_label;  // split-mesh sample -> copy vertex
  MapCopy copy;
  copy.samples = samples;
  copy.max_vertices = max_vertices;
  copy.patch_vertices = mesh.vertex_count();
  copy.patch.mesh = TriangleMesh(std::move(collapsed.vertices), std::move(collapsed.faces));
  copy.patch.input_vertex.assign(copy.patch.mesh.vertex_count(), -1);
  copy.patch.corners_reversed = patch.corners_reversed;
  for (int c = 0; c < 4; ++c) {
    copy.chains[c].reserve(samples);
    for (int v : sample_vertex[c]) {
      const auto it = of_label.find(v);
      if (it == of_label.end()) throw std::logic_error("map copy: a sample vertex was collapsed");
      copy.chains[c].push_back(it->second);
    }
  }
  // Corners: G start runs c0 -> c1, H start c1 -> c2, G end c3 -> c2.
  copy.patch.corners = {copy.chains[0].front(), copy.chains[1].front(), copy.chains[1].back(),
                        copy.chains[2].front()};
  const auto& loops = copy.patch.mesh.topology().boundary_loops;
  if (loops.size() != 1) throw std::logic_error("map copy: the copy has no single boundary loop");
  const std::vector<int>& loop = loops[0];
  const auto start = std::find(loop.begin(), loop.end(), copy.patch.corners[0]);
  if (start == loop.end())
    throw std::logic_error("map copy: corner c0 is not on the copy's boundary");
  std::vector<int> walk(start, loop.end());
  walk.insert(walk.end(), loop.begin(), start);  // the loop from c0, interior to the left
  int side = 0;
  for (std::size_t k = 0; k <= walk.size() && side < 4; ++k) {
    const int v = walk[k % walk.size()];
    copy.patch.sides[side].push_back(v);
    if (k > 0 && v == copy.patch.corners[(side + 1) % 4]) {
      ++side;
      if (side < 4) copy.patch.sides[side].push_back(v);
    }
  }
  if (side != 4)
    throw std::logic_error("map copy: the corners are not in order along the boundary");
  progress.report(kStage, 1.0);
  return copy;
}

SimplifiedMesh simplify_mesh(const TriangleMesh& mesh, int max_vertices,
                             const std::vector<int>& keep, const Progress& progress) {
  if (max_vertices < 1)
    throw InvalidInput("max_vertices", "must be at least 1, got " + std::to_string(max_vertices));
  CgalMesh cgal;
  cgal.reserve(mesh.vertex_count(), 3 * mesh.face_count() / 2 + 1, mesh.face_count());
  std::vector<VertexIndex> handle;
  handle.reserve(mesh.vertex_count());
  for (const Vec3& p : mesh.vertices()) handle.push_back(cgal.add_vertex({p.x(), p.y(), p.z()}));
  for (const Face& f : mesh.faces())
    if (cgal.add_face(handle[f[0]], handle[f[1]], handle[f[2]]) == CgalMesh::null_face())
      throw InvalidInput("mesh", "not a manifold surface: it cannot be simplified");
  auto label = cgal.add_property_map<VertexIndex, int>("v:keep", -1).first;
  for (int v : keep) {
    if (v < 0 || v >= mesh.vertex_count())
      throw InvalidInput("keep", "vertex " + std::to_string(v) + " is not a vertex of the mesh");
    label[handle[v]] = v;
  }
  // Vertices without faces are not part of the surface.
  std::size_t remaining = 0;
  for (VertexIndex v : cgal.vertices()) remaining += !cgal.is_isolated(v);
  Collapsed collapsed = collapse(cgal, label, remaining, max_vertices, progress);
  const std::map<int, int>& of_label = collapsed.of_label;
  SimplifiedMesh out;
  out.mesh = TriangleMesh(std::move(collapsed.vertices), std::move(collapsed.faces));
  out.of_input.assign(mesh.vertex_count(), -1);
  for (const auto& [input, vertex] : of_label) out.of_input[input] = vertex;
  for (int v : keep)
    if (out.of_input[v] < 0) throw std::logic_error("simplify_mesh: a kept vertex was collapsed");
  return out;
}

namespace {

// The copy's point for parameter u on family boundary chain c (0: G start, 1: H start, 2: G
// end, 3: H end): the sample vertex itself when u is a sample's parameter, else the point of
// the copy's boundary between the two samples around u closest to the patch's point.
SurfacePoint copy_point(const MapCopy& copy, const Patch& patch, int c, double u) {
  const Family family = static_cast<Family>(c % 2);
  const int end = c / 2;
  const TriangleMesh& mesh = copy.patch.mesh;
  const std::vector<int>& samples = copy.chains[c];
  const double x = std::clamp(u, 0.0, 1.0) * (copy.samples - 1);
  const int i = std::min(static_cast<int>(x), copy.samples - 2);
  if (x == i) return SurfacePoint::at_vertex(mesh, samples[i]);
  if (x == i + 1) return SurfacePoint::at_vertex(mesh, samples[i + 1]);
  const Vec3 target =
      point_on_chain(patch.mesh, family_boundary(patch, family, end), u).position(patch.mesh);
  // The copy's chain between samples i and i+1, in the chain's direction.
  const std::vector<int> chain = family_boundary(copy.patch, family, end);
  const auto from = std::find(chain.begin(), chain.end(), samples[i]);
  const auto to = std::find(from, chain.end(), samples[i + 1]);
  if (from == chain.end() || to == chain.end())
    throw std::logic_error("map copy: samples out of order along the boundary");
  SurfacePoint best = SurfacePoint::at_vertex(mesh, samples[i]);
  double best_distance = (mesh.vertices()[samples[i]] - target).squaredNorm();
  for (auto it = from; it != to; ++it) {
    const Vec3& a = mesh.vertices()[*it];
    const Vec3& b = mesh.vertices()[*(it + 1)];
    const double length2 = (b - a).squaredNorm();
    const double t = length2 > 0 ? std::clamp((target - a).dot(b - a) / length2, 0.0, 1.0) : 0.0;
    const double d = (a + t * (b - a) - target).squaredNorm();
    if (d < best_distance) {
      best_distance = d;
      best = t == 0.0   ? SurfacePoint::at_vertex(mesh, *it)
             : t == 1.0 ? SurfacePoint::at_vertex(mesh, *(it + 1))
                        : SurfacePoint::on_edge(mesh, *it, *(it + 1), t);
    }
  }
  return best;
}

}  // namespace

double map_copy_error(const MapCopy& copy, const Patch& patch,
                      const std::vector<BoundaryDistance>& checks, int threads,
                      const Progress& progress) {
  if (checks.empty()) return 0.0;
  const GeodesicSolver solver(copy.patch.mesh);
  std::vector<double> error(checks.size(), 0.0);
  ParallelOptions parallel;
  parallel.threads = threads;
  parallel_for(
      checks.size(),
      [&](std::size_t k, const Progress& inner) {
        const BoundaryDistance& check = checks[k];
        const int f = static_cast<int>(check.family);
        SolveOptions options;
        options.keep_windows = false;
        const SurfacePoint from = copy_point(copy, patch, f, check.u1);
        options.targets = {copy_point(copy, patch, 2 + f, check.u2)};
        // Pruned to paths up to 5 % longer than the exact member (the copy is ~1e-4 off): exact
        // when the copy's distance is within that bound, else a complete solve.
        options.goal.center = options.targets[0].position(copy.patch.mesh);
        options.goal.bound = 1.05 * check.distance;
        double d = solver.solve(from, options, inner).target_distances()[0];
        if (!(d <= options.goal.bound)) {
          options.goal = {};
          d = solver.solve(from, options, inner).target_distances()[0];
        }
        if (check.distance > 0) error[k] = std::abs(d - check.distance) / check.distance;
      },
      progress, parallel);
  return *std::max_element(error.begin(), error.end());
}

}  // namespace gridshell
