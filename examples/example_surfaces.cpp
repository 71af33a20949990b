// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — analytic example surfaces.
//
// Every example is a smooth surface S(u, v) over the unit parameter square, sampled on an
// nu x nv grid and triangulated as a disk: one boundary loop, faces counter-clockwise seen from
// above (S_u x S_v points up, +z), so every face normal has a positive z component. The sample
// counts nu, nv are odd so that the grid has a centre vertex and all four corner cells are split
// through their corner vertex (no corner "ear" triangle).
//
// Triangulation: the "4-8" pattern. Cell (i, j) is split along its main diagonal
// (i, j)-(i+1, j+1) when i + j is even and along the other one when i + j is odd, so diagonals
// alternate like a checkerboard; interior vertices have valence 4 or 8 and the mesh has no
// directional bias. The flat `plane` is the exception: jittered vertices, each cell split along
// the diagonal that maximises its smallest angle.
//
// Placement: the seven paper models are scaled per axis so that their bounding box is exactly
// Table 1's width x depth x height (Pillwein et al. 2020; the table's values are dimensionless).
// The analytic cases (cylinder, cone, hypar, plane) are never scaled, so that their formulas, and
// the developability of cylinder and cone, hold exactly. Every example is finally translated so
// that its bounding box is centred on the z axis with its lowest point at z = 0.
//
// Suggested corners: the four corners of the parameter square, listed counter-clockwise seen from
// above, i.e. in the order of the boundary loop: S(0,0), S(1,0), S(1,1), S(0,1).
#include "gridshell/example_surfaces.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>

#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

/// Largest accepted `resolution_scale` (the biggest model, waves-bump, then has ~3.5M vertices).
constexpr double kMaxResolutionScale = 32.0;

/// A surface point from parameters (u, v) in [0,1]^2; u runs roughly along +x, v along +y.
using Parametrization = std::function<Vec3(double u, double v)>;

/// Odd number of samples closest to base * scale, at least 3 (one interior row).
/// Scales the number of intervals (base - 1), so vertex counts grow with scale^2.
int scaled_samples(int base, double scale) {
  const double intervals = (base - 1) * scale;
  const long even = 2 * std::lround(intervals / 2.0);
  return static_cast<int>(std::max<long>(even, 2)) + 1;
}

int grid_index(int nu, int i, int j) { return i + nu * j; }

/// Samples S on an nu x nv grid (vertex (i, j) at u = i/(nu-1), v = j/(nv-1), index i + nu*j).
std::vector<Vec3> sample_grid(int nu, int nv, const Parametrization& surface) {
  std::vector<Vec3> vertices;
  vertices.reserve(static_cast<std::size_t>(nu) * nv);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i)
      vertices.push_back(
          surface(static_cast<double>(i) / (nu - 1), static_cast<double>(j) / (nv - 1)));
  return vertices;
}

/// Appends the two counter-clockwise (in the parameter plane) triangles of cell (i, j), split
/// along the main diagonal (i,j)-(i+1,j+1) or along the anti-diagonal (i+1,j)-(i,j+1).
void add_cell(std::vector<Face>& faces, int nu, int i, int j, bool main_diagonal) {
  const int a = grid_index(nu, i, j), b = grid_index(nu, i + 1, j);
  const int c = grid_index(nu, i + 1, j + 1), d = grid_index(nu, i, j + 1);
  if (main_diagonal) {
    faces.push_back({a, b, c});
    faces.push_back({a, c, d});
  } else {
    faces.push_back({a, b, d});
    faces.push_back({b, c, d});
  }
}

/// 4-8 (checkerboard-diagonal) triangulation of the nu x nv grid.
std::vector<Face> four_eight_faces(int nu, int nv) {
  std::vector<Face> faces;
  faces.reserve(2 * static_cast<std::size_t>(nu - 1) * (nv - 1));
  for (int j = 0; j + 1 < nv; ++j)
    for (int i = 0; i + 1 < nu; ++i) add_cell(faces, nu, i, j, (i + j) % 2 == 0);
  return faces;
}

TriangleMesh grid_mesh(int nu, int nv, const Parametrization& surface) {
  return TriangleMesh(sample_grid(nu, nv, surface), four_eight_faces(nu, nv));
}

std::array<int, 4> grid_corners(int nu, int nv) {
  return {grid_index(nu, 0, 0), grid_index(nu, nu - 1, 0), grid_index(nu, nu - 1, nv - 1),
          grid_index(nu, 0, nv - 1)};
}

