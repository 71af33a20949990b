// SPDX-License-Identifier: GPL-3.0-or-later
// Cutting the target patch out of a mesh along its four boundary geodesics (paper 3.2, 4.1).
//
// The corners are first made mesh vertices (splitting a face or an edge if needed). The four
// exact shortest paths between consecutive corners cross edges at arbitrary points; every such
// point becomes a new vertex, and every face a path passes through is re-triangulated so that
// the path segments are edges. The side of the closed loop that does not reach the input mesh's
// own boundary (or, if both do, the side to the left of c0->c1->c2->c3) is kept.
#include "gridshell/design/patch.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <queue>
#include <set>
#include <sstream>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/curvature.h"
#include "gridshell/mesh/mesh_topology.h"
#include "gridshell/mesh/surface_distance.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

// ---- Mesh surgery used to make corners vertices ------------------------------------------

// A mesh being edited as plain arrays. Input faces keep their index; a split input face's pieces
// are listed in `pieces` (the face itself first).
struct EditedMesh {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
  std::map<int, std::vector<int>> pieces;  // input face -> its pieces, for split faces only
  std::vector<int> origin;                 // face -> input face it is a piece of

  void add_piece(int of_face, Face face) {
    const int input_face = origin[of_face];
    auto [it, inserted] = pieces.try_emplace(input_face, std::vector<int>{input_face});
    it->second.push_back(static_cast<int>(faces.size()));
    faces.push_back(face);
    origin.push_back(input_face);
  }
  std::vector<int> pieces_of(int input_face) const {
    const auto it = pieces.find(input_face);
    return it == pieces.end() ? std::vector<int>{input_face} : it->second;
  }
};

// Inserts the point given by its face and barycentric weights (already snapped: interior to
// the face, or on an edge with the opposite weight exactly 0) and returns the new vertex index.
int insert_point(EditedMesh& mesh, const SurfacePoint& point) {
  const Face f = mesh.faces[point.face];
  const Vec3 position = point.barycentric[0] * mesh.vertices[f[0]] +
                        point.barycentric[1] * mesh.vertices[f[1]] +
                        point.barycentric[2] * mesh.vertices[f[2]];
  const int v = static_cast<int>(mesh.vertices.size());
  mesh.vertices.push_back(position);
  int zero = -1;
  for (int i = 0; i < 3; ++i)
    if (point.barycentric[i] == 0.0) zero = i;
  if (zero < 0) {  // inside the face: split into three
    mesh.faces[point.face] = {f[0], f[1], v};
    mesh.add_piece(point.face, {f[1], f[2], v});
    mesh.add_piece(point.face, {f[2], f[0], v});
    return v;
  }
  // On the edge opposite vertex `zero`: split this face and its neighbour across that edge.
  const int a = f[(zero + 1) % 3], b = f[(zero + 2) % 3];
  const int nf = static_cast<int>(mesh.faces.size());
  for (int g = 0; g < nf; ++g) {
    const Face t = mesh.faces[g];
    for (int i = 0; i < 3; ++i) {
      const int x = t[i], y = t[(i + 1) % 3], z = t[(i + 2) % 3];
      if ((x == a && y == b) || (x == b && y == a)) {
        mesh.faces[g] = {x, v, z};
        mesh.add_piece(g, {v, y, z});
        break;
      }
    }
  }
  return v;
}

// The point `point` of the input mesh located on the edited mesh: among the pieces of its input
// face, the one closest to it (the point lies on it, up to rounding), with its weights there.
SurfacePoint locate_on_pieces(const TriangleMesh& input, const EditedMesh& mesh,
                              const SurfacePoint& point) {
  const Vec3 position = point.position(input);
  SurfacePoint best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int f : mesh.pieces_of(point.face)) {
    const Face& t = mesh.faces[f];
    const Vec3 w = closest_point_on_triangle(position, mesh.vertices[t[0]], mesh.vertices[t[1]],
                                             mesh.vertices[t[2]]);
    const Vec3 q =
        w[0] * mesh.vertices[t[0]] + w[1] * mesh.vertices[t[1]] + w[2] * mesh.vertices[t[2]];
    const double d = (q - position).squaredNorm();
    if (d < best_distance) {
      best_distance = d;
      best.face = f;
      best.barycentric = w;
    }
  }
  return best;
}

// Snaps barycentric weights within `snap` of 0 to exactly 0 (renormalizing).
SurfacePoint snapped(SurfacePoint p, double snap) {
  for (int i = 0; i < 3; ++i)
    if (p.barycentric[i] < snap) p.barycentric[i] = 0.0;
  const double sum = p.barycentric.sum();
  p.barycentric /= sum;
  for (int i = 0; i < 3; ++i)
    if (p.barycentric[i] > 1.0 - snap) {
      p.barycentric = Vec3::Zero();
      p.barycentric[i] = 1.0;
    }
  return p;
}

