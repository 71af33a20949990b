// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/fabrication/compare.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <memory>
#include <nanoflann.hpp>
#include <numbers>
#include <numeric>
#include <random>

#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/parallel.h"
#include "gridshell/mesh/mesh_io.h"

namespace gridshell {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using CgalTriangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<CgalTriangle>::const_iterator>;
using AabbTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Kernel::Point_3 to_cgal(const Vec3& p) { return {p.x(), p.y(), p.z()}; }

/// CPU time of the process (all threads), for the stage times GRIDSHELL_DEBUG_COMPARE prints.
double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// nanoflann's view of a point list.
struct PointList {
  const std::vector<Vec3>* points = nullptr;
  size_t kdtree_get_point_count() const { return points->size(); }
  double kdtree_get_pt(size_t i, size_t d) const { return (*points)[i][static_cast<int>(d)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointList>,
                                                   PointList, 3, std::uint32_t>;

/// A reference surface: exact distances (AABB tree over its triangles) and, for ICP and as
/// hints, points sampled on it by area with their face normals in a k-d tree.
struct Reference {
  std::vector<CgalTriangle> triangles;
  std::unique_ptr<AabbTree> tree;
  std::vector<Vec3> samples, normals;
  PointList list;
  std::unique_ptr<KdTree> kd;
  double spacing = 0;  ///< typical distance between samples
  double extent = 0;   ///< bounding-box diagonal

  Reference(const std::vector<Triangle3>& input, int sample_count, unsigned seed) {
    std::vector<double> cumulative;
    double area = 0;
    Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
    for (const Triangle3& t : input) {
      const double a = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).norm();
      for (const Vec3& p : t) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      if (!(a > 0)) continue;
      triangles.emplace_back(to_cgal(t[0]), to_cgal(t[1]), to_cgal(t[2]));
      area += a;
      cumulative.push_back(area);
    }
    if (triangles.empty()) throw InvalidInput("", "the reference surface has no triangles");
    extent = (hi - lo).norm();
    tree = std::make_unique<AabbTree>(triangles.begin(), triangles.end());
    tree->accelerate_distance_queries();
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> uniform(0, 1);
    std::vector<int> faces;
    for (size_t i = 0; i < input.size(); ++i) {
      const Triangle3& t = input[i];
      if (0.5 * (t[1] - t[0]).cross(t[2] - t[0]).norm() > 0) faces.push_back(static_cast<int>(i));
    }
    samples.reserve(sample_count);
    normals.reserve(sample_count);
    for (int k = 0; k < sample_count; ++k) {
      const double r = uniform(random) * area;
      const size_t f =
          std::min(cumulative.size() - 1,
                   static_cast<size_t>(std::lower_bound(cumulative.begin(), cumulative.end(), r) -
                                       cumulative.begin()));
      const Triangle3& t = input[faces[f]];
      double a = uniform(random), b = uniform(random);
      if (a + b > 1) {
        a = 1 - a;
        b = 1 - b;
      }
      samples.push_back(t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]));
      normals.push_back((t[1] - t[0]).cross(t[2] - t[0]).normalized());
    }
    spacing = std::sqrt(area / sample_count);
    list.points = &samples;
    kd = std::make_unique<KdTree>(3, list, nanoflann::KDTreeSingleIndexAdaptorParams(12));
  }

