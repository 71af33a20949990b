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
// A window w lives on an edge AB of a face F and represents the straight unfolded paths from a
// (pseudo-)source image I, at distance sigma from the source, through the interval [b0, b1] of
// AB into F. It is stored in the frame of F's edge: A = (0,0), B = (L,0), the opposite corner
// C = (cx, cy) with cy > 0, the image I = (sx, sy) with sy <= 0. Every point p of the interval
// is reached by a real surface path of length sigma + |I p|. Propagating w across F gives at
// most two children, on CA and on BC (split by the ray I->C).
//
// Events are processed in increasing order of the window's minimum distance
// key(w) = sigma + dist(I, [b0,b1]) (a radix heap). Children are never closer than their parent
// (their points are reached through the parent's interval) and trimming only raises keys, so
// popped keys are non-decreasing: when the event of a vertex pops, its distance is final.
// Saddle vertices (angle sum > 2 pi) and reflex boundary vertices (angle sum > pi) become
// pseudo-sources at that moment and emit full-edge windows onto the opposite edges of all their
// faces (shortest paths can only bend there); the true source emits the same way.
//
// Vertex distances d(V) are upper bounds realised by real paths at every moment (set from
// windows that see V, or from a pseudo-source along an edge), as early as possible: when a window
// that sees the corner opposite its edge is created.
//
// Pruning rules. Each removes only paths that are longer than another real path to the same
// point (for E and B by more than a safety margin); such a path is not a shortest path, nor is
// any extension of it, so no shortest path is ever removed and all results, including distances
// to arbitrary surface points, stay exact:
//
//  (M) MMP trimming: each edge keeps its windows (from both sides) sorted along the edge. A new
//      window is compared with the overlapping ones: where an old window gives a shorter
//      distance the new one is cut away (possibly splitting it), where the new one is shorter at
//      an end of an old one, the old one is shortened. The crossover points are the roots of
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
// Queries: all windows are kept with their parent and pseudo-source, bucketed by the face they
// propagate into. The distance to a point q of face f is the minimum of sigma + |I q| over the
// windows entering f whose cone contains q, of d(V) + |V q| over f's corners and of |S q| if the
// source lies in f; the path is traced back through the window's ancestors (one point per edge
// crossing), then through pseudo-source vertices to the source.
#include "geodesic_fast.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>

#include "gridshell/errors.h"
#include "gridshell/mesh_topology.h"

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
/// A new window may be split by older, better windows into at most this many pieces.
constexpr int kMaxPieces = 4;

inline int next3(int i) { return i == 2 ? 0 : i + 1; }
inline int prev3(int i) { return i == 0 ? 2 : i - 1; }
inline double hyp(double x, double y) { return std::sqrt(x * x + y * y); }

/// Per-face geometry, in the frame of each of its edges e (A = v[e] at the origin, B = v[e+1]
/// on the positive x axis, C = v[e+2] above).
struct FaceGeom {
  std::array<int, 3> v;
  std::array<int, 3> nbr;               ///< face across edge e, -1 on the boundary
  std::array<std::int8_t, 3> nbr_edge;  ///< that face's local index of the shared edge
  std::array<double, 3> len;            ///< |v[e] v[e+1]|
  std::array<double, 3> cx, cy;         ///< C in frame e
  std::array<double, 3> ox, oy;         ///< neighbour's opposite corner in frame e (oy <= 0)
  std::array<double, 3> u1x, u1y;       ///< unit vector C->B in frame e (exit edge e+1)
  std::array<double, 3> u2x, u2y;       ///< unit vector A->C in frame e (exit edge e+2)
};

/// Everything a solve shares; immutable after construction.
struct FastMesh {
  TriangleMesh mesh;
  std::vector<FaceGeom> faces;
  std::vector<int> vf_start;  ///< CSR: faces around each vertex
  std::vector<int> vf_face;
  std::vector<std::int8_t> vf_local;  ///< the vertex's local index in that face
  std::vector<char> pseudo;           ///< saddle or reflex boundary vertex
  std::vector<int> edge_id;           ///< per half-edge 3 f + e: undirected edge index
  std::vector<char> edge_side;        ///< 1 if the half-edge runs against the edge's orientation
  int edge_count = 0;
  double margin = 0;
  /// Windows of the latest solve (+ slack), to reserve the next one's storage at once.
  mutable std::atomic<std::size_t> window_hint{0};
};

