// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — exact polyhedral geodesics by window propagation (GeodesicMethod::Fast).
//
// Algorithm
// ---------
// A continuous-Dijkstra window propagation: Mitchell, Mount & Papadimitriou, "The discrete
// geodesic problem", SIAM J. Comput. 16(4), 1987, in the implementation style of Surazhsky,
// Surazhsky, Kirsanov, Gortler & Hoppe, "Fast exact and approximate geodesics on meshes",
// SIGGRAPH 2005 (windows on edges, trimmed against each other), plus the vertex-distance filter
// of Xin & Wang, "Improving Chen and Han's algorithm on the discrete geodesic problem" (ICH),
// ACM TOG 28(4), 2009, and a barrier form of Chen & Han's "one angle, one split" rule (SoCG
// 1990) that Qin et al.'s VTP (ACM TOG 35(4), 2016) also builds on.
//
// A window w lives on a half-edge AB of a face F and represents the straight unfolded paths from
// a (pseudo-)source image I, at distance sigma from the source, through the interval [b0, b1] of
// AB into F. It is stored in the frame of the half-edge: A = (0,0), B = (L,0), the opposite
// corner C = (cx, cy) with cy > 0, the image I = (sx, sy) with sy <= 0. Every point p of the
// interval is reached by a real surface path of length sigma + |I p|. Propagating w across F
// gives at most two children, on CA and on BC (split by the ray I->C).
//
// Events are processed in increasing order of the window's minimum distance
// key(w) = sigma + dist(I, [b0,b1]) (a radix heap). Children are never closer than their parent
// (their points are reached through the parent's interval) and trimming only raises keys, so
// popped keys are non-decreasing: when the event of a vertex pops, its distance is final.
// Saddle vertices (angle sum > 2 pi) and reflex boundary vertices (angle sum > pi) become
// pseudo-sources at that moment and emit windows onto the opposite edges of their faces (shortest
// paths can only bend there); the true source emits the same way, onto all of them.
//
// Vertex distances d(V) are upper bounds realised by real paths at every moment (set from
// windows that see V, or from a pseudo-source along an edge), as early as possible: when a window
// that sees the corner opposite its edge is created.
//
// Pruning rules. Each removes only paths that are longer than another real path to the same
// point (for E and B by more than a safety margin) or that can be shortened (S); such a path is
// not a shortest path, nor is any extension of it, so no shortest path is ever removed and all
// results, including distances to arbitrary surface points, stay exact:
//
//  (M) MMP trimming: each edge keeps a list of its windows (from both sides). A new window is
//      compared with the overlapping ones: where an old window gives a shorter distance the new
//      one is cut away (possibly splitting it), where the new one is shorter at an end of an old
//      one, the old one is shortened. The crossover points are the roots of
//      sigma1 + |I1 p| = sigma2 + |I2 p| on the edge line (a quadratic after squaring twice;
//      signs are decided by direct evaluation between the roots). This keeps the number of
//      windows created close to the size of the final structure.
//  (E) endpoint vertices (ICH filter rules 1-2, strengthened to trimming). For a vertex A at
//      t = 0 of the window's edge, h(t) = |I - (t,0)| - t is non-increasing, so the set where
//      d(A) + |A p| < sigma + |I p| is an interval starting at A: it is cut away (closed form
//      t = (|I|^2 - K^2) / (2 (K + sx)), K = d(A) - sigma); the window dies if it covers all of
//      [b0,b1]. Symmetrically for B at t = L.
//  (B) barrier, a generalisation of Chen-Han's "one angle one split": for the corner C of F let
//      w1 be the window seeing C through AB with the smallest sigma1 + |I1 C|, crossing AB at
//      X1. For any other window w2 with sigma2 + |I2 C| > sigma1 + |I1 C|, a path of w2 that
//      crosses the segment X1-C at a point P is dominated there: sigma1 + |I1 P| =
//      d1(C) - |P C| < sigma2 + |I2 C| - |P C| <= sigma2 + |I2 P| (triangle inequality).
//      So w2's paths must not cross X1-C: its left child keeps only entries left of X1, its
//      right child only entries right of X1 (if C lies outside w2's cone one child is cut or
//      vanishes). When w2 covers C this is exactly "one angle one split".
//  (S) saddle cone: a shortest path bends at a vertex only with angles >= pi on both sides (at
//      a boundary vertex: an angle >= pi on the surface side), else it could be shortened
//      around the vertex. Only subpaths of shortest paths matter, so a path through a
//      pseudo-source u arrives along a shortest path to u, and (all shortest paths to u being
//      equally long) leaves at an angle in [pi, total - pi] from the incoming direction of any
//      one of them. u emits windows only into that cone, widened by 1e-6 rad on each side (the
//      incoming direction is known to ~1e-12 rad). Measured: -10% instructions on waves-bump,
//      -7% on torus-wide (saddles), nothing on convex surfaces.
//  An exact form of ICH's third rule (the opposite corner dominating a whole window) and
//  re-filtering at pop time were tried; once M was in place they (almost) never fired and were
//  dropped.
//
// Rounding: rules E and B use an absolute margin (1e-10 x bounding-box diagonal), far above the
// rounding error of unfolded coordinates, so a window realising a shortest path is never
// pruned; M cuts at the computed crossover, which moves the boundary between two windows by a
// rounding-level amount (distances change at that level only). Visibility of a corner accepts
// crossings up to 1e-9 x edge length outside the interval: the accepted straight segment differs
// from the real path through the interval end by a second-order amount (~1e-18 relative), and it
// keeps vertices that lie exactly on a cone boundary (rays through flat vertices of regular grids)
// from slipping between two windows.
//
// What a solve keeps (SolveOptions). By default all windows are kept with their parent and
// pseudo-source and indexed by the face they propagate into: the distance to a point q of face f
// is the minimum of sigma + |I q| over the windows entering f whose cone contains q, of
// d(V) + |V q| over f's corners and of |S q| if the source lies in f; the path is traced back
// through the window's ancestors (one point per edge crossing), then through pseudo-source
// vertices to the source. Without keep_windows the windows live in per-thread scratch memory
// reused by the next solve, and only the windows entering the targets' faces are collected to
// evaluate the targets. Every solve without stop_at_targets propagates in batches per half-edge
// instead of one window at a time in key order as described above (see "Batch propagation"
// below: 2.5-4x faster, the same rules except M and E, equal up to rounding). With stop_at_targets
// the propagation stops once the popped key exceeds an upper bound of the distance anywhere in the
// targets' closed faces (max corner distance + longest edge): every window or vertex event that
// could still lower a distance there has a key below that distance, so it has already been
// processed (its children exist).
//
// Goal pruning (SolveOptions::goal: a ball B and a bound U). A window is not created when
// sigma + dist(I, [b0,b1]) + dist([b0,b1], B) > U + margin: every path through its interval is
// at least that long before it reaches B (the straight 3D distance is a lower bound of any
// surface path). For a point x in B with d(x) <= U, every point y of its shortest path has
// d(y) + |y x| = d(x) <= U, so every window and pseudo-source on that path survives and x's
// distance and path are the same as in a complete solve; all rules still compare with real
// paths only, so what is left are upper bounds. This is A* with the Euclidean distance as the
// heuristic, applied to windows. Grid members use it (design/grid.cpp): the ball around the piece
// of the opposite boundary where the member's end is searched, the bound its longest planar
// length; measured on the examples' warm redesigns: <one third of the windows of a complete field.
// Such a solve that keeps windows also drops, from 2 M windows on, those no answer in the ball can
// use (see "Compaction" at Propagator::compact).
#include "geodesic_fast.h"

#include <sys/mman.h>  // madvise (huge pages for window storage)

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_topology.h"

namespace gridshell::geodesic_detail {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;
/// Corner visibility / query tolerance, relative to the edge length.
constexpr double kVisibilityTolerance = 1e-9;
/// Pruning margin, relative to the bounding-box diagonal.
constexpr double kMarginRelative = 1e-10;
/// A vertex is a pseudo-source if its angle sum exceeds 2*pi (interior) or pi (boundary) by this.
constexpr double kAngleTolerance = 1e-12;
/// Rule S widens the cone of directions a pseudo-source emits into by this angle (radians) on
/// each side, far above the rounding error of the incoming direction (~1e-12 rad).
constexpr double kConeTolerance = 1e-6;
/// Path points on an edge this close to an end (relative to the edge length) are that vertex.
constexpr double kSnapRelative = 1e-12;
/// Key width of the event queue's buckets, relative to the mean edge length.
constexpr double kBucketWidth = 0.002;
/// Meshes with at least this many vertices reserve kUpFrontPerVertex windows per vertex at the
/// start of a solve (see Propagator::init).
constexpr int kUpFrontVertices = 8192;
constexpr std::size_t kUpFrontPerVertex = 400;
/// A new window may be split by older, better windows into at most this many pieces.
constexpr int kMaxPieces = 4;
/// A goal-pruned solve that keeps windows compacts them once it holds this many (see
/// Propagator::compact), and again whenever they have doubled since.
constexpr std::size_t kCompactWindows = std::size_t{2} << 20;

// Tables, not conditionals: the branches were mispredicted often enough to show in profiles.
constexpr int kNext3[3] = {1, 2, 0};
constexpr int kPrev3[3] = {2, 0, 1};
inline int next3(int i) { return kNext3[i]; }
inline int prev3(int i) { return kPrev3[i]; }

/// Number of slots in [base, base + n) with lo < x (they are sorted by lo), without
/// data-dependent branches (binary searches over these short lists were a main source of
/// branch mispredictions).
template <class Slot>
inline int count_below(const Slot* base, int n, double x) {
  const Slot* b = base;
  while (n > 1) {
    const int half = n >> 1;
    b = b[half - 1].lo < x ? b + half : b;
    n -= half;
  }
  return static_cast<int>(b - base) + (n == 1 && b->lo < x);
}
inline double hyp(double x, double y) { return std::sqrt(x * x + y * y); }

/// Geometry of half-edge h = 3 f + e (edge e of face f, from v[e] to v[e+1]) in its own frame:
/// A = v[e] at the origin, B = v[e+1] = (len, 0), the opposite corner C = v[e+2] = (cx, cy) with
/// cy > 0. A window on h propagates into face f; its children lie on the twins of f's other two
/// half-edges, "left" = 3 f + e+2 (C -> A) and "right" = 3 f + e+1 (B -> C).
struct HalfEdge {
  double len, cx, cy;
  double u1x, u1y;       ///< unit vector C -> B (the right child's frame axis)
  double u2x, u2y;       ///< unit vector A -> C (the left child's frame axis)
  double ox, oy;         ///< the twin face's opposite corner in this frame (oy <= 0)
  int twin;              ///< the same edge in the neighbouring face, -1 on the boundary
  int edge;              ///< undirected edge id
  int va, vb, vc;        ///< vertices A, B, C
  std::int8_t flip;      ///< 1 if it runs against its undirected edge's orientation
  std::int8_t has_exit;  ///< a window on it can have children (a neighbour across CA or BC)
  /// The exits, copied here so that a propagation reads one record: the twins of C -> A (left)
  /// and B -> C (right), -1 on the boundary, and their lengths.
  int left_twin, right_twin;
  double left_len, right_len;
};

/// A window (see the file comment). 56 bytes: a complete field on a 60k-vertex mesh holds 10-18 M
/// of them, and the parent, the emitting vertex and the exit share one int (64 bytes before).
struct Window {
  double b0, b1;  ///< interval on the edge, 0 <= b0 < b1 <= L (b0 == b1: emptied)
  double sx, sy;  ///< source image, sy <= 0
  double sigma;   ///< distance from the source to the image
  int he;         ///< half-edge it lies on; it propagates into face he / 3
  /// parent * 4 + exit for a window propagated from `parent` (exit 1: on the parent's right exit
  /// B->C, 2: its left exit C->A); -2 - root for a window emitted by the pseudo-source vertex
  /// `root` (-1 for the true source).
  int link;
  int next;  ///< batch propagation: the next window pending on the same half-edge