  /// Index of the nearest sample and the squared distance to it.
  std::pair<std::uint32_t, double> nearest(const Vec3& p) const {
    std::uint32_t index = 0;
    double d2 = 0;
    nanoflann::KNNResultSet<double, std::uint32_t> result(1);
    result.init(&index, &d2);
    kd->findNeighbors(result, p.data(), nanoflann::SearchParams(16));
    return {index, d2};
  }
  /// Exact distance to the triangles. The AABB tree's answer is exact whatever the hint (a
  /// point on the surface: its distance bounds the search); a close hint only makes it cheaper.
  /// `last` is the closest point of the previous query (points come in Morton order, so it is
  /// usually near): used when it is within two sample spacings of `p`, else the k-d tree's
  /// nearest sample. `last` is updated to this query's closest point.
  double distance(const Vec3& p, Vec3& last, bool& have_last) const {
    Vec3 hint = last;
    if (!have_last || (p - last).squaredNorm() > 4 * spacing * spacing)
      hint = samples[nearest(p).first];
    const Kernel::Point_3 c = tree->closest_point(to_cgal(p), to_cgal(hint));
    last = Vec3(c.x(), c.y(), c.z());
    have_last = true;
    return (p - last).norm();
  }
  /// Distance estimate from the nearest sample: the plane distance where the sample is close
  /// along the surface, the straight distance beyond the sampling's reach.
  double estimate(const Vec3& p, std::uint32_t index, double d2) const {
    const double r = normals[index].dot(p - samples[index]);
    const double tangential2 = std::max(0.0, d2 - r * r);
    return std::sqrt(r * r + std::max(0.0, tangential2 - spacing * spacing));
  }
};

struct Pose {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 translation = Vec3::Zero();
  Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
};

Eigen::Matrix3d rotation_from_vector(const Vec3& omega) {
  const double angle = omega.norm();
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix();
}

double median_of(std::vector<double> values) {
  if (values.empty()) return 0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

struct IcpResult {
  Pose pose;
  int iterations = 0;
  double score = 0;  ///< trimmed RMS of the distance estimates at the end
};

/// Point-to-plane ICP of `points` (scan coordinates) against `reference` from `start`.
/// Correspondences farther than three robust standard deviations are dropped each iteration;
/// `trim` (0..1) additionally keeps only that fraction of the nearest (for the coarse search).
IcpResult icp(const std::vector<Vec3>& points, const Reference& reference, Pose pose,
              int iterations, double trim, const Progress& progress) {
  IcpResult out;
  const double floor = 1e-9 * reference.extent;
  std::vector<double> error(points.size());
  std::vector<std::uint32_t> match(points.size());
  std::vector<Vec3> moved(points.size());
  for (int it = 0; it < iterations; ++it) {
    progress.check();
    for (size_t i = 0; i < points.size(); ++i) {
      moved[i] = pose.apply(points[i]);
      const auto [index, d2] = reference.nearest(moved[i]);
      match[i] = index;
      error[i] = reference.estimate(moved[i], index, d2);
    }
    const double sigma = 1.4826 * median_of(error);
    double limit = std::max(3 * sigma, floor);
    if (trim < 1) {
      std::vector<double> sorted = error;
      const size_t keep = static_cast<size_t>(trim * (sorted.size() - 1));
      std::nth_element(sorted.begin(), sorted.begin() + keep, sorted.end());
      limit = std::max(limit, sorted[keep]);
    }
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    int used = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      if (error[i] > limit) continue;
      const Vec3& n = reference.normals[match[i]];
      const double r = n.dot(moved[i] - reference.samples[match[i]]);
      Eigen::Matrix<double, 6, 1> J;
      J << moved[i].cross(n), n;
      A += J * J.transpose();
      b += J * r;
      ++used;
    }
    out.iterations = it + 1;
    if (used < 6) break;
    // Levenberg-style damping keeps an ill-conditioned direction (a flat scan sliding in its
    // plane) from jumping.
    A.diagonal() += Eigen::Matrix<double, 6, 1>::Constant(1e-12 * A.diagonal().maxCoeff());
    const Eigen::Matrix<double, 6, 1> delta = -A.ldlt().solve(b);
    const Eigen::Matrix3d dR = rotation_from_vector(delta.head<3>());
    pose.rotation = dR * pose.rotation;
    pose.translation = dR * pose.translation + delta.tail<3>();
    if (delta.head<3>().norm() < 1e-10 && delta.tail<3>().norm() < 1e-10 * reference.extent) break;
  }
  // Score: RMS of the nearest 90 % of the estimates.
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3 p = pose.apply(points[i]);
    const auto [index, d2] = reference.nearest(p);
    error[i] = reference.estimate(p, index, d2);
  }
  std::sort(error.begin(), error.end());
  const size_t keep = std::max<size_t>(1, static_cast<size_t>(0.9 * error.size()));
  double sum = 0;
  for (size_t i = 0; i < keep; ++i) sum += error[i] * error[i];
  out.score = std::sqrt(sum / keep);
  out.pose = pose;
  return out;
}

/// Root mean square of the exact distances from `points` moved by `pose` to `reference`, over the
/// nearest `keep` fraction of them.
double trimmed_distance(const std::vector<Vec3>& points, const Reference& reference,
                        const Pose& pose, double keep) {
  std::vector<double> d(points.size());
  Vec3 last = Vec3::Zero();
  bool have_last = false;
  for (size_t i = 0; i < points.size(); ++i)
    d[i] = reference.distance(pose.apply(points[i]), last, have_last);
  const size_t n = std::max<size_t>(1, static_cast<size_t>(keep * static_cast<double>(d.size())));
  std::nth_element(d.begin(), d.begin() + (n - 1), d.end());
  double sum = 0;
  for (size_t i = 0; i < n; ++i) sum += d[i] * d[i];
  return std::sqrt(sum / static_cast<double>(n));
}

/// The lamellas seen from above: a raster over the plane (origin, e1, e2) holding each pixel's
/// distance to the nearest projected reference sample (an 8-neighbour chamfer transform). Scoring
/// a pose of the scan in the plane costs one lookup per point instead of a k-d tree query, so
/// turns about the normal and offsets in the plane can be searched together.
struct PlanView {
  Vec3 origin, e1, e2;
  double pixel = 1, lo_u = 0, lo_v = 0;
  int width = 0, height = 0;
  std::vector<float> distance;

