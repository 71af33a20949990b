// SPDX-License-Identifier: GPL-3.0-or-later
// Automatic layouts of a disk (see gridshell/design/layout.h, docs/multi-patch.md): the surface
// mapped onto a square by CGAL's mean value coordinates, a grid of patches on the square.
#define CGAL_EIGEN3_ENABLED 1  // CGAL's parameterization solves with Eigen
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/Error_code.h>
#include <CGAL/Surface_mesh_parameterization/Mean_value_coordinates_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/Square_border_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <numeric>
#include <queue>
#include <set>
#include <stdexcept>

#include "gridshell/design/layout.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/surface_distance.h"

namespace gridshell {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMP = CGAL::Surface_mesh_parameterization;

constexpr double kPi = std::numbers::pi;

/// What the automatic layout can cover: a disk (one boundary loop), a ring or tube (two) or a
/// closed surface without handles.
enum class Surface { Disk, Ring, Closed };

const char* surface_name(Surface s) {
  return s == Surface::Disk ? "disk" : s == Surface::Ring ? "ring" : "closed";
}

/// Euler characteristic V - E + F of the used vertices.
long euler_characteristic(const TriangleMesh& mesh) {
  std::vector<char> used(mesh.vertex_count(), 0);
  for (const Face& f : mesh.faces())
    for (int v : f) used[v] = 1;
  const long vertices = std::count(used.begin(), used.end(), 1);
  long boundary_edges = 0;
  for (const auto& loop : mesh.topology().boundary_loops)
    boundary_edges += static_cast<long>(loop.size());
  const long faces = mesh.face_count();
  const long edges = (3 * faces + boundary_edges) / 2;
  return vertices - edges + faces;
}

Surface classify(const TriangleMesh& mesh) {
  const size_t loops = mesh.topology().boundary_loops.size();
  const long euler = euler_characteristic(mesh);
  if (loops == 1 && euler == 1) return Surface::Disk;
  if (loops == 2 && euler == 0) return Surface::Ring;
  if (loops == 0 && euler == 2) return Surface::Closed;
  throw Infeasible("layout", "the surface has " + std::to_string(loops) +
                                 " boundary loops and Euler characteristic " +
                                 std::to_string(euler) +
                                 ": automatic layouts cover a disk (1 loop, 1), a ring or a tube "
                                 "(2 loops, 0) and a closed surface without handles (0 loops, 2) "
                                 "in one piece; give a layout file (docs/multi-patch.md)");
}

/// How much the boundary turns at each vertex of `loop`, seen in plan: on the plane of the
/// surface's two largest principal directions (where a roof's or a facade's corners are).
std::vector<double> turning(const TriangleMesh& mesh, const std::vector<int>& loop) {
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : mesh.vertices()) centre += p;
  centre /= std::max(1, mesh.vertex_count());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : mesh.vertices()) covariance += (p - centre) * (p - centre).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  const Vec3 ex = eigen.eigenvectors().col(2), ey = eigen.eigenvectors().col(1);
  const int n = static_cast<int>(loop.size());
  std::vector<Vec2> plan;
  for (int v : loop) {
    const Vec3 d = mesh.vertices()[v] - centre;
    plan.emplace_back(d.dot(ex), d.dot(ey));
  }
  // Signed so that the loop turns by +2 pi in all (either orientation of the plan).
  std::vector<double> out(n, 0.0);
  double total = 0;
  for (int i = 0; i < n; ++i) {
    const Vec2 a = plan[i] - plan[(i + n - 1) % n], b = plan[(i + 1) % n] - plan[i];
    out[i] = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
    total += out[i];
  }
  if (total < 0)
    for (double& t : out) t = -t;
  return out;
}

