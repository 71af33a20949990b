// SPDX-License-Identifier: GPL-3.0-or-later
#include "support.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>

namespace gridshell::testing {
namespace fs = std::filesystem;

namespace {
struct TempRoot {
  fs::path root;
  TempRoot() {
    std::string pattern = (fs::temp_directory_path() / "gridshell-test-XXXXXX").string();
    root = mkdtemp(pattern.data());
  }
  ~TempRoot() {
    std::error_code ignored;
    fs::remove_all(root, ignored);
  }
};
TempRoot& temp_root() {
  static TempRoot root;
  return root;
}
}  // namespace

std::string test_mesh_path(const std::string& name) {
  return (fs::path(GRIDSHELL_TEST_DATA_DIR) / "meshes" / name).string();
}

std::vector<std::string> test_mesh_paths() {
  const fs::path dir = fs::path(GRIDSHELL_TEST_DATA_DIR) / "meshes";
  return {(dir / "enneper2.obj").string(), (dir / "knet1.obj").string(),
          (dir / "pillow_1.obj").string()};
}

std::string temp_dir() {
  static std::mutex mutex;
  static int counter = 0;
  std::lock_guard lock(mutex);
  fs::path dir = temp_root().root / std::to_string(counter++);
  fs::create_directories(dir);
  return dir.string();
}

std::string sphere_layout_json() {
  std::string corners;
  for (int j : {0, 16, 32})
    for (int i : {0, 16, 32})
      corners += (corners.empty() ? "" : ",") + std::string("{\"vertex\":") +
                 std::to_string(j * 33 + i) + "}";
  return "{\"corners\":[" + corners +
         "],\"patches\":[{\"corners\":[0,1,4,3]},{\"corners\":[1,2,5,4]},"
         "{\"corners\":[3,4,7,6]},{\"corners\":[4,5,8,7]}]}";
}

std::string write_text(const std::string& dir, const std::string& name,
                       const std::string& contents) {
  const std::string path = (fs::path(dir) / name).string();
  std::ofstream(path, std::ios::binary) << contents;
  return path;
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;  // vertex region a
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;  // vertex region b
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;  // edge ab
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;  // vertex region c
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;  // edge ac
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)  // edge bc
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denominator = 1.0 / (va + vb + vc);  // inside the face
  return a + ab * (vb * denominator) + ac * (vc * denominator);
}

double brute_force_distance(const TriangleMesh& mesh, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  const auto& x = mesh.vertices();
  for (const Face& f : mesh.faces())
    best =
        std::min(best, (p - closest_point_on_triangle(p, x[f[0]], x[f[1]], x[f[2]])).squaredNorm());
  return std::sqrt(best);
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

TriangleMesh grid_mesh(int nu, int nv, const std::function<Vec3(double u, double v)>& map) {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) vertices.push_back(map(double(i) / nu, double(j) / nv));
  auto id = [nu](int i, int j) { return j * (nu + 1) + i; };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        faces.push_back({a, b, c});
        faces.push_back({a, c, d});
      } else {
        faces.push_back({a, b, d});
        faces.push_back({b, c, d});
      }
    }
  return TriangleMesh(std::move(vertices), std::move(faces));
}

TriangleMesh flat_square(int n) {
  return grid_mesh(n, n, [n](double u, double v) {
    const bool interior = u > 0 && u < 1 && v > 0 && v < 1;
    const double jitter = interior ? 0.3 / n : 0.0;
    return Vec3(10 * u + jitter * std::sin(37 * u + 11 * v),
                10 * v + jitter * std::cos(19 * u - 7 * v), 0);
  });
}

TriangleMesh bump(int n) {
  return grid_mesh(n, n, [](double u, double v) {
    const double x = 10 * u, y = 10 * v;
    return Vec3(x, y, 2.5 * std::exp(-((x - 5) * (x - 5) + (y - 5) * (y - 5)) / 8));
  });
}

TriangleMesh icosphere(int subdivisions, double radius) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> vertices = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Face> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                             {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                             {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                             {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (Vec3& v : vertices) v = radius * v.normalized();
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<int, int>, int> midpoint;
    auto middle = [&](int a, int b) {
      const std::pair<int, int> key{std::min(a, b), std::max(a, b)};
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      vertices.push_back(radius * (vertices[a] + vertices[b]).normalized());
      const int index = static_cast<int>(vertices.size()) - 1;
      midpoint[key] = index;
      return index;
    };
    std::vector<Face> finer;
    for (const Face& f : faces) {
      const int ab = middle(f[0], f[1]), bc = middle(f[1], f[2]), ca = middle(f[2], f[0]);
      finer.push_back({f[0], ab, ca});
      finer.push_back({f[1], bc, ab});
      finer.push_back({f[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    faces = std::move(finer);
  }
  return TriangleMesh(std::move(vertices), std::move(faces));
}

TriangleMesh annulus(double r0, double r1, int rings, int sectors) {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      const double r = r0 + (r1 - r0) * i / rings, angle = 2 * M_PI * j / sectors;
      vertices.push_back(Vec3(r * std::cos(angle), r * std::sin(angle), 0));
    }
  auto id = [sectors](int i, int j) { return i * sectors + (j % sectors); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      // (radius, angle) is counter-clockwise seen from +z.
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      faces.push_back({a, b, c});
      faces.push_back({a, c, d});
    }
  return TriangleMesh(std::move(vertices), std::move(faces));
}

TriangleMesh torus(double major, double minor, int nu, int nv) {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      vertices.push_back(Vec3((major + minor * std::cos(v)) * std::cos(u),
                              (major + minor * std::cos(v)) * std::sin(u), minor * std::sin(v)));
    }
  auto id = [&](int i, int j) { return (j % nv) * nu + (i % nu); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return TriangleMesh(std::move(vertices), std::move(faces));
}

CommandResult run_cli(const std::string& arguments) {
  return run_command(std::string("'") + GRIDSHELL_CLI + "' " + arguments);
}

CommandResult run_command(const std::string& command_line) {
  const std::string dir = temp_dir();
  const std::string out_path = dir + "/stdout", err_path = dir + "/stderr";
  const std::string command = command_line + " >'" + out_path + "' 2>'" + err_path + "' </dev/null";
  const int status = std::system(command.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = read_text(out_path);
  result.err = read_text(err_path);
  return result;
}

std::vector<Vec3> sample_triangles(const std::vector<std::array<Vec3, 3>>& triangles, int count,
                                   std::mt19937_64& random) {
  std::uniform_real_distribution<double> uniform(0, 1);
  std::vector<double> cumulative;
  double area = 0;
  for (const auto& t : triangles)
    cumulative.push_back(area += 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).norm());
  std::vector<Vec3> points;
  points.reserve(count);
  for (int i = 0; i < count; ++i) {
    const size_t f =
        std::lower_bound(cumulative.begin(), cumulative.end(), uniform(random) * area) -
        cumulative.begin();
    const auto& t = triangles[std::min(f, triangles.size() - 1)];
    double a = uniform(random), b = uniform(random);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    points.push_back(t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]));
  }
  return points;
}

}  // namespace gridshell::testing