std::shared_ptr<const FastMesh> build_fast_mesh(const TriangleMesh& mesh) {
  auto m = std::make_shared<FastMesh>();
  m->mesh = mesh;
  const MeshTopology top = build_topology(mesh);
  const int nv = mesh.vertex_count(), nf = mesh.face_count();
  m->faces.resize(nf);
  std::vector<double> angle(nv, 0.0);
  for (int f = 0; f < nf; ++f) {
    FaceGeom& g = m->faces[f];
    const Face& t = mesh.faces[f];
    for (int e = 0; e < 3; ++e) {
      g.v[e] = t[e];
      g.nbr[e] = top.face_neighbors[f][e];
      g.nbr_edge[e] = -1;
      if (g.nbr[e] >= 0) {
        const Face& n = mesh.faces[g.nbr[e]];
        for (int k = 0; k < 3; ++k)
          if (n[k] == t[next3(e)] && n[next3(k)] == t[e])
            g.nbr_edge[e] = static_cast<std::int8_t>(k);
        if (g.nbr_edge[e] < 0) throw InvalidInput("geodesic solver: inconsistent face orientation");
      }
    }
    for (int e = 0; e < 3; ++e) {
      const Vec3& a = mesh.vertices[t[e]];
      const Vec3& b = mesh.vertices[t[next3(e)]];
      const Vec3& c = mesh.vertices[t[prev3(e)]];
      const Vec3 ab = b - a;
      const double len = ab.norm();
      const Vec3 ex = ab / len;
      g.len[e] = len;
      g.cx[e] = (c - a).dot(ex);
      g.cy[e] = (c - a).cross(ex).norm();
      if (!(len > 0) || !(g.cy[e] > 0) || !std::isfinite(g.cy[e])) {
        std::ostringstream msg;
        msg << "geodesic solver: face " << f << " is degenerate (zero area)";
        throw InvalidInput(msg.str());
      }
      const double ac = (c - a).norm(), bc = (c - b).norm();
      g.u2x[e] = g.cx[e] / ac;
      g.u2y[e] = g.cy[e] / ac;
      g.u1x[e] = (len - g.cx[e]) / bc;
      g.u1y[e] = -g.cy[e] / bc;
      // Corner angle at a (between ab and ac).
      angle[t[e]] += std::atan2((c - a).cross(ab).norm(), (c - a).dot(ab));
    }
  }
  for (int f = 0; f < nf; ++f) {
    FaceGeom& g = m->faces[f];
    for (int e = 0; e < 3; ++e) {
      g.ox[e] = g.oy[e] = 0;
      if (g.nbr[e] < 0) continue;
      const FaceGeom& n = m->faces[g.nbr[e]];
      const Vec3& a = mesh.vertices[g.v[e]];
      const Vec3 ex = (mesh.vertices[g.v[next3(e)]] - a) / g.len[e];
      const Vec3 d = mesh.vertices[n.v[prev3(g.nbr_edge[e])]] - a;
      g.ox[e] = d.dot(ex);
      g.oy[e] = -d.cross(ex).norm();
    }
  }
  m->vf_start.assign(nv + 1, 0);
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) ++m->vf_start[mesh.faces[f][i] + 1];
  for (int v = 0; v < nv; ++v) m->vf_start[v + 1] += m->vf_start[v];
  m->vf_face.resize(3 * nf);
  m->vf_local.resize(3 * nf);
  std::vector<int> fill(m->vf_start.begin(), m->vf_start.end() - 1);
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) {
      const int slot = fill[mesh.faces[f][i]]++;
      m->vf_face[slot] = f;
      m->vf_local[slot] = static_cast<std::int8_t>(i);
    }
  m->pseudo.assign(nv, 0);
  for (int v = 0; v < nv; ++v) {
    const double flat = top.is_boundary_vertex[v] ? kPi : 2 * kPi;
    m->pseudo[v] = angle[v] > flat + kAngleTolerance;
  }
  m->edge_id.assign(3 * nf, -1);
  m->edge_side.assign(3 * nf, 0);
  for (int f = 0; f < nf; ++f)
    for (int e = 0; e < 3; ++e) {
      if (m->edge_id[3 * f + e] >= 0) continue;
      const int id = m->edge_count++;
      m->edge_id[3 * f + e] = id;
      const FaceGeom& g = m->faces[f];
      if (g.nbr[e] >= 0) {
        m->edge_id[3 * g.nbr[e] + g.nbr_edge[e]] = id;
        m->edge_side[3 * g.nbr[e] + g.nbr_edge[e]] = 1;
      }
    }
  const double diagonal = bounding_box_size(mesh).norm();
  m->margin = kMarginRelative * (diagonal > 0 ? diagonal : 1.0);
  return m;
}