/// The four boundary corners: positions in `loop`.
std::array<int, 4> square_corners(const TriangleMesh& mesh, const std::vector<int>& loop) {
  const std::vector<double> vertex_turn = turning(mesh, loop);
  const int n = static_cast<int>(loop.size());
  std::vector<double> arc(n + 1, 0.0);  // arc length from loop[0]
  for (int i = 0; i < n; ++i)
    arc[i + 1] = arc[i] + (mesh.vertices()[loop[(i + 1) % n]] - mesh.vertices()[loop[i]]).norm();
  const double perimeter = arc[n];
  // A rounded corner turns over several vertices: each vertex's turn is the boundary's turn
  // within a 32nd of the perimeter either side of it.
  const double reach = perimeter / 32;
  std::vector<double> turn(n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double along = std::abs(arc[j] - arc[i]);
      along = std::min(along, perimeter - along);
      if (along <= reach) turn[i] += vertex_turn[j];
    }
  // A corner found by its window is then the vertex that turns most within that window: the
  // sharp corner where there is one.
  const auto sharpest_near = [&](int c) {
    int best = c;
    for (int j = 0; j < n; ++j) {
      double along = std::abs(arc[j] - arc[c]);
      along = std::min(along, perimeter - along);
      if (along <= reach && vertex_turn[j] > vertex_turn[best]) best = j;
    }
    return best;
  };
  const int start =
      sharpest_near(static_cast<int>(std::max_element(turn.begin(), turn.end()) - turn.begin()));
  std::array<int, 4> corners{start, 0, 0, 0}, quarter{start, 0, 0, 0};
  for (int q = 1; q < 4; ++q) {
    const double ideal = q * perimeter / 4;
    int nearest = -1, sharpest = -1;
    double nearest_offset = 1e300;
    for (int i = 0; i < n; ++i) {
      const int at = (start + i) % n;
      double along = arc[at] - arc[start];
      if (along < 0) along += perimeter;
      const double offset = std::abs(along - ideal);
      if (offset > perimeter / 8) continue;
      if (offset < nearest_offset) nearest_offset = offset, nearest = at;
      if (turn[at] > kPi / 6 && (sharpest < 0 || turn[at] > turn[sharpest])) sharpest = at;
    }
    corners[q] = sharpest >= 0 ? sharpest_near(sharpest) : nearest;
    quarter[q] = nearest;
  }
  // A corner moved to the sharpest vertex near it may pass its neighbour (a cusp between two
  // windows took both on a public net's boundary, and the square's border then failed): the
  // corners must follow one another round the loop, else the quarter point is taken.
  const auto offset = [&](int at) {
    const double along = arc[at] - arc[start];
    return along < 0 ? along + perimeter : along;
  };
  for (int q = 1; q < 4; ++q)
    if (offset(corners[q]) <= offset(corners[q - 1]) || corners[q] == start)
      corners[q] = quarter[q];
  return corners;
}

/// The surface point at parameter `uv`: in the face whose barycentric coordinates of it are
/// least negative.
Vec3 point_at(const TriangleMesh& mesh, const std::vector<Vec2>& uv, const Vec2& target) {
  double best = -1e300;
  Vec3 point = Vec3::Zero();
  for (const Face& f : mesh.faces()) {
    const Vec2 &a = uv[f[0]], &b = uv[f[1]], &c = uv[f[2]];
    const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (std::abs(area) < 1e-300) continue;
    const auto cross = [](const Vec2& p, const Vec2& q, const Vec2& r) {
      return (q - p).x() * (r - p).y() - (q - p).y() * (r - p).x();
    };
    const double l0 = cross(target, b, c) / area, l1 = cross(a, target, c) / area, l2 = 1 - l0 - l1;
    const double worst = std::min({l0, l1, l2});
    if (worst > best) {
      best = worst;
      // Clamped to the face (a point just outside, by rounding, goes onto its edge).
      double w0 = std::max(0.0, l0), w1 = std::max(0.0, l1), w2 = std::max(0.0, l2);
      const double sum = w0 + w1 + w2;
      w0 /= sum, w1 /= sum, w2 /= sum;
      point = w0 * mesh.vertices()[f[0]] + w1 * mesh.vertices()[f[1]] + w2 * mesh.vertices()[f[2]];
    }
  }
  return point;
}

