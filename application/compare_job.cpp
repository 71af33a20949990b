// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/application/compare_job.h"

#include <cmath>

#include "gridshell/application/convert_deployment.h"
#include "gridshell/foundation/errors.h"

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

std::vector<SimulatedLamella> lamellas_from_proto(const v1::Deployment& deployment) {
  const bool with = deployment.rods_size() > 0;
  const auto& rods = with ? deployment.rods() : deployment.rods_without_notches();
  const std::string name = with ? "deployment.rods" : "deployment.rods_without_notches";
  if (rods.empty()) throw InvalidInput("deployment.rods", "the deployment has no lamellas");
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

CompareJob run_compare_job(const std::vector<Vec3>& scan, const v1::Design& design_message,
                           const v1::Deployment& deployment, const CompareOptions& options,
                           const Progress& progress) {
  Design design;
  try {
    design = design_from_proto(design_message);
  } catch (const Error& e) {
    rethrow_within(e, "design");
  }
  const std::vector<SimulatedLamella> lamellas = lamellas_from_proto(deployment);
  const std::vector<Triangle3> surface =
      lamella_surface(lamellas, design.lamella_width, design.lamella_thickness);
  const ScanComparison c = compare_scan(scan, surface, design.target.patch.mesh, options, progress);
  CompareJob job;
  v1::CompareReport& r = job.report;
  r.set_points_read(static_cast<int>(scan.size()));
  r.set_points_used(c.used);
  r.set_points_rejected(c.rejected);
  r.set_rejection_distance(c.rejection_distance);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      r.add_transform(i < 3 ? (j < 3 ? c.rotation(i, j) : c.translation[i]) : (j == 3 ? 1 : 0));
  const Eigen::AngleAxisd axis_angle(c.rotation);
  const Vec3 rv = axis_angle.axis() * axis_angle.angle();
  for (int k = 0; k < 3; ++k) r.add_rotation_vector(rv[k]);
  r.set_icp_iterations(c.icp_iterations);
  r.set_coarse(c.coarse);
  fill(r.mutable_deployment(), c.deployment, "deployment");
  fill(r.mutable_target(), c.target, "target");
  job.ply = compare_ply(scan, c);
  return job;
}

}  // namespace gridshell