  PlanView(const std::vector<Vec3>& samples, const Vec3& origin_, const Vec3& e1_, const Vec3& e2_,
           double margin, double pixel_)
      : origin(origin_), e1(e1_), e2(e2_), pixel(pixel_) {
    double hi_u = -1e300, hi_v = -1e300;
    lo_u = lo_v = 1e300;
    for (const Vec3& p : samples) {
      const double u = (p - origin).dot(e1), v = (p - origin).dot(e2);
      lo_u = std::min(lo_u, u), hi_u = std::max(hi_u, u);
      lo_v = std::min(lo_v, v), hi_v = std::max(hi_v, v);
    }
    lo_u -= margin, lo_v -= margin;
    width = static_cast<int>((hi_u + margin - lo_u) / pixel) + 1;
    height = static_cast<int>((hi_v + margin - lo_v) / pixel) + 1;
    constexpr float kFar = 1e30f;
    distance.assign(static_cast<size_t>(width) * height, kFar);
    for (const Vec3& p : samples) {
      const int i = static_cast<int>(((p - origin).dot(e1) - lo_u) / pixel);
      const int j = static_cast<int>(((p - origin).dot(e2) - lo_v) / pixel);
      distance[static_cast<size_t>(j) * width + i] = 0;
    }
    const float a = static_cast<float>(pixel), b = static_cast<float>(std::sqrt(2.0) * pixel);
    const auto at = [&](int i, int j) -> float& {
      return distance[static_cast<size_t>(j) * width + i];
    };
    for (int j = 0; j < height; ++j)
      for (int i = 0; i < width; ++i) {
        float& d = at(i, j);
        if (i > 0) d = std::min(d, at(i - 1, j) + a);
        if (j > 0) d = std::min(d, at(i, j - 1) + a);
        if (i > 0 && j > 0) d = std::min(d, at(i - 1, j - 1) + b);
        if (i + 1 < width && j > 0) d = std::min(d, at(i + 1, j - 1) + b);
      }
    for (int j = height - 1; j >= 0; --j)
      for (int i = width - 1; i >= 0; --i) {
        float& d = at(i, j);
        if (i + 1 < width) d = std::min(d, at(i + 1, j) + a);
        if (j + 1 < height) d = std::min(d, at(i, j + 1) + a);
        if (i + 1 < width && j + 1 < height) d = std::min(d, at(i + 1, j + 1) + b);
        if (i > 0 && j + 1 < height) d = std::min(d, at(i - 1, j + 1) + b);
      }
  }
  /// Plane coordinates of a point.
  Eigen::Vector2d project(const Vec3& p) const {
    return {(p - origin).dot(e1), (p - origin).dot(e2)};
  }
  /// Distance at plane coordinates (the margin beyond the raster).
  double at(const Eigen::Vector2d& q, double outside) const {
    const int i = static_cast<int>(std::floor((q.x() - lo_u) / pixel));
    const int j = static_cast<int>(std::floor((q.y() - lo_v) / pixel));
    if (i < 0 || j < 0 || i >= width || j >= height) return outside;
    return distance[static_cast<size_t>(j) * width + i];
  }
};

/// Mean and principal axes (columns, by increasing variance, right-handed).
std::pair<Vec3, Eigen::Matrix3d> principal_axes(const std::vector<Vec3>& points) {
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) covariance += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  Eigen::Matrix3d axes = solver.eigenvectors();
  if (axes.determinant() < 0) axes.col(0) = -axes.col(0);
  return {mean, axes};
}

DistanceStatistics statistics(const std::vector<double>& distance, const std::vector<char>& inlier,
                              double top, int bins) {
  DistanceStatistics s;
  std::vector<double> values;
  for (size_t i = 0; i < distance.size(); ++i)
    if (inlier[i]) values.push_back(distance[i]);
  s.points = static_cast<int>(values.size());
  if (values.empty()) return s;
  double sum = 0, sum2 = 0;
  for (double d : values) {
    sum += d;
    sum2 += d * d;
    s.max = std::max(s.max, d);
  }
  const double n = static_cast<double>(values.size());
  s.mean = sum / n;
  s.rms = std::sqrt(sum2 / n);
  s.standard_deviation = std::sqrt(std::max(0.0, sum2 / n - s.mean * s.mean));
  const size_t k = static_cast<size_t>(std::ceil(0.95 * n)) - 1;
  std::nth_element(values.begin(), values.begin() + k, values.end());
  s.p95 = values[k];
  const double width = std::max(top, s.max) / bins;
  s.histogram_counts.assign(bins, 0);
  for (int b = 0; b <= bins; ++b) s.histogram_edges.push_back(b * width);
  for (double d : values)
    s.histogram_counts[std::min(bins - 1, static_cast<int>(d / std::max(width, 1e-300)))] += 1;
  return s;
}