/// The mesh mapped onto the unit square with loop[corners[k]] at its corners in order.
std::vector<Vec2> square_map(const TriangleMesh& mesh, const std::vector<int>& loop,
                             const std::array<int, 4>& corners) {
  CgalMesh cgal;
  std::vector<CgalMesh::Vertex_index> handle;
  for (const Vec3& p : mesh.vertices()) handle.push_back(cgal.add_vertex({p.x(), p.y(), p.z()}));
  for (const Face& f : mesh.faces())
    if (cgal.add_face(handle[f[0]], handle[f[1]], handle[f[2]]) == CgalMesh::null_face())
      throw Infeasible("layout",
                       "the surface could not be mapped onto a square (a face is not "
                       "manifold for CGAL)");
  // A border halfedge of the loop; the corners run along the border in CGAL's direction.
  CgalMesh::Halfedge_index border;
  for (CgalMesh::Halfedge_index h : cgal.halfedges())
    if (cgal.is_border(h)) {
      border = h;
      break;
    }
  using Border = SMP::Square_border_arc_length_parameterizer_3<CgalMesh>;
  using Parameterizer = SMP::Mean_value_coordinates_parameterizer_3<CgalMesh, Border>;
  const Border border_map(handle[loop[corners[0]]], handle[loop[corners[1]]],
                          handle[loop[corners[2]]], handle[loop[corners[3]]]);
  auto uv_map = cgal.add_property_map<CgalMesh::Vertex_index, Kernel::Point_2>("v:uv").first;
  const SMP::Error_code status = SMP::parameterize(cgal, Parameterizer(border_map), border, uv_map);
  if (status != SMP::OK)
    throw Infeasible("layout", std::string("the surface could not be mapped onto a square: ") +
                                   SMP::get_error_message(status));
  std::vector<Vec2> uv(mesh.vertex_count(), Vec2::Zero());
  for (int v = 0; v < mesh.vertex_count(); ++v)
    uv[v] = Vec2(uv_map[handle[v]].x(), uv_map[handle[v]].y());
  return uv;
}

/// A ring cut open into a disk along the shortest edge path between its two boundary loops.
struct RingCut {
  TriangleMesh disk;              ///< the input's vertices, then one copy of each path vertex
  std::vector<int> path;          ///< input vertices from the longer loop (A) to the other (B)
  double length = 0;              ///< of the path
  double loop_a = 0, loop_b = 0;  ///< lengths of the two loops
  int copy(int k) const { return disk.vertex_count() - static_cast<int>(path.size()) + k; }
};

double loop_length(const TriangleMesh& mesh, const std::vector<int>& loop) {
  double length = 0;
  for (size_t i = 0; i < loop.size(); ++i)
    length += (mesh.vertices()[loop[(i + 1) % loop.size()]] - mesh.vertices()[loop[i]]).norm();
  return length;
}

