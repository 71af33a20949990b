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

#include "gridshell/mesh/curvature.h"
#include "gridshell/mesh/errors.h"
#include "gridshell/mesh/mesh_topology.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string current;
  for (char c : text) {
    if (c == separator) {
      parts.push_back(current);
      current.clear();
    } else {
      current += c;
    }
  }
  parts.push_back(current);
  return parts;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

double parse_number(const std::string& text, const std::string& what) {
  const std::string t = trim(text);
  try {
    size_t used = 0;
    const double value = std::stod(t, &used);
    if (used != t.size() || !std::isfinite(value)) throw std::invalid_argument(t);
    return value;
  } catch (const std::exception&) {
    throw InvalidInput("--corners: " + what + " '" + t + "' is not a finite number");
  }
}

// ---- Mesh surgery used to make corners vertices ------------------------------------------

// Inserts the point given by `point` (already classified as interior to a face or on an edge)
// and returns the new vertex index.
int insert_point(TriangleMesh& mesh, const SurfacePoint& point) {
  const Face f = mesh.faces[point.face];
  const Vec3 position = point.position(mesh);
  const int v = mesh.vertex_count();
  mesh.vertices.push_back(position);
  int zero = -1;
  for (int i = 0; i < 3; ++i)
    if (point.barycentric[i] == 0.0) zero = i;
  if (zero < 0) {  // inside the face: split into three
    mesh.faces[point.face] = {f[0], f[1], v};
    mesh.faces.push_back({f[1], f[2], v});
    mesh.faces.push_back({f[2], f[0], v});
    return v;
  }
  // On the edge opposite vertex `zero`: split this face and its neighbour across that edge.
  const int a = f[(zero + 1) % 3], b = f[(zero + 2) % 3];
  const int nf = mesh.face_count();
  for (int g = 0; g < nf; ++g) {
    const Face t = mesh.faces[g];
    for (int i = 0; i < 3; ++i) {
      const int x = t[i], y = t[(i + 1) % 3], z = t[(i + 2) % 3];
      if ((x == a && y == b) || (x == b && y == a)) {
        mesh.faces[g] = {x, v, z};
        mesh.faces.push_back({v, y, z});
        break;
      }
    }
  }
  return v;
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
  const Face& f = mesh.faces[point.face];
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
    const Face& t = mesh.faces[f];
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

CornerSpec parse_corners(const std::string& text) {
  CornerSpec spec;
  const std::string t = trim(text);
  if (t == "auto") {
    spec.kind = CornerSpec::Kind::Auto;
    return spec;
  }
  if (t.find(';') != std::string::npos) {
    const auto points = split(t, ';');
    if (points.size() != 4)
      throw InvalidInput("--corners: expected 4 points 'x,y,z;x,y,z;x,y,z;x,y,z', got " +
                         std::to_string(points.size()));
    spec.kind = CornerSpec::Kind::Points;
    for (int i = 0; i < 4; ++i) {
      const auto xyz = split(points[i], ',');
      if (xyz.size() != 3)
        throw InvalidInput("--corners: point " + std::to_string(i + 1) +
                           " must have 3 coordinates x,y,z, got '" + trim(points[i]) + "'");
      for (int k = 0; k < 3; ++k)
        spec.points[i][k] = parse_number(xyz[k], "coordinate of point " + std::to_string(i + 1));
    }
    return spec;
  }
  const auto parts = split(t, ',');
  if (parts.size() != 4)
    throw InvalidInput(
        "--corners: expected 4 vertex indices 'i,j,k,l', 4 points "
        "'x,y,z;x,y,z;x,y,z;x,y,z' or 'auto', got '" +
        text + "'");
  spec.kind = CornerSpec::Kind::Vertices;
  for (int i = 0; i < 4; ++i) {
    const std::string p = trim(parts[i]);
    size_t used = 0;
    long value = -1;
    try {
      value = std::stol(p, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != p.size() || p.empty() || value < 0 || value > std::numeric_limits<int>::max())
      throw InvalidInput("--corners: vertex index '" + p + "' is not a non-negative integer");
    spec.vertices[i] = static_cast<int>(value);
  }
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      if (spec.vertices[i] == spec.vertices[j])
        throw InvalidInput("--corners: vertex " + std::to_string(spec.vertices[i]) +
                           " is given twice");
  return spec;
}

std::array<int, 4> auto_corners(const TriangleMesh& mesh) {
  const MeshTopology topology = build_topology(mesh);
  if (topology.boundary_loops.empty())
    throw InvalidInput("--corners auto: the mesh has no boundary");
  const std::vector<int>& loop =
      *std::max_element(topology.boundary_loops.begin(), topology.boundary_loops.end(),
                        [](const auto& a, const auto& b) { return a.size() < b.size(); });
  if (loop.size() < 4) throw InvalidInput("--corners auto: the boundary has fewer than 4 vertices");
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

SurfacePoint closest_surface_point(const TriangleMesh& mesh, const Vec3& point) {
  SurfacePoint best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int f = 0; f < mesh.face_count(); ++f) {
    const Face& t = mesh.faces[f];
    const Vec3 w =
        closest_point_on_triangle(point, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
    const Vec3 q =
        w[0] * mesh.vertices[t[0]] + w[1] * mesh.vertices[t[1]] + w[2] * mesh.vertices[t[2]];
    const double d = (q - point).squaredNorm();
    if (d < best_distance) {
      best_distance = d;
      best.face = f;
      best.barycentric = w;
    }
  }
  if (best.face < 0) throw InvalidInput("--corners: the mesh has no faces");
  return best;
}

Patch cut_patch(const TriangleMesh& input, const std::array<SurfacePoint, 4>& corner_points,
                const PatchCutOptions& options, const Progress& progress) {
  progress.report("patch: corners", 0.0);
  const double snap = options.snap_fraction;

  // 1. Make every corner a vertex of a working copy of the mesh.
  TriangleMesh mesh = input;
  std::array<int, 4> corners{};
  std::array<Vec3, 4> corner_positions;
  for (int i = 0; i < 4; ++i) {
    if (corner_points[i].face < 0 || corner_points[i].face >= input.face_count())
      throw InvalidInput("corner " + std::to_string(i) + ": face index out of range");
    corner_positions[i] = corner_points[i].position(input);
  }
  for (int i = 0; i < 4; ++i) {
    SurfacePoint p = i == 0 ? corner_points[0] : closest_surface_point(mesh, corner_positions[i]);
    p = snapped(p, snap);
    const int v = p.vertex(mesh);
    corners[i] = v >= 0 ? v : insert_point(mesh, p);
  }
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      if (corners[i] == corners[j])
        throw InvalidInput("corners " + std::to_string(i) + " and " + std::to_string(j) +
                           " are the same surface point");
  const int input_vertex_count = input.vertex_count();

  // 2. The four boundary geodesics, exact shortest paths between consecutive corners.
  const MeshTopology topology = build_topology(mesh);
  GeodesicSolver solver(mesh, GeodesicOptions{options.method});
  std::array<std::vector<Location>, 4> paths;
  for (int i = 0; i < 4; ++i) {
    progress.report("patch: boundary geodesics", 0.1 + 0.2 * i);
    // solve + path_to is shortest_path with the cancellation flag polled during the solve.
    const auto path = solver.solve(SurfacePoint::at_vertex(mesh, corners[i]), progress.checker())
                          .path_to(SurfacePoint::at_vertex(mesh, corners[(i + 1) % 4]));
    std::vector<Location> locations;
    for (const SurfacePoint& p : path) {
      Location loc = classify(mesh, p, snap);
      if (!locations.empty() && locations.back().a == loc.a && locations.back().b == loc.b &&
          (loc.is_vertex() || std::abs(locations.back().t - loc.t) < snap))
        continue;
      locations.push_back(loc);
    }
    if (locations.size() < 2 || !locations.front().is_vertex() ||
        locations.front().a != corners[i] || !locations.back().is_vertex() ||
        locations.back().a != corners[(i + 1) % 4])
      throw std::logic_error("patch cut: geodesic " + side_name(i) + " does not join its corners");
    paths[i] = std::move(locations);
  }
  progress.report("patch: cutting", 0.9);

  // 3. New vertices for the points on edges; merge points of different paths at one spot.
  std::map<std::uint64_t, std::vector<std::pair<double, int>>> edge_points;  // key -> (t, vertex)
  auto node_of = [&](const Location& loc) -> int {
    if (loc.is_vertex()) return loc.a;
    auto& list = edge_points[edge_key(loc.a, loc.b)];
    for (const auto& [t, v] : list)
      if (std::abs(t - loc.t) < snap) return v;
    const int v = mesh.vertex_count();
    mesh.vertices.push_back((1 - loc.t) * mesh.vertices[loc.a] + loc.t * mesh.vertices[loc.b]);
    list.push_back({loc.t, v});
    return v;
  };
  std::array<std::vector<int>, 4> nodes;
  for (int i = 0; i < 4; ++i)
    for (const Location& loc : paths[i]) nodes[i].push_back(node_of(loc));

  // Criterion (iv): the closed loop c0->c1->c2->c3->c0 must be simple.
  {
    std::map<int, int> owner;  // node -> side that visits it
    for (int i = 0; i < 4; ++i)
      for (size_t k = 0; k + 1 < nodes[i].size(); ++k) {  // the last node is the next side's first
        const auto [it, inserted] = owner.emplace(nodes[i][k], i);
        if (!inserted) {
          std::ostringstream msg;
          const Vec3& p = mesh.vertices[nodes[i][k]];
          msg << "boundary geodesics " << side_name(it->second) << " and " << side_name(i)
              << " touch or cross at (" << p.x() << ", " << p.y() << ", " << p.z()
              << "): the patch is not a simple quadrilateral (grid criterion iv)";
          throw Infeasible(msg.str());
        }
      }
  }

  // 4. Chords: path segments that cross a face's interior.
  std::map<int, std::vector<std::pair<int, int>>> chords;  // face -> (node, node)
  std::vector<char> face_touched(mesh.face_count(), 0);
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
      chords[common[0]].push_back({nodes[i][k], nodes[i][k + 1]});
      face_touched[common[0]] = 1;
    }
  for (const auto& [key, list] : edge_points) {
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    for (int f : topology.vertex_faces[a]) {
      const Face& t = mesh.faces[f];
      if (t[0] == b || t[1] == b || t[2] == b) face_touched[f] = 1;
    }
  }

  // 5. Re-triangulate every touched face: boundary cycle with the new points, split by chords.
  std::vector<Face> faces;
  faces.reserve(mesh.faces.size() + 8 * chords.size());
  for (int f = 0; f < static_cast<int>(mesh.faces.size()); ++f) {
    const Face t = mesh.faces[f];
    if (!face_touched[f]) {
      faces.push_back(t);
      continue;
    }
    std::vector<int> cycle;
    for (int i = 0; i < 3; ++i) {
      const int a = t[i], b = t[(i + 1) % 3];
      cycle.push_back(a);
      auto it = edge_points.find(edge_key(a, b));
      if (it == edge_points.end()) continue;
      auto list = it->second;
      std::sort(list.begin(), list.end());
      if (a > b) std::reverse(list.begin(), list.end());  // t runs from min(a,b) to max(a,b)
      for (const auto& entry : list) cycle.push_back(entry.second);
    }
    // Local 2D frame of the face.
    const Vec3 o = mesh.vertices[t[0]];
    const Vec3 e1 = (mesh.vertices[t[1]] - o).normalized();
    const Vec3 n = e1.cross(mesh.vertices[t[2]] - o).normalized();
    const Vec3 e2 = n.cross(e1);
    auto to2d = [&](int v) {
      const Vec3 d = mesh.vertices[v] - o;
      return Vec2(d.dot(e1), d.dot(e2));
    };
    std::vector<std::vector<int>> polygons{cycle};
    for (const auto& [x, y] : chords[f]) {
      bool placed = false;
      for (size_t pi = 0; pi < polygons.size() && !placed; ++pi) {
        auto& poly = polygons[pi];
        const auto ix = std::find(poly.begin(), poly.end(), x);
        const auto iy = std::find(poly.begin(), poly.end(), y);
        if (ix == poly.end() || iy == poly.end()) continue;
        size_t i0 = ix - poly.begin(), i1 = iy - poly.begin();
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
        const Vec3& p = mesh.vertices[x];
        msg << "boundary geodesics cross inside a face near (" << p.x() << ", " << p.y() << ", "
            << p.z() << "): the patch is not a simple quadrilateral (grid criterion iv)";
        throw Infeasible(msg.str());
      }
    }
    for (const auto& poly : polygons) {
      std::vector<Vec2> points;
      for (int v : poly) points.push_back(to2d(v));
      for (const auto& tri : triangulate_convex(points))
        faces.push_back({poly[tri[0]], poly[tri[1]], poly[tri[2]]});
    }
  }
  mesh.faces = std::move(faces);

  // 6. Which side of the loop is the patch.
  const MeshTopology cut_topology = build_topology(mesh);
  std::set<std::uint64_t> loop_edges;
  std::vector<std::pair<int, int>> directed;
  for (int i = 0; i < 4; ++i)
    for (size_t k = 0; k + 1 < nodes[i].size(); ++k) {
      loop_edges.insert(edge_key(nodes[i][k], nodes[i][k + 1]));
      directed.push_back({nodes[i][k], nodes[i][k + 1]});
    }
  auto flood = [&](bool left) {
    std::vector<char> in(mesh.face_count(), 0);
    std::queue<int> queue;
    for (const auto& [a, b] : directed) {
      for (int f : cut_topology.vertex_faces[a]) {
        const Face& t = mesh.faces[f];
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
        const int g = cut_topology.face_neighbors[f][i];
        if (g < 0 || in[g]) continue;
        if (loop_edges.count(edge_key(mesh.faces[f][i], mesh.faces[f][(i + 1) % 3]))) continue;
        in[g] = 1;
        queue.push(g);
      }
    }
    return in;
  };
  const std::vector<char> left = flood(true), right = flood(false);
  auto reaches_outer_boundary = [&](const std::vector<char>& region) {
    for (int f = 0; f < mesh.face_count(); ++f) {
      if (!region[f]) continue;
      for (int i = 0; i < 3; ++i)
        if (cut_topology.face_neighbors[f][i] < 0 &&
            !loop_edges.count(edge_key(mesh.faces[f][i], mesh.faces[f][(i + 1) % 3])))
          return true;
    }
    return false;
  };
  auto count = [](const std::vector<char>& region) {
    return std::count(region.begin(), region.end(), 1);
  };
  for (int f = 0; f < mesh.face_count(); ++f)
    if (left[f] && right[f])
      throw Infeasible("the four boundary geodesics do not enclose a region (grid criterion iv)");
  bool use_left = true;
  if (count(left) == 0) {
    use_left = false;
  } else if (count(right) > 0 && reaches_outer_boundary(left) && !reaches_outer_boundary(right)) {
    use_left = false;
  }
  const std::vector<char>& region = use_left ? left : right;
  if (count(region) == 0) throw Infeasible("the patch enclosed by the corners is empty");

  // 7. Extract the patch.
  Patch patch;
  patch.corners_reversed = !use_left;
  std::vector<int> new_index(mesh.vertex_count(), -1);
  for (int f = 0; f < mesh.face_count(); ++f) {
    if (!region[f]) continue;
    Face t = mesh.faces[f];
    for (int& v : t) {
      if (new_index[v] < 0) {
        new_index[v] = patch.mesh.vertex_count();
        patch.mesh.vertices.push_back(mesh.vertices[v]);
        patch.input_vertex.push_back(v < input_vertex_count ? v : -1);
      }
      v = new_index[v];
    }
    patch.mesh.faces.push_back(t);
  }
  std::array<std::vector<int>, 4> sides;
  for (int i = 0; i < 4; ++i)
    for (int v : nodes[i]) sides[i].push_back(new_index[v]);
  if (use_left) {
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
  const MeshTopology patch_topology = build_topology(patch.mesh);
  if (patch_topology.boundary_loops.size() != 1)
    throw Infeasible("the cut patch has " + std::to_string(patch_topology.boundary_loops.size()) +
                     " boundary loops instead of one");
  progress.report("patch: cut", 1.0);
  return patch;
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
          (patch.mesh.vertices[patch.sides[i][k + 1]] - patch.mesh.vertices[patch.sides[i][k]])
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
      throw Infeasible(msg.str());
    }
}

}  // namespace gridshell