  int parent() const { return link >= 0 ? link >> 2 : -1; }
  int exit() const { return link >= 0 ? link & 3 : 0; }
  int root() const { return link < 0 ? -2 - link : -1; }
  static int child_link(int parent, int exit) { return parent * 4 + exit; }
  static int root_link(int root) { return -2 - root; }
};
static_assert(sizeof(Window) == 56);
/// Windows are numbered in an int with two bits for the exit (Window::link).
constexpr std::size_t kMaxWindows = std::size_t{1} << 29;

/// Allocator of window storage: blocks of 4 MiB and more are 2 MiB aligned and marked for
/// transparent huge pages (where the kernel leaves them to madvise, as on our CI machines).
/// A complete field on a 60k-vertex mesh holds 10-18 M windows (0.56-1.0 GB): in 4 KiB pages that
/// is up to 300k page faults, which cost more than the propagation itself on a virtual machine.
template <class T>
struct LargePageAllocator {
  using value_type = T;
  static constexpr std::size_t kHuge = std::size_t{2} << 20;
  static constexpr std::size_t kThreshold = std::size_t{4} << 20;
  LargePageAllocator() = default;
  template <class U>
  LargePageAllocator(const LargePageAllocator<U>&) {}
  static std::size_t rounded(std::size_t bytes) { return (bytes + kHuge - 1) & ~(kHuge - 1); }
  T* allocate(std::size_t n) {
    if (n > (std::numeric_limits<std::size_t>::max() - kHuge) / sizeof(T)) throw std::bad_alloc();
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kThreshold) return static_cast<T*>(::operator new(bytes));
    void* p = std::aligned_alloc(kHuge, rounded(bytes));
    if (!p) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    ::madvise(p, rounded(bytes), MADV_HUGEPAGE);  // advice only: failure changes nothing
#endif
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (n * sizeof(T) < kThreshold)
      ::operator delete(p);
    else
      std::free(p);
  }
  template <class U>
  bool operator==(const LargePageAllocator<U>&) const {
    return true;
  }
};
using WindowVector = std::vector<Window, LargePageAllocator<Window>>;

/// Everything a solve shares; immutable after construction.
struct FastMesh {
  TriangleMesh mesh;
  std::vector<HalfEdge> half;  ///< 3 per face
  std::vector<int> vf_start;   ///< CSR: half-edges 3 f + i with v[i] = v, per vertex v
  std::vector<int> vf_half;
  std::vector<char> pseudo;  ///< saddle or reflex boundary vertex
  /// Fans of pseudo-source vertices in rotation order (rule S): fan_start[v] .. fan_start[v+1]
  /// index fan_half (half-edge 3 f + i starting at v) and fan_angle[fan_start[v] + v + k], the
  /// angle at v from the fan's first edge to the start of slot k; fan_angle[fan_start[v + 1] + v]
  /// is v's total angle. Empty for other vertices (and for fans that could not be walked).
  std::vector<int> fan_start;
  std::vector<int> fan_half;
  std::vector<double> fan_angle;
  std::vector<char> fan_closed;  ///< interior vertex (closed fan) vs boundary (open fan)
  int edge_count = 0;
  double margin = 0;
  double bucket_width = 1;  ///< key width of the event queue's buckets
  /// Windows of the latest solve (+ slack), to reserve the next one's storage at once.
  mutable std::atomic<std::size_t> window_hint{0};
  /// Window storage of complete fields that have been destroyed, for the next solves: fresh
  /// memory costs a page fault per 4 KiB (as much as the solve itself on a 4k-vertex mesh).
  mutable std::mutex pool_mutex;
  mutable std::vector<WindowVector> pool;
};

std::shared_ptr<const FastMesh> build_fast_mesh(const TriangleMesh& mesh) {
  auto m = std::make_shared<FastMesh>();
  m->mesh = mesh;
  const MeshTopology& top = mesh.topology();
  const int nv = mesh.vertex_count(), nf = mesh.face_count();
  m->half.resize(3 * static_cast<size_t>(nf));
  std::vector<double> angle(nv, 0.0);
  for (int f = 0; f < nf; ++f) {
    const Face& t = mesh.faces()[f];
    for (int e = 0; e < 3; ++e) {
      HalfEdge& h = m->half[3 * f + e];
      h.va = t[e];
      h.vb = t[next3(e)];
      h.vc = t[prev3(e)];
      h.twin = -1;
      const int n = top.face_neighbors[f][e];
      if (n >= 0) {
        const Face& nt = mesh.faces()[n];
        for (int k = 0; k < 3; ++k)
          if (nt[k] == t[next3(e)] && nt[next3(k)] == t[e]) h.twin = 3 * n + k;
        if (h.twin < 0) throw std::logic_error("geodesic solver: inconsistent face orientation");
      }
      const Vec3& a = mesh.vertices()[h.va];
      const Vec3& b = mesh.vertices()[h.vb];
      const Vec3& c = mesh.vertices()[h.vc];
      const Vec3 ab = b - a;
      const double len = ab.norm();
      const Vec3 ex = ab / len;
      h.len = len;
      h.cx = (c - a).dot(ex);
      h.cy = (c - a).cross(ex).norm();
      if (!(len > 0) || !(h.cy > 0) || !std::isfinite(h.cy)) {
        std::ostringstream msg;
        msg << "degenerate (zero area): the geodesic solver needs triangles with area";
        throw InvalidInput("mesh.faces[" + std::to_string(f) + "]", msg.str());
      }
      const double ac = (c - a).norm(), bc = (c - b).norm();
      h.u2x = h.cx / ac;
      h.u2y = h.cy / ac;
      h.u1x = (len - h.cx) / bc;
      h.u1y = -h.cy / bc;
      angle[t[e]] += std::atan2((c - a).cross(ab).norm(), (c - a).dot(ab));
    }
  }
  for (int f = 0; f < nf; ++f)
    for (int e = 0; e < 3; ++e) {
      HalfEdge& h = m->half[3 * f + e];
      h.ox = h.oy = 0;
      h.has_exit = m->half[3 * f + prev3(e)].twin >= 0 || m->half[3 * f + next3(e)].twin >= 0;
      h.left_twin = m->half[3 * f + prev3(e)].twin;
      h.right_twin = m->half[3 * f + next3(e)].twin;
      h.left_len = m->half[3 * f + prev3(e)].len;
      h.right_len = m->half[3 * f + next3(e)].len;
      if (h.twin < 0) continue;
      const Vec3& a = mesh.vertices()[h.va];
      const Vec3 ex = (mesh.vertices()[h.vb] - a) / h.len;
      const Vec3 d = mesh.vertices()[m->half[h.twin].vc] - a;
      h.ox = d.dot(ex);
      h.oy = -d.cross(ex).norm();
    }
  m->vf_start.assign(nv + 1, 0);
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) ++m->vf_start[mesh.faces()[f][i] + 1];
  for (int v = 0; v < nv; ++v) m->vf_start[v + 1] += m->vf_start[v];
  m->vf_half.resize(3 * static_cast<size_t>(nf));
  {
    std::vector<int> fill(m->vf_start.begin(), m->vf_start.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int i = 0; i < 3; ++i) m->vf_half[fill[mesh.faces()[f][i]]++] = 3 * f + i;
  }
  m->pseudo.assign(nv, 0);
  for (int v = 0; v < nv; ++v) {
    const double flat = top.is_boundary_vertex[v] ? kPi : 2 * kPi;
    m->pseudo[v] = angle[v] > flat + kAngleTolerance;
  }
  // Fans of the pseudo-source vertices, in rotation order. From half-edge 3 f + i (v = v[i]),
  // the slot spans the directions v -> v[i+1] to v -> v[i+2]; the next face around v lies across
  // f's edge v[i+2] -> v, whose twin starts the next slot. A boundary fan starts at the slot
  // whose edge v -> v[i+1] is a boundary edge. Every vertex takes count + 1 angle entries (one
  // for a vertex without a fan), so that v's angles start at fan_start[v] + v.
  m->fan_start.assign(nv + 1, 0);
  m->fan_closed.assign(nv, 0);
  std::vector<int> fan;
  for (int v = 0; v < nv; ++v) {
    m->fan_start[v + 1] = m->fan_start[v];
    const int first = m->vf_start[v], count = m->vf_start[v + 1] - first;
    fan.clear();
    bool closed = false, boundary = false;
    if (m->pseudo[v] && count > 0) {
      int start = m->vf_half[first];
      for (int k = first; k < first + count; ++k)
        if (m->half[m->vf_half[k]].twin < 0) {
          start = m->vf_half[k];
          boundary = true;
        }
      int h = start;
      while (static_cast<int>(fan.size()) < count) {
        fan.push_back(h);
        const int across = m->half[h - h % 3 + prev3(h % 3)].twin;
        if (across < 0) break;
        h = across;
        if (h == start) {
          closed = true;
          break;
        }
      }
    }
    if (fan.empty() || static_cast<int>(fan.size()) != count || closed == boundary) {
      m->fan_angle.push_back(0.0);  // no fan: rule S does not apply at v
      continue;
    }
    double phi = 0;
    for (int k : fan) {
      m->fan_half.push_back(k);
      m->fan_angle.push_back(phi);
      phi += std::atan2(m->half[k].cy, m->half[k].cx);
    }
    m->fan_angle.push_back(phi);
    m->fan_start[v + 1] = m->fan_start[v] + count;
    m->fan_closed[v] = closed;
  }
  m->edge_count = 0;
  std::vector<int> edge_of(3 * static_cast<size_t>(nf), -1);
  for (int h = 0; h < 3 * nf; ++h) {
    if (edge_of[h] >= 0) continue;
    const int id = m->edge_count++;
    edge_of[h] = id;
    m->half[h].edge = id;
    m->half[h].flip = 0;
    const int t = m->half[h].twin;
    if (t >= 0) {
      edge_of[t] = id;
      m->half[t].edge = id;
      m->half[t].flip = 1;
    }
  }
  double total_length = 0;
  for (const HalfEdge& h : m->half) total_length += h.len;
  m->bucket_width = kBucketWidth * (nf > 0 ? total_length / (3.0 * nf) : 1.0);
  const double diagonal = bounding_box_size(mesh).norm();
  m->margin = kMarginRelative * (diagonal > 0 ? diagonal : 1.0);
  return m;
}

/// Best window seeing the corner opposite a half-edge (for the barrier rule).
struct CornerRecord {
  double d = kInf;  ///< sigma + |I C|
  double x = 0;     ///< crossing of I->C with the edge
};

// Vertex provenance codes: >= 0 window id that sees the vertex; -1 straight from the source;
// <= -2: straight along an edge from pseudo-source vertex (-2 - code).
constexpr int kFromSource = -1;
/// A goal-pruned solve kept no path to this vertex (neither a corner of a face near the goal nor
/// a pseudo-source, so its window may have been dropped by Propagator::compact): path_to cannot
/// pass through it.
constexpr int kPathNotKept = std::numeric_limits<int>::min();

