// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/mesh/mesh_topology.h"

#include <algorithm>
#include <map>
#include <sstream>
#include <unordered_map>

#include "gridshell/mesh/errors.h"

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

TopologyProblem check_manifold(int nv, const std::vector<Face>& faces) {
  TopologyProblem problem;
  const int nf = static_cast<int>(faces.size());
  std::unordered_map<std::uint64_t, int> directed;  // directed edge -> count
  std::unordered_map<std::uint64_t, int> undirected;
  directed.reserve(faces.size() * 3);
  undirected.reserve(faces.size() * 3);
  for (int f = 0; f < nf; ++f) {
    const Face& t = faces[f];
    for (int i = 0; i < 3; ++i) {
      if (t[i] < 0 || t[i] >= nv || t[i] == t[(i + 1) % 3]) {
        problem.kind = TopologyProblem::Kind::InvalidIndex;
        problem.element = f;
        return problem;
      }
    }
    for (int i = 0; i < 3; ++i) {
      const int a = t[i], b = t[(i + 1) % 3];
      if (++undirected[edge_key(std::min(a, b), std::max(a, b))] > 2) {
        problem.kind = TopologyProblem::Kind::NonManifoldEdge;
        problem.element = std::min(a, b);
        problem.other = std::max(a, b);
        return problem;
      }
      if (++directed[edge_key(a, b)] > 1) {
        problem.kind = TopologyProblem::Kind::InconsistentOrientation;
        problem.element = f;
        return problem;
      }
    }
  }
  // Vertex manifoldness: the faces around a vertex must form one fan (a single chain or cycle).
  std::vector<std::vector<int>> vertex_faces(nv);
  for (int f = 0; f < nf; ++f)
    for (int v : faces[f]) vertex_faces[v].push_back(f);
  for (int v = 0; v < nv; ++v) {
    const auto& fan = vertex_faces[v];
    if (fan.size() <= 1) continue;
    // For each incident face: the "next" vertex (after v) and "previous" vertex (before v).
    std::unordered_map<int, int> next_of_prev;  // prev vertex -> face index in list
    std::vector<int> nextv(fan.size()), prevv(fan.size());
    for (size_t k = 0; k < fan.size(); ++k) {
      const Face& t = faces[fan[k]];
      const int i = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
      nextv[k] = t[(i + 1) % 3];
      prevv[k] = t[(i + 2) % 3];
      next_of_prev[prevv[k]] = static_cast<int>(k);
    }
    // Walk from a start face (a face whose next vertex is no one's prev, if the fan is open).
    std::unordered_map<int, int> by_next;
    for (size_t k = 0; k < fan.size(); ++k) by_next[nextv[k]] = static_cast<int>(k);
    int start = 0;
    for (size_t k = 0; k < fan.size(); ++k)
      if (!by_next.count(prevv[k])) {
        start = static_cast<int>(k);
        break;
      }
    size_t visited = 0;
    int k = start;
    std::vector<char> seen(fan.size(), 0);
    while (k >= 0 && !seen[k]) {
      seen[k] = 1;
      ++visited;
      auto it = next_of_prev.find(nextv[k]);
      k = it == next_of_prev.end() ? -1 : it->second;
    }
    if (visited != fan.size()) {
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
  top.vertex_faces.assign(nv, {});
  top.is_boundary_vertex.assign(nv, 0);
  std::unordered_map<std::uint64_t, int> half;  // directed edge -> face*3+i
  half.reserve(nf * 3);
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) {
      half[edge_key(faces[f][i], faces[f][(i + 1) % 3])] = f * 3 + i;
      top.vertex_faces[faces[f][i]].push_back(f);
    }
  std::unordered_map<int, int> boundary_next;  // boundary vertex a -> b along a boundary edge
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) {
      const int a = faces[f][i], b = faces[f][(i + 1) % 3];
      auto it = half.find(edge_key(b, a));
      if (it != half.end()) {
        top.face_neighbors[f][i] = it->second / 3;
      } else {
        top.is_boundary_vertex[a] = top.is_boundary_vertex[b] = 1;
        boundary_next[a] = b;
      }
    }
  std::vector<char> used(nv, 0);
  std::vector<int> starts;
  for (const auto& [a, b] : boundary_next) starts.push_back(a);
  std::sort(starts.begin(), starts.end());
  for (int s : starts) {
    if (used[s]) continue;
    std::vector<int> loop;
    int v = s;
    while (!used[v]) {
      used[v] = 1;
      loop.push_back(v);
      v = boundary_next.at(v);
    }
    top.boundary_loops.push_back(std::move(loop));
  }
  return top;
}

}  // namespace gridshell
