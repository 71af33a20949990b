// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/mesh/mesh_topology.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

std::uint64_t edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

}  // namespace

std::string TopologyProblem::message() const {
  std::ostringstream out;
  switch (kind) {
    case Kind::None:
      return "no problem";
    case Kind::InvalidIndex:
      out << "face " << element << " has an invalid or repeated vertex index";
      break;
    case Kind::NonManifoldEdge:
      out << "non-manifold edge between vertices " << element << " and " << other
          << " (shared by more than two faces)";
      break;
    case Kind::NonManifoldVertex:
      out << "non-manifold vertex " << element << " (its faces do not form a single fan)";
      break;
    case Kind::InconsistentOrientation:
      out << "face " << element << " is oriented against its neighbour";
      break;
  }
  return out.str();
}

std::string TopologyProblem::field() const {
  switch (kind) {
    case Kind::None:
      return "";
    case Kind::InvalidIndex:
    case Kind::InconsistentOrientation:
      return "faces[" + std::to_string(element) + "]";
    case Kind::NonManifoldEdge:
    case Kind::NonManifoldVertex:
      return "vertices[" + std::to_string(element) + "]";
  }
  return "";
}

namespace {

/// Every half-edge f*3+i (from faces[f][i] to faces[f][i+1]) under the key of its undirected
/// edge, sorted by (key, half-edge): the two half-edges of an inner edge are neighbours. Sorting
/// replaced hash maps (and per-vertex maps in the fan check): build_topology and check_manifold
/// took 0.25 s of every 59k-vertex mesh built (load, cut, copies), most of it in allocations.
std::vector<std::pair<std::uint64_t, int>> sorted_half_edges(const std::vector<Face>& faces,
                                                             int nf) {
  std::vector<std::pair<std::uint64_t, int>> half(static_cast<std::size_t>(nf) * 3);
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) {
      const int a = faces[f][i], b = faces[f][(i + 1) % 3];
      half[f * 3 + i] = {edge_key(std::min(a, b), std::max(a, b)), f * 3 + i};
    }
  std::sort(half.begin(), half.end());
  return half;
}

/// Faces around each vertex in increasing face order, as offsets into one list.
struct VertexFaces {
  std::vector<int> offset;  // nv + 1
  std::vector<int> face;
  VertexFaces(int nv, const std::vector<Face>& faces, int nf) : offset(nv + 1, 0) {
    for (int f = 0; f < nf; ++f)
      for (int v : faces[f]) ++offset[v + 1];
    for (int v = 0; v < nv; ++v) offset[v + 1] += offset[v];
    face.resize(offset[nv]);
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int v : faces[f]) face[fill[v]++] = f;
  }
};

}  // namespace