class FastField final : public DistanceField::Impl {
 public:
  ~FastField() override;
  std::shared_ptr<const FastMesh> m;
  WindowVector windows;
  std::vector<int> provenance;  ///< per vertex, see the codes above
  std::vector<int> face_start;  ///< CSR: live windows per face
  std::vector<int> face_window;
  std::array<int, 2> source_faces = {-1, -1};  ///< faces whose closure holds the source
  bool has_windows = true;

  double distance_to(const SurfacePoint& target) const override;
  std::vector<SurfacePoint> path_to(const SurfacePoint& target) const override;
  std::size_t memory_bytes() const override {
    return windows.size() * sizeof(Window) +
           (face_start.size() + face_window.size() + provenance.size()) * sizeof(int);
  }
  std::size_t peak_memory_bytes() const override {
    return memory_bytes() + (std::max(peak_windows, windows.size()) - windows.size()) *
                                (sizeof(Window) + sizeof(int));  // + Propagator::compact's table
  }
  std::size_t peak_windows = 0;  ///< windows before the last compaction (Propagator::compact)

  void build_index();

 private:
  struct Best {
    double d = kInf;
    int kind = -1;  ///< 0 window, 1 vertex, 2 source
    int index = -1;
    double qx = 0, qy = 0;  ///< target in the window's frame
  };
  Best locate(const SurfacePoint& q) const;
  SurfacePoint vertex_point(int v) const;
  SurfacePoint edge_point(int he, double x) const;
};

/// The faces whose closure holds a (normalised) surface point, with the point's weights in each;
/// a vertex point gets only its own face (its distance is the vertex's).
struct PointFaces {
  int count = 0;
  std::array<int, 2> face{-1, -1};
  std::array<Vec3, 2> weights;
  int vertex = -1;
};

PointFaces point_faces(const FastMesh& m, const SurfacePoint& q) {
  PointFaces out;
  const int zeros = zero_weight_count(q);
  if (zeros == 2) {
    out.vertex = q.vertex(m.mesh);
    return out;
  }
  out.count = 1;
  out.face[0] = q.face;
  out.weights[0] = q.barycentric;
  if (zeros == 1) {
    int e = 0;
    for (int i = 0; i < 3; ++i)
      if (q.barycentric[i] == 0.0) e = next3(i);  // the edge opposite the zero weight
    const int twin = m.half[3 * q.face + e].twin;
    if (twin >= 0) {
      const int n = twin / 3, k = twin % 3;
      out.face[1] = n;
      out.weights[1] = Vec3::Zero();
      out.weights[1][k] = q.barycentric[next3(e)];
      out.weights[1][next3(k)] = q.barycentric[e];
      out.count = 2;
    }
  }
  return out;
}

/// The distance to q offered by window w (entering q's face f, q in the frame of w's edge), or
/// +inf if q lies outside w's cone.
inline double window_distance(const Window& w, const HalfEdge& h, double px, double py) {
  const double x = py <= 0 ? px : w.sx + (px - w.sx) * (-w.sy) / (py - w.sy);
  const double tol = kVisibilityTolerance * h.len;
  if (x < w.b0 - tol || x > w.b1 + tol) return kInf;
  return w.sigma + hyp(px - w.sx, py - w.sy);
}

/// q (weights w in face f) in the frame of each of f's half-edges.
inline void point_in_frames(const FastMesh& m, int f, const Vec3& w, std::array<double, 3>& qx,
                            std::array<double, 3>& qy) {
  for (int e = 0; e < 3; ++e) {
    const HalfEdge& h = m.half[3 * f + e];
    qx[e] = w[next3(e)] * h.len + w[prev3(e)] * h.cx;
    qy[e] = w[prev3(e)] * h.cy;
  }
}

// ---------------------------------------------------------------------------------------------
// Propagation

/// Monotone priority queue of events (window or vertex ids) by key. Keys are bucketed by a fixed
/// width (a fraction of the mean edge length); a bucket is sorted once, when it becomes the
/// current one, and then popped in order, so pops come out in exact key order while pushes cost
/// O(1) (children's keys exceed their parent's by about an edge crossing, so nearly all pushes
/// land in later buckets; one into the current bucket is inserted in order). Keys pushed below
/// the last key popped (rounding-level, children are never closer than their parent) are
/// clamped to it: they only reorder events equal up to rounding.
class EventQueue {
 public:
  struct Entry {
    double key;
    int id;
  };
  void reset(double width) {
    inverse_width_ = 1.0 / width;
    heads_.clear();
    pool_.clear();
    current_.clear();
    bucket_ = 0;
    last_ = 0;
    size_ = 0;
  }
  bool empty() const { return size_ == 0; }
  void push(double key, int id) {
    if (!(key > last_)) key = last_;
    ++size_;
    const double scaled = key * inverse_width_;
    const std::size_t b =
        scaled < 1e15 ? static_cast<std::size_t>(scaled) : std::numeric_limits<std::size_t>::max();
    if (b <= bucket_) {  // into the current run, kept sorted by descending key
      auto it = std::upper_bound(current_.begin(), current_.end(), key,
                                 [](double k, const Entry& e) { return k > e.key; });
      current_.insert(it, Entry{key, id});
      return;
    }
    if (b >= heads_.size()) {
      if (b > (std::size_t{1} << 26)) {  // absurd spread of keys: keep them in the last bucket
        overflow_.push_back(Entry{key, id});
        return;
      }
      heads_.resize(std::max(b + 1, 2 * heads_.size()), -1);
    }
    pool_.push_back(Node{key, id, heads_[b]});
    heads_[b] = static_cast<int>(pool_.size()) - 1;
  }
  Entry pop() {
    while (current_.empty()) advance();
    const Entry e = current_.back();
    current_.pop_back();
    last_ = e.key;
    --size_;
    return e;
  }

 private:
  struct Node {
    double key;
    int id, next;
  };
  void advance() {
    ++bucket_;
    if (bucket_ >= heads_.size()) {  // only the overflow is left
      current_.swap(overflow_);
      std::sort(current_.begin(), current_.end(),
                [](const Entry& a, const Entry& b) { return a.key > b.key; });
      return;
    }
    for (int k = heads_[bucket_]; k >= 0; k = pool_[k].next)
      current_.push_back(Entry{pool_[k].key, pool_[k].id});
    heads_[bucket_] = -1;
    std::sort(current_.begin(), current_.end(),
              [](const Entry& a, const Entry& b) { return a.key > b.key; });
  }
  double inverse_width_ = 1;
  std::vector<int> heads_;  ///< per bucket: the latest pushed node, -1 if empty
  std::vector<Node> pool_;
  std::vector<Entry> current_;  ///< the current bucket, sorted by descending key
  std::vector<Entry> overflow_;
  std::size_t bucket_ = 0;
  double last_ = 0;
  std::size_t size_ = 0;
};

/// One entry of an edge's window list: the window's interval in the orientation of the
/// undirected edge (so windows from both sides compare directly). Lists are sorted by lo.
struct EdgeSlot {
  double lo, hi;
  int id;
  int flip;  ///< the window's half-edge runs against the edge (it fills the padding)
};

struct EdgeList {
  int start = 0, count = 0, capacity = 0;
};

/// Splits [lo, hi] into at most three sub-intervals on which d1(t) - d2(t) keeps its sign, where
/// d_i(t) = s_i + sqrt((t - x_i)^2 + yy_i) (yy_i = y_i^2). cuts[0..n] bound the n sub-intervals;
/// sign[k] > 0 where d1 > d2 (window 2 better), < 0 where d1 < d2, 0 where equal.
/// d1 = d2 means |P I1| - |P I2| = A = s2 - s1 for P = (t, 0): squaring twice gives
/// a t^2 + b t + c = 0 with a = alpha^2 - 4 A^2, whose discriminant factors as
/// 16 A^2 ((alpha x2 + beta)^2 + yy2 a) (no cancellation when A -> 0). Spurious roots introduced
/// by squaring only add cuts; the signs come from evaluating d1 - d2 at each sub-interval's
/// midpoint.
int compare_windows(double x1, double yy1, double s1, double x2, double yy2, double s2, double lo,
                    double hi, double* cuts, int* sign) {
  double roots[2];
  int nr = 0;
  const double A = s2 - s1;
  const double alpha = 2 * (x2 - x1);
  const double beta = x1 * x1 - x2 * x2 + yy1 - yy2 - A * A;
  const double a = alpha * alpha - 4 * A * A;
  const double b = 2 * alpha * beta + 8 * A * A * x2;
  const double c = beta * beta - 4 * A * A * (x2 * x2 + yy2);
  if (std::abs(a) <= 1e-14 * (alpha * alpha + 4 * A * A)) {
    if (b != 0) roots[nr++] = -c / b;
  } else {
    const double g = (alpha * x2 + beta) * (alpha * x2 + beta) + yy2 * a;
    if (g >= 0) {
      const double root_disc = 4 * std::abs(A) * std::sqrt(g);
      const double q = -0.5 * (b + std::copysign(root_disc, b));
      if (q != 0) {
        roots[nr++] = q / a;
        roots[nr++] = c / q;
      } else {
        roots[nr++] = 0;
      }
    }
  }
  int n = 0;
  cuts[0] = lo;
  if (nr == 2 && roots[1] < roots[0]) std::swap(roots[0], roots[1]);
  for (int i = 0; i < nr; ++i)
    if (roots[i] > cuts[n] && roots[i] < hi) cuts[++n] = roots[i];
  cuts[++n] = hi;
  int m = 0;  // signs at midpoints; neighbours with equal signs merged
  for (int k = 0; k < n; ++k) {
    const double t = 0.5 * (cuts[k] + cuts[k + 1]);
    const double d =
        (s1 - s2) + (std::sqrt((t - x1) * (t - x1) + yy1) - std::sqrt((t - x2) * (t - x2) + yy2));
    const int sg = d > 0 ? 1 : (d < 0 ? -1 : 0);
    if (m > 0 && sign[m - 1] == sg) {
      cuts[m] = cuts[k + 1];
    } else {
      sign[m] = sg;
      cuts[m] = cuts[k];
      cuts[m + 1] = cuts[k + 1];
      ++m;
    }
  }
  return m;
}

/// Batch propagation: the windows pending on a half-edge (a list through Window::next).
struct HalfEdgeState {
  int head = -1;    ///< first pending window, -1 if none
  char queued = 0;  ///< in the fifo
  char ready = 0;   ///< an end vertex has been popped: windows propagate on arrival
};

/// A window of the batch being propagated: its slot, the crossing x of I->C with the edge and
/// sigma + |I C| if it sees C (else negative).
struct BatchEntry {
  int id;
  double x, corner;
};

/// Per-thread scratch memory of a solve (reused by the next solve on the same thread, so that
/// repeated solves do not pay for fresh pages).
/// The goal ball's centre in cylinder coordinates about a half-edge's line: its projection
/// along A -> B (p) and its squared distance from the line (h2).
struct GoalCoordinates {
  double p, h2;
};

struct Scratch {
  std::vector<char> emitted;
  std::vector<CornerRecord> corner;
  std::vector<EdgeList> lists;  ///< per undirected edge: its windows, in slots
  std::vector<EdgeSlot> slots;
  WindowVector windows;  ///< the windows of a solve that does not keep them
  std::vector<char> target_face;
  std::vector<int> target_windows;
  EventQueue heap;
  // Batch propagation (see Propagator::run_batch).
  std::vector<HalfEdgeState> pending;  ///< per half-edge
  std::vector<int> fifo;               ///< half-edges whose pending windows are ready
  std::vector<char> inside;            ///< per vertex: popped
  std::vector<BatchEntry> batch;       ///< the list being propagated
  std::vector<int> free;               ///< recycled window slots
  WindowVector target_copies;          ///< windows that entered a target face
  std::vector<double> incoming;        ///< per vertex: rule S's incoming direction
  std::vector<GoalCoordinates> goal;   ///< per half-edge: the goal ball's centre (goal pruning)
  std::vector<char> keep_face;         ///< per face: meets the goal ball (compact keeps windows)
  std::vector<char> hold;              ///< per vertex: compact keeps its provenance
  std::vector<int> renumber;           ///< compact: per window, live flag then new slot
};