/// A window (see the file comment). 56 bytes, stored flat.
struct Window {
  double b0, b1;  ///< interval on the edge, 0 <= b0 < b1 <= L (b0 == b1: emptied)
  double sx, sy;  ///< source image, sy <= 0
  double sigma;   ///< distance from the source to the image
  int face;       ///< the face the window propagates into; the window lies on its edge `edge`
  int parent;     ///< window it was propagated from, -1 for a window emitted by a source
  int root;       ///< emitting pseudo-source vertex, -1 for the true source
  std::int8_t edge;
  std::int8_t exit;  ///< 1: lies on the parent's edge e+1 (C->B), 2: on e+2 (A->C), 0: root
};

/// Best window seeing the corner opposite an edge (for the barrier rule).
struct CornerRecord {
  double d = kInf;  ///< sigma + |I C|
  double x = 0;     ///< crossing of I->C with the edge
};

// Vertex provenance codes: >= 0 window id that sees the vertex; -1 straight from the source;
// <= -2: straight along an edge from pseudo-source vertex (-2 - code).
constexpr int kFromSource = -1;

class FastField final : public DistanceField::Impl {
 public:
  std::shared_ptr<const FastMesh> m;
  std::vector<Window> windows;
  std::vector<int> provenance;  ///< per vertex, see the codes above
  std::vector<int> face_start;  ///< CSR: live windows per face
  std::vector<int> face_window;
  std::array<int, 2> source_faces = {-1, -1};  ///< faces whose closure holds the source

  double distance_to(const SurfacePoint& target) const override;
  std::vector<SurfacePoint> path_to(const SurfacePoint& target) const override;

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
  SurfacePoint edge_point(int face, int edge, double x) const;
};

// ---------------------------------------------------------------------------------------------
// Propagation

/// Monotone priority queue: a radix heap over the bit patterns of non-negative doubles (ordered
/// like the values). Entry k of bucket b differs from the last popped key first in bit b - 1;
/// popping redistributes the lowest non-empty bucket around its minimum. Keys pushed must not be
/// below the last key popped; rounding-level violations are clamped (they only reorder events
/// equal up to rounding).
class RadixHeap {
 public:
  struct Entry {
    std::uint64_t key;
    int id;
  };
  bool empty() const { return size_ == 0; }
  void clear() {
    for (auto& b : buckets_) b.clear();
    high_mask_ = 0;
    last_ = 0;
    size_ = 0;
  }
  void push(double key, int id) {
    std::uint64_t k = key > 0 ? std::bit_cast<std::uint64_t>(key) : 0;
    if (k < last_) k = last_;
    const int b = bucket(k);
    buckets_[b].push_back({k, id});
    if (b > 0) high_mask_ |= std::uint64_t{1} << (b - 1);
    ++size_;
  }
  Entry pop() {
    if (buckets_[0].empty()) {
      const int i = 1 + std::countr_zero(high_mask_);
      std::vector<Entry>& from = buckets_[i];
      std::uint64_t lowest = from[0].key;
      for (const Entry& e : from) lowest = std::min(lowest, e.key);
      last_ = lowest;
      for (const Entry& e : from) {
        const int b = bucket(e.key);
        buckets_[b].push_back(e);
        if (b > 0) high_mask_ |= std::uint64_t{1} << (b - 1);
      }
      from.clear();
      high_mask_ &= ~(std::uint64_t{1} << (i - 1));
    }
    const Entry e = buckets_[0].back();
    buckets_[0].pop_back();
    --size_;
    return e;
  }