RingCut cut_ring(const TriangleMesh& mesh) {
  const int n = mesh.vertex_count();
  RingCut out;
  std::vector<int> loop_a = mesh.topology().boundary_loops[0],
                   loop_b = mesh.topology().boundary_loops[1];
  out.loop_a = loop_length(mesh, loop_a), out.loop_b = loop_length(mesh, loop_b);
  if (out.loop_b > out.loop_a) std::swap(loop_a, loop_b), std::swap(out.loop_a, out.loop_b);
  // Faces on each edge, and each vertex's neighbours.
  std::map<std::pair<int, int>, std::vector<int>> edge_faces;
  std::vector<std::vector<int>> neighbours(n);
  for (int f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces()[f][k], b = mesh.faces()[f][(k + 1) % 3];
      edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
      neighbours[a].push_back(b), neighbours[b].push_back(a);
    }
  // Dijkstra from every vertex of loop A; the path ends at the nearest vertex of loop B.
  std::vector<double> distance(n, std::numeric_limits<double>::infinity());
  std::vector<int> previous(n, -1);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (int v : loop_a) distance[v] = 0, queue.push({0.0, v});
  std::vector<char> in_b(n, 0);
  for (int v : loop_b) in_b[v] = 1;
  int end = -1;
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > distance[v]) continue;
    if (in_b[v]) {
      end = v;
      break;
    }
    for (int w : neighbours[v]) {
      const double next = d + (mesh.vertices()[w] - mesh.vertices()[v]).norm();
      if (next < distance[w]) distance[w] = next, previous[w] = v, queue.push({next, w});
    }
  }
  if (end < 0) throw Infeasible("layout", "the surface's two boundary loops are not connected");
  for (int v = end; v >= 0; v = previous[v]) out.path.push_back(v);
  std::reverse(out.path.begin(), out.path.end());
  out.length = distance[end];
  // Each path vertex gets a copy, which the faces on one side of the path take: the faces on
  // the right of the path's edges (where an edge runs backwards) and those reached from them
  // around the vertex without crossing a path edge.
  const int m = static_cast<int>(out.path.size());
  std::set<std::pair<int, int>> path_edges;
  for (int k = 0; k + 1 < m; ++k)
    path_edges.insert(
        {std::min(out.path[k], out.path[k + 1]), std::max(out.path[k], out.path[k + 1])});
  std::vector<Face> faces = mesh.faces();
  const auto runs = [&](int f, int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (mesh.faces()[f][k] == a && mesh.faces()[f][(k + 1) % 3] == b) return true;
    return false;
  };
  for (int k = 0; k < m; ++k) {
    const int v = out.path[k];
    std::vector<int> stack;
    for (int j : {k - 1, k + 1}) {
      if (j < 0 || j >= m) continue;
      const int w = out.path[j];
      for (int f : edge_faces[{std::min(v, w), std::max(v, w)}])
        if (runs(f, j > k ? w : v, j > k ? v : w)) stack.push_back(f);
    }
    std::set<int> side;
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      if (!side.insert(f).second) continue;
      for (int w : mesh.faces()[f]) {
        if (w == v) continue;
        const std::pair<int, int> e{std::min(v, w), std::max(v, w)};
        if (path_edges.count(e)) continue;
        for (int g : edge_faces[e])
          if (g != f) stack.push_back(g);
      }
    }
    for (int f : side)
      for (int& w : faces[f])
        if (w == v) w = n + k;
  }
  std::vector<Vec3> vertices = mesh.vertices();
  for (int v : out.path) vertices.push_back(mesh.vertices()[v]);
  out.disk = TriangleMesh(std::move(vertices), std::move(faces));
  if (classify(out.disk) != Surface::Disk)
    throw Infeasible("layout",
                     "the ring could not be cut open into a disk along the shortest "
                     "path between its boundary loops");
  return out;
}

/// The uv map of a ring cut open, turned so that loop A runs along v = 0 from u = 0 to 1 and
/// loop B along v = 1: u goes round the ring, v across it.
std::vector<Vec2> ring_map(const RingCut& cut) {
  const std::vector<int>& loop = cut.disk.topology().boundary_loops.front();
  const int m = static_cast<int>(cut.path.size());
  const std::array<int, 4> ends{cut.path[0], cut.copy(0), cut.path[m - 1], cut.copy(m - 1)};
  std::array<int, 4> corners{};
  for (int k = 0; k < 4; ++k) {
    const auto at = std::find(loop.begin(), loop.end(), ends[k]);
    if (at == loop.end()) throw std::logic_error("ring_map: a cut end is not on the border");
    corners[k] = static_cast<int>(at - loop.begin());
  }
  std::sort(corners.begin(), corners.end());
  std::swap(corners[1], corners[3]);  // CGAL walks the border against the loop's order
  const std::vector<Vec2> uv = square_map(cut.disk, loop, corners);
  // The border runs p0 -> (loop A) -> copy of p0 -> (copies along the cut) -> copy of pm ->
  // (loop B) -> pm -> (the cut) -> p0: p0's neighbours on the square are its copy and pm.
  const Vec2 origin = uv[ends[0]], along = uv[ends[1]] - origin, across = uv[ends[2]] - origin;
  std::vector<Vec2> out(uv.size());
  for (size_t v = 0; v < uv.size(); ++v)
    out[v] = Vec2((uv[v] - origin).dot(along), (uv[v] - origin).dot(across));
  return out;
}