/// Returns the pages of `windows` from its size up to `touched` windows to the system (large
/// blocks only: those are page-aligned mappings of their own, see LargePageAllocator).
void release_pages(WindowVector& windows, std::size_t touched) {
  if (windows.capacity() * sizeof(Window) < LargePageAllocator<Window>::kThreshold) return;
  constexpr std::uintptr_t kPage = 4096;
  const auto base = reinterpret_cast<std::uintptr_t>(windows.data());
  const std::uintptr_t from = (base + windows.size() * sizeof(Window) + kPage - 1) & ~(kPage - 1);
  const std::uintptr_t to = (base + touched * sizeof(Window)) & ~(kPage - 1);
  if (to > from) madvise(reinterpret_cast<void*>(from), to - from, MADV_DONTNEED);
}

/// Scratch memory is kept for the next solve on the thread, unless it grew large (a big mesh).
void release_if_large(Scratch& scratch) {
  constexpr std::size_t kKeepBytes = std::size_t{64} << 20;
  if (scratch.slots.capacity() * sizeof(EdgeSlot) + scratch.lists.capacity() * sizeof(EdgeList) +
          scratch.corner.capacity() * sizeof(CornerRecord) +
          scratch.windows.capacity() * sizeof(Window) >
      kKeepBytes)
    scratch = Scratch{};
}

class Propagator {
 public:
  Propagator(const FastMesh& m, FastField& out, WindowVector& windows, const SolveOptions& options,
             const Progress& progress, Scratch& scratch)
      : m_(m),
        out_(out),
        options_(options),
        progress_(progress),
        windows_(windows),
        dist_(out.distances),
        prov_(out.provenance),
        emitted_(scratch.emitted),
        corner_(scratch.corner),
        lists_(scratch.lists),
        slots_(scratch.slots),
        target_face_(scratch.target_face),
        target_windows_(scratch.target_windows),
        heap_(scratch.heap),
        pending_(scratch.pending),
        fifo_(scratch.fifo),
        inside_(scratch.inside),
        batch_list_(scratch.batch),
        free_(scratch.free),
        target_copies_(scratch.target_copies),
        incoming_(scratch.incoming),
        goal_coordinates_(scratch.goal),
        keep_face_(scratch.keep_face),
        hold_(scratch.hold),
        renumber_(scratch.renumber),
        margin_(m.margin) {
    const int nv = m.mesh.vertex_count();
    dist_.assign(nv, kInf);
    prov_.assign(nv, kFromSource);
    emitted_.assign(nv, 0);
    corner_.assign(m.half.size(), CornerRecord{});
    heap_.reset(m.bucket_width);
    windows_.clear();
    // On a large mesh, room for every window up front: a growing std::vector copies its windows
    // into a buffer twice the size, so a 59k-vertex solve briefly held 1.5-3x its windows (design
    // peaks of 1.6-2.2 GB). Blocks this large are mapped by the allocator on demand: pages of the
    // reservation that are never written are never resident, so the bound costs address space
    // only. (A complete field at 60k vertices holds 170-300 windows per vertex; beyond the bound
    // the vector grows as before.)
    const std::size_t hint = m.window_hint.load(std::memory_order_relaxed);
    windows_.reserve(nv >= kUpFrontVertices ? std::max(hint, kUpFrontPerVertex * nv) : hint);
    target_windows_.clear();
    batch_ = !options.stop_at_targets;
    recycle_ = batch_ && !options.keep_windows;
    if (!batch_) {  // the edges' window lists of rule M
      lists_.assign(m.edge_count, EdgeList{});
      slots_.clear();
    } else {
      pending_.assign(m.half.size(), HalfEdgeState{});
      inside_.assign(nv, 0);
      fifo_.clear();
      free_.clear();
      target_copies_.clear();
      incoming_.assign(nv, -1.0);
      reemit_.clear();
    }
    goal_ = options.goal.bound < kInf;
    if (goal_) {
      goal_bound_ = options.goal.bound + margin_;
      goal_radius_ = options.goal.radius;
      const auto& P = m.mesh.vertices();
      goal_coordinates_.resize(m.half.size());
      for (std::size_t h = 0; h < m.half.size(); ++h) {
        const HalfEdge& e = m.half[h];
        const Vec3 d = options.goal.center - P[e.va];
        const double p = d.dot(P[e.vb] - P[e.va]) / e.len;
        goal_coordinates_[h] = {p, std::max(0.0, d.squaredNorm() - p * p)};
      }
      compact_ = batch_ && options.keep_windows;
      if (compact_) {
        // Faces that meet the ball (by their bounding sphere about the centroid: a superset) keep
        // their windows; their corners and the pseudo-sources keep the path to them.
        const int nf = static_cast<int>(m.half.size() / 3);
        keep_face_.assign(nf, 0);
        hold_.assign(m.pseudo.begin(), m.pseudo.end());
        const double reach = goal_radius_ + margin_;
        for (int f = 0; f < nf; ++f) {
          const Vec3& a = P[m.half[3 * f].va];
          const Vec3& b = P[m.half[3 * f].vb];
          const Vec3& c = P[m.half[3 * f].vc];
          const Vec3 centroid = (a + b + c) / 3;
          const double r =
              std::max({(a - centroid).norm(), (b - centroid).norm(), (c - centroid).norm()});
          if ((centroid - options.goal.center).norm() - r > reach) continue;
          keep_face_[f] = 1;
          for (int e = 0; e < 3; ++e) hold_[m.half[3 * f + e].va] = 1;
        }
        compact_at_ = kCompactWindows;
      }
    }
    // Windows entering the targets' faces are collected when the field keeps no index of them.
    track_targets_ = !options.targets.empty() && !options.keep_windows;
    if (track_targets_ || options.stop_at_targets) {
      target_face_.assign(m.half.size() / 3, 0);
      for (const SurfacePoint& t : options.targets) {
        const PointFaces pf = point_faces(m, t);
        for (int k = 0; k < pf.count; ++k) target_face_[pf.face[k]] = 1;
        if (pf.vertex >= 0) stop_vertices_.push_back(pf.vertex);
      }
      for (int f = 0; f < static_cast<int>(target_face_.size()); ++f)
        if (target_face_[f]) stop_faces_.push_back(f);
      // A vertex target's closed faces: its whole fan (distance_to / path_to near it).
      if (options.stop_at_targets)
        for (int v : stop_vertices_)
          for (int k = m.vf_start[v]; k < m.vf_start[v + 1]; ++k)
            stop_faces_.push_back(m.vf_half[k] / 3);
    }
  }

  void init(const SurfacePoint& s);
  void run();
  /// Goal-pruned solves that keep windows: drops the windows that no answer of the field can
  /// use, keeping the others in their order (see the comment at its definition).
  void compact();
  /// Target distances from the collected windows (solves that keep no windows).
  void evaluate_targets(const SurfacePoint& source);

 private:
  void relax(int v, double d, int provenance) {
    if (d < dist_[v]) {
      dist_[v] = d;
      prov_[v] = provenance;
      if (batch_) {
        if (!inside_[v])
          heap_.push(d, -1 - v);
        else if (m_.pseudo[v])
          reemit_.push_back(v);  // a pseudo-source improved after it emitted: emit again
      } else if (m_.pseudo[v] && !emitted_[v]) {
        heap_.push(d, -1 - v);
      }
    }
  }
  /// An end vertex of half-edge h has been popped: its windows propagate from now on.
  void make_ready(int h) {
    if (h < 0) return;
    HalfEdgeState& p = pending_[h];
    p.ready = 1;
    if (p.head >= 0 && !p.queued) {
      p.queued = 1;
      fifo_.push_back(h);
    }
  }
  void append_pending(const Window& w);
  /// Batch propagation's propagate(): the same children, written straight into pending lists.
  void propagate_batch(const Window& w, int id, double x, double corner);
  void push_child(int he, double len, double b0, double b1, double sx, double sy, double sigma,
                  int link);
  /// Goal pruning: true if no path through the window can reach the goal ball within the bound.
  bool beyond_goal(int he, double b0, double b1, double sx, double sy, double sigma) const {
    const double near = std::clamp(sx, b0, b1);
    const double reach = sigma + std::sqrt((near - sx) * (near - sx) + sy * sy);
    if (reach > goal_bound_) return true;
    const GoalCoordinates& g = goal_coordinates_[he];
    const double t = std::clamp(g.p, b0, b1);
    const double to_ball = std::sqrt((t - g.p) * (t - g.p) + g.h2) - goal_radius_;
    return to_ball > 0 && reach + to_ball > goal_bound_;
  }
  void process_list(int h);
  void edges_ready(int v);
  void drain();
  void run_batch();
  /// Upper bound on the distance anywhere in the faces the solve must finish (stop_at_targets).
  double stop_bound() const;
  double incoming_angle(int u) const;
  /// The direction, in u's fan coordinate, back along window w's straight path to u = C.
  double window_angle(int u, const Window& w) const;
  void emit_vertex(int u);
  void emit_window(int h, double b0, double b1, double sigma, int root);
  void emit_from_point(const Vec3& s, int face, int skip_edge);
  void insert(Window& w);
  bool trim_by_endpoints(Window& w, double length, double da, double db, double& f0,
                         double& f1) const;
  /// `corner`: sigma + |I C| if the caller has it, else negative.
  void propagate(const Window& w, int id, double corner = -1);
  /// The (at most two) children of w across its face, by rule B's barrier: calls
  /// emit(half-edge, its length, b0, b1, image x, image y, exit) for each non-empty one. x is the
  /// crossing of I->C with the edge, corner as for propagate().
  template <class Emit>
  void children(const Window& w, double x, double corner, Emit&& emit) const;
  /// Inserts into the edge's sorted list; `hint` is an index at or after the insertion position.
  void insert_slot(int edge, double lo, double hi, int id, int flip, int hint);

  const FastMesh& m_;
  FastField& out_;
  const SolveOptions& options_;
  const Progress& progress_;
  WindowVector& windows_;
  std::vector<double>& dist_;
  std::vector<int>& prov_;
  std::vector<char>& emitted_;
  std::vector<CornerRecord>& corner_;
  std::vector<EdgeList>& lists_;
  std::vector<EdgeSlot>& slots_;
  std::vector<char>& target_face_;
  std::vector<int>& target_windows_;
  EventQueue& heap_;
  std::vector<HalfEdgeState>& pending_;
  std::vector<int>& fifo_;
  std::vector<char>& inside_;
  std::vector<BatchEntry>& batch_list_;
  std::vector<int>& free_;
  WindowVector& target_copies_;
  std::vector<double>& incoming_;
  std::vector<int> reemit_;
  std::vector<GoalCoordinates>& goal_coordinates_;
  std::vector<char>& keep_face_;
  std::vector<char>& hold_;
  std::vector<int>& renumber_;
  const double margin_;
  bool goal_ = false;  ///< goal pruning (SolveOptions::goal)
  double goal_bound_ = kInf, goal_radius_ = 0;
  bool batch_ = false;    ///< batch propagation (see run_batch)
  bool recycle_ = false;  ///< batch propagation without keeping windows: slots are reused
  bool compact_ = false;  ///< goal-pruned batch solve keeping windows: see compact()
  std::size_t compact_at_ = 0;
  bool track_targets_ = false;
  std::vector<int> stop_faces_, stop_vertices_;
};

