// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — comparing a scan of the built grid with its simulation (paper Section 6.2: a laser
// scan registered by ICP, RMS between the point cloud and the simulated lamellas).
//
// Registration is rigid: a coarse start from principal axes (every proper axis assignment, and
// turns about the shell's normal axis, each tried with a short ICP on a subsample), then
// point-to-plane ICP with outlier rejection (a correspondence farther than three robust standard
// deviations of the residuals is dropped). Nearest neighbours for ICP come from a k-d tree
// (nanoflann) over points sampled on the reference surface with their normals; the final
// distances are exact point-to-triangle distances (CGAL's AABB tree).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "gridshell/foundation/progress.h"
#include "gridshell/mesh/mesh.h"
#include "gridshell/simulation/simulation.h"

namespace gridshell {

using Triangle3 = std::array<Vec3, 3>;

/// The lamellas of a deployment as closed boxes of their width and thickness around the rod
/// centerlines (the surface deployed_obj writes), as triangles.
std::vector<Triangle3> lamella_surface(const std::vector<SimulatedLamella>& lamellas, double width,
                                       double thickness);

/// A point cloud file: .ply (ASCII or binary), .xyz / .txt / .pts ("x y z [more columns]" per
/// line, blank and '#' lines skipped), .obj (its `v` lines) or .off. Normals may be present
/// and are not needed. Throws InvalidInput naming `path`: unreadable, unknown extension,
/// malformed, NaN/Inf.
std::vector<Vec3> read_point_cloud(const std::string& path);

/// At least 100 points, not all (nearly) on one line; InvalidInput naming `name` otherwise.
void check_point_cloud(const std::vector<Vec3>& points, const std::string& name);

struct CompareOptions {
  int max_iterations = 60;         ///< ICP iterations of the final refinement
  int icp_points = 10000;          ///< scan points used by ICP (a fixed random subset)
  int reference_samples = 200000;  ///< points sampled on the reference surface for ICP
  int histogram_bins = 20;
  int threads = 0;    ///< distance evaluation; 0 = all cores
  unsigned seed = 1;  ///< subsets and samples are pseudo-random but repeatable
};

struct DistanceStatistics {
  int points = 0;
  double mean = 0, rms = 0, standard_deviation = 0, max = 0, p95 = 0;
  std::vector<double> histogram_edges;
  std::vector<int> histogram_counts;
};

struct ScanComparison {
  /// Scan -> design coordinates: x' = rotation x + translation.
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 translation = Vec3::Zero();
  int icp_iterations = 0;
  std::string coarse;  ///< the start ICP was refined from
  /// How unambiguous the pose is: the coarse orientations started from, the distinct poses
  /// refined against the lamellas, the chosen pose's trimmed RMS and, if another distinct pose
  /// was left, its trimmed RMS.
  int orientations_tried = 0, poses_refined = 0;
  double residual = 0, runner_up = 0;
  bool has_runner_up = false;
  /// The runner-up pose (identity if none was left).
  Eigen::Matrix3d runner_up_rotation = Eigen::Matrix3d::Identity();
  Vec3 runner_up_translation = Vec3::Zero();
  double rejection_distance = 0;
  int used = 0, rejected = 0;
  std::vector<double> deployment_distance;  ///< per scan point (after registration)
  std::vector<double> target_distance;
  std::vector<char> inlier;
  DistanceStatistics deployment, target;
};

/// Registers `scan` to the deployment surface and measures every point's distance to it and to
/// the target patch. The extent of the reference sets the scale of every tolerance.
ScanComparison compare_scan(const std::vector<Vec3>& scan, const std::vector<Triangle3>& deployment,
                            const TriangleMesh& target, const CompareOptions& options = {},
                            const Progress& progress = {});

/// The registered scan as a binary PLY: points in design coordinates coloured by their distance
/// to the deployment (blue 0 to red at the rejection distance; outliers grey), with the distances
/// as float properties.
std::string compare_ply(const std::vector<Vec3>& scan, const ScanComparison& comparison);

}  // namespace gridshell