TopologyProblem check_manifold(int nv, const std::vector<Face>& faces) {
  TopologyProblem problem;
  // The first problem in the order of a walk over the faces, checking each face's indices, then
  // its edges i = 0, 1, 2 (an edge in a third face first, then a repeated direction).
  int nf = static_cast<int>(faces.size());
  for (int f = 0; f < nf; ++f) {
    const Face& t = faces[f];
    bool valid = true;
    for (int i = 0; i < 3; ++i)
      if (t[i] < 0 || t[i] >= nv || t[i] == t[(i + 1) % 3]) valid = false;
    if (!valid) {
      problem.kind = TopologyProblem::Kind::InvalidIndex;
      problem.element = f;
      nf = f;  // the edges of the faces before it may hold an earlier problem
      break;
    }
  }
  // Position of an edge problem: half-edge * 2 + (0: third face on the edge, 1: same direction
  // twice); the smallest one is met first.
  std::int64_t first = std::numeric_limits<std::int64_t>::max();
  const auto half = sorted_half_edges(faces, nf);
  for (std::size_t lo = 0; lo < half.size();) {
    std::size_t hi = lo + 1;
    while (hi < half.size() && half[hi].first == half[lo].first) ++hi;
    if (hi - lo > 2) first = std::min<std::int64_t>(first, std::int64_t{half[lo + 2].second} * 2);
    // Same direction twice: the first half-edge (in face order) whose direction came before.
    bool seen[2] = {false, false};
    for (std::size_t k = lo; k < hi; ++k) {
      const int h = half[k].second;
      const int forward = faces[h / 3][h % 3] < faces[h / 3][(h % 3 + 1) % 3];
      if (seen[forward]) {
        first = std::min<std::int64_t>(first, std::int64_t{h} * 2 + 1);
        break;
      }
      seen[forward] = true;
    }
    lo = hi;
  }
  if (first != std::numeric_limits<std::int64_t>::max()) {
    const int h = static_cast<int>(first / 2), a = faces[h / 3][h % 3],
              b = faces[h / 3][(h % 3 + 1) % 3];
    problem = TopologyProblem();
    if (first % 2 == 0) {
      problem.kind = TopologyProblem::Kind::NonManifoldEdge;
      problem.element = std::min(a, b);
      problem.other = std::max(a, b);
    } else {
      problem.kind = TopologyProblem::Kind::InconsistentOrientation;
      problem.element = h / 3;
    }
    return problem;
  }
  if (problem.kind != TopologyProblem::Kind::None) return problem;
  // Vertex manifoldness: the faces around a vertex must form one fan (a single chain or cycle).
  // With every directed edge used once, the "next" vertices (after v) around v are distinct, and
  // so are the "previous" ones.
  const VertexFaces around(nv, faces, nf);
  std::vector<std::pair<int, int>> by_prev, by_next;  // (vertex, position in the fan)
  std::vector<int> nextv, prevv;
  std::vector<char> seen;
  const auto find = [](const std::vector<std::pair<int, int>>& sorted, int vertex) {
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), std::pair{vertex, -1});
    return it != sorted.end() && it->first == vertex ? it->second : -1;
  };
  for (int v = 0; v < nv; ++v) {
    const int begin = around.offset[v], size = around.offset[v + 1] - begin;
    if (size <= 1) continue;
    nextv.resize(size);
    prevv.resize(size);
    by_prev.resize(size);
    by_next.resize(size);
    for (int k = 0; k < size; ++k) {
      const Face& t = faces[around.face[begin + k]];
      const int i = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
      nextv[k] = t[(i + 1) % 3];
      prevv[k] = t[(i + 2) % 3];
      by_prev[k] = {prevv[k], k};
      by_next[k] = {nextv[k], k};
    }
    std::sort(by_prev.begin(), by_prev.end());
    std::sort(by_next.begin(), by_next.end());
    // Walk from a start face (a face whose previous vertex is no face's next, if the fan is open).
    int start = 0;
    for (int k = 0; k < size; ++k)
      if (find(by_next, prevv[k]) < 0) {
        start = k;
        break;
      }
    seen.assign(size, 0);
    int visited = 0;
    for (int k = start; k >= 0 && !seen[k]; k = find(by_prev, nextv[k])) {
      seen[k] = 1;
      ++visited;
    }
    if (visited != size) {
      problem.kind = TopologyProblem::Kind::NonManifoldVertex;
      problem.element = v;
      return problem;
    }
  }
  return problem;
}

MeshTopology build_topology(int nv, const std::vector<Face>& faces) {
  const TopologyProblem problem = check_manifold(nv, faces);
  if (problem.kind != TopologyProblem::Kind::None)
    throw InvalidInput(problem.field(), problem.message());
  const int nf = static_cast<int>(faces.size());
  MeshTopology top;
  top.face_neighbors.assign(nf, {-1, -1, -1});
  top.is_boundary_vertex.assign(nv, 0);
  {
    const VertexFaces around(nv, faces, nf);
    top.vertex_faces.resize(nv);
    for (int v = 0; v < nv; ++v)
      top.vertex_faces[v].assign(around.face.begin() + around.offset[v],
                                 around.face.begin() + around.offset[v + 1]);
  }
  std::vector<int> boundary_next(nv, -1);  // boundary vertex a -> b along a boundary edge
  const auto half = sorted_half_edges(faces, nf);
  for (std::size_t lo = 0; lo < half.size();) {
    if (lo + 1 < half.size() && half[lo + 1].first == half[lo].first) {  // an inner edge
      const int h = half[lo].second, g = half[lo + 1].second;
      top.face_neighbors[h / 3][h % 3] = g / 3;
      top.face_neighbors[g / 3][g % 3] = h / 3;
      lo += 2;
    } else {
      const int h = half[lo].second, a = faces[h / 3][h % 3], b = faces[h / 3][(h % 3 + 1) % 3];
      top.is_boundary_vertex[a] = top.is_boundary_vertex[b] = 1;
      boundary_next[a] = b;
      lo += 1;
    }
  }
  std::vector<char> used(nv, 0);
  for (int s = 0; s < nv; ++s) {
    if (boundary_next[s] < 0 || used[s]) continue;
    std::vector<int> loop;
    int v = s;
    while (v >= 0 && !used[v]) {
      used[v] = 1;
      loop.push_back(v);
      v = boundary_next[v];
    }
    top.boundary_loops.push_back(std::move(loop));
  }
  return top;
}

}  // namespace gridshell
