// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell bench fabricate`: the fabrication kit of the seven paper-like examples (time,
// sheets, rows and utilisation next to one lamella per row), and `compare` on a synthetic scan of
// a million points (double-vault's deployment sampled, moved, noised, with outliers and only 60 %
// of it seen). Writes section "fabricate" of docs/benchmarks.md.
//
// Times are wall-clock medians of `repeats` runs in this process (the CLI's work minus process
// start: design.json parsed, kit built, every file rendered; scan file read, registered and
// measured) and the process CPU time of the same runs.
#include <time.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <random>
#include <sstream>
#include <thread>

#include "bench_support.h"
#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/compare_job.h"
#include "gridshell/application/convert_deployment.h"
#include "gridshell/application/fabricate.h"
#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"
#include "paper_table1.h"

namespace gridshell::cli {
namespace {

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

v1::Design design_of(const std::string& example) {
  v1::DesignRequest request;
  request.mutable_mesh()->set_example(example);
  return gridshell::run_design(request).design();
}

/// A scan made from a surface, and the motion that was applied to it.
struct SyntheticScan {
  std::vector<Vec3> points;
  Eigen::Matrix3d rotation;  // scan point = rotation * surface point + translation
  Vec3 translation;
  double size = 0;          // bounding-box diagonal of the surface
  std::vector<Vec3> model;  // surface points to measure a recovered motion on
};

SyntheticScan synthesise_scan(const std::vector<Triangle3>& surface, int count, double sigma,
                              double outliers, double seen, unsigned seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(0, 1);
  std::normal_distribution<double> gauss(0, 1);
  std::vector<double> cumulative;
  double area = 0;
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Triangle3& t : surface) {
    area += 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).norm();
    cumulative.push_back(area);
    for (const Vec3& p : t) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  }
  SyntheticScan scan;
  scan.size = (hi - lo).norm();
  Vec3 direction(gauss(random), gauss(random), gauss(random));
  direction.normalize();
  // Points on the surface; seen: those below a plane across `direction` (a one-sided view).
  std::vector<Vec3> surface_points;
  const int inliers = static_cast<int>(count * (1 - outliers) / seen);
  for (int i = 0; i < inliers; ++i) {
    const size_t f =
        std::min(surface.size() - 1,
                 static_cast<size_t>(std::lower_bound(cumulative.begin(), cumulative.end(),
                                                      uniform(random) * area) -
                                     cumulative.begin()));
    const Triangle3& t = surface[f];
    double a = uniform(random), b = uniform(random);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    surface_points.push_back(t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]));
  }
  std::vector<double> along;
  for (const Vec3& p : surface_points) along.push_back(p.dot(direction));
  double cut = 1e300;
  if (seen < 1) {
    std::vector<double> sorted = along;
    const size_t k = static_cast<size_t>(seen * (sorted.size() - 1));
    std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
    cut = sorted[k];
  }
  for (size_t i = 0; i < surface_points.size(); ++i)
    if (along[i] <= cut)
      scan.points.push_back(surface_points[i] +
                            sigma * Vec3(gauss(random), gauss(random), gauss(random)));
  const Vec3 margin = 0.1 * (hi - lo);
  while (static_cast<int>(scan.points.size()) < count)
    scan.points.push_back(
        lo - margin +
        (hi - lo + 2 * margin)
            .cwiseProduct(Vec3(uniform(random), uniform(random), uniform(random))));
  Eigen::Quaterniond q(gauss(random), gauss(random), gauss(random), gauss(random));
  q.normalize();
  scan.rotation = q.toRotationMatrix();
  scan.translation =
      scan.size * Vec3(uniform(random) - 0.5, uniform(random) - 0.5, 2 * uniform(random));
  for (Vec3& p : scan.points) p = scan.rotation * p + scan.translation;
  std::shuffle(scan.points.begin(), scan.points.end(), random);
  for (size_t i = 0; i < surface.size(); i += 37) scan.model.push_back(surface[i][0]);
  return scan;
}