 private:
  int bucket(std::uint64_t k) const { return k == last_ ? 0 : 64 - std::countl_zero(k ^ last_); }
  std::array<std::vector<Entry>, 65> buckets_;
  std::uint64_t high_mask_ = 0;  ///< bit b - 1 set iff bucket b (>= 1) is non-empty
  std::uint64_t last_ = 0;
  std::size_t size_ = 0;
};

/// One entry of an edge's window array: the interval in the edge's own orientation.
struct EdgeSlot {
  double lo, hi;
  int id;
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

/// Per-thread scratch memory of a solve (reused by the next solve on the same thread, so that
/// repeated solves do not pay for fresh pages).
struct Scratch {
  std::vector<char> emitted;
  std::vector<CornerRecord> corner;
  std::vector<EdgeList> lists;  ///< per undirected edge: its windows, in slots
  std::vector<EdgeSlot> slots;
  RadixHeap heap;
};

/// Scratch memory is kept for the next solve on the thread, unless it grew large (a big mesh).
void release_if_large(Scratch& scratch) {
  constexpr std::size_t kKeepBytes = std::size_t{32} << 20;
  if (scratch.slots.capacity() * sizeof(EdgeSlot) + scratch.lists.capacity() * sizeof(EdgeList) +
          scratch.corner.capacity() * sizeof(CornerRecord) >
      kKeepBytes)
    scratch = Scratch{};
}

class Propagator {
 public:
  Propagator(const FastMesh& m, FastField& out, const Progress& progress, Scratch& scratch)
      : m_(m),
        out_(out),
        progress_(progress),
        dist_(out.distances),
        prov_(out.provenance),
        emitted_(scratch.emitted),
        corner_(scratch.corner),
        lists_(scratch.lists),
        slots_(scratch.slots),
        heap_(scratch.heap),
        margin_(m.margin) {
    const int nv = m.mesh.vertex_count();
    dist_.assign(nv, kInf);
    prov_.assign(nv, kFromSource);
    emitted_.assign(nv, 0);
    corner_.assign(3 * m.faces.size(), CornerRecord{});
    lists_.assign(m.edge_count, EdgeList{});
    slots_.clear();
    heap_.clear();
    out_.windows.reserve(m.window_hint.load(std::memory_order_relaxed));
  }

  void init(const SurfacePoint& s);
  void run();

 private:
  void relax(int v, double d, int provenance) {
    if (d < dist_[v]) {
      dist_[v] = d;
      prov_[v] = provenance;
      if (m_.pseudo[v] && !emitted_[v]) heap_.push(d, -1 - v);
    }
  }
  void emit_vertex(int u);
  void emit_from_point(const Vec3& s, int face, int skip_edge);
  void add_window(Window& w);
  bool trim_by_endpoints(Window& w, double length, double da, double db, double& f0,
                         double& f1) const;
  void propagate(const Window& w, int id);
  void insert_slot(int edge, double lo, double hi, int id);
  /// w's interval in the orientation of its undirected edge.
  void canonical(const Window& w, double& lo, double& hi) const {
    if (m_.edge_side[3 * w.face + w.edge]) {
      const double len = m_.faces[w.face].len[w.edge];
      lo = len - w.b1;
      hi = len - w.b0;
    } else {
      lo = w.b0;
      hi = w.b1;
    }
  }

