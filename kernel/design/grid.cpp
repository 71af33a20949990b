// SPDX-License-Identifier: GPL-3.0-or-later
// The grid: members on both patches and their crossings (paper 4.1, 4.4, 4.5).
//
// Inner members are refined on the exact distances: the member's start u1 is kept; its end u2
// is moved (from the value read off the sampled cladding function) to the root of
//   phi(u2) = d_surface(p(u1), q(u2)) - |p̄(u1) q̄(u2)|
// by safeguarded secant/bisection on one distance field from p(u1), so that criterion (i) holds
// to the tolerance asked for, not only to the map's resolution. That field is a complete one (with
// windows, for distances to boundary points and the path): the batch propagation it gets is
// faster than the window-ordered one that could stop once the faces around the second boundary
// are final, since little of the patch lies beyond that boundary.
#include "gridshell/design/grid.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <unordered_map>

#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"
#include "gridshell/mesh/mesh_topology.h"

namespace gridshell {
namespace {

int zero_count(const SurfacePoint& p) {
  return (p.barycentric[0] == 0.0) + (p.barycentric[1] == 0.0) + (p.barycentric[2] == 0.0);
}

// Faces that contain a surface point (1 inside a face, 2 on an interior edge, the fan at a vertex).
// Weights below 1e-10 count as zero: a path running along a line of edges (regular grids on
// developable surfaces) passes vertices with weights of 1e-15 instead of exact zeros, and its
// segments would otherwise belong to no common face.
std::vector<int> faces_containing(const TriangleMesh& mesh, const MeshTopology& topology,
                                  SurfacePoint p) {
  for (int i = 0; i < 3; ++i)
    if (p.barycentric[i] < 1e-10) p.barycentric[i] = 0.0;
  const int zeros = zero_count(p);
  if (zeros >= 2) {
    for (int i = 0; i < 3; ++i)
      if (p.barycentric[i] != 0.0) return topology.vertex_faces[mesh.faces()[p.face][i]];
  }
  std::vector<int> faces{p.face};
  if (zeros == 1) {
    int k = 0;
    while (p.barycentric[k] != 0.0) ++k;
    const int neighbour = topology.face_neighbors[p.face][(k + 1) % 3];
    if (neighbour >= 0) faces.push_back(neighbour);
  }
  return faces;
}

struct Segment {
  int member = 0;
  Vec3 a, b;
  double s0 = 0;  // arc length at a
};

// 2D coordinates of a point in the plane of face f.
struct FaceFrame {
  Vec3 origin, e1, e2;
  Vec2 operator()(const Vec3& p) const {
    const Vec3 d = p - origin;
    return Vec2(d.dot(e1), d.dot(e2));
  }
};

FaceFrame frame_of(const TriangleMesh& mesh, int f) {
  const Face& t = mesh.faces()[f];
  FaceFrame frame;
  frame.origin = mesh.vertices()[t[0]];
  frame.e1 = (mesh.vertices()[t[1]] - frame.origin).normalized();
  const Vec3 n = frame.e1.cross(mesh.vertices()[t[2]] - frame.origin).normalized();
  frame.e2 = n.cross(frame.e1);
  return frame;
}

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Intersection parameters (t on ab, s on cd) of two 2D segments, if they intersect within
// [-eps, 1+eps]; parallel segments give none.
bool intersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d, double eps, double& t,
               double& s) {
  const Vec2 r = b - a, q = d - c;
  const double denom = cross2(r, q);
  const double scale = r.norm() * q.norm();
  if (std::abs(denom) <= 1e-14 * scale) return false;
  t = cross2(c - a, q) / denom;
  s = cross2(c - a, r) / denom;
  return t >= -eps && t <= 1 + eps && s >= -eps && s <= 1 + eps;
}

std::vector<SurfacePoint> chain_path(const TriangleMesh& mesh, std::vector<int> chain,
                                     bool reverse) {
  if (reverse) std::reverse(chain.begin(), chain.end());
  std::vector<SurfacePoint> path;
  for (int v : chain) path.push_back(SurfacePoint::at_vertex(mesh, v));
  return path;
}

std::string member_name(Family family, int index) {
  return std::string(family == Family::G ? "g" : "h") + std::to_string(index);
}

// Refines u2 so that surface and planar lengths agree: the root of phi in [lo, hi], searched by
// widening a bracket around u2 (steps of 0.005, doubled), then Illinois regula falsi. Returns
// nothing if no sign change lies within [lo, hi].
std::optional<double> refine_end(const DistanceField& field, const TriangleMesh& mesh,
                                 const std::vector<int>& second_boundary, const PlanarPatch& planar,
                                 Family family, double u1, double u2, double tolerance,
                                 double lo_limit, double hi_limit) {
  const Vec2 start = planar_boundary_point(planar, family, 0, u1);
  auto phi = [&](double t) {
    const double surface = field.distance_to(point_on_chain(mesh, second_boundary, t));
    const double flat = (planar_boundary_point(planar, family, 1, t) - start).norm();
    return surface - flat;
  };
  double f2 = phi(u2);
  const double scale = (planar_boundary_point(planar, family, 1, u2) - start).norm();
  if (std::abs(f2) <= tolerance * scale) return u2;
  // Bracket a sign change around u2, widening step by step.
  double lo = u2, hi = u2, flo = f2, fhi = f2;
  bool bracketed = false;
  for (double step = 0.005; !bracketed; step *= 2) {
    const double a = std::max(lo_limit, u2 - step), b = std::min(hi_limit, u2 + step);
    const double fa = phi(a), fb = phi(b);
    if ((fa < 0) != (f2 < 0)) {
      lo = a, flo = fa, hi = u2, fhi = f2;
      bracketed = true;
    } else if ((fb < 0) != (f2 < 0)) {
      lo = u2, flo = f2, hi = b, fhi = fb;
      bracketed = true;
    }
    if (a == lo_limit && b == hi_limit) break;
  }
  if (!bracketed) return std::nullopt;
  // Illinois-modified regula falsi with bisection fallback: superlinear and always bracketed.
  int side = 0;
  for (int iteration = 0; iteration < 200; ++iteration) {
    double mid = (lo * fhi - hi * flo) / (fhi - flo);
    if (!(mid > lo && mid < hi)) mid = 0.5 * (lo + hi);
    const double fm = phi(mid);
    if (std::abs(fm) <= tolerance * scale || hi - lo < 1e-15) return mid;
    if ((fm < 0) == (flo < 0)) {
      lo = mid, flo = fm;
      if (side == -1) fhi *= 0.5;
      side = -1;
    } else {
      hi = mid, fhi = fm;
      if (side == 1) flo *= 0.5;
      side = 1;
    }
  }
  return 0.5 * (lo + hi);
}

// Half-width, in u2, of the piece of the opposite boundary where a member's end is searched
// first (with goal pruning). The refined ends of the examples' members lie within 2.8e-3 of the
// cladding function's u2 (p95 1e-3); the bracket search's first two steps stay inside.
constexpr double kEndWindow = 0.01;
constexpr double kEndLimit = 1e-9;  // member ends stay this far inside (0, 1)

// Options of a member's solve: exact only where its end can be, the piece [lo, hi] of the
// opposite boundary, for distances up to the longest planar length there (the planar length is
// convex in u2 along a straight planar side, so it is largest at an end of the piece), plus the
// length tolerance the root may be off by.
SolveOptions end_goal(const TriangleMesh& mesh, const std::vector<int>& second,
                      const PlanarPatch& planar, Family family, double u1, double lo, double hi,
                      double tolerance) {
  std::vector<Vec3> points{point_on_chain(mesh, second, lo).position(mesh)};
  const double total = chain_length(mesh, second);
  double s = 0;
  for (size_t k = 0; k + 1 < second.size(); ++k) {
    s += (mesh.vertices()[second[k + 1]] - mesh.vertices()[second[k]]).norm();
    const double t = total > 0 ? s / total : 0;
    if (t > lo && t < hi) points.push_back(mesh.vertices()[second[k + 1]]);
  }
  points.push_back(point_on_chain(mesh, second, hi).position(mesh));
  Eigen::AlignedBox3d box;
  for (const Vec3& p : points) box.extend(p);
  SolveOptions options;
  options.goal.center = box.center();
  double radius = 0;
  for (const Vec3& p : points) radius = std::max(radius, (p - options.goal.center).norm());
  options.goal.radius = radius * (1 + 1e-12);
  const Vec2 start = planar_boundary_point(planar, family, 0, u1);
  const double longest = std::max((planar_boundary_point(planar, family, 1, lo) - start).norm(),
                                  (planar_boundary_point(planar, family, 1, hi) - start).norm());
  options.goal.bound = longest * (1 + 2 * tolerance) + 1e-9 * longest;
  return options;
}

/// Admission of member solves by estimated memory (GridOptions::member_memory): a solve waits
/// while the ones in flight and its own estimate exceed the budget (one always runs). The
/// estimate is twice the peak of the family's last finished solve (members of a family grow or
/// shrink gradually across the patch; neighbours differ by up to 1.7x on the 59k double vaults,
/// and a neighbour still in flight has not reported yet), before the first a bound from the
/// patch size.
class MemberMemoryGate {
 public:
  MemberMemoryGate(std::size_t budget, std::size_t first_estimate)
      : budget_(budget), last_{0, 0}, first_(first_estimate) {}
  /// Blocks until the solve may start (polling `progress` for cancellation); returns its estimate.
  std::size_t enter(int family, const Progress& progress) {
    std::unique_lock lock(mutex_);
    const std::size_t estimate = last_[family] > 0 ? 2 * last_[family] : first_;
    if (budget_ == 0) return 0;
    while (in_flight_ > 0 && in_flight_ + estimate > budget_) {
      changed_.wait_for(lock, std::chrono::milliseconds(20));
      progress.check();
    }
    in_flight_ += estimate;
    return estimate;
  }
  void leave(int family, std::size_t estimate, std::size_t used) {
    {
      std::lock_guard lock(mutex_);
      in_flight_ -= estimate;
      last_[family] = std::max<std::size_t>(used, 1);
    }
    changed_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::size_t budget_, in_flight_ = 0;
  std::array<std::size_t, 2> last_;
  std::size_t first_;
};

Infeasible no_end(Family family, int index, double u1) {
  std::ostringstream msg;
  msg << "member " << member_name(family, index) << " (u1 = " << u1
      << "): no end point on the opposite boundary has equal surface and planar length "
         "(criterion i)";
  return Infeasible(family == Family::G ? "options.members_u" : "options.members_v", msg.str(),
                    family == Family::G ? Reason::GMembersDoNotFit : Reason::HMembersDoNotFit);
}

}  // namespace

MemberMemo::Key MemberMemo::key(Family family, const MemberPosition& position,
                                const PlanarPatch& planar, double length_tolerance,
                                bool goal_pruning) {
  Key key;
  key.family = static_cast<int>(family);
  std::array<double, 12> values{position.u1, position.u2, length_tolerance,
                                goal_pruning ? 1.0 : 0.0};
  for (int c = 0; c < 4; ++c) {
    values[4 + 2 * c] = planar.corners[c].x();
    values[5 + 2 * c] = planar.corners[c].y();
  }
  std::memcpy(key.bits.data(), values.data(), sizeof values);
  return key;
}

std::size_t MemberMemo::member_bytes(const Member& member) {
  return sizeof(Member) + 64 + member.surface_path.capacity() * sizeof(SurfacePoint) +
         member.surface.capacity() * sizeof(Vec3);
}

std::optional<Member> MemberMemo::find(const Key& key) const {
  std::lock_guard lock(mutex_);
  const auto it = members_.find(key);
  if (it == members_.end()) return std::nullopt;
  ++hits_;
  return it->second;
}

void MemberMemo::insert(const Key& key, const Member& member) {
  const std::size_t bytes = member_bytes(member);
  std::lock_guard lock(mutex_);
  if (bytes > max_bytes_ || members_.count(key)) return;
  members_.emplace(key, member);
  order_.push_back(key);
  bytes_ += bytes;
  while (bytes_ > max_bytes_ && !order_.empty()) {
    const auto it = members_.find(order_.front());
    bytes_ -= member_bytes(it->second);
    members_.erase(it);
    order_.pop_front();
  }
}

std::size_t MemberMemo::bytes() const {
  std::lock_guard lock(mutex_);
  return bytes_;
}

std::size_t MemberMemo::size() const {
  std::lock_guard lock(mutex_);
  return members_.size();
}

std::uint64_t MemberMemo::hits() const {
  std::lock_guard lock(mutex_);
  return hits_;
}

Grid build_grid(const Patch& patch, const GeodesicSolver& solver, const PlanarPatch& planar,
                const std::vector<MemberPosition>& g_members,
                const std::vector<MemberPosition>& h_members, const GridOptions& options,
                const Progress& progress, MemberMemo* memo) {
  const TriangleMesh& mesh = patch.mesh;
  const MeshTopology& topology = mesh.topology();
  Grid grid;
  const std::array<const std::vector<MemberPosition>*, 2> positions{&g_members, &h_members};
  const std::array<std::vector<Member>*, 2> families{&grid.g, &grid.h};
  const std::array<double, 4> sides = side_lengths(patch);
  const auto& c = planar.corners;

  // Boundary members (paper 4.1: the patch boundaries are members of both families).
  auto boundary_member = [&](Family family, int index, double u, int side, bool reverse,
                             const Vec2& a, const Vec2& b) {
    Member m;
    m.family = family;
    m.index = index;
    m.boundary = true;
    m.u_start = m.u_end = u;
    m.surface_path = chain_path(mesh, patch.sides[side], reverse);
    for (const SurfacePoint& p : m.surface_path) m.surface.push_back(p.position(mesh));
    m.planar = {a, b};
    m.length = sides[side];
    m.planar_length = (b - a).norm();
    return m;
  };
  for (int f = 0; f < 2; ++f) {
    const auto& list = *positions[f];
    for (size_t k = 0; k < list.size(); ++k)
      if (!(list[k].u1 > 0 && list[k].u1 < 1 && list[k].u2 > 0 && list[k].u2 < 1) ||
          (k > 0 && !(list[k].u1 > list[k - 1].u1 && list[k].u2 > list[k - 1].u2)))
        throw InvalidInput(f ? "h_members" : "g_members",
                           "positions must be inside (0,1) and strictly increasing");
    families[f]->resize(list.size() + 2);
  }
  // g0: c0 -> c3 (side 3 reversed), g_last: c1 -> c2 (side 1); h0: c1 -> c0 (side 0 reversed),
  // h_last: c2 -> c3 (side 2).
  grid.g.front() = boundary_member(Family::G, 0, 0.0, 3, true, c[0], c[3]);
  grid.g.back() =
      boundary_member(Family::G, static_cast<int>(grid.g.size()) - 1, 1.0, 1, false, c[1], c[2]);
  grid.h.front() = boundary_member(Family::H, 0, 0.0, 0, true, c[1], c[0]);
  grid.h.back() =
      boundary_member(Family::H, static_cast<int>(grid.h.size()) - 1, 1.0, 2, false, c[2], c[3]);

  // Inner members, in parallel (each writes its own slot: deterministic for any thread count).
  // Jobs alternate between the families, so that under the memory gate a cheap member of one
  // family can run beside an expensive one of the other.
  std::vector<std::pair<int, int>> jobs;  // (family, position index)
  for (size_t k = 0; k < std::max(g_members.size(), h_members.size()); ++k)
    for (int f = 0; f < 2; ++f)
      if (k < positions[f]->size()) jobs.push_back({f, static_cast<int>(k)});
  // Before a family's first solve: 150 windows of 56 bytes per vertex (the largest member solve
  // of the 58653-vertex double vault peaks at 10 KB per vertex, the windows it no longer needs
  // dropped as it goes: geodesic_fast.cpp, "Compaction").
  MemberMemoryGate gate(options.member_memory,
                        std::size_t{8400} * static_cast<std::size_t>(mesh.vertex_count()));
  const std::array<std::vector<int>, 2> first{family_boundary(patch, Family::G, 0),
                                              family_boundary(patch, Family::H, 0)};
  const std::array<std::vector<int>, 2> second{family_boundary(patch, Family::G, 1),
                                               family_boundary(patch, Family::H, 1)};
  std::atomic<int> complete_solves{0};
  ParallelOptions parallel;
  parallel.threads = options.threads;
  // Progress as members finish (7 s without a report at 59k vertices before).
  parallel.stage = "grid: members";
  parallel_for(
      jobs.size(),
      [&](std::size_t job, const Progress& inner) {
        const auto [f, k] = jobs[job];
        const Family family = static_cast<Family>(f);
        const MemberPosition& pos = (*positions[f])[k];
        std::optional<MemberMemo::Key> key;
        if (memo) {
          key =
              MemberMemo::key(family, pos, planar, options.length_tolerance, options.goal_pruning);
          if (std::optional<Member> known = memo->find(*key)) {
            known->index = k + 1;  // the same member may have another rank in another design
            (*families[f])[k + 1] = std::move(*known);
            return;
          }
        }
        Member m;
        m.family = family;
        m.index = k + 1;
        m.u_start = pos.u1;
        std::size_t used = 0;
        const std::size_t estimate = gate.enter(f, inner);
        struct Leave {
          MemberMemoryGate& gate;
          int family;
          std::size_t estimate;
          const std::size_t& used;
          ~Leave() { gate.leave(family, estimate, used); }
        } leave{gate, f, estimate, used};
        const SurfacePoint start = point_on_chain(mesh, first[f], pos.u1);
        // First a solve that is exact only near the expected end (goal pruning, about a third of
        // the work); if the end is not within that piece of the boundary, a complete one.
        const double window = options.goal_pruning ? kEndWindow : 1.0;
        const double lo = std::max(kEndLimit, pos.u2 - window);
        const double hi = std::min(1 - kEndLimit, pos.u2 + window);
        DistanceField field = options.goal_pruning
                                  ? solver.solve(start,
                                                 end_goal(mesh, second[f], planar, family, pos.u1,
                                                          lo, hi, options.length_tolerance),
                                                 inner)
                                  : solver.solve(start, inner);
        std::optional<double> end = refine_end(field, mesh, second[f], planar, family, pos.u1,
                                               pos.u2, options.length_tolerance, lo, hi);
        if (!end && options.goal_pruning) {
          ++complete_solves;
          field = solver.solve(start, inner);
          end = refine_end(field, mesh, second[f], planar, family, pos.u1, pos.u2,
                           options.length_tolerance, kEndLimit, 1 - kEndLimit);
        }
        if (!end) throw no_end(family, m.index, pos.u1);
        m.u_end = *end;
        used = field.peak_memory_bytes();
        m.surface_path = field.path_to(point_on_chain(mesh, second[f], m.u_end));
        for (const SurfacePoint& p : m.surface_path) m.surface.push_back(p.position(mesh));
        m.length = path_length(mesh, m.surface_path);
        m.planar = {planar_boundary_point(planar, family, 0, m.u_start),
                    planar_boundary_point(planar, family, 1, m.u_end)};
        m.planar_length = (m.planar[1] - m.planar[0]).norm();
        if (memo) memo->insert(*key, m);
        (*families[f])[k + 1] = std::move(m);
      },
      progress, parallel);
  grid.complete_member_solves = complete_solves.load();
  progress.report("grid: members", 1.0);

  // Crossings. Boundary crossings lie at member ends and follow from the parameters.
  const int ng = static_cast<int>(grid.g.size()), nh = static_cast<int>(grid.h.size());
  std::map<std::pair<int, int>, Crossing> crossings;
  for (int i = 0; i < ng; ++i) {
    const Member& g = grid.g[i];
    for (int j : {0, nh - 1}) {
      const Member& h = grid.h[j];
      Crossing x;
      x.g = i, x.h = j, x.on_boundary = true;
      if (j == 0) {  // at g's start, on h0 = c1 -> c0
        x.surface_point = g.surface.front();
        x.planar_point = g.planar[0];
        x.s_g = x.s_bar_g = 0;
        x.s_h = (1 - g.u_start) * h.length;
        x.s_bar_h = (1 - g.u_start) * h.planar_length;
      } else {  // at g's end, on h_last = c2 -> c3
        x.surface_point = g.surface.back();
        x.planar_point = g.planar[1];
        x.s_g = g.length, x.s_bar_g = g.planar_length;
        x.s_h = (1 - g.u_end) * h.length;
        x.s_bar_h = (1 - g.u_end) * h.planar_length;
      }
      crossings[{i, j}] = x;
    }
  }
  for (int j = 1; j + 1 < nh; ++j) {
    const Member& h = grid.h[j];
    for (int i : {0, ng - 1}) {
      const Member& g = grid.g[i];
      Crossing x;
      x.g = i, x.h = j, x.on_boundary = true;
      if (i == 0) {  // at h's end, on g0 = c0 -> c3
        x.surface_point = h.surface.back();
        x.planar_point = h.planar[1];
        x.s_h = h.length, x.s_bar_h = h.planar_length;
        x.s_g = h.u_end * g.length, x.s_bar_g = h.u_end * g.planar_length;
      } else {  // at h's start, on g_last = c1 -> c2
        x.surface_point = h.surface.front();
        x.planar_point = h.planar[0];
        x.s_h = x.s_bar_h = 0;
        x.s_g = h.u_start * g.length, x.s_bar_g = h.u_start * g.planar_length;
      }
      crossings[{i, j}] = x;
    }
  }

  // Inner crossings on the surface: segments of g and h meeting inside a common face.
  std::unordered_map<int, std::vector<Segment>> h_segments;  // face -> segments of inner h
  for (int j = 1; j + 1 < nh; ++j) {
    const Member& h = grid.h[j];
    double s = 0;
    for (size_t k = 0; k + 1 < h.surface_path.size(); ++k) {
      const Segment seg{j, h.surface[k], h.surface[k + 1], s};
      std::vector<int> fa = faces_containing(mesh, topology, h.surface_path[k]);
      std::vector<int> fb = faces_containing(mesh, topology, h.surface_path[k + 1]);
      for (int f : fa)
        if (std::find(fb.begin(), fb.end(), f) != fb.end()) h_segments[f].push_back(seg);
      s += (h.surface[k + 1] - h.surface[k]).norm();
    }
  }
  std::map<std::pair<int, int>, std::vector<std::array<double, 2>>> found;  // (g,h) -> (s_g, s_h)
  // Paths through a common vertex cross there, but their segments around it may lie in
  // different faces of the fan: match vertex path points directly.
  auto vertex_of = [&](SurfacePoint p) {
    for (int i = 0; i < 3; ++i)
      if (p.barycentric[i] < 1e-10) p.barycentric[i] = 0.0;
    if (zero_count(p) < 2) return -1;
    for (int i = 0; i < 3; ++i)
      if (p.barycentric[i] != 0.0) return mesh.faces()[p.face][i];
    return -1;
  };
  std::unordered_map<int, std::vector<std::pair<int, double>>> h_vertices;  // vertex -> (h, s_h)
  for (int j = 1; j + 1 < nh; ++j) {
    const Member& h = grid.h[j];
    double s = 0;
    for (size_t k = 0; k < h.surface_path.size(); ++k) {
      if (k > 0) s += (h.surface[k] - h.surface[k - 1]).norm();
      const int v = vertex_of(h.surface_path[k]);
      if (v >= 0) h_vertices[v].push_back({j, s});
    }
  }
  for (int i = 1; i + 1 < ng; ++i) {
    const Member& g = grid.g[i];
    double s = 0;
    for (size_t k = 0; k < g.surface_path.size(); ++k) {
      if (k > 0) s += (g.surface[k] - g.surface[k - 1]).norm();
      const int v = vertex_of(g.surface_path[k]);
      if (v < 0) continue;
      auto it = h_vertices.find(v);
      if (it == h_vertices.end()) continue;
      for (const auto& [j, s_h] : it->second) found[{i, j}].push_back({s, s_h});
    }
  }
  std::unordered_map<int, FaceFrame> frames;
  for (int i = 1; i + 1 < ng; ++i) {
    const Member& g = grid.g[i];
    double s = 0;
    for (size_t k = 0; k + 1 < g.surface_path.size(); ++k) {
      const double length = (g.surface[k + 1] - g.surface[k]).norm();
      std::vector<int> fa = faces_containing(mesh, topology, g.surface_path[k]);
      std::vector<int> fb = faces_containing(mesh, topology, g.surface_path[k + 1]);
      for (int f : fa) {
        if (std::find(fb.begin(), fb.end(), f) == fb.end()) continue;
        auto it = h_segments.find(f);
        if (it == h_segments.end()) continue;
        auto frame_it = frames.find(f);
        if (frame_it == frames.end()) frame_it = frames.emplace(f, frame_of(mesh, f)).first;
        const FaceFrame& frame = frame_it->second;
        for (const Segment& seg : it->second) {
          double t = 0, u = 0;
          if (!intersect(frame(g.surface[k]), frame(g.surface[k + 1]), frame(seg.a), frame(seg.b),
                         1e-9, t, u))
            continue;
          t = std::clamp(t, 0.0, 1.0), u = std::clamp(u, 0.0, 1.0);
          found[{i, seg.member}].push_back({s + t * length, seg.s0 + u * (seg.b - seg.a).norm()});
        }
      }
      s += length;
    }
  }
  for (int i = 1; i + 1 < ng; ++i)
    for (int j = 1; j + 1 < nh; ++j) {
      const Member& g = grid.g[i];
      const Member& h = grid.h[j];
      auto hits = found[{i, j}];
      // One geometric crossing can be found in several faces (on an edge or at a vertex).
      std::sort(hits.begin(), hits.end());
      std::vector<std::array<double, 2>> distinct;
      const double merge = 1e-7 * std::max(g.length, h.length);
      for (const auto& hit : hits)
        if (distinct.empty() || std::abs(hit[0] - distinct.back()[0]) > merge ||
            std::abs(hit[1] - distinct.back()[1]) > merge)
          distinct.push_back(hit);
      if (distinct.size() != 1) {
        std::ostringstream msg;
        msg << "members g" << i << " and h" << j << " cross " << distinct.size()
            << " times on the surface instead of once (criterion iii)";
        throw Infeasible("options.members_u", msg.str());
      }
      double t = 0, u = 0;
      if (!intersect(g.planar[0], g.planar[1], h.planar[0], h.planar[1], 1e-12, t, u)) {
        std::ostringstream msg;
        msg << "members g" << i << " and h" << j
            << " do not cross in the planar grid (criterion iii)";
        throw Infeasible("options.members_u", msg.str());
      }
      Crossing x;
      x.g = i, x.h = j;
      x.s_g = distinct[0][0], x.s_h = distinct[0][1];
      x.s_bar_g = t * g.planar_length, x.s_bar_h = u * h.planar_length;
      x.planar_point = g.planar[0] + t * (g.planar[1] - g.planar[0]);
      // Surface point: interpolate along g's polyline at arc length s_g.
      double acc = 0;
      x.surface_point = g.surface.back();
      for (size_t k = 0; k + 1 < g.surface.size(); ++k) {
        const double l = (g.surface[k + 1] - g.surface[k]).norm();
        if (acc + l >= x.s_g) {
          const double w = l > 0 ? (x.s_g - acc) / l : 0;
          x.surface_point = g.surface[k] + w * (g.surface[k + 1] - g.surface[k]);
          break;
        }
        acc += l;
      }
      crossings[{i, j}] = x;
    }
  // Criterion (iii) in the plane: no two members of one family cross.
  for (const auto* family : {&grid.g, &grid.h})
    for (size_t a = 0; a < family->size(); ++a)
      for (size_t b = a + 1; b < family->size(); ++b) {
        double t = 0, u = 0;
        const Member& m = (*family)[a];
        const Member& n = (*family)[b];
        if (intersect(m.planar[0], m.planar[1], n.planar[0], n.planar[1], -1e-9, t, u)) {
          std::ostringstream msg;
          msg << "members " << member_name(m.family, m.index) << " and "
              << member_name(n.family, n.index)
              << " of the same family cross in the planar grid (criterion iii)";
          throw Infeasible(
              m.family == Family::G ? "options.members_u" : "options.members_v", msg.str(),
              m.family == Family::G ? Reason::GMembersDoNotFit : Reason::HMembersDoNotFit);
        }
      }
  for (auto& [key, x] : crossings) grid.crossings.push_back(x);
  progress.report("grid: crossings", 1.0);
  return grid;
}

}  // namespace gridshell