/// Translates the mesh so that its bounding box is centred on the z axis and starts at z = 0.
void place_on_ground(TriangleMesh& mesh) {
  Vec3 lo = mesh.vertices().front(), hi = lo;
  for (const Vec3& p : mesh.vertices()) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 shift(-(lo.x() + hi.x()) / 2, -(lo.y() + hi.y()) / 2, -lo.z());
  std::vector<Vec3> moved = mesh.vertices();
  for (Vec3& p : moved) p += shift;
  mesh.set_vertices(std::move(moved));
}

/// Scales each axis so that the bounding box is exactly `size`, then places it on the ground.
void fit_bounding_box(TriangleMesh& mesh, const Vec3& size) {
  const Vec3 current = bounding_box_size(mesh);
  const Vec3 factor = size.cwiseQuotient(current);
  std::vector<Vec3> scaled = mesh.vertices();
  for (Vec3& p : scaled) p = p.cwiseProduct(factor);
  mesh.set_vertices(std::move(scaled));
  place_on_ground(mesh);
}

/// Bounding box of a Table 1 model (width x depth x height; the table is dimensionless).
struct PaperModel {
  double width, depth, height;
};

ExampleSurface paper_model(const char* name, const char* description, const PaperModel& table,
                           int base_nu, int base_nv, double scale, const Parametrization& shape) {
  const int nu = scaled_samples(base_nu, scale), nv = scaled_samples(base_nv, scale);
  ExampleSurface example{name, description, grid_mesh(nu, nv, shape), grid_corners(nu, nv)};
  fit_bounding_box(example.mesh, Vec3(table.width, table.depth, table.height));
  return example;
}

// ---------------------------------------------------------------------------------------------
// The paper's seven models. Each is defined on normalised coordinates (xi, eta) = (u, v) in
// [0,1]^2 or on angles, and is then scaled per axis to Table 1's bounding box.
// ---------------------------------------------------------------------------------------------

/// Torus Wide (Table 1: 100 x 61.9 x 27.2, |M_V| 2122). The upper half of a torus tube, a wide
/// strip over the top of the ring: with major radius R = 4, tube radius r = 1,
///   theta in [-0.42, 0.42] (around the ring, u), phi in [pi - 0.1, 0.1] (across the tube, v),
///   rho = R + r cos(phi),  S = (rho sin(theta), rho cos(theta), r sin(phi)).
/// The outer half of the strip has K > 0, the inner half K < 0. R = 4 rather than a tighter ring:
/// with R = 2.25 the inner side was 2.6 times shorter than the outer one and no planar angle
/// made both cladding functions valid (the planar corner angles at c2, c3 could not reach the
/// surface ones); with R = 4 the design is feasible. Scaled per axis to the table's box.
ExampleSurface torus_wide(double scale) {
  constexpr double R = 4.0, r = 1.0, theta0 = 0.42, phi0 = 0.1;
  return paper_model(
      "torus-wide",
      "Torus Wide: a wide strip over the top of a torus tube (K>0 outside, K<0 inside)",
      {100.0, 61.9, 27.2}, 43, 49, scale, [=](double u, double v) {
        const double theta = -theta0 + 2 * theta0 * u;
        const double phi = (kPi - phi0) - v * (kPi - 2 * phi0);
        const double rho = R + r * std::cos(phi);
        return Vec3(rho * std::sin(theta), rho * std::cos(theta), r * std::sin(phi));
      });
}

/// Waves Bump (Table 1: 100 x 100 x 12.7, |M_V| 3385). Two crossing cosine wave trains of two
/// periods each plus a Gaussian bump in the middle: with x = xi - 1/2, y = eta - 1/2,
///   z = (cos(4 pi x) + cos(4 pi y)) / 2 + 1.2 exp(-(x^2 + y^2) / (2 * 0.12^2)).
ExampleSurface waves_bump(double scale) {
  return paper_model("waves-bump",
                     "Waves Bump: crossing cosine waves with a Gaussian bump in the middle",
                     {100.0, 100.0, 12.7}, 59, 59, scale, [](double u, double v) {
                       const double x = u - 0.5, y = v - 0.5;
                       const double waves = 0.5 * (std::cos(4 * kPi * x) + std::cos(4 * kPi * y));
                       const double bump = 1.2 * std::exp(-(x * x + y * y) / (2 * 0.12 * 0.12));
                       return Vec3(u, v, waves + bump);
                     });
}