void Propagator::insert_slot(int edge, double lo, double hi, int id, int flip, int hint) {
  EdgeList& list = lists_[edge];
  if (list.count == list.capacity) {  // move the edge's list to the end of the arena, doubled
    const int capacity = list.capacity ? 2 * list.capacity : 4;
    const int start = static_cast<int>(slots_.size());
    slots_.resize(slots_.size() + capacity);
    std::copy_n(slots_.data() + list.start, list.count, slots_.data() + start);
    list.start = start;
    list.capacity = capacity;
  }
  EdgeSlot* base = slots_.data() + list.start;
  // Before the first slot with start > lo (the hint is past it: the new window's range).
  int k = std::min(hint, list.count);
  while (k > 0 && base[k - 1].lo > lo) --k;
  std::copy_backward(base + k, base + list.count, base + list.count + 1);
  base[k] = {lo, hi, id, flip};
  ++list.count;
}

bool Propagator::trim_by_endpoints(Window& w, double length, double da, double db, double& f0,
                                   double& f1) const {
  const double sx = w.sx, sy2 = w.sy * w.sy;
  if (da < kInf) {
    // h(t) = |I-(t,0)| - t is non-increasing: A dominates an initial part of the interval.
    if (f1 > da + w.b1 + margin_) return false;
    if (f0 > da + w.b0 + margin_) {
      const double k = da + margin_ - w.sigma;
      const double den = 2 * (k + sx);  // > 0 whenever h(t) = k has a solution
      if (den > 0) {
        const double t = (sx * sx + sy2 - k * k) / den;
        if (t > w.b0) {
          w.b0 = std::min(t, w.b1);
          f0 = w.sigma + std::sqrt((w.b0 - sx) * (w.b0 - sx) + sy2);
        }
      }
    }
  }
  if (db < kInf) {
    if (f0 > db + (length - w.b0) + margin_) return false;
    if (f1 > db + (length - w.b1) + margin_) {
      const double k = db + margin_ - w.sigma;
      const double sxr = length - sx;
      const double den = 2 * (k + sxr);
      if (den > 0) {
        const double t = length - (sxr * sxr + sy2 - k * k) / den;
        if (t < w.b1) {
          w.b1 = std::max(t, w.b0);
          f1 = w.sigma + std::sqrt((w.b1 - sx) * (w.b1 - sx) + sy2);
        }
      }
    }
  }
  return w.b1 > w.b0;
}

void Propagator::insert(Window& w) {
  const HalfEdge& h = m_.half[w.he];
  const double length = h.len;
  if (w.sy > 0) w.sy = 0;
  if (w.b0 < 0) w.b0 = 0;
  if (w.b1 > length) w.b1 = length;
  if (!(w.b1 > w.b0)) return;
  if (batch_) {
    append_pending(w);
    return;
  }
  if (goal_ && beyond_goal(w.he, w.b0, w.b1, w.sx, w.sy, w.sigma)) return;
  const double yy = w.sy * w.sy;
  double f0 = w.sigma + std::sqrt((w.b0 - w.sx) * (w.b0 - w.sx) + yy);
  double f1 = w.sigma + std::sqrt((w.b1 - w.sx) * (w.b1 - w.sx) + yy);
  if (!trim_by_endpoints(w, length, dist_[h.va], dist_[h.vb], f0, f1)) return;

  // Rule (M), Mitchell-Mount-Papadimitriou trimming: compare with the windows already on this
  // edge (either side). Where an old window is better the new one is cut away (it may split in
  // pieces); where the new one is better at an end of the old one, the old one is shortened.
  // Everything here is in the edge's own orientation; each edge keeps its windows sorted by
  // start (lists are long: ~50 windows on a busy edge of a 4k-vertex mesh, so a binary search
  // beats a scan), and they are disjoint except where a new window beat an old one in the
  // middle (the old one is not split): a comparison missed because of such an overlap only
  // prunes less, it never makes the result wrong.
  const bool flip = h.flip;
  const double nx = flip ? length - w.sx : w.sx;
  std::array<double, 2 * kMaxPieces> piece;
  int pieces = 1;
  piece[0] = flip ? length - w.b1 : w.b0;
  piece[1] = flip ? length - w.b0 : w.b1;
  EdgeList& list = lists_[h.edge];
  EdgeSlot* base = slots_.data() + list.start;
  // First slot that may overlap: by start, then back over long predecessors.
  int i = count_below(base, list.count, piece[0]);
  while (i > 0 && base[i - 1].hi > piece[0]) --i;
  while (i < list.count && pieces > 0 && base[i].lo < piece[2 * pieces - 1]) {
    double olo = base[i].lo, ohi = base[i].hi;
    if (ohi <= piece[0]) {
      ++i;
      continue;
    }
    Window& o = windows_[base[i].id];
    const bool oflip = base[i].flip;
    const double ox = oflip ? length - o.sx : o.sx, oyy = o.sy * o.sy;
    std::array<double, 2 * kMaxPieces> kept;
    int nk = 0;
    bool overflow = false;
    const auto keep = [&](double lo, double hi) {
      if (nk < kMaxPieces) {
        kept[2 * nk] = lo;
        kept[2 * nk + 1] = hi;
        ++nk;
      } else {
        overflow = true;
      }
    };
    for (int p = 0; p < pieces; ++p) {
      const double lo = std::max(piece[2 * p], olo), hi = std::min(piece[2 * p + 1], ohi);
      if (!(hi > lo)) {
        keep(piece[2 * p], piece[2 * p + 1]);
        continue;
      }
      double cuts[4];
      int sign[3];
      const int n = compare_windows(nx, yy, w.sigma, ox, oyy, o.sigma, lo, hi, cuts, sign);
      // The new window keeps the sub-intervals where it is strictly better.
      double cur = piece[2 * p];
      for (int k = 0; k < n; ++k) {
        if (sign[k] < 0) continue;
        if (cuts[k] > cur) keep(cur, cuts[k]);
        cur = cuts[k + 1];
      }
      if (piece[2 * p + 1] > cur) keep(cur, piece[2 * p + 1]);
      // The old window loses a prefix / suffix where the new one is strictly better.
      if (sign[0] < 0 && cuts[0] <= olo) olo = cuts[1];
      if (sign[n - 1] < 0 && cuts[n] >= ohi) ohi = cuts[n - 1];
    }
    if (overflow) {  // too fragmented: keep the new window whole (only less pruned)
      nk = 1;
      kept[0] = flip ? length - w.b1 : w.b0;
      kept[1] = flip ? length - w.b0 : w.b1;
    }
    pieces = nk;
    piece = kept;
    if (olo != base[i].lo || ohi != base[i].hi) {
      // Shrink the old window (never beyond what it covers: conversions round).
      const double b0 = oflip ? length - ohi : olo, b1 = oflip ? length - olo : ohi;
      o.b0 = std::max(o.b0, b0);
      o.b1 = std::min(o.b1, b1);
      if (!(o.b1 > o.b0) || !(ohi > olo)) {
        o.b1 = o.b0;  // emptied
        for (int k = i + 1; k < list.count; ++k) base[k - 1] = base[k];
        --list.count;
        continue;
      }
      base[i].lo = olo;
      base[i].hi = ohi;
    }
    ++i;
  }
  if (flip)  // back to the new window's frame
    for (int p = 0; p < pieces; ++p) {
      const double lo = piece[2 * p];
      piece[2 * p] = length - piece[2 * p + 1];
      piece[2 * p + 1] = length - lo;
    }

  const double cx = h.cx, cy = h.cy;
  const double tol = kVisibilityTolerance * length;
  const double x = (w.sx * cy - w.sy * cx) / (cy - w.sy);  // crossing of I->C with the edge
  double dc = -1;
  const int face = w.he / 3;
  for (int p = 0; p < pieces; ++p) {
    w.b0 = piece[2 * p];
    w.b1 = piece[2 * p + 1];
    if (!(w.b1 > w.b0)) continue;
    if (windows_.size() >= kMaxWindows) throw std::length_error("geodesic: too many windows");
    const int id = static_cast<int>(windows_.size());
    // Corner C visible through the window: early distance bound and barrier record.
    if (x >= w.b0 - tol && x <= w.b1 + tol) {
      if (dc < 0) dc = w.sigma + hyp(cx - w.sx, cy - w.sy);
      CornerRecord& rec = corner_[w.he];
      if (dc < rec.d) {
        rec.d = dc;
        rec.x = x;
      }
      relax(h.vc, dc, id);
    }
    windows_.push_back(w);
    insert_slot(h.edge, flip ? length - w.b1 : w.b0, flip ? length - w.b0 : w.b1, id, flip, i);
    ++i;
    if (track_targets_ && target_face_[face]) target_windows_.push_back(id);
    if (!h.has_exit) continue;  // no children: nothing to propagate
    double key = w.sigma - w.sy;
    if (w.sx < w.b0) key = w.sigma + std::sqrt((w.b0 - w.sx) * (w.b0 - w.sx) + yy);
    if (w.sx > w.b1) key = w.sigma + std::sqrt((w.b1 - w.sx) * (w.b1 - w.sx) + yy);
    heap_.push(key, id);
  }
}

void Propagator::propagate(const Window& w, int id, double corner) {
  const HalfEdge& h = m_.half[w.he];
  const double x = (w.sx * h.cy - w.sy * h.cx) / (h.cy - w.sy);
  children(w, x, corner,
           [&](int he, double, double b0, double b1, double sx, double sy, std::int8_t exit) {
             Window c;
             c.b0 = b0;
             c.b1 = b1;
             c.sx = sx;
             c.sy = sy;
             c.sigma = w.sigma;
             c.he = he;
             c.link = Window::child_link(id, exit);
             insert(c);
           });
}

/// The direction, as an angle in u's fan coordinate, in which the shortest path found to the
/// pseudo-source u arrives (pointing back along the path), or a negative value if unknown.
double Propagator::incoming_angle(int u) const {
  const int first = m_.fan_start[u], count = m_.fan_start[u + 1] - first;
  if (count == 0) return -1;
  const double* phi = m_.fan_angle.data() + first + u;
  const int* fan = m_.fan_half.data() + first;
  const int code = prov_[u];
  if (code == kPathNotKept) return batch_ ? incoming_[u] : -1;
  if (code >= 0) {
    // Batch propagation recycles windows: the angle was taken when the window set d(u).
    if (batch_) return incoming_[u];
    return window_angle(u, windows_[code]);
  }
  if (code <= -2) {  // straight along the edge u - p from pseudo-source vertex p
    for (int k = 0; k < count; ++k)
      if (m_.half[fan[k]].vb == -2 - code) return phi[k];
    if (m_.half[fan[count - 1]].vc == -2 - code) return phi[count];  // last edge of an open fan
    return -1;
  }
  return -1;  // straight from the source: no restriction
}