/// 21 bits of each coordinate interleaved (x lowest): the Z-order curve's key.
std::uint64_t morton_key(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  const auto spread = [](std::uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}

/// Indices of `points` (moved by `pose`) sorted along the Z-order curve of their bounding box.
std::vector<std::uint32_t> morton_order(const std::vector<Vec3>& points, const Pose& pose) {
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Vec3& p : points) {
    const Vec3 q = pose.apply(p);
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const double scale = 2097151.0 / std::max((hi - lo).maxCoeff(), 1e-300);
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3 q = (pose.apply(points[i]) - lo) * scale;
    keyed[i] = {morton_key(static_cast<std::uint32_t>(q.x()), static_cast<std::uint32_t>(q.y()),
                           static_cast<std::uint32_t>(q.z())),
                static_cast<std::uint32_t>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order(points.size());
  for (size_t i = 0; i < points.size(); ++i) order[i] = keyed[i].second;
  return order;
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

std::vector<Triangle3> lamella_surface(const std::vector<SimulatedLamella>& lamellas, double width,
                                       double thickness) {
  std::vector<Triangle3> out;
  // The corners deployed_obj uses: (+w,+t) (-w,+t) (-w,-t) (+w,-t) in (width, normal).
  const double sw[4] = {0.5, -0.5, -0.5, 0.5}, st[4] = {0.5, 0.5, -0.5, -0.5};
  for (const SimulatedLamella& l : lamellas) {
    const size_t n = l.centerline.size();
    if (n < 2 || l.normals.size() != n) continue;
    std::vector<std::array<Vec3, 4>> ring(n);
    for (size_t v = 0; v < n; ++v) {
      Vec3 w = v < l.widths.size() ? l.widths[v] : Vec3::Zero();
      if (!(w.norm() > 0)) {
        const Vec3 t = l.centerline[std::min(v + 1, n - 1)] - l.centerline[v > 0 ? v - 1 : 0];
        w = t.cross(l.normals[v]).normalized();
      }
      for (int c = 0; c < 4; ++c)
        ring[v][c] = l.centerline[v] + sw[c] * width * w + st[c] * thickness * l.normals[v];
    }
    for (size_t v = 0; v + 1 < n; ++v)
      for (int c = 0; c < 4; ++c) {
        const Vec3 &a = ring[v][c], &b = ring[v][(c + 1) % 4], &a1 = ring[v + 1][c],
                   &b1 = ring[v + 1][(c + 1) % 4];
        out.push_back({a, a1, b1});
        out.push_back({a, b1, b});
      }
    // End caps facing outwards: the corner order turns about -tangent at the start.
    const auto& a = ring.front();
    out.push_back({a[0], a[1], a[2]});
    out.push_back({a[0], a[2], a[3]});
    const auto& b = ring.back();
    out.push_back({b[0], b[2], b[1]});
    out.push_back({b[0], b[3], b[2]});
  }
  return out;
}

std::vector<Vec3> read_point_cloud(const std::string& path) {
  const std::string ext = lower_extension(path);
  const std::string data = read_file_bytes(path);
  if (ext == ".ply") return read_points(data, MeshFormat::Ply, path);
  if (ext == ".obj") return read_points(data, MeshFormat::Obj, path);
  if (ext == ".off") return read_points(data, MeshFormat::Off, path);
  if (ext != ".xyz" && ext != ".txt" && ext != ".pts" && ext != ".asc" && ext != ".csv")
    throw InvalidInput(path, "unknown point cloud format '" + ext +
                                 "' (expected .ply, .xyz, .txt, .pts, .asc, .csv, .obj or .off)");
  std::vector<Vec3> points;
  const char* p = data.data();
  const char* end = p + data.size();
  int line = 0;
  while (p < end) {
    const char* eol = static_cast<const char*>(std::memchr(p, '\n', end - p));
    if (!eol) eol = end;
    ++line;
    const char* q = p;
    const auto skip = [&] {
      while (q < eol && (*q == ' ' || *q == '\t' || *q == ',' || *q == ';' || *q == '\r')) ++q;
    };
    skip();
    if (q < eol && *q != '#') {
      Vec3 point;
      for (int k = 0; k < 3; ++k) {
        skip();
        if (*q == '+') ++q;
        const auto [next, ec] = std::from_chars(q, eol, point[k]);
        if (ec != std::errc() || (next < eol && *next != ' ' && *next != '\t' && *next != ',' &&
                                  *next != ';' && *next != '\r'))
          throw InvalidInput(path, "line " + std::to_string(line) +
                                       ": expected three numbers x y z (then anything)");
        if (!std::isfinite(point[k]))
          throw InvalidInput(path,
                             "line " + std::to_string(line) + ": not a finite number (NaN or Inf)");
        q = next;
      }
      points.push_back(point);
    }
    p = eol + 1;
  }
  if (points.empty()) throw InvalidInput(path, "no points");
  return points;
}

void check_point_cloud(const std::vector<Vec3>& points, const std::string& name) {
  if (points.empty()) throw InvalidInput(name, "no points");
  for (size_t i = 0; i < points.size(); ++i)
    if (!points[i].allFinite())
      throw InvalidInput(name, "point " + std::to_string(i) + " is not finite (NaN or Inf)");
  if (points.size() < 100)
    throw InvalidInput(
        name, "only " + std::to_string(points.size()) + " points: a comparison needs at least 100");
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) covariance += (p - mean) * (p - mean).transpose();
  const Vec3 variance = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvalues();
  if (!(variance[2] > 0)) throw InvalidInput(name, "all points are the same point");
  if (variance[1] <= 1e-12 * variance[2])
    throw InvalidInput(name, "all points lie on one line: nothing to register");
}

ScanComparison compare_scan(const std::vector<Vec3>& scan, const std::vector<Triangle3>& deployment,
                            const TriangleMesh& target, const CompareOptions& options,
                            const Progress& progress) {
  check_point_cloud(scan, "scan");
  progress.report("compare: reference", 0);
  const auto t_reference = std::chrono::steady_clock::now();
  const double c_reference = process_cpu_seconds();
  const Reference lamellas(deployment, options.reference_samples, options.seed);
  std::vector<Triangle3> target_triangles;
  for (const Face& f : target.faces())
    target_triangles.push_back(
        {target.vertices()[f[0]], target.vertices()[f[1]], target.vertices()[f[2]]});
  const Reference patch(target_triangles, std::max(1000, options.reference_samples / 4),
                        options.seed + 1);

  if (std::getenv("GRIDSHELL_DEBUG_COMPARE"))
    std::fprintf(
        stderr, "references %.3f s (cpu %.3f s)\n",
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_reference).count(),
        process_cpu_seconds() - c_reference);
  // A fixed pseudo-random subset of the scan for ICP.
  std::mt19937_64 random(options.seed);
  std::vector<size_t> order(scan.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), random);
  const auto subset = [&](size_t n) {
    std::vector<Vec3> out;
    for (size_t i = 0; i < std::min(n, scan.size()); ++i) out.push_back(scan[order[i]]);
    return out;
  };

  // Coarse, then fine. (1) Orientation: principal axes of the scan onto those of the target
  // patch, with both orientations of the axis of least variance (the shell's normal) and 12
  // turns about it, each tried with a short ICP against the patch: a smooth surface, so a start
  // a few lamella spacings off still slides home. Every orientation that fits nearly as well as
  // the best goes on: a symmetric shape fits in several. (2) Position on the lamellas: the grid
  // of lamellas repeats itself every member spacing, and ICP started a spacing off stays there,
  // so turns about the normal and offsets in the shell's plane are searched on the lamellas seen
  // from above. (3) The best few are refined by ICP against the lamellas and (4) ranked by exact
  // distances. (5) Each orientation's best (and at least three) are refined to the end and the
  // one nearest the lamellas wins; the runner-up says how ambiguous the choice was.
  const bool debug = std::getenv("GRIDSHELL_DEBUG_COMPARE") != nullptr;
  const auto clock = [] { return std::chrono::steady_clock::now(); };
  double c0 = process_cpu_seconds();
  // Wall time since t0, and (in the debug line) the process's CPU time since c0.
  const auto since = [&](auto t0) { return std::chrono::duration<double>(clock() - t0).count(); };
  const auto cpu = [&] {
    const double c = process_cpu_seconds(), d = c - c0;
    c0 = c;
    return d;
  };
  auto t0 = clock();
  ScanComparison out;
  const std::vector<Vec3> coarse_points = subset(1500);
  // Named variables, not structured bindings: the lambda below uses them, and Clang 14 (the
  // fuzzing build) does not capture structured bindings.
  const std::pair<Vec3, Eigen::Matrix3d> scan_frame = principal_axes(subset(20000));
  const std::pair<Vec3, Eigen::Matrix3d> ref_frame = principal_axes(patch.samples);
  const Vec3& scan_mean = scan_frame.first;
  const Eigen::Matrix3d& scan_axes = scan_frame.second;
  const Vec3& ref_mean = ref_frame.first;
  const Eigen::Matrix3d& ref_axes = ref_frame.second;
  struct Orientation {
    IcpResult icp;
    int flip = 0, turn = 0;
  };
  // The 24 starts are independent: one job each, on all threads.
  constexpr int kTurns = 12;
  std::vector<Orientation> orientations(2 * kTurns);
  parallel_for(
      orientations.size(),
      [&](size_t candidate, const Progress& inner) {
        const int flip = static_cast<int>(candidate) / kTurns;
        const int turn = static_cast<int>(candidate) % kTurns;
        Eigen::Matrix3d A = Eigen::AngleAxisd(2 * std::numbers::pi * turn / kTurns, Vec3::UnitX())
                                .toRotationMatrix();
        if (flip) A = A * Eigen::Vector3d(-1, -1, 1).asDiagonal();
        Pose start;
        start.rotation = ref_axes * A * scan_axes.transpose();
        start.translation = ref_mean - start.rotation * scan_mean;
        orientations[candidate] = {icp(coarse_points, patch, start, 12, 0.8, inner), flip, turn};
      },
      progress, {options.threads, "compare: coarse registration", 0, 0.5});
  if (debug)
    for (const Orientation& o : orientations)
      std::fprintf(stderr, "candidate flip %d turn %d score %g\n", o.flip, o.turn, o.icp.score);
  // Every orientation that fits the smooth target nearly as well as the best, if it differs from
  // the better ones by more than 20 degrees: a shell with symmetries (a vault turned by half a
  // turn, a saddle by a quarter turn with its normal flipped, a dome by any turn) fits its target
  // in each, and only the lamellas tell them apart.
  std::sort(orientations.begin(), orientations.end(),
            [](const Orientation& a, const Orientation& b) { return a.icp.score < b.icp.score; });
  std::vector<Orientation> distinct;
  for (const Orientation& o : orientations) {
    if (o.icp.score > 3 * orientations.front().icp.score + 1e-6 * patch.extent) break;
    bool near = false;
    for (const Orientation& d : distinct)
      near =
          near || Eigen::AngleAxisd(o.icp.pose.rotation * d.icp.pose.rotation.transpose()).angle() <
                      20 * std::numbers::pi / 180;
    if (!near) distinct.push_back(o);
    if (distinct.size() == 12) break;
  }
  out.orientations_tried = static_cast<int>(distinct.size());
  if (debug) std::fprintf(stderr, "orientation %.3f s (cpu %.3f s)\n", since(t0), cpu());
  t0 = clock();
  // Sub-stage CPU times for the debug lines.
  double c_sub = process_cpu_seconds();
  const auto sub_cpu = [&] {
    const double c = process_cpu_seconds(), d = c - c_sub;
    c_sub = c;
    return d;
  };
  const std::vector<Vec3> probe = subset(300);
  const std::vector<Vec3> patch_points = subset(3000);
  const Vec3 e1 = ref_axes.col(1), e2 = ref_axes.col(2);
  const double step = 0.008 * lamellas.extent;
  // (1b) Each orientation settled on the patch with more points.
  std::vector<Pose> poses(distinct.size());
  parallel_for(distinct.size(),
               [&](size_t o, const Progress& inner) {
                 poses[o] = icp(patch_points, patch, distinct[o].icp.pose, 20, 0.8, inner).pose;
               },
               progress, {options.threads, "compare: coarse registration", 0.5, 0.6});
  if (debug) std::fprintf(stderr, "  patch ICPs cpu %.3f s\n", sub_cpu());
  // (2) Turns about the normal and offsets in the plane of the shell, searched on the lamellas
  // seen from above (PlanView): the target patch fixes the orientation only up to what slides
  // along a smooth surface (a vault along its axis, a dome about its axis), and the grid of
  // lamellas repeats itself every member spacing. Turns of +-15 degrees (the orientations are
  // 30 degrees apart) and offsets of +-19 % of the extent (a partial scan of a dome slides far
  // on it), scored by the share of scan points off the lamellas in plan: coarse first (steps of
  // 3 degrees and 1.6 %, 100 points), then around the best 8 of each orientation (1.5 degrees
  // and 0.4 %, 300 points).
  const double margin = 0.1 * lamellas.extent;
  const PlanView plan(lamellas.samples, ref_mean, e1, e2, margin,
                      std::max(0.5 * lamellas.spacing, lamellas.extent / 1500));
  constexpr int kTurnSteps = 10;
  constexpr int kPlanSteps = 12;
  const double turn_step = 1.5 * std::numbers::pi / 180;
  struct PlanPose {
    double score = 0, turn = 0, du = 0, dv = 0;
  };
  const auto plan_score = [&](const std::vector<Eigen::Vector2d>& points,
                              const Eigen::Vector2d& centre, double turn, double du, double dv,
                              std::vector<double>& error) {
    const double c = std::cos(turn), s = std::sin(turn);
    error.resize(points.size());
    for (size_t k = 0; k < points.size(); ++k) {
      const Eigen::Vector2d d = points[k] - centre;
      const Eigen::Vector2d q(centre.x() + c * d.x() - s * d.y() + du,
                              centre.y() + s * d.x() + c * d.y() + dv);
      error[k] = plan.at(q, margin);
    }
    // The share of points farther than two pixels from every lamella: half of the plan is
    // lamellas, so a trimmed mean is small at any pose, but only the right one puts (nearly)
    // all the scan on them.
    size_t off = 0;
    for (double e : error) off += e > 2 * plan.pixel;
    return static_cast<double>(off) / static_cast<double>(error.size());
  };
  constexpr size_t kBest = 3;
  std::vector<std::vector<PlanPose>> best_plan(distinct.size());
  std::vector<Eigen::Vector2d> plan_centre(distinct.size());
  parallel_for(
      distinct.size(),
      [&](size_t o, const Progress& inner) {
        std::vector<Eigen::Vector2d> few, many;
        Eigen::Vector2d centre = Eigen::Vector2d::Zero();
        for (size_t k = 0; k < probe.size(); ++k) {
          many.push_back(plan.project(poses[o].apply(probe[k])));
          if (k < 100) few.push_back(many.back());
          centre += many.back();
        }
        centre /= static_cast<double>(many.size());
        plan_centre[o] = centre;
        std::vector<double> error;
        std::vector<PlanPose> coarse;
        for (int t = -kTurnSteps / 2; t <= kTurnSteps / 2; ++t) {
          inner.check();
          for (int i = -kPlanSteps; i <= kPlanSteps; ++i)
            for (int j = -kPlanSteps; j <= kPlanSteps; ++j) {
              const double turn = 2 * t * turn_step, du = 2 * i * step, dv = 2 * j * step;
              coarse.push_back({plan_score(few, centre, turn, du, dv, error), turn, du, dv});
            }
        }
        const size_t top = std::min<size_t>(8, coarse.size());
        std::partial_sort(coarse.begin(), coarse.begin() + top, coarse.end(),
                          [](const PlanPose& a, const PlanPose& b) { return a.score < b.score; });
        std::vector<PlanPose> fine;
        for (size_t c = 0; c < top; ++c)
          for (int t = -1; t <= 1; ++t)
            for (int i = -2; i <= 2; ++i)
              for (int j = -2; j <= 2; ++j) {
                const double turn = coarse[c].turn + t * turn_step;
                const double du = coarse[c].du + 0.5 * i * step, dv = coarse[c].dv + 0.5 * j * step;
                fine.push_back({plan_score(many, centre, turn, du, dv, error), turn, du, dv});
              }
        std::sort(fine.begin(), fine.end(),
                  [](const PlanPose& a, const PlanPose& b) { return a.score < b.score; });
        // The best few that are not neighbours of a better one.
        for (const PlanPose& f : fine) {
          bool near = false;
          for (const PlanPose& b : best_plan[o])
            near = near || (std::abs(f.turn - b.turn) <= 2 * turn_step &&
                            std::abs(f.du - b.du) <= 2 * step && std::abs(f.dv - b.dv) <= 2 * step);
          if (!near) best_plan[o].push_back(f);
          if (best_plan[o].size() == kBest) break;
        }
      },
      progress, {options.threads, "compare: coarse registration", 0.6, 0.8});
  if (debug) std::fprintf(stderr, "  plan search cpu %.3f s\n", sub_cpu());
  // (3) The best few of each orientation, refined against the lamellas.
  std::vector<std::pair<size_t, Pose>> starts;  // (orientation, start)
  std::vector<double> start_offset_score;
  for (size_t o = 0; o < distinct.size(); ++o)
    for (const PlanPose& b : best_plan[o]) {
      // Turned about the normal through the scan's centre in the plane, then moved in the plane.
      const Vec3 axis_point = ref_mean + plan_centre[o].x() * e1 + plan_centre[o].y() * e2;
      const Eigen::Matrix3d turn = Eigen::AngleAxisd(b.turn, e1.cross(e2)).toRotationMatrix();
      Pose start;
      start.rotation = turn * poses[o].rotation;
      start.translation =
          turn * (poses[o].translation - axis_point) + axis_point + b.du * e1 + b.dv * e2;
      starts.push_back({o, start});
      start_offset_score.push_back(b.score);
    }
  std::vector<IcpResult> refined(starts.size());
  parallel_for(starts.size(),
               [&](size_t k, const Progress& inner) {
                 refined[k] = icp(coarse_points, lamellas, starts[k].second, 30, 1.0, inner);
               },
               progress, {options.threads, "compare: coarse registration", 0.8, 0.85});
  if (debug) std::fprintf(stderr, "  refinements cpu %.3f s\n", sub_cpu());
  // (4) The refined starts ranked by exact distances (the AABB tree, not the sampled estimate:
  // its error, a fraction of the sample spacing, is as large as the differences between the
  // poses), the nearest 80 % of a fixed subset: the rest may be outliers or parts the scan has
  // and the model lacks.
  const std::vector<Vec3> judge_points = subset(1000);
  const Vec3 scan_centre = scan_mean;
  const auto same_pose = [&](const Pose& a, const Pose& b) {
    return Eigen::AngleAxisd(a.rotation * b.rotation.transpose()).angle() <
               2 * std::numbers::pi / 180 &&
           (a.apply(scan_centre) - b.apply(scan_centre)).norm() < 0.005 * lamellas.extent;
  };
  std::vector<double> exact(starts.size());
  parallel_for(starts.size(),
               [&](size_t k, const Progress&) {
                 exact[k] = trimmed_distance(judge_points, lamellas, refined[k].pose, 0.8);
               },
               progress, {options.threads, "compare: coarse registration", 0.85, 0.87});
  std::vector<size_t> ranked(starts.size());
  std::iota(ranked.begin(), ranked.end(), 0);
  std::stable_sort(ranked.begin(), ranked.end(),
                   [&](size_t a, size_t b) { return exact[a] < exact[b]; });
  if (debug)
    for (size_t k : ranked)
      std::fprintf(stderr, "orientation %zu start (plan %g) -> estimate %g exact %g\n",
                   starts[k].first, start_offset_score[k], refined[k].score, exact[k]);
  // (5) The finalists: each orientation's best pose, and the next best to make at least three,
  // all distinct. A symmetric shape may fit the scan as well in another orientation, but its
  // coarse pose there is often still a few lamella thicknesses off and only the fine ICP says
  // so: every orientation gets its chance. Each finalist is refined on a larger subset with
  // outliers rejected at three robust standard deviations and judged again; the best is the
  // result, the best of the others that stayed distinct from it says how unambiguous it is.
  std::vector<size_t> finalists;
  const auto take = [&](size_t k) {
    for (size_t f : finalists)
      if (same_pose(refined[k].pose, refined[f].pose)) return;
    if (finalists.size() < 6) finalists.push_back(k);
  };
  for (size_t o = 0; o < distinct.size(); ++o)
    for (size_t k : ranked)
      if (starts[k].first == o) {
        if (exact[k] <= 3 * exact[ranked.front()] + 1e-9 * lamellas.extent) take(k);
        break;
      }
  for (size_t k : ranked)
    if (finalists.size() < 3) take(k);
  if (debug) std::fprintf(stderr, "offsets %.3f s (cpu %.3f s)\n", since(t0), cpu());
  t0 = clock();
  const std::vector<Vec3> icp_points = subset(options.icp_points);
  const std::vector<Vec3> final_judge = subset(3000);
  std::vector<IcpResult> fine(finalists.size());
  std::vector<double> residual(finalists.size());
  parallel_for(finalists.size(),
               [&](size_t f, const Progress& inner) {
                 fine[f] = icp(icp_points, lamellas, refined[finalists[f]].pose,
                               options.max_iterations, 1.0, inner);
                 residual[f] = trimmed_distance(final_judge, lamellas, fine[f].pose, 0.8);
               },
               progress, {options.threads, "compare: ICP", 0, 1});
  const size_t best =
      static_cast<size_t>(std::min_element(residual.begin(), residual.end()) - residual.begin());
  out.poses_refined = static_cast<int>(finalists.size());
  out.residual = residual[best];
  for (size_t f = 0; f < finalists.size(); ++f)
    if (f != best && !same_pose(fine[f].pose, fine[best].pose) &&
        (!out.has_runner_up || residual[f] < out.runner_up)) {
      out.has_runner_up = true;
      out.runner_up = residual[f];
      out.runner_up_rotation = fine[f].pose.rotation;
      out.runner_up_translation = fine[f].pose.translation;
    }
  {
    const Orientation& o = distinct[starts[finalists[best]].first];
    out.coarse = "principal axes, " + std::string(o.flip ? "normal flipped, " : "") + "turned " +
                 std::to_string(360 * o.turn / kTurns) +
                 " degrees about the normal axis, ICP on the target patch, turn and offset "
                 "search on the lamellas in plan; the best of " +
                 std::to_string(finalists.size()) + " poses refined";
  }
  out.rotation = fine[best].pose.rotation;
  out.translation = fine[best].pose.translation;
  out.icp_iterations = fine[best].iterations;
  if (debug)
    for (size_t f = 0; f < finalists.size(); ++f)
      std::fprintf(stderr, "fine %zu: %d iterations, estimate %g, exact %g, rotation %g rad\n", f,
                   fine[f].iterations, fine[f].score, residual[f],
                   Eigen::AngleAxisd(fine[f].pose.rotation).angle());
  if (debug) std::fprintf(stderr, "fine ICP %.3f s (cpu %.3f s)\n", since(t0), cpu());
  t0 = clock();
  const Pose& chosen = fine[best].pose;

  // Exact distances of every point, in parallel chunks of points taken in Morton (Z-curve)
  // order: a scan file's order may be anything (the bench's is shuffled), and neighbouring
  // queries walk the same branches of the k-d and AABB trees, which then stay in cache.
  const size_t n = scan.size(), chunk = 1 << 14;
  const std::vector<std::uint32_t> order_z = morton_order(scan, chosen);
  out.deployment_distance.assign(n, 0);
  out.target_distance.assign(n, 0);
  parallel_for((n + chunk - 1) / chunk,
               [&](size_t job, const Progress& inner) {
                 const size_t from = job * chunk, to = std::min(n, from + chunk);
                 Vec3 on_lamellas, on_patch;
                 bool have_lamellas = false, have_patch = false;
                 for (size_t k = from; k < to; ++k) {
                   if ((k & 1023) == 0) inner.check();
                   const size_t i = order_z[k];
                   const Vec3 p = chosen.apply(scan[i]);
                   out.deployment_distance[i] = lamellas.distance(p, on_lamellas, have_lamellas);
                   out.target_distance[i] = patch.distance(p, on_patch, have_patch);
                 }
               },
               progress, {options.threads, "compare: distances", 0, 1});
  if (debug) std::fprintf(stderr, "distances %.3f s (cpu %.3f s)\n", since(t0), cpu());
  // Outliers: farther from the lamellas than four robust standard deviations of all distances,
  // and never nearer than a millionth of the model's size: an exact scan's distances are the
  // rounding of its file's numbers (a float's 6e-8 of the coordinates, which may be larger than
  // the model), and rejecting by them would throw away good points.
  const double sigma = 1.4826 * median_of(out.deployment_distance);
  out.rejection_distance = std::max(4 * sigma, 1e-6 * lamellas.extent);
  out.inlier.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    out.inlier[i] = out.deployment_distance[i] <= out.rejection_distance;
    (out.inlier[i] ? out.used : out.rejected) += 1;
  }
  out.deployment = statistics(out.deployment_distance, out.inlier, out.rejection_distance,
                              options.histogram_bins);
  double target_top = 0;
  for (size_t i = 0; i < n; ++i)
    if (out.inlier[i]) target_top = std::max(target_top, out.target_distance[i]);
  out.target = statistics(out.target_distance, out.inlier, target_top, options.histogram_bins);
  return out;
}

