// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/application/compare_job.h"

#include <cmath>
#include <numbers>

#include "gridshell/application/convert_deployment.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/simulation/layout_deployment.h"

namespace gridshell {
namespace {

std::vector<Vec3> points_of(const google::protobuf::ListValue& list, const std::string& field) {
  std::vector<Vec3> out;
  for (int i = 0; i < list.values_size(); ++i) {
    const auto& v = list.values(i);
    if (v.kind_case() != google::protobuf::Value::kListValue || v.list_value().values_size() != 3)
      throw InvalidInput(field + "[" + std::to_string(i) + "]", "expected a list of 3 numbers");
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
      p[k] = v.list_value().values(k).number_value();
      if (!std::isfinite(p[k]))
        throw InvalidInput(field + "[" + std::to_string(i) + "]", "not a finite number");
    }
    out.push_back(p);
  }
  return out;
}

void fill(v1::DistanceStatistics* out, const DistanceStatistics& s, const char* reference) {
  out->set_reference(reference);
  out->set_points(s.points);
  out->set_mean(s.mean);
  out->set_rms(s.rms);
  out->set_standard_deviation(s.standard_deviation);
  out->set_max(s.max);
  out->set_p95(s.p95);
  for (double e : s.histogram_edges) out->add_histogram_edges(e);
  for (int c : s.histogram_counts) out->add_histogram_counts(c);
}

}  // namespace

namespace {

std::vector<SimulatedLamella> lamellas_of(
    const google::protobuf::RepeatedPtrField<v1::Lamella>& rods, const std::string& name) {
  if (rods.empty()) throw InvalidInput(name, "the deployment has no lamellas");
  std::vector<SimulatedLamella> out;
  for (int i = 0; i < rods.size(); ++i) {
    const std::string field = name + "[" + std::to_string(i) + "]";
    SimulatedLamella l;
    l.centerline = points_of(rods[i].centerline(), field + ".centerline");
    l.normals = points_of(rods[i].normals(), field + ".normals");
    if (l.centerline.size() < 2 || l.normals.size() != l.centerline.size())
      throw InvalidInput(field, "needs at least 2 centerline points and one normal per point");
    out.push_back(std::move(l));
  }
  return out;
}

/// The scan registered to the lamellas' surface and measured against it and the target.
CompareJob compare_job(const std::vector<Vec3>& scan, const std::vector<SimulatedLamella>& lamellas,
                       double width, double thickness, const TriangleMesh& target,
                       const CompareOptions& options, const Progress& progress) {
  const std::vector<Triangle3> surface = lamella_surface(lamellas, width, thickness);
  const ScanComparison c = compare_scan(scan, surface, target, options, progress);
  CompareJob job;
  v1::CompareReport& r = job.report;
  r.set_points_read(static_cast<int>(scan.size()));
  r.set_points_used(c.used);
  r.set_points_rejected(c.rejected);
  r.set_rejection_distance(c.rejection_distance);
  const auto add_transform = [](const Eigen::Matrix3d& R, const Vec3& t,
                                google::protobuf::RepeatedField<double>& to) {
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) to.Add(i < 3 ? (j < 3 ? R(i, j) : t[i]) : (j == 3 ? 1 : 0));
  };
  add_transform(c.rotation, c.translation, *r.mutable_transform());
  const Eigen::AngleAxisd axis_angle(c.rotation);
  const Vec3 rv = axis_angle.axis() * axis_angle.angle();
  for (int k = 0; k < 3; ++k) r.add_rotation_vector(rv[k]);
  r.set_icp_iterations(c.icp_iterations);
  r.set_coarse(c.coarse);
  v1::Registration& g = *r.mutable_registration();
  g.set_orientations_tried(c.orientations_tried);
  g.set_poses_refined(c.poses_refined);
  g.set_residual(c.residual);
  g.set_runner_up(c.runner_up);
  // Two poses that both fit exactly (residuals 0) are as ambiguous as can be.
  g.set_ambiguity(!c.has_runner_up ? 0 : c.runner_up > 0 ? c.residual / c.runner_up : 1);
  g.set_rotation_degrees(axis_angle.angle() * 180 / std::numbers::pi);
  g.set_translation(c.translation.norm());
  if (c.has_runner_up)
    add_transform(c.runner_up_rotation, c.runner_up_translation, *g.mutable_runner_up_transform());
  fill(r.mutable_deployment(), c.deployment, "deployment");
  fill(r.mutable_target(), c.target, "target");
  job.ply = compare_ply(scan, c);
  return job;
}

}  // namespace

std::vector<SimulatedLamella> lamellas_from_proto(const v1::Deployment& deployment) {
  const bool with = deployment.rods_size() > 0;
  if (!with && deployment.rods_without_notches().empty())
    throw InvalidInput("deployment.rods", "the deployment has no lamellas");
  return lamellas_of(with ? deployment.rods() : deployment.rods_without_notches(),
                     with ? "deployment.rods" : "deployment.rods_without_notches");
}

CompareJob run_compare_job(const std::vector<Vec3>& scan, const v1::Design& design_message,
                           const v1::Deployment& deployment, const CompareOptions& options,
                           const Progress& progress) {
  Design design;
  try {
    design = design_from_proto(design_message);
  } catch (const Error& e) {
    rethrow_within(e, "design");
  }
  return compare_job(scan, lamellas_from_proto(deployment), design.lamella_width,
                     design.lamella_thickness, design.target.patch.mesh, options, progress);
}

CompareJob run_compare_layout_job(const std::vector<Vec3>& scan,
                                  const std::vector<v1::Design>& designs,
                                  const v1::LayoutDeployment& deployment,
                                  const CompareOptions& options, const Progress& progress) {
  if (!deployment.seams_joined() || deployment.rods().empty())
    throw InvalidInput("deployment.rods",
                       "the layout run's seams were not joined, so there is no whole to compare "
                       "with; compare a patch's folder (patches/<name>/) instead");
  if (designs.empty()) throw InvalidInput("design.patch_designs", "no patch was designed");
  std::vector<Design> patches;
  for (size_t j = 0; j < designs.size(); ++j) {
    try {
      patches.push_back(design_from_proto(designs[j]));
    } catch (const Error& e) {
      rethrow_within(e, "design.patch_designs[" + std::to_string(j) + "]");
    }
  }
  std::vector<const TriangleMesh*> targets;
  for (const Design& d : patches) targets.push_back(&d.target.patch.mesh);
  return compare_job(scan, lamellas_of(deployment.rods(), "deployment.rods"),
                     patches.front().lamella_width, patches.front().lamella_thickness,
                     merge_meshes(targets), options, progress);
}

}  // namespace gridshell