double Propagator::window_angle(int u, const Window& w) const {
  const int first = m_.fan_start[u], count = m_.fan_start[u + 1] - first;
  if (count == 0) return -1;
  const double* phi = m_.fan_angle.data() + first + u;
  const int* fan = m_.fan_half.data() + first;
  // A window on half-edge AB sees u = C: u's slot is the half-edge of the same face starting at
  // C (C -> A), which spans the directions from C->A to C->B.
  const HalfEdge& h = m_.half[w.he];
  const int slot_half = w.he - w.he % 3 + prev3(w.he % 3);
  for (int k = 0; k < count; ++k) {
    if (fan[k] != slot_half) continue;
    const double ax = -h.cx, ay = -h.cy;
    const double ix = w.sx - h.cx, iy = w.sy - h.cy;
    const double a = std::atan2(std::abs(ax * iy - ay * ix), ax * ix + ay * iy);
    return phi[k] + std::clamp(a, 0.0, phi[k + 1] - phi[k]);
  }
  return -1;
}

void Propagator::emit_window(int h, double b0, double b1, double sigma, int root) {
  const HalfEdge& g = m_.half[h];
  Window w;
  w.b0 = b0;
  w.b1 = b1;
  w.sx = g.ox;
  w.sy = g.oy;
  w.sigma = sigma;
  w.he = h;
  w.link = Window::root_link(root);
  insert(w);
}

void Propagator::emit_vertex(int u) {
  emitted_[u] = 1;
  const double du = dist_[u];
  for (int k = m_.vf_start[u]; k < m_.vf_start[u + 1]; ++k) {
    const HalfEdge& g = m_.half[m_.vf_half[k]];  // u -> v[i+1], C = v[i+2]
    relax(g.vb, du + g.len, -2 - u);
    relax(g.vc, du + m_.half[m_.vf_half[k] - m_.vf_half[k] % 3 + prev3(m_.vf_half[k] % 3)].len,
          -2 - u);
  }
  // Rule (S): shortest paths bend at a vertex only with angles >= pi on both sides (on the
  // surface side, at a boundary vertex); otherwise they could be shortened around it. Paths
  // through u therefore leave it only in the directions at angle [pi, total - pi] from the
  // incoming direction of (any) shortest path to u (for a boundary vertex: at least pi away
  // within its fan), and u emits windows only into that cone, widened by kConeTolerance.
  const double back = incoming_angle(u);
  const int first = m_.fan_start[u], count = m_.fan_start[u + 1] - first;
  if (back < 0 || count == 0) {
    for (int k = m_.vf_start[u]; k < m_.vf_start[u + 1]; ++k) {
      const int h = m_.vf_half[k];
      const int opposite = m_.half[h - h % 3 + next3(h % 3)].twin;
      if (opposite >= 0) emit_window(opposite, 0, m_.half[opposite].len, du, u);
    }
    return;
  }
  const double* phi = m_.fan_angle.data() + first + u;
  const double total = phi[count];
  // Allowed directions as up to two absolute ranges in [0, total] (a closed fan's cone may wrap).
  std::array<double, 4> allowed;
  int ranges = 0;
  const auto add_range = [&](double lo, double hi) {
    lo = std::max(lo, 0.0);
    hi = std::min(hi, total);
    if (hi >= lo && ranges < 2) {
      allowed[2 * ranges] = lo;
      allowed[2 * ranges + 1] = hi;
      ++ranges;
    }
  };
  if (m_.fan_closed[u]) {
    const double lo = back + kPi - kConeTolerance, hi = back + total - kPi + kConeTolerance;
    if (hi - lo >= total) {
      add_range(0, total);
    } else if (lo >= total) {
      add_range(lo - total, hi - total);
    } else {
      add_range(lo, hi);
      if (hi > total) add_range(0, hi - total);
    }
  } else {
    add_range(0, back - kPi + kConeTolerance);
    add_range(back + kPi - kConeTolerance, total);
  }
  const int* fan = m_.fan_half.data() + first;
  for (int k = 0; k < count; ++k) {
    const int h = fan[k];
    const HalfEdge& g = m_.half[h];
    const int opposite = m_.half[h - h % 3 + next3(h % 3)].twin;
    if (opposite < 0) continue;
    const double theta = phi[k + 1] - phi[k];
    // Directions of this face allowed, as local angles [a0, a1] from u->v[i+1] (the hull of the
    // allowed parts: a superset only prunes less).
    double a0 = kInf, a1 = -kInf;
    for (int r = 0; r < ranges; ++r) {
      const double lo = std::max(allowed[2 * r], phi[k]),
                   hi = std::min(allowed[2 * r + 1], phi[k + 1]);
      if (hi >= lo) {
        a0 = std::min(a0, lo - phi[k]);
        a1 = std::max(a1, hi - phi[k]);
      }
    }
    if (!(a1 >= a0)) continue;
    // The ray at local angle a meets the opposite edge (v[i+1] -> v[i+2]) at the fraction
    // s = dy L / (cy dx + (L - cx) dy) from v[i+1]; on the twin (from v[i+2]) at x = (1 - s) len.
    const double L = g.len, cx = g.cx, cy = g.cy;
    const auto s_of = [&](double a) {
      const double dx = std::cos(a), dy = std::sin(a);
      return std::clamp(dy * L / (cy * dx + (L - cx) * dy), 0.0, 1.0);
    };
    const double len = m_.half[opposite].len;
    const double b0 = a1 < theta ? (1.0 - s_of(a1)) * len : 0.0;
    const double b1 = a0 > 0 ? (1.0 - s_of(a0)) * len : len;
    if (b1 > b0) emit_window(opposite, b0, b1, du, u);
  }
}

/// The source point s lies in face `face` (on its edge `skip_edge` if >= 0): straight segments
/// to the face's corners, and windows onto its other edges.
void Propagator::emit_from_point(const Vec3& s, int face, int skip_edge) {
  const auto& P = m_.mesh.vertices();
  for (int i = 0; i < 3; ++i) {
    const int v = m_.half[3 * face + i].va;
    relax(v, (P[v] - s).norm(), kFromSource);
  }
  for (int j = 0; j < 3; ++j) {
    const int twin = m_.half[3 * face + j].twin;
    if (j == skip_edge || twin < 0) continue;
    const HalfEdge& n = m_.half[twin];
    const Vec3& a = P[n.va];
    const Vec3 ex = (P[n.vb] - a) / n.len;
    const Vec3 d = s - a;
    Window w;
    w.b0 = 0;
    w.b1 = n.len;
    w.sx = d.dot(ex);
    w.sy = -d.cross(ex).norm();
    w.sigma = 0;
    w.he = twin;
    w.link = Window::root_link(-1);
    insert(w);
  }
}

void Propagator::init(const SurfacePoint& s) {
  const TriangleMesh& mesh = m_.mesh;
  const int zeros = zero_weight_count(s);
  if (zeros == 2) {
    const int v = s.vertex(mesh);
    dist_[v] = 0;
    prov_[v] = kFromSource;
    out_.source_faces = {-1, -1};
    if (batch_) inside_[v] = 1;
    emit_vertex(v);
    if (batch_) edges_ready(v);
    return;
  }
  const Vec3 p = s.position(mesh);
  if (zeros == 1) {
    int e = 0;
    for (int i = 0; i < 3; ++i)
      if (s.barycentric[i] == 0.0) e = next3(i);  // the edge opposite the zero weight
    const int twin = m_.half[3 * s.face + e].twin;
    out_.source_faces = {s.face, twin >= 0 ? twin / 3 : -1};
    emit_from_point(p, s.face, e);
    if (twin >= 0) emit_from_point(p, twin / 3, twin % 3);
  } else {
    out_.source_faces = {s.face, -1};
    emit_from_point(p, s.face, -1);
  }
}

double Propagator::stop_bound() const {
  // Any point q of a face is within the face's longest edge of each corner V, so its distance is
  // at most max_V d(V) + longest edge.
  double bound = 0;
  for (int f : stop_faces_) {
    double corner = 0, longest = 0;
    for (int e = 0; e < 3; ++e) {
      const HalfEdge& h = m_.half[3 * f + e];
      corner = std::max(corner, dist_[h.va]);
      longest = std::max(longest, h.len);
    }
    bound = std::max(bound, corner + longest);
  }
  for (int v : stop_vertices_) bound = std::max(bound, dist_[v]);
  return bound;
}

void Propagator::run() {
  if (batch_) {
    run_batch();
    return;
  }
  const int nv = m_.mesh.vertex_count();
  std::uint64_t events = 0;
  double bound = kInf;
  const bool stop = options_.stop_at_targets;
  progress_.report("geodesic distances", 0.0);
  while (!heap_.empty()) {
    const EventQueue::Entry ev = heap_.pop();
    if ((++events & 4095) == 0) {
      progress_.check();
      if ((events & 262143) == 0) {
        int reached = 0;
        for (double d : dist_) reached += d < kInf;
        progress_.report("geodesic distances", nv ? 0.99 * reached / nv : 0.0);
      }
    }
    if (stop) {
      // Every window or vertex event that could still lower a distance in the target faces has
      // a key below that distance; once the keys pass the faces' bound, they are final.
      const double key = ev.key;
      if (key > bound || (events & 255) == 0) bound = stop_bound();
      if (key > bound + margin_) break;
    }
    if (ev.id < 0) {
      const int v = -1 - ev.id;
      if (!emitted_[v]) emit_vertex(v);
      continue;
    }
    const Window w = windows_[ev.id];
    if (!(w.b1 > w.b0)) continue;  // emptied by a better window meanwhile
    propagate(w, ev.id);
  }
  progress_.report("geodesic distances", 1.0);
}

// Batch propagation (every solve without stop_at_targets). The organisation of Qin et
// al.'s VTP (ACM TOG 35(4), 2016): windows are not processed one at a time in key order but
// collected per half-edge and propagated as a batch once one of the edge's end vertices has been
// popped from a queue of vertices ordered by their (upper-bound) distance; a window's children
// move on at once while their edge touches a popped vertex, so windows pile up on the edges just
// ahead of the popped region and are decided together. No MMP trimming against other windows of
// the edge and no rule E (see process_list): the pruning is the barrier (rule B) of the best
// window through the edge seeing the opposite corner, which now is the best of the whole batch
// (and of earlier batches on that half-edge), and rule S at pseudo-sources. Every rule compares
// with the length of a real path, so the order changes only how much is pruned, never the
// result: a popped vertex may still improve (a pseudo-source then emits again from its new
// distance, in the direction of its new path), and the solve ends when no window is pending and
// no vertex is queued. Without keep_windows a window's slot is recycled once it has propagated
// (the memory in use is the wavefront's), so rule S's incoming direction is taken when a window
// sets a distance, and the windows entering target faces are copied for evaluate_targets(); with
// keep_windows every window stays, with its parent and root, for distance_to and path_to.
void Propagator::append_pending(const Window& w) {
  push_child(w.he, m_.half[w.he].len, w.b0, w.b1, w.sx, w.sy, w.sigma, w.link);
}

[[gnu::always_inline]] inline void Propagator::push_child(int he, double len, double b0, double b1,
                                                          double sx, double sy, double sigma,
                                                          int link) {
  if (sy > 0) sy = 0;
  if (b0 < 0) b0 = 0;
  if (b1 > len) b1 = len;
  if (!(b1 > b0)) return;
  if (goal_ && beyond_goal(he, b0, b1, sx, sy, sigma)) return;
  int id;
  if (!free_.empty()) {
    id = free_.back();
    free_.pop_back();
  } else {
    if (windows_.size() >= kMaxWindows) throw std::length_error("geodesic: too many windows");
    id = static_cast<int>(windows_.size());
    windows_.emplace_back();
  }
  Window& c = windows_[id];
  c.b0 = b0;
  c.b1 = b1;
  c.sx = sx;
  c.sy = sy;
  c.sigma = sigma;
  c.he = he;
  c.link = link;
  HalfEdgeState& p = pending_[he];
  c.next = p.head;
  p.head = id;
  if (p.ready && !p.queued) {
    p.queued = 1;
    fifo_.push_back(he);
  }
}