// ---- Locations of path points -------------------------------------------------------------

// A path point: either a mesh vertex (b == -1) or the point (1-t) a + t b on edge a<b.
struct Location {
  int a = -1, b = -1;
  double t = 0;
  bool is_vertex() const { return b < 0; }
};

Location classify(const TriangleMesh& mesh, const SurfacePoint& point, double snap) {
  const Face& f = mesh.faces()[point.face];
  Vec3 w = point.barycentric.cwiseMax(0.0);
  w /= w.sum();
  // Order coordinates: the smallest is treated as zero (geodesic interior points lie on edges).
  int smallest = 0;
  for (int i = 1; i < 3; ++i)
    if (w[i] < w[smallest]) smallest = i;
  const int i1 = (smallest + 1) % 3, i2 = (smallest + 2) % 3;
  const double s = w[i1] + w[i2];
  double t = w[i2] / s;  // position from f[i1] to f[i2]
  Location loc;
  if (t <= snap) {
    loc.a = f[i1];
  } else if (t >= 1 - snap) {
    loc.a = f[i2];
  } else if (f[i1] < f[i2]) {
    loc.a = f[i1];
    loc.b = f[i2];
    loc.t = t;
  } else {
    loc.a = f[i2];
    loc.b = f[i1];
    loc.t = 1 - t;
  }
  return loc;
}

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
}

// Faces containing a location.
std::vector<int> faces_of(const TriangleMesh& mesh, const MeshTopology& topology,
                          const Location& loc) {
  if (loc.is_vertex()) return topology.vertex_faces[loc.a];
  std::vector<int> faces;
  for (int f : topology.vertex_faces[loc.a]) {
    const Face& t = mesh.faces()[f];
    if (t[0] == loc.b || t[1] == loc.b || t[2] == loc.b) faces.push_back(f);
  }
  return faces;
}

// Ear-clipping triangulation of a convex polygon given by 2D points (vertices may be collinear
// on a side). Picks the best-shaped valid ear each time; an ear is valid if it has positive area
// and contains no other polygon vertex (which would make a T-junction).
std::vector<std::array<int, 3>> triangulate_convex(const std::vector<Vec2>& points) {
  std::vector<int> ring(points.size());
  for (size_t i = 0; i < ring.size(); ++i) ring[i] = static_cast<int>(i);
  std::vector<std::array<int, 3>> triangles;
  auto cross = [&](int o, int a, int b) {
    const Vec2 u = points[a] - points[o], v = points[b] - points[o];
    return u.x() * v.y() - u.y() * v.x();
  };
  double scale = 0;
  for (const Vec2& p : points) scale = std::max(scale, (p - points[0]).squaredNorm());
  const double eps = 1e-14 * scale;
  while (ring.size() > 3) {
    const int n = static_cast<int>(ring.size());
    int best = -1;
    double best_quality = -1;
    for (int k = 0; k < n; ++k) {
      const int p = ring[(k + n - 1) % n], c = ring[k], q = ring[(k + 1) % n];
      const double area = cross(p, c, q);
      if (area <= eps) continue;
      bool valid = true;
      for (int j = 0; j < n && valid; ++j) {
        const int o = ring[j];
        if (o == p || o == c || o == q) continue;
        if (cross(p, c, o) >= -eps && cross(c, q, o) >= -eps && cross(q, p, o) >= -eps)
          valid = false;
      }
      if (!valid) continue;
      // Quality: smallest angle sine proxy = area / (longest edge squared).
      const double l =
          std::max({(points[p] - points[c]).squaredNorm(), (points[c] - points[q]).squaredNorm(),
                    (points[q] - points[p]).squaredNorm()});
      const double quality = area / l;
      if (quality > best_quality) {
        best_quality = quality;
        best = k;
      }
    }
    if (best < 0) throw std::logic_error("patch cut: no valid ear in a face polygon");
    triangles.push_back({ring[(best + n - 1) % n], ring[best], ring[(best + 1) % n]});
    ring.erase(ring.begin() + best);
  }
  if (cross(ring[0], ring[1], ring[2]) <= eps)
    throw std::logic_error("patch cut: degenerate last triangle in a face polygon");
  triangles.push_back({ring[0], ring[1], ring[2]});
  return triangles;
}

std::string side_name(int i) {
  return "c" + std::to_string(i) + "-c" + std::to_string((i + 1) % 4);
}

}  // namespace