/// A closed surface seen from its centre: the area-weighted centroid, the principal axes and
/// the extents along them. Throws Infeasible unless every face faces away from the centre (the
/// surface is star-shaped about it, so each ray from it meets the surface once).
struct CubeFrame {
  Vec3 centre = Vec3::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  ///< columns, right-handed
  Vec3 extent = Vec3::Ones();
};

CubeFrame cube_frame(const TriangleMesh& mesh) {
  CubeFrame out;
  double area = 0;
  for (const Face& f : mesh.faces()) {
    const Vec3 &a = mesh.vertices()[f[0]], &b = mesh.vertices()[f[1]], &c = mesh.vertices()[f[2]];
    const double w = 0.5 * (b - a).cross(c - a).norm();
    out.centre += w * (a + b + c) / 3, area += w;
  }
  if (!(area > 0)) throw Infeasible("layout", "the closed surface has no area");
  out.centre /= area;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : mesh.vertices())
    covariance += (p - out.centre) * (p - out.centre).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  out.axes.col(0) = eigen.eigenvectors().col(2), out.axes.col(1) = eigen.eigenvectors().col(1);
  out.axes.col(2) = out.axes.col(0).cross(out.axes.col(1));
  out.extent = Vec3::Zero();
  for (const Vec3& p : mesh.vertices())
    out.extent = out.extent.cwiseMax((out.axes.transpose() * (p - out.centre)).cwiseAbs());
  int outward = 0, inward = 0;
  for (const Face& f : mesh.faces()) {
    const Vec3 &a = mesh.vertices()[f[0]], &b = mesh.vertices()[f[1]], &c = mesh.vertices()[f[2]];
    const Vec3 normal = (b - a).cross(c - a);
    const double side = normal.dot((a + b + c) / 3 - out.centre);
    const double scale = normal.norm() * ((a + b + c) / 3 - out.centre).norm();
    if (side > 1e-9 * scale)
      ++outward;
    else if (side < -1e-9 * scale)
      ++inward;
  }
  if (std::min(outward, inward) > 0 || outward + inward < mesh.face_count())
    throw Infeasible(
        "layout", std::to_string(std::min(outward, inward) + mesh.face_count() - outward - inward) +
                      " faces of the closed surface do not face away from its centre: "
                      "automatic layouts of a closed surface split it along a cube about its "
                      "centre and need every ray from there to meet the surface once; cut it "
                      "open or give a layout file (docs/multi-patch.md)");
  return out;
}

/// The grids a surface is tried with, fewest patches first, and how each is laid out.
struct Grids {
  struct Size {
    int columns = 0, rows = 0, patches = 0;
  };
  std::vector<Size> sizes;
  std::function<PatchLayout(int columns, int rows)> layout;
};

/// For each patch count up to `max_patches`, the columns x rows grid whose patches are closest
/// to square when the grid spans `aspect` (its length along the columns over the rows'), if
/// they are at most twice as long one way as the other; columns at least `min_columns`.
std::vector<Grids::Size> grid_sizes(double aspect, int max_patches, int min_columns) {
  std::vector<Grids::Size> out;
  for (int n = 1; n <= max_patches; ++n) {
    Grids::Size best;
    double best_error = 1e300;
    for (int columns = min_columns; columns <= n; ++columns) {
      if (n % columns) continue;
      const int rows = n / columns;
      const double error = std::abs(std::log(aspect * rows / columns));
      if (error < best_error) best_error = error, best = {columns, rows, n};
    }
    if (best.patches > 0 && best_error <= std::log(2.0) + 1e-12) out.push_back(best);
  }
  return out;
}