std::string binary_ply(const std::vector<Vec3>& points) {
  std::string out = "ply\nformat binary_little_endian 1.0\nelement vertex " +
                    std::to_string(points.size()) +
                    "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  const size_t header = out.size();
  out.resize(header + 12 * points.size());
  char* p = out.data() + header;
  for (const Vec3& v : points) {
    const float f[3] = {static_cast<float>(v.x()), static_cast<float>(v.y()),
                        static_cast<float>(v.z())};
    std::memcpy(p, f, 12);
    p += 12;
  }
  return out;
}

/// The largest distance between a model point and where `transform` (4x4 row-major, scan to
/// design) puts its scanned copy, over the model's size.
double motion_error(const SyntheticScan& scan,
                    const google::protobuf::RepeatedField<double>& transform) {
  Eigen::Matrix3d R;
  Vec3 t;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) R(i, j) = transform.Get(4 * i + j);
    t[i] = transform.Get(4 * i + 3);
  }
  double worst = 0;
  for (const Vec3& p : scan.model)
    worst = std::max(worst, (R * (scan.rotation * p + scan.translation) + t - p).norm());
  return worst / scan.size;
}

}  // namespace

int bench_fabricate(int repeats, int scan_points, const std::vector<std::string>& scan_examples,
                    const std::vector<double>& scan_noise, const std::string& out, bool no_write,
                    bool compare_only) {
  std::ostringstream table;
  table << "## Fabrication kits and scan comparison\n\n"
        << "Measured " << today() << " on " << cpu_name() << ", "
        << std::thread::hardware_concurrency()
        << " hardware threads. `fabricate`: each example designed with default options, its "
           "design.json parsed and the kit built and rendered (every DXF/SVG sheet, kit.json, "
           "assembly.svg, supports.csv, bom.csv) at `--unit cm` on 1200 x 600 mm sheets, "
        << repeats
        << " times; wall time median, CPU time of the process per run. Rows and utilisation "
           "(part area / sheet area) of the first-fit-decreasing rows next to one lamella per "
           "row.\n\n"
        << "| example | lamellas | holes / slots | sheets (one per row) | rows (one per row) | "
           "utilisation (one per row) | time s | CPU s |\n"
        << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
  char line[1024];
  for (const PaperModel& row : kPaperTable1) {
    if (compare_only) break;
    std::cerr << "bench fabricate: " << row.name << "\n";
    try {
      const std::string json = to_json(design_of(row.name));
      std::vector<double> wall, cpu;
      v1::FabricateResult result;
      for (int r = 0; r < repeats; ++r) {
        const double w0 = wall_seconds(), c0 = cpu_seconds();
        v1::FabricateRequest request;
        try {
          from_json(json, *request.mutable_design());
        } catch (const InvalidInput& e) {
          throw std::runtime_error(std::string("design.json does not parse: ") + e.what());
        }
        request.mutable_options()->set_unit("cm");
        result = gridshell::run_fabricate(request);
        const FileBundle files = fabricate_files(result);
        wall.push_back(wall_seconds() - w0);
        cpu.push_back(cpu_seconds() - c0);
      }
      const v1::Kit& kit = result.kit();
      std::snprintf(line, sizeof line,
                    "| %s | %d | %d / %d | %d (%d) | %d (%d) | %.1f %% (%.1f %%) | %.3f | %.3f |\n",
                    row.name, kit.parts_size(), kit.holes(), kit.slots(), kit.sheets_size(),
                    kit.baseline_sheets(), kit.rows(), kit.parts_size(), 100 * kit.utilisation(),
                    100 * kit.baseline_utilisation(), median(wall), median(cpu));
    } catch (const std::exception& e) {
      std::snprintf(line, sizeof line, "| %s | failed: %s | | | | | | |\n", row.name, e.what());
    }
    table << line;
    std::cerr << line;
  }

  // compare: each example's deployment with notches, synthetic scans of `scan_points` points
  // at each noise level.
  table << "\n`compare`: examples (about 100 units wide, lamellas 1 x 0.1) simulated with "
           "notches; scans of "
        << scan_points
        << " points sampled on the deployed lamella boxes, 60 % of the grid seen (a half-space "
           "cut), Gaussian noise sigma per coordinate (0: an exact scan, only float rounding in "
           "the PLY), 5 % outliers in the enlarged bounding box, a random rigid motion (seeds 1.."
        << repeats
        << "). Time: the binary PLY read, registered (coarse + ICP) and every point measured "
           "against both references, as `gridshell compare` does. Motion error: the largest "
           "distance between a model point and where the recovered motion puts its scanned "
           "copy, over the model's size; RMS: of the inliers' distances to the deployment, over "
           "sigma or (exact scans) over the model's size.\n\n"
        << "| example | sigma | seed | points | time s | CPU s | motion error / size | RMS | "
           "rejected (added 5 %) | orientations / poses refined | best / runner-up |\n"
        << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  std::vector<double> times;
  for (const std::string& example : scan_examples) {
    std::cerr << "bench fabricate: compare (simulating " << example << ")\n";
    v1::SimulateRequest simulate;
    *simulate.mutable_design() = design_of(example);
    simulate.mutable_options()->set_notches("on");
    const v1::SimulateResult simulated = gridshell::run_simulate(simulate);
    const Design design = design_from_proto(simulate.design());
    const std::vector<Triangle3> surface =
        lamella_surface(lamellas_from_proto(simulated.deployment()), design.lamella_width,
                        design.lamella_thickness);
    const std::string dir = (std::filesystem::temp_directory_path() /
                             ("gridshell-bench-compare-" + std::to_string(::getpid())))
                                .string();
    std::filesystem::create_directories(dir);
    for (const double noise : scan_noise) {
      const double sigma = noise * design.lamella_thickness;
      for (int r = 0; r < repeats; ++r) {
        const SyntheticScan scan = synthesise_scan(surface, scan_points, sigma, 0.05, 0.6, r + 1);
        const std::string file = dir + "/scan.ply";
        write_file_atomically(file, binary_ply(scan.points));
        const double w0 = wall_seconds(), c0 = cpu_seconds();
        const std::vector<Vec3> points = read_point_cloud(file);
        const CompareJob job = run_compare_job(points, simulate.design(), simulated.deployment());
        const double wall = wall_seconds() - w0, cpu = cpu_seconds() - c0;
        times.push_back(wall);
        const v1::CompareReport& report = job.report;
        const double rms = report.deployment().rms() / (sigma > 0 ? sigma : scan.size);
        // A symmetric deployment fits the scan in two poses equally well; the motion is then
        // either of them (the runner-up is reported as such).
        const v1::Registration& g = report.registration();
        double error = motion_error(scan, report.transform());
        std::string other;
        if (g.runner_up_transform_size() == 16) {
          const double e = motion_error(scan, g.runner_up_transform());
          if (e < error) {
            char text[64];
            std::snprintf(text, sizeof text, " (runner-up %.1e)", e);
            other = text;
          }
        }
        std::snprintf(line, sizeof line,
                      "| %s | %g | %d | %zu | %.2f | %.2f | %.1e%s | %.3g %s | %.2f %% | %d / %d | "
                      "%.3g |\n",
                      example.c_str(), sigma, r + 1, points.size(), wall, cpu, error, other.c_str(),
                      rms, sigma > 0 ? "sigma" : "size",
                      100.0 * report.points_rejected() / points.size(), g.orientations_tried(),
                      g.poses_refined(), g.ambiguity());
        table << line;
        std::cerr << line;
      }
    }
    std::filesystem::remove_all(dir);
  }
  table << "\nMedian compare time " << (times.empty() ? 0.0 : median(times))
        << " s. Command: `gridshell bench fabricate --repeats " << repeats << "`\n";
  // --compare-only: the kit rows are missing, so the section is printed, never written.
  publish_section(out, "fabricate", table.str(), no_write || compare_only);
  return 0;
}

}  // namespace gridshell::cli