  const FastMesh& m_;
  FastField& out_;
  const Progress& progress_;
  std::vector<double>& dist_;
  std::vector<int>& prov_;
  std::vector<char>& emitted_;
  std::vector<CornerRecord>& corner_;
  std::vector<EdgeList>& lists_;
  std::vector<EdgeSlot>& slots_;
  RadixHeap& heap_;
  const double margin_;
};

void Propagator::insert_slot(int edge, double lo, double hi, int id) {
  EdgeList& list = lists_[edge];
  if (list.count == list.capacity) {  // move the edge's array to the end of the arena, doubled
    const int capacity = list.capacity ? 2 * list.capacity : 4;
    const int start = static_cast<int>(slots_.size());
    slots_.resize(slots_.size() + capacity);
    std::copy(slots_.begin() + list.start, slots_.begin() + list.start + list.count,
              slots_.begin() + start);
    list.start = start;
    list.capacity = capacity;
  }
  EdgeSlot* base = slots_.data() + list.start;
  const EdgeSlot* pos = std::lower_bound(base, base + list.count, lo,
                                         [](const EdgeSlot& s, double x) { return s.lo < x; });
  const int k = static_cast<int>(pos - base);
  std::copy_backward(base + k, base + list.count, base + list.count + 1);
  base[k] = {lo, hi, id};
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

void Propagator::add_window(Window& w) {
  const FaceGeom& f = m_.faces[w.face];
  const int e = w.edge;
  const double length = f.len[e];
  if (w.sy > 0) w.sy = 0;
  if (w.b0 < 0) w.b0 = 0;
  if (w.b1 > length) w.b1 = length;
  if (!(w.b1 > w.b0)) return;
  const double yy = w.sy * w.sy;
  double f0 = w.sigma + std::sqrt((w.b0 - w.sx) * (w.b0 - w.sx) + yy);
  double f1 = w.sigma + std::sqrt((w.b1 - w.sx) * (w.b1 - w.sx) + yy);
  if (!trim_by_endpoints(w, length, dist_[f.v[e]], dist_[f.v[next3(e)]], f0, f1)) return;

  // Rule (M), Mitchell-Mount-Papadimitriou trimming: compare with the windows already on this
  // edge (either side). Where an old window is better the new one is cut away (it may split in
  // pieces); where the new one is better at an end of the old one, the old one is shortened.
  // Everything here is in the edge's own orientation ("canonical"); each edge keeps its windows
  // sorted by start, and they are disjoint except where a new window beat an old one in the
  // middle (the old one is not split): a comparison missed because of such an overlap only
  // prunes less, it never makes the result wrong.
  const int he = 3 * w.face + e;
  const int eid = m_.edge_id[he];
  const bool flip = m_.edge_side[he];
  const double nx = flip ? length - w.sx : w.sx;
  std::array<double, 2 * kMaxPieces> piece;
  int pieces = 1;
  piece[0] = flip ? length - w.b1 : w.b0;
  piece[1] = flip ? length - w.b0 : w.b1;
  EdgeList& list = lists_[eid];
  EdgeSlot* base = slots_.data() + list.start;
  int i = static_cast<int>(std::lower_bound(base, base + list.count, piece[0],
                                            [](const EdgeSlot& s, double x) { return s.lo < x; }) -
                           base);
  while (i > 0 && base[i - 1].hi > piece[0]) --i;
  while (i < list.count && pieces > 0 && base[i].lo < piece[2 * pieces - 1]) {
    double olo = base[i].lo, ohi = base[i].hi;
    if (ohi <= piece[0]) {
      ++i;
      continue;
    }
    Window& o = out_.windows[base[i].id];
    const bool oflip = m_.edge_side[3 * o.face + o.edge];
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
      // Shrink the old window (never beyond what it covers: a trim at its pop may be newer).
      const double b0 = oflip ? length - ohi : olo, b1 = oflip ? length - olo : ohi;
      o.b0 = std::max(o.b0, b0);
      o.b1 = std::min(o.b1, b1);
      if (!(o.b1 > o.b0) || !(ohi > olo)) {
        o.b1 = o.b0;  // emptied
        std::copy(base + i + 1, base + list.count, base + i);
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

  const int vc = f.v[prev3(e)];
  const double cx = f.cx[e], cy = f.cy[e];
  const double tol = kVisibilityTolerance * length;
  const double x = (w.sx * cy - w.sy * cx) / (cy - w.sy);  // crossing of I->C with the edge
  for (int p = 0; p < pieces; ++p) {
    w.b0 = piece[2 * p];
    w.b1 = piece[2 * p + 1];
    if (!(w.b1 > w.b0)) continue;
    double key = w.sigma - w.sy;
    if (w.sx < w.b0) key = w.sigma + std::sqrt((w.b0 - w.sx) * (w.b0 - w.sx) + yy);
    if (w.sx > w.b1) key = w.sigma + std::sqrt((w.b1 - w.sx) * (w.b1 - w.sx) + yy);
    const int id = static_cast<int>(out_.windows.size());
    // Corner C visible through the window: early distance bound and barrier record.
    if (x >= w.b0 - tol && x <= w.b1 + tol) {
      const double dc = w.sigma + hyp(cx - w.sx, cy - w.sy);
      CornerRecord& rec = corner_[he];
      if (dc < rec.d) {
        rec.d = dc;
        rec.x = x;
      }
      relax(vc, dc, id);
    }
    out_.windows.push_back(w);
    double lo, hi;
    canonical(w, lo, hi);
    insert_slot(eid, lo, hi, id);
    heap_.push(key, id);
  }
}

void Propagator::propagate(const Window& w, int id) {
  const FaceGeom& f = m_.faces[w.face];
  const int e = w.edge, e1 = next3(e), e2 = prev3(e);
  const double length = f.len[e], cx = f.cx[e], cy = f.cy[e];
  const double sx = w.sx, sy = w.sy;
  // Crossing of the line I->C with the edge: entries left of it exit through C->A (edge e2),
  // entries right of it through B->C (edge e1).
  const double x = (sx * cy - sy * cx) / (cy - sy);
  double hi_left = std::min(w.b1, x), lo_right = std::max(w.b0, x);
  const CornerRecord& rec = corner_[3 * w.face + e];
  if (rec.d < kInf && rec.d + margin_ < w.sigma + hyp(cx - sx, cy - sy)) {
    hi_left = std::min(hi_left, rec.x);  // barrier X1-C (rule B)
    lo_right = std::max(lo_right, rec.x);
  }
  if (hi_left > w.b0 && f.nbr[e2] >= 0) {
    // Ray through (b,0) meets A + s (C - A) at s = b sy / ((b - sx) cy + sy cx).
    const double l2 = f.len[e2];
    const auto t_of = [&](double b) { return l2 * (b * sy) / ((b - sx) * cy + sy * cx); };
    Window c;
    c.b0 = t_of(w.b0);
    c.b1 = hi_left >= x ? l2 : t_of(hi_left);
    const double ux = f.u2x[e], uy = f.u2y[e];
    c.sx = sx * ux + sy * uy;
    c.sy = ux * sy - uy * sx;
    c.sigma = w.sigma;
    c.face = f.nbr[e2];
    c.edge = f.nbr_edge[e2];
    c.parent = id;
    c.root = w.root;
    c.exit = 2;
    add_window(c);
  }
  if (lo_right < w.b1 && f.nbr[e1] >= 0) {
    // Ray through (b,0) meets B + s (C - B) at s = sy (b - L) / ((b - sx) cy + sy (cx - L)).
    const double l1 = f.len[e1];
    const auto t_of = [&](double b) {
      return l1 * (1.0 - sy * (b - length) / ((b - sx) * cy + sy * (cx - length)));
    };
    Window c;
    c.b0 = lo_right <= x ? 0.0 : t_of(lo_right);
    c.b1 = t_of(w.b1);
    const double ux = f.u1x[e], uy = f.u1y[e];
    const double dx = sx - cx, dy = sy - cy;
    c.sx = dx * ux + dy * uy;
    c.sy = ux * dy - uy * dx;
    c.sigma = w.sigma;
    c.face = f.nbr[e1];
    c.edge = f.nbr_edge[e1];
    c.parent = id;
    c.root = w.root;
    c.exit = 1;
    add_window(c);
  }
}

void Propagator::emit_vertex(int u) {
  emitted_[u] = 1;
  const double du = dist_[u];
  for (int k = m_.vf_start[u]; k < m_.vf_start[u + 1]; ++k) {
    const FaceGeom& g = m_.faces[m_.vf_face[k]];
    const int i = m_.vf_local[k], j = next3(i);
    relax(g.v[j], du + g.len[i], -2 - u);
    relax(g.v[prev3(i)], du + g.len[prev3(i)], -2 - u);
    const int n = g.nbr[j];
    if (n < 0) continue;
    const FaceGeom& nf = m_.faces[n];
    const int ke = g.nbr_edge[j];
    Window w;
    w.b0 = 0;
    w.b1 = nf.len[ke];
    w.sx = nf.ox[ke];
    w.sy = nf.oy[ke];
    w.sigma = du;
    w.face = n;
    w.edge = static_cast<std::int8_t>(ke);
    w.parent = -1;
    w.root = u;
    w.exit = 0;
    add_window(w);
  }
}

/// The source point s lies in face `face` (on its edge `skip_edge` if >= 0): straight segments
/// to the face's corners, and windows onto its other edges.
void Propagator::emit_from_point(const Vec3& s, int face, int skip_edge) {
  const FaceGeom& g = m_.faces[face];
  const auto& P = m_.mesh.vertices;
  for (int i = 0; i < 3; ++i) relax(g.v[i], (P[g.v[i]] - s).norm(), kFromSource);
  for (int j = 0; j < 3; ++j) {
    if (j == skip_edge || g.nbr[j] < 0) continue;
    const int n = g.nbr[j], ke = g.nbr_edge[j];
    const FaceGeom& nf = m_.faces[n];
    const Vec3& a = P[nf.v[ke]];
    const Vec3 ex = (P[nf.v[next3(ke)]] - a) / nf.len[ke];
    const Vec3 d = s - a;
    Window w;
    w.b0 = 0;
    w.b1 = nf.len[ke];
    w.sx = d.dot(ex);
    w.sy = -d.cross(ex).norm();
    w.sigma = 0;
    w.face = n;
    w.edge = static_cast<std::int8_t>(ke);
    w.parent = -1;
    w.root = -1;
    w.exit = 0;
    add_window(w);
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
    emit_vertex(v);
    return;
  }
  const Vec3 p = s.position(mesh);
  if (zeros == 1) {
    int e = 0;
    for (int i = 0; i < 3; ++i)
      if (s.barycentric[i] == 0.0) e = next3(i);  // the edge opposite the zero weight
    const FaceGeom& g = m_.faces[s.face];
    out_.source_faces = {s.face, g.nbr[e]};
    emit_from_point(p, s.face, e);
    if (g.nbr[e] >= 0) emit_from_point(p, g.nbr[e], g.nbr_edge[e]);
  } else {
    out_.source_faces = {s.face, -1};
    emit_from_point(p, s.face, -1);
  }
}

void Propagator::run() {
  const int nv = m_.mesh.vertex_count();
  std::uint64_t events = 0;
  progress_.report("geodesic distances", 0.0);
  while (!heap_.empty()) {
    const RadixHeap::Entry ev = heap_.pop();
    if ((++events & 4095) == 0) {
      progress_.check();
      if ((events & 262143) == 0) {
        int reached = 0;
        for (double d : dist_) reached += d < kInf;
        progress_.report("geodesic distances", nv ? 0.99 * reached / nv : 0.0);
      }
    }
    if (ev.id < 0) {
      const int v = -1 - ev.id;
      if (!emitted_[v]) emit_vertex(v);
      continue;
    }
    const Window w = out_.windows[ev.id];
    if (!(w.b1 > w.b0)) continue;  // emptied by a better window meanwhile
    propagate(w, ev.id);
  }
  progress_.report("geodesic distances", 1.0);
}

// ---------------------------------------------------------------------------------------------
// Queries

void FastField::build_index() {
  const int nf = static_cast<int>(m->faces.size());
  face_start.assign(nf + 1, 0);
  for (const Window& w : windows)
    if (w.b1 > w.b0) ++face_start[w.face + 1];
  for (int f = 0; f < nf; ++f) face_start[f + 1] += face_start[f];
  face_window.resize(face_start[nf]);
  std::vector<int> fill(face_start.begin(), face_start.end() - 1);
  for (int i = 0; i < static_cast<int>(windows.size()); ++i)
    if (windows[i].b1 > windows[i].b0) face_window[fill[windows[i].face]++] = i;
}

SurfacePoint FastField::vertex_point(int v) const {
  SurfacePoint p;
  p.face = m->vf_face[m->vf_start[v]];
  p.barycentric = Vec3::Zero();
  p.barycentric[m->vf_local[m->vf_start[v]]] = 1.0;
  return p;
}

SurfacePoint FastField::edge_point(int face, int edge, double x) const {
  const double s = x / m->faces[face].len[edge];
  SurfacePoint p;
  p.face = face;
  p.barycentric = Vec3::Zero();
  if (s <= 0) {
    p.barycentric[edge] = 1.0;
  } else if (s >= 1) {
    p.barycentric[next3(edge)] = 1.0;
  } else {
    p.barycentric[edge] = 1.0 - s;
    p.barycentric[next3(edge)] = s;
  }
  return p;
}

FastField::Best FastField::locate(const SurfacePoint& target) const {
  const TriangleMesh& mesh = m->mesh;
  const SurfacePoint q = normalize_surface_point(mesh, target, "target");
  Best best;
  const int zeros = zero_weight_count(q);
  if (zeros == 2) {
    const int v = q.vertex(mesh);
    best.d = distances[v];
    best.kind = 1;
    best.index = v;
    return best;
  }
  const Vec3 qp = q.position(mesh);
  // The faces whose closure holds q, with q's weights in each.
  std::array<int, 2> faces = {q.face, -1};
  std::array<Vec3, 2> weights = {q.barycentric, Vec3::Zero()};
  if (zeros == 1) {
    int e = 0;
    for (int i = 0; i < 3; ++i)
      if (q.barycentric[i] == 0.0) e = next3(i);
    const FaceGeom& g = m->faces[q.face];
    if (g.nbr[e] >= 0) {
      faces[1] = g.nbr[e];
      const int k = g.nbr_edge[e];
      weights[1][k] = q.barycentric[next3(e)];
      weights[1][next3(k)] = q.barycentric[e];
    }
  }
  for (int slot = 0; slot < 2; ++slot) {
    const int f = faces[slot];
    if (f < 0) continue;
    const FaceGeom& g = m->faces[f];
    const Vec3& w = weights[slot];
    for (int i = 0; i < 3; ++i) {
      const double d = distances[g.v[i]] + (mesh.vertices[g.v[i]] - qp).norm();
      if (d < best.d) {
        best.d = d;
        best.kind = 1;
        best.index = g.v[i];
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
    for (int e = 0; e < 3; ++e) {
      qx[e] = w[next3(e)] * g.len[e] + w[prev3(e)] * g.cx[e];
      qy[e] = w[prev3(e)] * g.cy[e];
    }
    for (int k = face_start[f]; k < face_start[f + 1]; ++k) {
      const Window& win = windows[face_window[k]];
      const int e = win.edge;
      const double px = qx[e], py = qy[e];
      const double x = py <= 0 ? px : win.sx + (px - win.sx) * (-win.sy) / (py - win.sy);
      const double tol = kVisibilityTolerance * g.len[e];
      if (x < win.b0 - tol || x > win.b1 + tol) continue;
      const double d = win.sigma + hyp(px - win.sx, py - win.sy);
      if (d < best.d) {
        best.d = d;
        best.kind = 0;
        best.index = face_window[k];
        best.qx = px;
        best.qy = py;
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
    throw InvalidInput("shortest path: the target is not reachable from the source");
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
      const FaceGeom& f = m->faces[w.face];
      double x = py <= 0 ? px : w.sx + (px - w.sx) * (-w.sy) / (py - w.sy);
      x = std::clamp(x, w.b0, w.b1);
      out.push_back(edge_point(w.face, w.edge, x));
      if (w.parent < 0) {
        window = -1;
        vertex = w.root;
        if (vertex >= 0) out.push_back(vertex_point(vertex));
        continue;
      }
      const Window& p = windows[w.parent];
      const FaceGeom& pf = m->faces[p.face];
      const int pe = p.edge;
      if (w.exit == 2) {
        px = x * pf.u2x[pe];
        py = x * pf.u2y[pe];
      } else {
        px = pf.cx[pe] + x * pf.u1x[pe];
        py = pf.cy[pe] + x * pf.u1y[pe];
      }
      (void)f;
      window = w.parent;
    } else {
      const int code = provenance[vertex];
      if (code == kFromSource) {
        vertex = -1;
      } else if (code <= -2) {
        vertex = -2 - code;
        out.push_back(vertex_point(vertex));
      } else {
        window = code;
        vertex = -1;
        const Window& w = windows[window];
        px = m->faces[w.face].cx[w.edge];
        py = m->faces[w.face].cy[w.edge];
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

  DistanceField solve(const SurfacePoint& source, const Progress& progress) const override {
    auto field = std::make_shared<FastField>();
    field->m = data_;
    field->source = source;
    thread_local Scratch scratch;
    {
      Propagator run(*data_, *field, progress, scratch);
      run.init(source);
      run.run();
    }
    release_if_large(scratch);
    data_->window_hint.store(field->windows.size() + field->windows.size() / 4,
                             std::memory_order_relaxed);
    field->build_index();
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