std::string compare_ply(const std::vector<Vec3>& scan, const ScanComparison& c) {
  std::string out =
      "ply\nformat binary_little_endian 1.0\ncomment gridshell compare: scan points registered "
      "to the design, coloured by distance to the deployment (blue 0, red at the rejection "
      "distance " +
      std::to_string(c.rejection_distance) + "; grey: outliers)\nelement vertex " +
      std::to_string(scan.size()) +
      "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty "
      "uchar green\nproperty uchar blue\nproperty float deployment_distance\nproperty float "
      "target_distance\nend_header\n";
  const size_t header = out.size();
  constexpr size_t kRecord = 3 * 4 + 3 + 2 * 4;
  out.resize(header + kRecord * scan.size());
  char* p = out.data() + header;
  const auto put_float = [&](double v) {
    const float f = static_cast<float>(v);
    std::memcpy(p, &f, 4);  // x86-64 is little endian, as the header says
    p += 4;
  };
  for (size_t i = 0; i < scan.size(); ++i) {
    const Vec3 q = c.rotation * scan[i] + c.translation;
    put_float(q.x());
    put_float(q.y());
    put_float(q.z());
    unsigned char rgb[3] = {128, 128, 128};
    if (c.inlier.empty() || c.inlier[i]) {
      const double f =
          std::clamp(c.deployment_distance[i] / std::max(c.rejection_distance, 1e-300), 0.0, 1.0);
      rgb[0] = static_cast<unsigned char>(255 * f);
      rgb[1] = static_cast<unsigned char>(255 * (1 - std::abs(2 * f - 1)));
      rgb[2] = static_cast<unsigned char>(255 * (1 - f));
    }
    std::memcpy(p, rgb, 3);
    p += 3;
    put_float(c.deployment_distance[i]);
    put_float(c.target_distance[i]);
  }
  return out;
}

}  // namespace gridshell