/// Sphere (Table 1: 100 x 100 x 29.9, |M_V| 1083). A spherical cap over the square
/// [-50, 50]^2 whose height above the corners is h = 29.9:
///   z = sqrt(R^2 - x^2 - y^2),  R = (50^2 + 50^2 + h^2) / (2 h) = 98.56.
/// The grid samples the centre and the corners, so the final per-axis scale is the identity
/// (up to rounding) and the cap stays a true sphere.
ExampleSurface sphere(double scale) {
  constexpr double half = 50.0, h = 29.9;
  constexpr double R = (2 * half * half + h * h) / (2 * h);
  return paper_model("sphere", "Sphere: a spherical cap (radius 98.6) over a 100 x 100 square",
                     {100.0, 100.0, h}, 33, 33, scale, [=](double u, double v) {
                       const double x = (2 * u - 1) * half, y = (2 * v - 1) * half;
                       return Vec3(x, y, std::sqrt(R * R - x * x - y * y));
                     });
}

/// A row of n vaults along x: an arch sin(pi eta) across the depth whose crown height varies
/// along the width with n humps,
///   z = sin(pi eta) * (a + (1 - a) sin^2(n pi xi)),   a = 0.55,
/// so each bay is a dome-like vault and neighbouring bays meet in a saddle.
Parametrization vault_row(int n) {
  return [n](double u, double v) {
    constexpr double a = 0.55;
    const double hump = std::sin(n * kPi * u);
    return Vec3(u, v, std::sin(kPi * v) * (a + (1 - a) * hump * hump));
  };
}

/// Double Vault (Table 1: 100 x 51.7 x 14.6, |M_V| 571): vault_row(2), see there.
ExampleSurface double_vault(double scale) {
  return paper_model("double-vault", "Double Vault: two vaults side by side meeting in a saddle",
                     {100.0, 51.7, 14.6}, 33, 17, scale, vault_row(2));
}

/// Waves (Table 1: 100 x 65.5 x 15.1, |M_V| 1929). A wave train of 1.25 periods along the
/// width whose crests meander across the depth:
///   z = sin(2.5 pi xi - pi/4 + 0.6 sin(2 pi eta)).
ExampleSurface waves(double scale) {
  return paper_model("waves", "Waves: a sine wave train along the width with meandering crests",
                     {100.0, 65.5, 15.1}, 55, 35, scale, [](double u, double v) {
                       return Vec3(u, v,
                                   std::sin(2.5 * kPi * u - kPi / 4 + 0.6 * std::sin(2 * kPi * v)));
                     });
}

/// Archway (Table 1: 100 x 58 x 20.7, |M_V| 975). A barrel arch spanning the depth whose
/// crown dips towards the middle of its length (K > 0 near the ends, K < 0 in the middle):
///   z = sin(pi eta) * (1 - 0.35 sin^2(pi xi)).
ExampleSurface archway(double scale) {
  return paper_model("archway", "Archway: a barrel arch whose crown dips towards the middle",
                     {100.0, 58.0, 20.7}, 39, 25, scale, [](double u, double v) {
                       const double s = std::sin(kPi * u);
                       return Vec3(u, v, std::sin(kPi * v) * (1 - 0.35 * s * s));
                     });
}

/// Triple Vault (Table 1: 100 x 42.8 x 16.3, |M_V| 1322): vault_row(3), see there.
ExampleSurface triple_vault(double scale) {
  return paper_model("triple-vault", "Triple Vault: three vaults in a row meeting in saddles",
                     {100.0, 42.8, 16.3}, 57, 23, scale, vault_row(3));
}

// ---------------------------------------------------------------------------------------------
// Analytic test cases: exact formulas, translated but never scaled.
// ---------------------------------------------------------------------------------------------

ExampleSurface analytic(const char* name, const char* description, int base_nu, int base_nv,
                        double scale, const Parametrization& shape) {
  const int nu = scaled_samples(base_nu, scale), nv = scaled_samples(base_nv, scale);
  ExampleSurface example{name, description, grid_mesh(nu, nv, shape), grid_corners(nu, nv)};
  place_on_ground(example.mesh);
  return example;
}