/// A disk: four boundary vertices at the corners of a square, a grid on the square.
Grids disk_grids(const TriangleMesh& mesh, const AutoLayoutOptions& options, AutoLayout& out) {
  const std::vector<int>& loop = mesh.topology().boundary_loops.front();
  std::array<int, 4> corners = square_corners(mesh, loop);
  // CGAL walks the border against the faces' orientation: corners in the order it meets them,
  // and each at the square's corner it was mapped to.
  std::swap(corners[1], corners[3]);
  auto uv = std::make_shared<const std::vector<Vec2>>(square_map(mesh, loop, corners));
  const std::array<Vec2, 4> square{Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  out.boundary_corners.assign(4, -1);
  for (int k = 0; k < 4; ++k) {
    for (int c : corners)
      if (((*uv)[loop[c]] - square[k]).norm() < 1e-9) out.boundary_corners[k] = loop[c];
    if (out.boundary_corners[k] < 0)
      throw std::logic_error("auto_layout: a corner of the square is not a chosen vertex");
  }
  // The square's sides u (corner 0 -> 1, 3 -> 2) and v (1 -> 2, 0 -> 3): their lengths on the
  // surface, averaged over opposite sides, give the patches' best shape.
  const auto arc_between = [&](int from, int to) {
    const int n = static_cast<int>(loop.size());
    double length = 0;
    for (int i = corners[from]; i != corners[to]; i = (i + 1) % n)
      length += (mesh.vertices()[loop[(i + 1) % n]] - mesh.vertices()[loop[i]]).norm();
    return length;
  };
  const double length_u = 0.5 * (arc_between(0, 1) + arc_between(2, 3));
  const double length_v = 0.5 * (arc_between(1, 2) + arc_between(3, 0));
  Grids grids;
  grids.sizes = grid_sizes(length_v > 0 ? length_u / length_v : 1.0, options.max_patches, 1);
  if (grids.sizes.empty()) grids.sizes.push_back({1, 1, 1});
  const std::vector<int> square_corner = out.boundary_corners;
  grids.layout = [&mesh, uv, square_corner](int columns, int rows) {
    PatchLayout layout;
    for (int j = 0; j <= rows; ++j)
      for (int i = 0; i <= columns; ++i) {
        LayoutCorner c;
        const bool corner = (i == 0 || i == columns) && (j == 0 || j == rows);
        if (corner) {
          c.vertex = square_corner[i == 0 ? (j == 0 ? 0 : 3) : (j == 0 ? 1 : 2)];
        } else {
          c.point = point_at(mesh, *uv,
                             Vec2(static_cast<double>(i) / columns, static_cast<double>(j) / rows));
        }
        layout.corners.push_back(c);
      }
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < columns; ++i) {
        const int a = j * (columns + 1) + i;
        layout.patches.push_back({"", {a, a + 1, a + columns + 2, a + columns + 1}});
      }
    return layout;
  };
  return grids;
}