template <class Emit>
void Propagator::children(const Window& w, double x, double corner, Emit&& emit) const {
  const HalfEdge& h = m_.half[w.he];
  const double length = h.len, cx = h.cx, cy = h.cy;
  const double sx = w.sx, sy = w.sy;
  // Entries left of x exit through C->A, entries right of it through B->C.
  double hi_left = std::min(w.b1, x), lo_right = std::max(w.b0, x);
  const CornerRecord& rec = corner_[w.he];
  // Rule B applies if rec.d + margin < sigma + |I C|; squared when both sides are positive.
  bool barrier = false;
  if (rec.d < kInf) {
    if (corner >= 0) {
      barrier = rec.d + margin_ < corner;
    } else {
      const double r = rec.d + margin_ - w.sigma;
      barrier = r < 0 || r * r < (cx - sx) * (cx - sx) + (cy - sy) * (cy - sy);
    }
  }
  if (barrier) {
    hi_left = std::min(hi_left, rec.x);  // barrier X1-C (rule B)
    lo_right = std::max(lo_right, rec.x);
  }
  if (hi_left > w.b0 && h.left_twin >= 0) {
    // Ray through (b,0) meets A + s (C - A) at s = b sy / ((b - sx) cy + sy cx).
    const double l2 = h.left_len;
    const double den = sy * cx;
    const double b0 = l2 * (w.b0 * sy) / ((w.b0 - sx) * cy + den);
    const double b1 = hi_left >= x ? l2 : l2 * (hi_left * sy) / ((hi_left - sx) * cy + den);
    const double ux = h.u2x, uy = h.u2y;
    emit(h.left_twin, l2, b0, b1, sx * ux + sy * uy, ux * sy - uy * sx, std::int8_t{2});
  }
  if (lo_right < w.b1 && h.right_twin >= 0) {
    // Ray through (b,0) meets B + s (C - B) at s = sy (b - L) / ((b - sx) cy + sy (cx - L)).
    const double l1 = h.right_len;
    const double den = sy * (cx - length);
    const auto t_of = [&](double b) {
      return l1 * (1.0 - sy * (b - length) / ((b - sx) * cy + den));
    };
    const double b0 = lo_right <= x ? 0.0 : t_of(lo_right);
    const double b1 = t_of(w.b1);
    const double ux = h.u1x, uy = h.u1y;
    const double dx = sx - cx, dy = sy - cy;
    emit(h.right_twin, l1, b0, b1, dx * ux + dy * uy, ux * dy - uy * dx, std::int8_t{1});
  }
}

void Propagator::propagate_batch(const Window& w, int id, double x, double corner) {
  children(w, x, corner,
           [&](int he, double len, double b0, double b1, double sx, double sy, std::int8_t exit) {
             push_child(he, len, b0, b1, sx, sy, w.sigma, Window::child_link(id, exit));
           });
}

void Propagator::process_list(int h) {
  HalfEdgeState& p = pending_[h];
  int id = p.head;
  p.head = -1;
  p.queued = 0;
  const HalfEdge& e = m_.half[h];
  const double cx = e.cx, cy = e.cy;
  const double tol = kVisibilityTolerance * e.len;
  // No rule E here: with the end vertices' distances as they are when a batch moves on, it
  // removed 0.2% of the windows and cost 14-19% more instructions per solve than it saved
  // (measured on waves-bump at 1k and 3.5k vertices, torus-wide, hypar, sphere). The pruning is
  // rule B's, with the batch's best path to the opposite corner, and rule S's at saddles.
  CornerRecord& rec = corner_[h];
  double best = kInf;
  int best_id = kFromSource;
  batch_list_.clear();
  // A window whose nearest point is farther than an end vertex's distance plus the edge's
  // length is dominated on all of its interval by the real path through that vertex (and so is
  // everything beyond it): dropped. Rule B alone never kills a window that keeps finding no
  // better path to its opposite corner, and on a closed surface windows then go round for ever
  // (a closed sphere ran out of memory, issue 18); this one comparison ends them.
  const double near = std::min(dist_[e.va], dist_[e.vb]) + e.len + margin_;
  for (; id >= 0; id = windows_[id].next) {
    const Window& w = windows_[id];
    if (near < kInf) {
      const double dx = w.sx < w.b0 ? w.b0 - w.sx : (w.sx > w.b1 ? w.sx - w.b1 : 0.0);
      if (w.sigma + std::sqrt(dx * dx + w.sy * w.sy) > near) {
        if (recycle_) free_.push_back(id);
        continue;
      }
    }
    // The opposite corner C seen straight through the window: a distance for C and the barrier
    // record (rule B), now the best of the whole batch before any of it propagates.
    // x = num / den (den > 0); the division only for windows that see C: for the others only
    // the side matters (children() treats x < b0 as -inf and x > b1 as +inf).
    const double num = w.sx * cy - w.sy * cx, den = cy - w.sy;
    const bool before = num<(w.b0 - tol) * den, after = num>(w.b1 + tol) * den;
    double x = before ? -kInf : kInf;
    double dc = -1;
    if (!before && !after) {
      x = num / den;
      dc = w.sigma + hyp(cx - w.sx, cy - w.sy);
      if (dc < rec.d) {
        rec.d = dc;
        rec.x = x;
      }
      if (dc < best) {
        best = dc;
        best_id = id;
      }
    }
    batch_list_.push_back(BatchEntry{id, x, dc});
  }
  if (batch_list_.empty()) return;
  if (!(best < kInf)) {
    // No window sees C: a path through the nearer end of an interval is still real, and C must
    // get a finite distance (it is popped later, so the windows beyond it move on). Plus the
    // margin: such a path bends inside an edge, so it is never a shortest path, and with the
    // margin a real one always replaces it (with its provenance, for paths and rule S).
    // Any one real path will do (the first window's).
    const BatchEntry& b = batch_list_.front();
    const Window& w = windows_[b.id];
    const double end = b.x < w.b0 ? w.b0 : w.b1;
    best = w.sigma + hyp(end - w.sx, w.sy) + hyp(cx - end, cy) + margin_;
  }
  if (best < dist_[e.vc] && best_id >= 0 && m_.pseudo[e.vc])
    incoming_[e.vc] = window_angle(e.vc, windows_[best_id]);
  relax(e.vc, best, best_id);
  const bool target = track_targets_ && target_face_[h / 3];
  // Room for every child of the batch (at most two per window), so that windows_ does not move
  // while a window propagates from its slot; its slot is freed only afterwards.
  const std::size_t room = windows_.size() + 2 * batch_list_.size();
  if (windows_.capacity() < room) windows_.reserve(std::max(room, 2 * windows_.capacity()));
  for (std::size_t k = 0; k < batch_list_.size(); ++k) {
    const BatchEntry b = batch_list_[k];
    const Window& w = windows_[b.id];
    if (target) target_copies_.push_back(w);
    propagate_batch(w, b.id, b.x, b.corner);
    if (recycle_) free_.push_back(b.id);
  }
}

void Propagator::edges_ready(int v) {
  // The lists on the edges at v (both sides).
  for (int k = m_.vf_start[v]; k < m_.vf_start[v + 1]; ++k) {
    // Each face's v -> v[i+1] and its twin; v[i+2] -> v is the next face's v -> v[i+1] (or its
    // twin), except on the boundary.
    const int a = m_.vf_half[k];  // v -> v[i+1]
    make_ready(a);
    make_ready(m_.half[a].twin);
    const int b = a - a % 3 + prev3(a % 3);  // v[i+2] -> v
    if (m_.half[b].twin < 0) make_ready(b);
  }
}

void Propagator::drain() {
  std::size_t next = 0;
  while (true) {
    while (!reemit_.empty()) {
      const int u = reemit_.back();
      reemit_.pop_back();
      emit_vertex(u);
    }
    if (next == fifo_.size()) break;
    process_list(fifo_[next++]);
  }
  fifo_.clear();
}

void Propagator::run_batch() {
  const int nv = m_.mesh.vertex_count();
  progress_.report("geodesic distances", 0.0);
  std::uint64_t pops = 0;
  int inside = 0;
  drain();
  while (!heap_.empty()) {
    const int v = -1 - heap_.pop().id;
    if (inside_[v]) continue;
    inside_[v] = 1;
    ++inside;
    if ((++pops & 1023) == 0) {
      progress_.check();
      if ((pops & 65535) == 0)
        progress_.report("geodesic distances", nv ? 0.99 * inside / nv : 0.0);
    }
    if (m_.pseudo[v]) emit_vertex(v);
    edges_ready(v);
    drain();
    if (compact_ && windows_.size() >= compact_at_) compact();
  }
  if (compact_ && windows_.size() >= kCompactWindows) {
    const std::size_t touched = windows_.size();
    compact();
    // The pages past the kept windows go back to the system: the field then holds what it
    // answers with (its memory_bytes(), which the buffer pool also counts when it keeps it).
    release_pages(windows_, touched);
  }
  if (recycle_) {
    // evaluate_targets() reads windows_[target_windows_]: the copies of the target faces'
    // windows (the slots have been reused).
    windows_.swap(target_copies_);
    target_windows_.resize(windows_.size());
    for (std::size_t k = 0; k < target_windows_.size(); ++k)
      target_windows_[k] = static_cast<int>(k);
  }
  progress_.report("geodesic distances", 1.0);
}

// Compaction (goal-pruned solves that keep windows). Such a field answers exactly only in the
// goal ball, so the windows worth keeping are those entering a face that meets the ball (a
// distance or a path's last piece there), the provenance of the vertices a path can pass
// through (the corners of those faces, where locate() may pick a vertex, and the pseudo-sources,
// where paths bend), the windows still pending, and all their ancestors (path_to traces back
// through parents). Everything else is dropped: about two thirds of a member solve's windows
// (measured on the 15k double vault: 22-33 % live at the end of each solve). A window's parent
// is always older, so one backward sweep marks the ancestors and one forward sweep moves the live
// windows down in their order and renumbers parents, pending lists and provenance. The kept
// windows keep their relative order, so the face index lists them in the same order as without
// compaction and every query picks the same window: results are identical to the bit.
void Propagator::compact() {
  const std::size_t n = windows_.size();
  out_.peak_windows = std::max(out_.peak_windows, n);
  renumber_.assign(n, 0);
  for (HalfEdgeState& p : pending_)
    for (int id = p.head; id >= 0; id = windows_[id].next) renumber_[id] = 1;
  const int nv = static_cast<int>(prov_.size());
  for (int v = 0; v < nv; ++v) {
    const int code = prov_[v];
    if (code < 0) continue;
    if (hold_[v])
      renumber_[code] = 1;
    else
      prov_[v] = kPathNotKept;  // its window may go
  }
  for (std::size_t id = n; id-- > 0;) {
    const Window& w = windows_[id];
    if (!renumber_[id] && !keep_face_[w.he / 3]) continue;
    renumber_[id] = 1;
    if (w.link >= 0) renumber_[w.parent()] = 1;
  }
  int kept = 0;
  for (std::size_t id = 0; id < n; ++id) {
    if (!renumber_[id]) {
      renumber_[id] = -1;
      continue;
    }
    Window& w = windows_[kept];
    if (static_cast<int>(id) != kept) w = windows_[id];
    if (w.link >= 0) w.link = Window::child_link(renumber_[w.parent()], w.exit());
    renumber_[id] = kept++;
  }
  windows_.resize(kept);
  for (HalfEdgeState& p : pending_) {
    if (p.head < 0) continue;
    p.head = renumber_[p.head];
    for (int id = p.head; id >= 0; id = windows_[id].next)
      if (windows_[id].next >= 0) windows_[id].next = renumber_[windows_[id].next];
  }
  for (int v = 0; v < nv; ++v)
    if (prov_[v] >= 0) prov_[v] = renumber_[prov_[v]];
  compact_at_ = std::max(kCompactWindows, static_cast<std::size_t>(kept) * 2);
}