/// Cylinder (developable): a circular barrel with axis along y, radius R = 62.5, spanning
/// theta in [-theta0, theta0], theta0 = 2 atan(1/2) (so the chord is 100 and the rise 25), and
/// 70 along the axis:
///   S = (R sin(theta), y, R cos(theta)),  y in [0, 70].
/// Grid lines follow the rulings, so every cell is a planar rectangle and the triangle mesh is
/// exactly developable (angle sum 2 pi at interior vertices).
ExampleSurface cylinder(double scale) {
  constexpr double R = 62.5, depth = 70.0;
  const double theta0 = 2 * std::atan(0.5);
  return analytic("cylinder",
                  "Cylinder: part of a circular barrel (R 62.5), 100 x 70 x 25, developable", 49,
                  31, scale, [=](double u, double v) {
                    const double theta = -theta0 + 2 * theta0 * u;
                    return Vec3(R * std::sin(theta), depth * v, R * std::cos(theta));
                  });
}

/// Cone (developable): a circular cone with apex at the origin, axis direction (0, 1, k) tilted so
/// that its crown ruling is horizontal, half-opening atan(k), k = 0.5. Before the tilt,
///   S = (k t sin(theta), t, k t cos(theta)),  theta in [-1, 1],  t in [60, 118.8],
/// then rotated about the x axis by -atan(k). The apex (t = 0) lies 67 units outside the patch.
/// Grid lines are rulings (theta = const) and circles (t = const), so every cell is a planar
/// isosceles trapezoid and the mesh is exactly developable. About 100 x 71.9 x 24.4; the patch
/// flares from radius 30 to 59.4.
ExampleSurface cone(double scale) {
  constexpr double k = 0.5, theta0 = 1.0, t0 = 60.0, t1 = 118.8;
  const double alpha = std::atan(k);
  const double ca = std::cos(alpha), sa = std::sin(alpha);
  ExampleSurface example =
      analytic("cone", "Cone: part of a flaring cone with a level crown, apex outside, developable",
               45, 33, scale, [=](double u, double v) {
                 const double theta = -theta0 + 2 * theta0 * u;
                 const double t = t0 + (t1 - t0) * v;
                 const double x = k * t * std::sin(theta), y = t, z = k * t * std::cos(theta);
                 return Vec3(x, y * ca + z * sa, -y * sa + z * ca);
               });
  // Developed, the cone is an annulus sector (half angle theta0 sin(alpha) at the apex). The
  // inner arc t = t0 is concave, so the straight line between corners on it would leave the
  // patch and the boundary geodesic would hug the arc instead. The near corners are therefore
  // moved out along the rulings to the first row t with t cos(theta0 sin(alpha)) > t0, where
  // the chord between them clears the inner arc.
  const int nu = scaled_samples(45, scale), nv = scaled_samples(33, scale);
  const double t_min = t0 / std::cos(theta0 * sa);
  int row = static_cast<int>(std::ceil((t_min - t0) / (t1 - t0) * (nv - 1)));
  while (t0 + (t1 - t0) * row / (nv - 1.0) <= t_min) ++row;
  example.corners[0] = row * nu;
  example.corners[1] = row * nu + nu - 1;
  return example;
}

/// Hyperbolic paraboloid (saddle, K < 0 everywhere):
///   z = c x y,  c = 0.02,  over the square |x| + |y| <= 50 (a diamond).
/// The grid is aligned with the principal directions x = +-y, i.e. rotated by 45 degrees against
/// the straight rulings x = const, y = const: a grid along the rulings would give the valence-4
/// vertices of the 4-8 triangulation an angle sum of exactly 2 pi. Bounding box 100 x 100 x 25
/// (z in [-12.5, 12.5] before the shift to z >= 0). Corners at the diamond's tips.
ExampleSurface hypar(double scale) {
  constexpr double c = 0.02, half_diagonal = 50.0;
  return analytic("hypar", "Hypar: hyperbolic paraboloid z = 0.02 x y over a diamond, saddle", 41,
                  41, scale, [=](double u, double v) {
                    // (p, q) in [-1/2, 1/2]^2 rotated by 45 degrees onto the diamond.
                    const double p = u - 0.5, q = v - 0.5;
                    const double x = (p - q) * half_diagonal, y = (p + q) * half_diagonal;
                    return Vec3(x, y, c * x * y);
                  });
}