/// A ring or a tube: cut open between its loops into a disk, mapped onto a square whose two
/// cut sides are the same points; a grid of columns around the ring (at least 3) and rows
/// across it, the last column joining the first.
Grids ring_grids(const TriangleMesh& mesh, const AutoLayoutOptions& options, AutoLayout& out) {
  auto cut = std::make_shared<const RingCut>(cut_ring(mesh));
  auto uv = std::make_shared<const std::vector<Vec2>>(ring_map(*cut));
  const int a = cut->path.front(), b = cut->path.back();
  out.boundary_corners = {a, a, b, b};
  for (int v : cut->path) out.cut_path.push_back(mesh.vertices()[v]);
  const Vec3 &from = mesh.vertices()[a], &to = mesh.vertices()[b];
  char text[480];
  std::snprintf(text, sizeof text,
                "a ring (2 boundary loops, %.6g and %.6g long): cut open for its map along the "
                "shortest edge path between them (%zu points, %.6g long, from (%.6g, %.6g, %.6g) "
                "to (%.6g, %.6g, %.6g)); the patches go round it, the first column's seam starts "
                "at the cut",
                cut->loop_a, cut->loop_b, cut->path.size(), cut->length, from.x(), from.y(),
                from.z(), to.x(), to.y(), to.z());
  out.cut = text;
  Grids grids;
  const double across = cut->length > 0 ? cut->length : 1.0;
  grids.sizes = grid_sizes(0.5 * (cut->loop_a + cut->loop_b) / across, options.max_patches, 3);
  if (grids.sizes.empty() && options.max_patches >= 3) grids.sizes.push_back({3, 1, 3});
  grids.layout = [cut, uv, a, b](int columns, int rows) {
    PatchLayout layout;
    for (int j = 0; j <= rows; ++j)
      for (int i = 0; i < columns; ++i) {
        LayoutCorner c;
        if (i == 0 && (j == 0 || j == rows)) {
          c.vertex = j == 0 ? a : b;
        } else {
          c.point = point_at(cut->disk, *uv,
                             Vec2(static_cast<double>(i) / columns, static_cast<double>(j) / rows));
        }
        layout.corners.push_back(c);
      }
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < columns; ++i) {
        const int next = (i + 1) % columns;
        layout.patches.push_back({"",
                                  {j * columns + i, j * columns + next, (j + 1) * columns + next,
                                   (j + 1) * columns + i}});
      }
    return layout;
  };
  return grids;
}

/// A closed surface: split along a cube about its centre (its axes the principal directions,
/// stretched to the extents), each face of the cube a k x k grid of patches; the corners are
/// where the rays from the centre through the grid's points (equal angles) meet the surface.
Grids closed_grids(const TriangleMesh& mesh, const AutoLayoutOptions& options, AutoLayout& out) {
  const CubeFrame frame = cube_frame(mesh);
  auto surface = std::make_shared<const SurfaceDistance>(mesh);
  char text[400];
  std::snprintf(text, sizeof text,
                "a closed surface: split along the edges of a cube about its centre (%.6g, "
                "%.6g, %.6g), its axes the principal directions; 6 faces of k x k patches",
                frame.centre.x(), frame.centre.y(), frame.centre.z());
  out.cut = text;
  Grids grids;
  for (int k = 1; 6 * k * k <= options.max_patches; ++k) grids.sizes.push_back({k, k, 6 * k * k});
  grids.layout = [frame, surface](int k, int) {
    PatchLayout layout;
    std::map<std::array<int, 3>, int> index;
    const auto corner = [&](std::array<int, 3> at) {
      const auto found = index.find(at);
      if (found != index.end()) return found->second;
      Vec3 direction = Vec3::Zero();
      for (int axis = 0; axis < 3; ++axis) {
        const double t = 2.0 * at[axis] / k - 1;
        direction += std::tan(kPi / 4 * t) * frame.extent[axis] * frame.axes.col(axis);
      }
      const std::optional<Vec3> hit = surface->first_hit(frame.centre, direction);
      if (!hit)
        throw Infeasible("layout",
                         "a ray from the closed surface's centre misses it (the "
                         "mesh has a gap)");
      LayoutCorner c;
      c.point = *hit;
      layout.corners.push_back(c);
      return index[at] = static_cast<int>(layout.corners.size()) - 1;
    };
    for (int axis = 0; axis < 3; ++axis)
      for (int sign : {1, -1}) {
        // On the face whose outward normal is sign * axis, (u, v) with u x v outward.
        int u = (axis + 1) % 3, v = (axis + 2) % 3;
        if (sign < 0) std::swap(u, v);
        for (int j = 0; j < k; ++j)
          for (int i = 0; i < k; ++i) {
            std::array<int, 4> quad{};
            const std::array<std::pair<int, int>, 4> steps{
                {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}}};
            for (int q = 0; q < 4; ++q) {
              std::array<int, 3> at{};
              at[axis] = sign > 0 ? k : 0;
              at[u] = steps[q].first, at[v] = steps[q].second;
              quad[q] = corner(at);
            }
            layout.patches.push_back({"", quad});
          }
      }
    return layout;
  };
  return grids;
}

}  // namespace

