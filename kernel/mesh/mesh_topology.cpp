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

TopologyProblem check_manifold(const TriangleMesh& mesh) {
  TopologyProblem problem;
  const int nv = mesh.vertex_count();
  std::unordered_map<std::uint64_t, int> directed;  // directed edge -> count
  std::unordered_map<std::uint64_t, int> undirected;
  directed.reserve(mesh.faces.size() * 3);
  undirected.reserve(mesh.faces.size() * 3);
  for (int f = 0; f < mesh.face_count(); ++f) {
    const Face& t = mesh.faces[f];
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
  for (int f = 0; f < mesh.face_count(); ++f)
    for (int v : mesh.faces[f]) vertex_faces[v].push_back(f);
  for (int v = 0; v < nv; ++v) {
    const auto& faces = vertex_faces[v];
    if (faces.size() <= 1) continue;
    // For each incident face: the "next" vertex (after v) and "previous" vertex (before v).
    std::unordered_map<int, int> next_of_prev;  // prev vertex -> face index in list
    std::vector<int> nextv(faces.size()), prevv(faces.size());
    for (size_t k = 0; k < faces.size(); ++k) {
      const Face& t = mesh.faces[faces[k]];
      const int i = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
      nextv[k] = t[(i + 1) % 3];
      prevv[k] = t[(i + 2) % 3];
      next_of_prev[prevv[k]] = static_cast<int>(k);
    }
    // Walk from a start face (a face whose next vertex is no one's prev, if the fan is open).
    std::unordered_map<int, int> by_next;
    for (size_t k = 0; k < faces.size(); ++k) by_next[nextv[k]] = static_cast<int>(k);
    int start = 0;
    for (size_t k = 0; k < faces.size(); ++k)
      if (!by_next.count(prevv[k])) {
        start = static_cast<int>(k);
        break;
      }
    size_t visited = 0;
    int k = start;
    std::vector<char> seen(faces.size(), 0);
    while (k >= 0 && !seen[k]) {
      seen[k] = 1;
      ++visited;
      auto it = next_of_prev.find(nextv[k]);
      k = it == next_of_prev.end() ? -1 : it->second;
    }
    if (visited != faces.size()) {
      problem.kind = TopologyProblem::Kind::NonManifoldVertex;
      problem.element = v;
      return problem;
    }
  }
  return problem;
}

MeshTopology build_topology(const TriangleMesh& mesh) {
  const TopologyProblem problem = check_manifold(mesh);
  if (problem.kind != TopologyProblem::Kind::None) throw InvalidInput(problem.message());
  const int nv = mesh.vertex_count(), nf = mesh.face_count();
  MeshTopology top;
  top.face_neighbors.assign(nf, {-1, -1, -1});
  top.vertex_faces.assign(nv, {});
  top.is_boundary_vertex.assign(nv, 0);
  std::unordered_map<std::uint64_t, int> half;  // directed edge -> face*3+i
  half.reserve(nf * 3);
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) {
      half[edge_key(mesh.faces[f][i], mesh.faces[f][(i + 1) % 3])] = f * 3 + i;
      top.vertex_faces[mesh.faces[f][i]].push_back(f);
    }
  std::unordered_map<int, int> boundary_next;  // boundary vertex a -> b along a boundary edge
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) {
      const int a = mesh.faces[f][i], b = mesh.faces[f][(i + 1) % 3];
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

std::array<int, 2> find_edge(const TriangleMesh& mesh, const MeshTopology& topology, int a, int b) {
  if (a < 0 || a >= mesh.vertex_count()) return {-1, -1};
  for (int f : topology.vertex_faces[a]) {
    const Face& t = mesh.faces[f];
    for (int i = 0; i < 3; ++i) {
      const int x = t[i], y = t[(i + 1) % 3];
      if ((x == a && y == b) || (x == b && y == a)) return {f, i};
    }
  }
  return {-1, -1};
}

}  // namespace gridshell