/// Plane (flat, z = 0): a 100 x 80 rectangle with an irregular triangulation. Interior grid
/// vertices are jittered by up to +-0.2 of the spacing in x and y, boundary vertices (except
/// corners) by up to +-0.2 of the spacing along their side; each cell is split along the
/// diagonal that maximises the cell's smallest angle. Jitter comes from a fixed-seed mt19937, so
/// the mesh is the same on every platform.
ExampleSurface plane(double scale) {
  constexpr double width = 100.0, depth = 80.0, jitter = 0.2;
  const int nu = scaled_samples(43, scale), nv = scaled_samples(35, scale);
  const double hx = width / (nu - 1), hy = depth / (nv - 1);
  std::mt19937 random(20200719u);
  const auto uniform = [&random] {  // in [-1, 1), platform independent
    return 2.0 * (static_cast<double>(random()) / 4294967296.0) - 1.0;
  };
  std::vector<Vec3> vertices;
  vertices.reserve(static_cast<std::size_t>(nu) * nv);
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      const double dx = jitter * hx * uniform(), dy = jitter * hy * uniform();
      const bool side_x = i == 0 || i == nu - 1, side_y = j == 0 || j == nv - 1;
      double x = i * hx, y = j * hy;
      if (!side_x) x += dx;  // interior and bottom/top sides move in x
      if (!side_y) y += dy;  // interior and left/right sides move in y
      vertices.emplace_back(x, y, 0.0);
    }
  }
  const auto smallest_angle = [&vertices](int a, int b, int c) {
    const Vec3 p[3] = {vertices[a], vertices[b], vertices[c]};
    double smallest = kPi;
    for (int k = 0; k < 3; ++k) {
      const Vec3 e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
      smallest = std::min(smallest, std::atan2(e1.cross(e2).norm(), e1.dot(e2)));
    }
    return smallest;
  };
  std::vector<Face> faces;
  faces.reserve(2 * static_cast<std::size_t>(nu - 1) * (nv - 1));
  for (int j = 0; j + 1 < nv; ++j) {
    for (int i = 0; i + 1 < nu; ++i) {
      const int a = grid_index(nu, i, j), b = grid_index(nu, i + 1, j);
      const int c = grid_index(nu, i + 1, j + 1), d = grid_index(nu, i, j + 1);
      const double main_quality = std::min(smallest_angle(a, b, c), smallest_angle(a, c, d));
      const double anti_quality = std::min(smallest_angle(a, b, d), smallest_angle(b, c, d));
      add_cell(faces, nu, i, j, main_quality >= anti_quality);
    }
  }
  TriangleMesh mesh(std::move(vertices), std::move(faces));
  ExampleSurface example{"plane",
                         "Plane: a flat 100 x 80 rectangle, jittered irregular triangulation",
                         std::move(mesh), grid_corners(nu, nv)};
  place_on_ground(example.mesh);
  return example;
}

struct Generator {
  const char* name;
  ExampleSurface (*build)(double scale);
};

constexpr Generator kGenerators[] = {
    {"torus-wide", torus_wide},
    {"waves-bump", waves_bump},
    {"sphere", sphere},
    {"double-vault", double_vault},
    {"waves", waves},
    {"archway", archway},
    {"triple-vault", triple_vault},
    {"cylinder", cylinder},
    {"cone", cone},
    {"hypar", hypar},
    {"plane", plane},
};

}  // namespace

std::vector<std::string> example_names() {
  std::vector<std::string> names;
  for (const Generator& generator : kGenerators) names.emplace_back(generator.name);
  return names;
}

ExampleSurface make_example(const std::string& name, double resolution_scale) {
  const Generator* found = nullptr;
  for (const Generator& generator : kGenerators)
    if (name == generator.name) found = &generator;
  if (found == nullptr) {
    std::ostringstream message;
    message << "unknown example '" << name << "'; known examples:";
    const char* separator = " ";
    for (const Generator& generator : kGenerators) {
      message << separator << generator.name;
      separator = ", ";
    }
    throw InvalidInput("mesh", message.str());
  }
  if (!(resolution_scale > 0.0 && resolution_scale <= kMaxResolutionScale)) {
    std::ostringstream message;
    message << "example '" << name << "': resolution_scale must be in (0, " << kMaxResolutionScale
            << "], got " << resolution_scale;
    throw InvalidInput("scale", message.str());
  }
  return found->build(resolution_scale);
}

}  // namespace gridshell