AutoLayout auto_layout(const TriangleMesh& mesh, const TargetPatchOptions& patch_options,
                       const AutoLayoutOptions& options, const Progress& progress) {
  const Surface surface = classify(mesh);
  progress.report("layout: square map", 0);
  AutoLayout out;
  out.surface = surface_name(surface);
  const Grids grids = surface == Surface::Disk   ? disk_grids(mesh, options, out)
                      : surface == Surface::Ring ? ring_grids(mesh, options, out)
                                                 : closed_grids(mesh, options, out);
  if (grids.sizes.empty())
    throw InvalidInput("max_patches", surface == Surface::Ring
                                          ? "a ring needs at least 3 patches (columns round it)"
                                          : "a closed surface needs at least 6 patches (the faces "
                                            "of a cube)");
  std::vector<PatchLayout> layouts;
  bool chosen = false;
  size_t checked = 0;
  const auto check = [&](size_t t) {
    AutoLayoutTrial& trial = out.trials[t];
    progress.report(
        "layout: check " + std::to_string(trial.columns) + " x " + std::to_string(trial.rows),
        0.5 + 0.5 * static_cast<double>(++checked) / out.trials.size());
    const auto start = std::chrono::steady_clock::now();
    LayoutResult result = cut_layout(mesh, layouts[t], patch_options, progress.checker());
    trial.checked = true;
    trial.coverage = result.coverage();
    for (const LayoutPatch& p : result.patches) {
      if (!p.problem && p.target) continue;
      if (trial.failing++ == 0)
        trial.first_problem = p.name + ": " + (p.problem ? p.problem->what() : "not cut");
    }
    trial.seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const bool better =
        !chosen || trial.coverage > out.result.coverage() + 1e-12 ||
        (trial.coverage > out.result.coverage() - 1e-12 && trial.patches < out.patches);
    if (better) {
      out.result = std::move(result);
      out.columns = trial.columns, out.rows = trial.rows, out.patches = trial.patches;
      chosen = true;
    }
    return trial.coverage >= options.coverage_goal;
  };
  // Fewest patches first, each grid cut with its patches' corners checked only: an upper bound
  // of its coverage at a fraction of the full checks' cost (coverability and smoothing of every
  // patch). A grid whose bound reaches the goal is checked in full; the first that covers the
  // goal is kept.
  bool reached = false;
  for (size_t t = 0; t < grids.sizes.size() && !reached; ++t) {
    const auto [columns, rows, patches] = grids.sizes[t];
    progress.report("layout: cut " + std::to_string(columns) + " x " + std::to_string(rows),
                    static_cast<double>(t) / grids.sizes.size());
    const auto start = std::chrono::steady_clock::now();
    PatchLayout layout = grids.layout(columns, rows);
    const LayoutResult cut =
        cut_layout(mesh, layout, patch_options, progress.checker(), LayoutChecks::CutOnly);
    AutoLayoutTrial trial;
    trial.columns = columns, trial.rows = rows, trial.patches = patches;
    trial.cut_coverage = cut.coverage();
    trial.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out.trials.push_back(trial);
    layouts.push_back(std::move(layout));
    if (trial.cut_coverage >= options.coverage_goal) reached = check(t);
  }
  // No grid reached the goal: the largest bounds checked until none left is above the best
  // coverage found.
  if (!reached) {
    std::vector<size_t> order(out.trials.size());
    std::iota(order.begin(), order.end(), size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) {
      return out.trials[x].cut_coverage > out.trials[y].cut_coverage;
    });
    for (size_t t : order) {
      if (out.trials[t].checked) continue;
      if (chosen && out.trials[t].cut_coverage <= out.result.coverage() + 1e-12) break;
      check(t);
    }
  }
  progress.report("layout", 1.0);
  return out;
}

}  // namespace gridshell