void Propagator::evaluate_targets(const SurfacePoint& source) {
  const TriangleMesh& mesh = m_.mesh;
  std::vector<double>& out = out_.target_distances;
  out.assign(options_.targets.size(), kInf);
  // Collected windows bucketed by face (only target faces have any).
  std::sort(target_windows_.begin(), target_windows_.end(),
            [&](int a, int b) { return windows_[a].he / 3 < windows_[b].he / 3; });
  const Vec3 s = source.position(mesh);
  for (size_t t = 0; t < options_.targets.size(); ++t) {
    const SurfacePoint& q = options_.targets[t];
    const PointFaces pf = point_faces(m_, q);
    if (pf.vertex >= 0) {
      out[t] = dist_[pf.vertex];
      continue;
    }
    const Vec3 qp = q.position(mesh);
    double best = kInf;
    for (int k = 0; k < pf.count; ++k) {
      const int f = pf.face[k];
      for (int e = 0; e < 3; ++e) {
        const int v = m_.half[3 * f + e].va;
        best = std::min(best, dist_[v] + (mesh.vertices()[v] - qp).norm());
      }
      if (f == out_.source_faces[0] || f == out_.source_faces[1])
        best = std::min(best, (s - qp).norm());
      std::array<double, 3> qx, qy;
      point_in_frames(m_, f, pf.weights[k], qx, qy);
      auto it = std::lower_bound(target_windows_.begin(), target_windows_.end(), f,
                                 [&](int id, int face) { return windows_[id].he / 3 < face; });
      for (; it != target_windows_.end() && windows_[*it].he / 3 == f; ++it) {
        const Window& w = windows_[*it];
        if (!(w.b1 > w.b0)) continue;
        const int e = w.he % 3;
        best = std::min(best, window_distance(w, m_.half[w.he], qx[e], qy[e]));
      }
    }
    out[t] = best;
  }
}

// ---------------------------------------------------------------------------------------------
// Queries

FastField::~FastField() {
  // Hand the window storage back to the mesh's pool: at most 4 buffers and 64 MiB of written
  // windows in all, held until the solver is destroyed. Counted by size, not capacity: a large
  // mesh reserves far more than it writes (Propagator::init), and only written pages are resident
  // (a compacted solve returns the pages past its size, run_batch). 256 MiB of pooled buffers
  // beside two running member solves made the peak of a 59k-vertex design (docs/decisions.md).
  constexpr std::size_t kMaxBytes = std::size_t{64} << 20;
  constexpr std::size_t kMaxBuffers = 4;
  const std::size_t bytes = windows.size() * sizeof(Window);
  if (!m || windows.capacity() == 0 || bytes > kMaxBytes) return;
  std::lock_guard<std::mutex> lock(m->pool_mutex);
  std::size_t held = bytes;
  for (const WindowVector& b : m->pool) held += b.size() * sizeof(Window);
  if (m->pool.size() < kMaxBuffers && held <= kMaxBytes) m->pool.push_back(std::move(windows));
}

void FastField::build_index() {
  const int nf = static_cast<int>(m->half.size() / 3);
  face_start.assign(nf + 1, 0);
  for (const Window& w : windows)
    if (w.b1 > w.b0) ++face_start[w.he / 3 + 1];
  for (int f = 0; f < nf; ++f) face_start[f + 1] += face_start[f];
  face_window.resize(face_start[nf]);
  std::vector<int> fill(face_start.begin(), face_start.end() - 1);
  for (int i = 0; i < static_cast<int>(windows.size()); ++i)
    if (windows[i].b1 > windows[i].b0) face_window[fill[windows[i].he / 3]++] = i;
}

SurfacePoint FastField::vertex_point(int v) const {
  const int h = m->vf_half[m->vf_start[v]];
  SurfacePoint p;
  p.face = h / 3;
  p.barycentric = Vec3::Zero();
  p.barycentric[h % 3] = 1.0;
  return p;
}

SurfacePoint FastField::edge_point(int he, double x) const {
  const int face = he / 3, edge = he % 3;
  const double s = x / m->half[he].len;
  SurfacePoint p;
  p.face = face;
  p.barycentric = Vec3::Zero();
  // A crossing within rounding distance of an end is that vertex (paths along a line of edges
  // through flat vertices would otherwise report points a few ulps off the vertex).
  if (s <= kSnapRelative) {
    p.barycentric[edge] = 1.0;
  } else if (s >= 1 - kSnapRelative) {
    p.barycentric[next3(edge)] = 1.0;
  } else {
    p.barycentric[edge] = 1.0 - s;
    p.barycentric[next3(edge)] = s;
  }
  return p;
}

FastField::Best FastField::locate(const SurfacePoint& target) const {
  const TriangleMesh& mesh = m->mesh;
  if (!has_windows)
    throw InvalidInput(
        "",
        "distance field was solved without windows (SolveOptions::keep_windows = false): it "
        "answers vertex and target distances only");
  const SurfacePoint q = normalize_surface_point(mesh, target, "target");
  Best best;
  const PointFaces pf = point_faces(*m, q);
  if (pf.vertex >= 0) {
    best.d = distances[pf.vertex];
    best.kind = 1;
    best.index = pf.vertex;
    return best;
  }
  const Vec3 qp = q.position(mesh);
  for (int slot = 0; slot < pf.count; ++slot) {
    const int f = pf.face[slot];
    for (int i = 0; i < 3; ++i) {
      const int v = m->half[3 * f + i].va;
      const double d = distances[v] + (mesh.vertices()[v] - qp).norm();
      if (d < best.d) {
        best.d = d;
        best.kind = 1;
        best.index = v;
      }
    }
    if (f == source_faces[0] || f == source_faces[1]) {
      const double d = (source.position(mesh) - qp).norm();
      if (d < best.d) {
        best.d = d;
        best.kind = 2;
      }
    }
    std::array<double, 3> qx, qy;  // q in the frame of each edge
    point_in_frames(*m, f, pf.weights[slot], qx, qy);
    for (int k = face_start[f]; k < face_start[f + 1]; ++k) {
      const Window& win = windows[face_window[k]];
      const int e = win.he % 3;
      const double d = window_distance(win, m->half[win.he], qx[e], qy[e]);
      if (d < best.d) {
        best.d = d;
        best.kind = 0;
        best.index = face_window[k];
        best.qx = qx[e];
        best.qy = qy[e];
      }
    }
  }
  return best;
}

double FastField::distance_to(const SurfacePoint& target) const { return locate(target).d; }

std::vector<SurfacePoint> FastField::path_to(const SurfacePoint& target) const {
  const TriangleMesh& mesh = m->mesh;
  const Best best = locate(target);
  if (!(best.d < kInf))
    throw InvalidInput("target", "not reachable from the source (another connected piece)");
  std::vector<SurfacePoint> out;  // target first, built backwards
  out.push_back(normalize_surface_point(mesh, target, "target"));
  // State machine: a window with a point in its frame, or a vertex, or done.
  int window = -1, vertex = -1;
  double px = 0, py = 0;
  if (best.kind == 0) {
    window = best.index;
    px = best.qx;
    py = best.qy;
  } else if (best.kind == 1) {
    vertex = best.index;
    out.push_back(vertex_point(vertex));
  }
  for (size_t guard = 0; (window >= 0 || vertex >= 0) && guard < 4 * windows.size() + 16; ++guard) {
    if (window >= 0) {
      const Window& w = windows[window];
      double x = py <= 0 ? px : w.sx + (px - w.sx) * (-w.sy) / (py - w.sy);
      x = std::clamp(x, w.b0, w.b1);
      out.push_back(edge_point(w.he, x));
      if (w.parent() < 0) {
        window = -1;
        vertex = w.root();
        if (vertex >= 0) out.push_back(vertex_point(vertex));
        continue;
      }
      const Window& p = windows[w.parent()];
      const HalfEdge& ph = m->half[p.he];
      if (w.exit() == 2) {
        px = x * ph.u2x;
        py = x * ph.u2y;
      } else {
        px = ph.cx + x * ph.u1x;
        py = ph.cy + x * ph.u1y;
      }
      window = w.parent();
    } else {
      const int code = provenance[vertex];
      if (code == kPathNotKept)
        throw InvalidInput("target",
                           "outside the goal of a goal-pruned solve (SolveOptions::goal): the "
                           "shortest path there was not kept");
      if (code == kFromSource) {
        vertex = -1;
      } else if (code <= -2) {
        vertex = -2 - code;
        out.push_back(vertex_point(vertex));
      } else {
        window = code;
        vertex = -1;
        const Window& w = windows[window];
        px = m->half[w.he].cx;
        py = m->half[w.he].cy;
      }
    }
  }
  out.push_back(source);
  // Drop consecutive duplicates (a crossing at a vertex followed by that vertex, ...).
  std::vector<SurfacePoint> path;
  path.reserve(out.size());
  for (auto it = out.rbegin(); it != out.rend(); ++it) {
    if (!path.empty() && (path.back().position(mesh) - it->position(mesh)).norm() == 0.0) {
      if (it + 1 == out.rend()) path.back() = *it;  // keep the target itself last
      continue;
    }
    path.push_back(*it);
  }
  if (path.size() == 1) path.insert(path.begin(), source);  // target at the source
  return path;
}

// ---------------------------------------------------------------------------------------------

class FastSolver final : public GeodesicSolver::Impl {
 public:
  explicit FastSolver(const TriangleMesh& mesh) : data_(build_fast_mesh(mesh)) {
    this->mesh = mesh;
  }

  DistanceField solve(const SurfacePoint& source, const SolveOptions& options,
                      const Progress& progress) const override {
    auto field = std::make_shared<FastField>();
    field->m = data_;
    field->source = source;
    field->has_windows = options.keep_windows;
    thread_local Scratch scratch;
    if (options.keep_windows) {
      std::lock_guard<std::mutex> lock(data_->pool_mutex);
      if (!data_->pool.empty()) {
        field->windows = std::move(data_->pool.back());
        data_->pool.pop_back();
      }
    }
    WindowVector& windows = options.keep_windows ? field->windows : scratch.windows;
    {
      Propagator run(*data_, *field, windows, options, progress, scratch);
      run.init(field->source);
      run.run();
      if (!options.keep_windows) run.evaluate_targets(field->source);
    }
    data_->window_hint.store(windows.size() + windows.size() / 4, std::memory_order_relaxed);
    if (options.keep_windows) {
      field->build_index();
      field->target_distances.clear();
      for (const SurfacePoint& t : options.targets)
        field->target_distances.push_back(field->distance_to(t));
    } else {
      // The provenance codes refer to windows that are not kept.
      field->provenance.clear();
      field->provenance.shrink_to_fit();
    }
    release_if_large(scratch);
    return DistanceField(std::move(field));
  }

 private:
  std::shared_ptr<const FastMesh> data_;
};

}  // namespace

std::unique_ptr<GeodesicSolver::Impl> make_fast_solver(const TriangleMesh& mesh) {
  return std::make_unique<FastSolver>(mesh);
}

}  // namespace gridshell::geodesic_detail