// ---------------------------------------------------------------------------------------------

std::array<int, 4> auto_corners(const TriangleMesh& mesh) {
  const MeshTopology& topology = mesh.topology();
  if (topology.boundary_loops.empty())
    throw InvalidInput("corners", "auto: the mesh has no boundary");
  const std::vector<int>& loop =
      *std::max_element(topology.boundary_loops.begin(), topology.boundary_loops.end(),
                        [](const auto& a, const auto& b) { return a.size() < b.size(); });
  if (loop.size() < 4)
    throw InvalidInput("corners", "auto: the boundary has fewer than 4 vertices");
  const std::vector<double> sums = vertex_angle_sums(mesh);
  std::vector<int> order(loop.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  // Sharpest turning = smallest interior angle; ties broken by boundary order (deterministic).
  std::stable_sort(order.begin(), order.end(),
                   [&](int x, int y) { return sums[loop[x]] < sums[loop[y]]; });
  std::array<int, 4> picked{order[0], order[1], order[2], order[3]};
  std::sort(picked.begin(), picked.end());
  return {loop[picked[0]], loop[picked[1]], loop[picked[2]], loop[picked[3]]};
}

namespace {

// ---- The steps of cut_patch ------------------------------------------------------------------

// Step 1: the mesh with every corner a vertex (faces or edges split where a corner lies inside)
// and the corner vertices. The input mesh itself when every corner is a vertex already.
struct CornerMesh {
  TriangleMesh mesh;
  std::vector<int> corners;
};
CornerMesh corner_vertices(const TriangleMesh& input,
                           const std::vector<SurfacePoint>& corner_points, double snap,
                           const std::string& what) {
  const int n = static_cast<int>(corner_points.size());
  for (int i = 0; i < n; ++i)
    if (corner_points[i].face < 0 || corner_points[i].face >= input.face_count())
      throw InvalidInput(what + "[" + std::to_string(i) + "]",
                         "face index " + std::to_string(corner_points[i].face) +
                             " is out of range (the mesh has " +
                             std::to_string(input.face_count()) + " faces)");
  CornerMesh out;
  out.corners.assign(n, -1);
  EditedMesh edited;
  bool edited_any = false;
  for (int i = 0; i < n; ++i) {
    if (!edited_any) {
      const int v = snapped(corner_points[i], snap).vertex(input);
      if (v >= 0) {
        out.corners[i] = v;
        continue;
      }
      edited.vertices = input.vertices();
      edited.faces = input.faces();
      edited.origin.resize(edited.faces.size());
      for (size_t f = 0; f < edited.origin.size(); ++f) edited.origin[f] = static_cast<int>(f);
      edited_any = true;
    }
    // Earlier insertions may have split the corner's face: find it among the pieces.
    const SurfacePoint q = snapped(locate_on_pieces(input, edited, corner_points[i]), snap);
    const Face& face = edited.faces[q.face];
    int vertex = -1;
    for (int k = 0; k < 3; ++k)
      if (q.barycentric[k] == 1.0) vertex = face[k];
    out.corners[i] = vertex >= 0 ? vertex : insert_point(edited, q);
  }
  out.mesh = edited_any ? TriangleMesh(std::move(edited.vertices), std::move(edited.faces)) : input;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (out.corners[i] == out.corners[j])
        throw InvalidInput(what + "[" + std::to_string(j) + "]",
                           "the same surface point as " + what + "[" + std::to_string(i) + "]");
  return out;
}

// Step 2: the four boundary geodesics c_i -> c_{i+1}, exact shortest paths, as locations.
std::vector<SurfacePoint> solve_side(const GeodesicSolver& solver, const TriangleMesh& mesh, int a,
                                     int b, const std::string& names, const Progress& progress) {
  if (!std::isfinite(edge_path_bound(mesh, SurfacePoint::at_vertex(mesh, a),
                                     SurfacePoint::at_vertex(mesh, b))))
    throw Infeasible("corners", "corners " + names +
                                    " lie on separate pieces of the surface: no geodesic joins "
                                    "them");
  // A goal-pruned solve (shortest_path): on a 60k-vertex mesh a complete field held 2 GB.
  return solver.shortest_path(SurfacePoint::at_vertex(mesh, a), SurfacePoint::at_vertex(mesh, b),
                              progress.checker());
}

std::vector<Location> side_locations(const TriangleMesh& mesh,
                                     const std::vector<SurfacePoint>& path, int from, int to,
                                     double snap, int side) {
  std::vector<Location> locations;
  for (const SurfacePoint& p : path) {
    Location loc = classify(mesh, p, snap);
    if (!locations.empty() && locations.back().a == loc.a && locations.back().b == loc.b &&
        (loc.is_vertex() || std::abs(locations.back().t - loc.t) < snap))
      continue;
    locations.push_back(loc);
  }
  if (locations.size() < 2 || !locations.front().is_vertex() || locations.front().a != from ||
      !locations.back().is_vertex() || locations.back().a != to)
    throw std::logic_error("patch cut: geodesic " + side_name(side) + " does not join its corners");
  return locations;
}

std::array<std::vector<Location>, 4> boundary_geodesics(const TriangleMesh& mesh,
                                                        const std::array<int, 4>& corners,
                                                        const GeodesicOptions& geodesic,
                                                        double snap, const Progress& progress) {
  GeodesicSolver solver(mesh, geodesic);
  std::array<std::vector<Location>, 4> paths;
  for (int i = 0; i < 4; ++i) {
    progress.report("patch: boundary geodesics", 0.1 + 0.2 * i);
    const int next = corners[(i + 1) % 4];
    const std::vector<SurfacePoint> path =
        solve_side(solver, mesh, corners[i], next,
                   "c" + std::to_string(i) + " and c" + std::to_string((i + 1) % 4), progress);
    paths[i] = side_locations(mesh, path, corners[i], next, snap, i);
  }
  return paths;
}

// Step 3: a vertex for every path point on an edge (points of different paths at one spot are
// merged); `nodes[i]` are the vertices along path i.
struct PathNodes {
  std::vector<Vec3> vertices;  ///< the mesh's vertices and then the new ones
  std::map<std::uint64_t, std::vector<std::pair<double, int>>> edge_points;  // edge -> (t, v)
  std::array<std::vector<int>, 4> nodes;
};
PathNodes insert_path_points(const TriangleMesh& mesh,
                             const std::array<std::vector<Location>, 4>& paths, double snap) {
  PathNodes out;
  out.vertices = mesh.vertices();
  auto node_of = [&](const Location& loc) -> int {
    if (loc.is_vertex()) return loc.a;
    auto& list = out.edge_points[edge_key(loc.a, loc.b)];
    for (const auto& [t, v] : list)
      if (std::abs(t - loc.t) < snap) return v;
    const int v = static_cast<int>(out.vertices.size());
    out.vertices.push_back((1 - loc.t) * out.vertices[loc.a] + loc.t * out.vertices[loc.b]);
    list.push_back({loc.t, v});
    return v;
  };
  for (int i = 0; i < 4; ++i)
    for (const Location& loc : paths[i]) out.nodes[i].push_back(node_of(loc));
  return out;
}

// Step 4, criterion (iv): the closed loop c0->c1->c2->c3->c0 must be simple.
void check_simple_loop(const PathNodes& path) {
  std::map<int, int> owner;  // node -> side that visits it
  for (int i = 0; i < 4; ++i)
    for (size_t k = 0; k + 1 < path.nodes[i].size(); ++k) {  // the last is the next side's first
      const auto [it, inserted] = owner.emplace(path.nodes[i][k], i);
      if (!inserted) {
        std::ostringstream msg;
        const Vec3& p = path.vertices[path.nodes[i][k]];
        msg << "boundary geodesics " << side_name(it->second) << " and " << side_name(i)
            << " touch or cross at (" << p.x() << ", " << p.y() << ", " << p.z()
            << "): the patch is not a simple quadrilateral (grid criterion iv)";
        throw Infeasible("corners", msg.str());
      }
    }
}

// Step 5: the path segments that cross a face's interior (chords), by face, and the faces a
// path touches (crossed, or with a new vertex on an edge).
struct Chords {
  std::map<int, std::vector<std::pair<int, int>>> by_face;  // face -> (node, node)
  std::vector<char> touched;                                // per face
};
Chords find_chords(const TriangleMesh& mesh, const std::array<std::vector<Location>, 4>& paths,
                   const PathNodes& path) {
  const MeshTopology& topology = mesh.topology();
  Chords out;
  out.touched.assign(mesh.face_count(), 0);
  for (int i = 0; i < 4; ++i)
    for (size_t k = 0; k + 1 < paths[i].size(); ++k) {
      const Location& p = paths[i][k];
      const Location& q = paths[i][k + 1];
      std::vector<int> fp = faces_of(mesh, topology, p), fq = faces_of(mesh, topology, q);
      std::sort(fp.begin(), fp.end());
      std::sort(fq.begin(), fq.end());
      std::vector<int> common;
      std::set_intersection(fp.begin(), fp.end(), fq.begin(), fq.end(), std::back_inserter(common));
      if (common.empty())
        throw std::logic_error("patch cut: consecutive points of geodesic " + side_name(i) +
                               " share no face");
      // Along an edge (both points on one edge, or two vertices of an edge): no chord.
      std::set<int> pv{p.a}, qv{q.a};
      if (!p.is_vertex()) pv.insert(p.b);
      if (!q.is_vertex()) qv.insert(q.b);
      std::set<int> all = pv;
      all.insert(qv.begin(), qv.end());
      if (all.size() <= 2) continue;  // both on one edge: the segment is (part of) that edge
      if (common.size() != 1)
        throw std::logic_error("patch cut: a segment of geodesic " + side_name(i) +
                               " lies in more than one face");
      out.by_face[common[0]].push_back({path.nodes[i][k], path.nodes[i][k + 1]});
      out.touched[common[0]] = 1;
    }
  for (const auto& [key, list] : path.edge_points) {
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    for (int f : topology.vertex_faces[a]) {
      const Face& t = mesh.faces()[f];
      if (t[0] == b || t[1] == b || t[2] == b) out.touched[f] = 1;
    }
  }
  return out;
}

// Step 6: every touched face re-triangulated (its boundary cycle with the new points, split
// by its chords), so that the four paths consist of mesh edges.
std::vector<Face> retriangulate(const TriangleMesh& mesh, const PathNodes& path,
                                const Chords& chords) {
  const std::vector<Vec3>& x = path.vertices;
  std::vector<Face> faces;
  faces.reserve(mesh.faces().size() + 8 * chords.by_face.size());
  for (int f = 0; f < mesh.face_count(); ++f) {
    const Face t = mesh.faces()[f];
    if (!chords.touched[f]) {
      faces.push_back(t);
      continue;
    }
    std::vector<int> cycle;
    for (int i = 0; i < 3; ++i) {
      const int a = t[i], b = t[(i + 1) % 3];
      cycle.push_back(a);
      auto it = path.edge_points.find(edge_key(a, b));
      if (it == path.edge_points.end()) continue;
      auto list = it->second;
      std::sort(list.begin(), list.end());
      if (a > b) std::reverse(list.begin(), list.end());  // t runs from min(a,b) to max(a,b)
      for (const auto& entry : list) cycle.push_back(entry.second);
    }
    // Local 2D frame of the face.
    const Vec3 o = x[t[0]];
    const Vec3 e1 = (x[t[1]] - o).normalized();
    const Vec3 n = e1.cross(x[t[2]] - o).normalized();
    const Vec3 e2 = n.cross(e1);
    auto to2d = [&](int v) {
      const Vec3 d = x[v] - o;
      return Vec2(d.dot(e1), d.dot(e2));
    };
    std::vector<std::vector<int>> polygons{cycle};
    const auto face_chords = chords.by_face.find(f);
    if (face_chords != chords.by_face.end())
      for (const auto& [a, b] : face_chords->second) {
        bool placed = false;
        for (size_t pi = 0; pi < polygons.size() && !placed; ++pi) {
          auto& poly = polygons[pi];
          const auto ia = std::find(poly.begin(), poly.end(), a);
          const auto ib = std::find(poly.begin(), poly.end(), b);
          if (ia == poly.end() || ib == poly.end()) continue;
          size_t i0 = ia - poly.begin(), i1 = ib - poly.begin();
          if (i0 > i1) std::swap(i0, i1);
          std::vector<int> first(poly.begin() + i0, poly.begin() + i1 + 1);
          std::vector<int> second(poly.begin() + i1, poly.end());
          second.insert(second.end(), poly.begin(), poly.begin() + i0 + 1);
          poly = std::move(first);
          polygons.push_back(std::move(second));
          placed = true;
        }
        if (!placed) {
          std::ostringstream msg;
          const Vec3& p = x[a];
          msg << "boundary geodesics cross inside a face near (" << p.x() << ", " << p.y() << ", "
              << p.z() << "): the patch is not a simple quadrilateral (grid criterion iv)";
          throw Infeasible("corners", msg.str());
        }
      }
    for (const auto& poly : polygons) {
      std::vector<Vec2> points;
      for (int v : poly) points.push_back(to2d(v));
      for (const auto& tri : triangulate_convex(points))
        faces.push_back({poly[tri[0]], poly[tri[1]], poly[tri[2]]});
    }
  }
  return faces;
}

// Step 7: which side of the loop is the patch. Each side is flooded from the loop without
// crossing it. A side can be the patch only if it is a disk bounded by the loop alone: no edge of
// the mesh's own boundary (a hole, or the mesh's outer edge) and Euler characteristic 1 (no
// handle). On an open disk mesh with corners on or inside its boundary that is one side; on a
// closed surface (a sphere) both sides are disks, and the patch is the one with convex corners
// (the other has the reflex complements), else the left one (c0->c1->c2->c3 counter-clockwise).
// If neither side is a disk, the error says which case it is and where. `reversed` says the
// patch is the right side.
struct LoopSide {
  std::vector<char> faces;
  long long face_count = 0;
  int boundary_edge_face = -1;  ///< a face with an edge on the mesh's own boundary, or -1
  int boundary_edge = -1;       ///< that edge (local index)
  long long euler = 0;          ///< V - E + F of the side's faces
  bool disk() const { return face_count > 0 && boundary_edge_face < 0 && euler == 1; }
};

std::string point_text(const Vec3& p) {
  std::ostringstream out;
  out << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return out.str();
}

std::vector<char> patch_region(const TriangleMesh& cut,
                               const std::array<std::vector<int>, 4>& nodes, bool* reversed) {
  const MeshTopology& topology = cut.topology();
  std::set<std::uint64_t> loop_edges;
  std::vector<std::pair<int, int>> directed;
  for (int i = 0; i < 4; ++i)
    for (size_t k = 0; k + 1 < nodes[i].size(); ++k) {
      loop_edges.insert(edge_key(nodes[i][k], nodes[i][k + 1]));
      directed.push_back({nodes[i][k], nodes[i][k + 1]});
    }
  const std::vector<Face>& faces = cut.faces();
  auto flood = [&](bool left) {
    LoopSide side;
    std::vector<char>& in = side.faces;
    in.assign(cut.face_count(), 0);
    std::queue<int> queue;
    for (const auto& [a, b] : directed) {
      for (int f : topology.vertex_faces[a]) {
        const Face& t = faces[f];
        for (int i = 0; i < 3; ++i) {
          const bool match =
              left ? (t[i] == a && t[(i + 1) % 3] == b) : (t[i] == b && t[(i + 1) % 3] == a);
          if (match && !in[f]) {
            in[f] = 1;
            queue.push(f);
          }
        }
      }
    }
    while (!queue.empty()) {
      const int f = queue.front();
      queue.pop();
      for (int i = 0; i < 3; ++i) {
        const int g = topology.face_neighbors[f][i];
        if (g < 0 || in[g]) continue;
        if (loop_edges.count(edge_key(faces[f][i], faces[f][(i + 1) % 3]))) continue;
        in[g] = 1;
        queue.push(g);
      }
    }
    // Its boundary edges other than the loop's, and its Euler characteristic.
    std::set<int> vertices;
    long long edges2 = 0;  // interior edges of the side count twice, its boundary edges once
    for (int f = 0; f < cut.face_count(); ++f) {
      if (!in[f]) continue;
      ++side.face_count;
      for (int i = 0; i < 3; ++i) {
        vertices.insert(faces[f][i]);
        const int g = topology.face_neighbors[f][i];
        const bool on_loop = loop_edges.count(edge_key(faces[f][i], faces[f][(i + 1) % 3])) > 0;
        edges2 += (g >= 0 && in[g]) ? 1 : 2;
        if (g < 0 && !on_loop && side.boundary_edge_face < 0) {
          side.boundary_edge_face = f;
          side.boundary_edge = i;
        }
      }
    }
    side.euler = static_cast<long long>(vertices.size()) - edges2 / 2 + side.face_count;
    return side;
  };
  const LoopSide left = flood(true), right = flood(false);
  for (int f = 0; f < cut.face_count(); ++f)
    if (left.faces[f] && right.faces[f]) {
      const Face& t = faces[f];
      const Vec3 p = (cut.vertices()[t[0]] + cut.vertices()[t[1]] + cut.vertices()[t[2]]) / 3;
      throw Infeasible("corners",
                       "the four boundary geodesics do not bound a region: both sides of the "
                       "loop c0->c1->c2->c3 are one connected piece (the loop goes around a "
                       "handle or a tube of the surface), e.g. near " +
                           point_text(p) + " (the patch must be a disk)");
    }
  // A closed surface: both sides are disks; the one with convex corners (inner angle < pi at
  // every corner) is the patch.
  auto convex_corners = [&](const LoopSide& side) {
    for (int i = 0; i < 4; ++i) {
      const int c = nodes[i].front();
      double sum = 0;
      for (int f : topology.vertex_faces[c]) {
        if (!side.faces[f]) continue;
        const Face& t = faces[f];
        for (int k = 0; k < 3; ++k)
          if (t[k] == c) {
            const Vec3 u = cut.vertices()[t[(k + 1) % 3]] - cut.vertices()[c];
            const Vec3 v = cut.vertices()[t[(k + 2) % 3]] - cut.vertices()[c];
            sum += std::atan2(u.cross(v).norm(), u.dot(v));
          }
      }
      if (sum >= kPi) return false;
    }
    return true;
  };
  bool use_left = true;
  if (left.disk() && right.disk()) {
    use_left = convex_corners(left) || !convex_corners(right);
  } else if (left.disk() || right.disk()) {
    use_left = left.disk();
  } else {
    // Neither side is a disk: say why, for each side that has faces.
    auto why = [&](const LoopSide& side, const char* name) {
      std::string text = std::string("the ") + name + " side ";
      if (side.face_count == 0) return text + "is empty";
      if (side.boundary_edge_face >= 0) {
        const Face& t = faces[side.boundary_edge_face];
        const int a = t[side.boundary_edge];
        // A hole: a boundary loop of the mesh that the patch loop does not touch.
        bool touches = false;
        std::vector<int> loop;
        for (const auto& l : topology.boundary_loops)
          if (std::find(l.begin(), l.end(), a) != l.end()) loop = l;
        std::set<int> on_loop;
        for (const auto& n : nodes) on_loop.insert(n.begin(), n.end());
        for (int v : loop) touches = touches || on_loop.count(v) > 0;
        return text + (touches ? "reaches the mesh's boundary" : "contains a hole of the mesh") +
               " (a boundary edge at " + point_text(cut.vertices()[a]) + ")";
      }
      std::ostringstream out;
      out << text << "is not a disk (Euler characteristic " << side.euler
          << ": it contains a handle)";
      return out.str();
    };
    throw Infeasible("corners",
                     "the region bounded by the four boundary geodesics is not a disk: " +
                         why(left, "left (c0->c1->c2->c3 counter-clockwise)") + "; " +
                         why(right, "right") + " (grid criterion iv: the patch must be a disk)");
  }
  *reversed = !use_left;
  return use_left ? left.faces : right.faces;
}

// Step 8: the patch: the region's faces and vertices, renumbered, its corners and sides
// counter-clockwise.
Patch extract_patch(const TriangleMesh& cut, const std::vector<char>& region, bool reversed,
                    const std::array<int, 4>& corners, const std::array<std::vector<int>, 4>& nodes,
                    int input_vertex_count, const Progress& progress) {
  Patch patch;
  patch.corners_reversed = reversed;
  std::vector<int> new_index(cut.vertex_count(), -1);
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
  for (int f = 0; f < cut.face_count(); ++f) {
    if (!region[f]) continue;
    Face t = cut.faces()[f];
    for (int& v : t) {
      if (new_index[v] < 0) {
        new_index[v] = static_cast<int>(vertices.size());
        vertices.push_back(cut.vertices()[v]);
        patch.input_vertex.push_back(v < input_vertex_count ? v : -1);
      }
      v = new_index[v];
    }
    faces.push_back(t);
  }
  patch.mesh = TriangleMesh(std::move(vertices), std::move(faces));
  progress.report("patch: cutting", 0.99);  // the topology below is another 0.1 s at 59k
  std::array<std::vector<int>, 4> sides;
  for (int i = 0; i < 4; ++i)
    for (int v : nodes[i]) sides[i].push_back(new_index[v]);
  if (!reversed) {
    for (int i = 0; i < 4; ++i) patch.corners[i] = new_index[corners[i]];
    patch.sides = sides;
  } else {  // reverse: corners c0, c3, c2, c1
    const std::array<int, 4> order{0, 3, 2, 1};
    for (int i = 0; i < 4; ++i) patch.corners[i] = new_index[corners[order[i]]];
    for (int i = 0; i < 4; ++i) {
      // side from corners[order[i]] to corners[order[i+1]] is the reverse of path order[i+1].
      std::vector<int> s = sides[order[(i + 1) % 4]];
      std::reverse(s.begin(), s.end());
      patch.sides[i] = std::move(s);
    }
  }
  for (const auto& side : patch.sides)
    for (int v : side)
      if (v < 0) throw std::logic_error("patch cut: a boundary vertex is not in the patch");
  const size_t loops = patch.mesh.topology().boundary_loops.size();
  if (loops != 1)
    throw Infeasible(
        "corners", "the cut patch has " + std::to_string(loops) + " boundary loops instead of one");
  return patch;
}

}  // namespace

namespace {

/// Steps 3-5 for corners that are vertices of `mesh` and their sides as locations.
Patch cut_along(const TriangleMesh& mesh, const std::array<int, 4>& corners,
                const std::array<std::vector<Location>, 4>& paths, double snap,
                int input_vertex_count, const Progress& progress) {
  // Each step below is linear in the mesh (0.1-0.2 s at 59k vertices): a report between them
  // keeps a cancellation within 0.2 s (it took 0.55 s through the daemon).
  progress.report("patch: cutting", 0.9);
  PathNodes path = insert_path_points(mesh, paths, snap);
  check_simple_loop(path);
  progress.report("patch: cutting", 0.92);
  const Chords chords = find_chords(mesh, paths, path);
  std::vector<Face> faces = retriangulate(mesh, path, chords);
  progress.report("patch: cutting", 0.94);
  const TriangleMesh cut(std::move(path.vertices), std::move(faces));
  progress.report("patch: cutting", 0.96);
  bool reversed = false;
  const std::vector<char> region = patch_region(cut, path.nodes, &reversed);
  progress.report("patch: cutting", 0.98);
  Patch patch =
      extract_patch(cut, region, reversed, corners, path.nodes, input_vertex_count, progress);
  progress.report("patch: cut", 1.0);
  return patch;
}

}  // namespace

Patch cut_patch(const TriangleMesh& input, const std::array<SurfacePoint, 4>& corner_points,
                const GeodesicOptions& geodesic, const PatchCutOptions& options,
                const Progress& progress) {
  progress.report("patch: corners", 0.0);
  const double snap = options.snap_fraction;
  const CornerMesh corner_mesh =
      corner_vertices(input, std::vector<SurfacePoint>(corner_points.begin(), corner_points.end()),
                      snap, "corners");
  const std::array<int, 4> corners{corner_mesh.corners[0], corner_mesh.corners[1],
                                   corner_mesh.corners[2], corner_mesh.corners[3]};
  const auto paths = boundary_geodesics(corner_mesh.mesh, corners, geodesic, snap, progress);
  return cut_along(corner_mesh.mesh, corners, paths, snap, input.vertex_count(), progress);
}

MeshWithCorners insert_corners(const TriangleMesh& mesh, const std::vector<SurfacePoint>& points,
                               const std::string& field, const PatchCutOptions& options) {
  CornerMesh corner_mesh = corner_vertices(mesh, points, options.snap_fraction, field);
  return {std::move(corner_mesh.mesh), std::move(corner_mesh.corners)};
}

std::vector<SurfacePoint> side_geodesic(const GeodesicSolver& solver, const TriangleMesh& mesh,
                                        int from, int to, const Progress& progress) {
  return solve_side(solver, mesh, from, to,
                    std::to_string(from) + " and " + std::to_string(to) + " (vertices)", progress);
}

Patch cut_patch_along(const TriangleMesh& mesh, const std::array<int, 4>& corners,
                      const std::array<std::vector<SurfacePoint>, 4>& sides, int input_vertex_count,
                      const PatchCutOptions& options, const Progress& progress) {
  const double snap = options.snap_fraction;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      if (corners[i] == corners[j])
        throw InvalidInput("corners[" + std::to_string(j) + "]",
                           "the same vertex as corners[" + std::to_string(i) + "]");
  std::array<std::vector<Location>, 4> paths;
  for (int i = 0; i < 4; ++i)
    paths[i] = side_locations(mesh, sides[i], corners[i], corners[(i + 1) % 4], snap, i);
  return cut_along(mesh, corners, paths, snap, input_vertex_count, progress);
}

std::array<double, 4> corner_angles(const Patch& patch) {
  const std::vector<double> sums = vertex_angle_sums(patch.mesh);
  return {sums[patch.corners[0]], sums[patch.corners[1]], sums[patch.corners[2]],
          sums[patch.corners[3]]};
}

std::array<double, 4> side_lengths(const Patch& patch) {
  std::array<double, 4> lengths{};
  for (int i = 0; i < 4; ++i)
    for (size_t k = 0; k + 1 < patch.sides[i].size(); ++k)
      lengths[i] +=
          (patch.mesh.vertices()[patch.sides[i][k + 1]] - patch.mesh.vertices()[patch.sides[i][k]])
              .norm();
  return lengths;
}

void check_convex_corners(const Patch& patch) {
  const auto angles = corner_angles(patch);
  for (int i = 0; i < 4; ++i)
    if (angles[i] >= kPi) {
      std::ostringstream msg;
      msg << "corner c" << i << " has inner angle " << angles[i] * 180 / kPi
          << " degrees >= 180: the patch is not convex (grid criterion iv)";
      throw Infeasible("corners[" + std::to_string(i) + "]", msg.str());
    }
}

}  // namespace gridshell
