// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/application/convert_deployment.h"

#include <cmath>
#include <string>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh.h"

namespace gridshell {
namespace {

using google::protobuf::ListValue;

/// Every field here is a field of the Design message (the caller names where it came from).
[[noreturn]] void fail(const std::string& field, const std::string& problem) {
  throw InvalidInput(field, problem);
}

double number(const google::protobuf::Value& value, const std::string& field) {
  if (value.kind_case() != google::protobuf::Value::kNumberValue) fail(field, "expected a number");
  const double v = value.number_value();
  if (!std::isfinite(v) || std::abs(v) > kMaxCoordinate)
    fail(field, "not a finite number within +-1e15");
  return v;
}

/// A list of points of `dimension` coordinates.
template <int N>
std::vector<Eigen::Matrix<double, N, 1>> points(const ListValue& list, const std::string& field) {
  std::vector<Eigen::Matrix<double, N, 1>> out;
  for (int i = 0; i < list.values_size(); ++i) {
    const std::string item = field + "[" + std::to_string(i) + "]";
    const auto& value = list.values(i);
    if (value.kind_case() != google::protobuf::Value::kListValue ||
        value.list_value().values_size() != N)
      fail(item, "expected a list of " + std::to_string(N) + " numbers");
    Eigen::Matrix<double, N, 1> p;
    for (int k = 0; k < N; ++k) p[k] = number(value.list_value().values(k), item);
    out.push_back(p);
  }
  return out;
}

double finite(double v, const std::string& field) {
  if (!std::isfinite(v) || std::abs(v) > kMaxCoordinate)
    fail(field, "not a finite number within +-1e15");
  return v;
}

void add_point(ListValue* list, const Vec3& p) {
  ListValue* point = list->add_values()->mutable_list_value();
  for (int k = 0; k < 3; ++k) point->add_values()->set_number_value(p[k]);
}

// The run's largest stresses and, where the material's strengths are known, how close they
// come to them: the normal stress at a cross-section's corner against the bending strength, the
// torsion shear stress against the shear strength.
void fill_stresses(const DeploymentRun& run, const v1::SimulationOptions& options,
                   v1::SimulationRun* out) {
  double bending = 0, normal = 0, torsion = 0;
  for (const SimulatedLamella& l : run.lamellas) {
    bending = std::max(bending, l.max_bending_stress);
    normal = std::max(normal, l.max_normal_stress);
    torsion = std::max(torsion, l.max_torsion_stress);
  }
  out->set_max_bending_stress(bending);
  out->set_max_normal_stress(normal);
  out->set_max_torsion_stress(torsion);
  if (options.bending_strength() > 0) {
    out->set_bending_utilization(normal / options.bending_strength());
    int over = 0;
    for (const SimulatedLamella& l : run.lamellas)
      over += l.max_normal_stress > options.bending_strength() ||
              (options.shear_strength() > 0 && l.max_torsion_stress > options.shear_strength());
    out->set_overstressed_lamellas(over);
  }
  if (options.shear_strength() > 0) out->set_shear_utilization(torsion / options.shear_strength());
}

void fill_run(const DeploymentRun& run, const v1::SimulationOptions& options,
              v1::SimulationRun* out) {
  out->set_notches(run.notches);
  out->set_rms(run.rms);
  out->set_max_deviation(run.max_deviation);
  out->set_grid_vertices(run.grid_vertices);
  out->set_iterations(run.iterations);
  out->set_outer_iterations(run.outer_iterations);
  out->set_connection_moves(run.connection_moves);
  out->set_connections_at_vertices(run.connections_at_vertices);
  out->set_converged(run.converged);
  out->set_gradient_norm(run.gradient_norm);
  out->set_gradient_tolerance(run.gradient_tolerance);
  out->set_termination(run.termination);
  out->set_seconds(run.seconds);
  for (const auto& [term, value] : run.energies) (*out->mutable_energies())[term] = value;
  out->set_energy_unit(run.energy_unit);
  if (!run.profile.factorization.empty()) {
    const SolverProfile& p = run.profile;
    v1::SolverProfile* profile = out->mutable_solver_profile();
    profile->set_factorization(p.factorization);
    profile->set_unknowns(p.unknowns);
    profile->set_factor_nonzeros(p.factor_nonzeros);
    profile->set_analyses(p.analyses);
    profile->set_evaluations(p.evaluations);
    profile->set_factorizations(p.factorizations);
    profile->set_failed_factorizations(p.failed_factorizations);
    profile->set_cost_evaluations(p.cost_evaluations);
    profile->set_seconds_analyze(p.analyze_seconds);
    profile->set_seconds_evaluate(p.evaluate_seconds);
    profile->set_seconds_factorize(p.factorize_seconds);
    profile->set_seconds_solve(p.solve_seconds);
    profile->set_seconds_cost(p.cost_seconds);
  }
  fill_stresses(run, options, out);
  for (const SimulatedConnection& c : run.connections) {
    v1::Connection* connection = out->add_connections();
    connection->set_g(c.g);
    connection->set_h(c.h);
    connection->set_sliding_g(c.sliding_g);
    connection->set_sliding_h(c.sliding_h);
    connection->set_slide_g(c.slide_g);
    connection->set_slide_h(c.slide_h);
    connection->set_notch_g(c.notch_g);
    connection->set_notch_h(c.notch_h);
    connection->set_gap(c.gap);
    connection->set_at_vertex_g(c.at_vertex_g);
    connection->set_at_vertex_h(c.at_vertex_h);
  }
}

}  // namespace

void fill_lamellas(const DeploymentRun& run, google::protobuf::RepeatedPtrField<v1::Lamella>* out) {
  for (const SimulatedLamella& l : run.lamellas) {
    v1::Lamella* lamella = out->Add();
    lamella->mutable_member()->set_family(l.family == Family::G ? "g" : "h");
    lamella->mutable_member()->set_index(l.index);
    lamella->set_boundary(l.boundary);
    lamella->set_rest_length(l.rest_length);
    for (const Vec3& p : l.centerline) add_point(lamella->mutable_centerline(), p);
    for (const Vec3& n : l.normals) add_point(lamella->mutable_normals(), n);
    for (double d : l.deviation) lamella->add_deviation(d);
    lamella->set_max_weak_curvature(l.max_weak_curvature);
    lamella->set_max_strong_curvature(l.max_strong_curvature);
    lamella->set_max_twist_rate(l.max_twist_rate);
    lamella->set_max_bending_stress(l.max_bending_stress);
    lamella->set_max_strong_bending_stress(l.max_strong_bending_stress);
    lamella->set_max_torsion_stress(l.max_torsion_stress);
    lamella->set_max_normal_stress(l.max_normal_stress);
  }
}

Design design_from_proto(const v1::Design& in) {
  Design design;
  Patch& patch = design.target.patch;
  std::vector<Vec3> vertices = points<3>(in.patch().vertices(), "patch.vertices");
  const int nv = static_cast<int>(vertices.size());
  const auto faces = points<3>(in.patch().faces(), "patch.faces");
  std::vector<Face> patch_faces;
  for (size_t i = 0; i < faces.size(); ++i) {
    Face f;
    for (int k = 0; k < 3; ++k) {
      const double v = faces[i][k];
      if (v != std::floor(v) || v < 0 || v >= nv)
        fail("patch.faces[" + std::to_string(i) + "]", "vertex index " + std::to_string(v) +
                                                           " is not one of the " +
                                                           std::to_string(nv) + " vertices");
      f[k] = static_cast<int>(v);
    }
    patch_faces.push_back(f);
  }
  if (patch_faces.empty()) fail("patch.faces", "the target patch has no faces");
  try {
    patch.mesh = TriangleMesh(std::move(vertices), std::move(patch_faces));
  } catch (const Error& e) {
    rethrow_within(e, "patch");  // "patch.faces[12]": not a manifold patch
  }
  if (in.patch().corners_size() == 4)
    for (int k = 0; k < 4; ++k) {
      const int c = in.patch().corners(k);
      if (c < 0 || c >= nv) fail("patch.corners", "corner vertex out of range");
      patch.corners[k] = c;
    }
  design.alpha = finite(in.alpha(), "alpha");
  design.alpha_bar = finite(in.alpha_bar(), "alpha_bar");
  design.lamella_width = in.options().lamella_width();
  design.lamella_thickness = in.options().lamella_thickness();
  if (!(design.lamella_width > 0) || !std::isfinite(design.lamella_width))
    fail("options.lamella_width", "must be a positive number");
  if (!(design.lamella_thickness > 0) || !std::isfinite(design.lamella_thickness))
    fail("options.lamella_thickness", "must be a positive number");

  for (int i = 0; i < in.members_size(); ++i) {
    const v1::Member& m = in.members(i);
    const std::string field = "members[" + std::to_string(i) + "]";
    Member member;
    if (m.family() == "g")
      member.family = Family::G;
    else if (m.family() == "h")
      member.family = Family::H;
    else
      fail(field + ".family", "expected \"g\" or \"h\", got \"" + m.family() + "\"");
    std::vector<Member>& family = member.family == Family::G ? design.grid.g : design.grid.h;
    if (m.index() != static_cast<int>(family.size()))
      fail(field + ".index", "members of a family must be listed by index from 0 (expected " +
                                 std::to_string(family.size()) + ", got " +
                                 std::to_string(m.index()) + ")");
    member.index = m.index();
    member.boundary = m.boundary();
    member.u_start = finite(m.u_start(), field + ".u_start");
    member.u_end = finite(m.u_end(), field + ".u_end");
    member.surface = points<3>(m.surface(), field + ".surface");
    if (member.surface.size() < 2) fail(field + ".surface", "needs at least 2 points");
    const auto planar = points<2>(m.planar(), field + ".planar");
    if (planar.size() != 2) fail(field + ".planar", "expected 2 points");
    member.planar = {planar[0], planar[1]};
    member.length = finite(m.length(), field + ".length");
    member.planar_length = finite(m.planar_length(), field + ".planar_length");
    if (!(member.planar_length > 0)) fail(field + ".planar_length", "must be positive");
    family.push_back(std::move(member));
  }
  const int ng = static_cast<int>(design.grid.g.size()),
            nh = static_cast<int>(design.grid.h.size());
  if (ng < 2 || nh < 2) fail("members", "each family needs at least its two boundary members");
  // A crossing's or anchor's member indices.
  const auto check_members = [&](const std::string& field, int g, int h) {
    if (g < 0 || g >= ng) fail(field + ".g", "no such g member");
    if (h < 0 || h >= nh) fail(field + ".h", "no such h member");
  };
  for (int i = 0; i < in.crossings_size(); ++i) {
    const v1::Crossing& c = in.crossings(i);
    const std::string field = "crossings[" + std::to_string(i) + "]";
    Crossing x;
    x.g = c.g();
    x.h = c.h();
    check_members(field, x.g, x.h);
    if (c.surface_point_size() != 3) fail(field + ".surface_point", "expected 3 numbers");
    if (c.planar_point_size() != 2) fail(field + ".planar_point", "expected 2 numbers");
    for (int k = 0; k < 3; ++k)
      x.surface_point[k] = finite(c.surface_point(k), field + ".surface_point");
    for (int k = 0; k < 2; ++k)
      x.planar_point[k] = finite(c.planar_point(k), field + ".planar_point");
    x.s_g = finite(c.s_g(), field + ".s_g");
    x.s_bar_g = finite(c.s_bar_g(), field + ".s_bar_g");
    x.s_h = finite(c.s_h(), field + ".s_h");
    x.s_bar_h = finite(c.s_bar_h(), field + ".s_bar_h");
    x.on_boundary = c.on_boundary();
    design.grid.crossings.push_back(x);
  }
  for (int i = 0; i < in.anchors_size(); ++i) {
    const v1::Anchor& a = in.anchors(i);
    const std::string field = "anchors[" + std::to_string(i) + "]";
    Anchor anchor;
    anchor.g = a.g();
    anchor.h = a.h();
    check_members(field, anchor.g, anchor.h);
    anchor.corner = a.corner();
    anchor.side = a.side();
    if (a.position_size() != 3) fail(field + ".position", "expected 3 numbers");
    if (a.normal_size() != 3) fail(field + ".normal", "expected 3 numbers");
    for (int k = 0; k < 3; ++k) anchor.position[k] = finite(a.position(k), field + ".position");
    for (int k = 0; k < 3; ++k) anchor.normal[k] = finite(a.normal(k), field + ".normal");
    if (!(anchor.normal.norm() > 0)) fail(field + ".normal", "must not be zero");
    anchor.boundary_curvature = a.boundary_curvature();
    design.anchors.push_back(anchor);
  }
  return design;
}

v1::Deployment to_proto(const DeploymentRun* without_notches, const DeploymentRun* with_notches,
                        const v1::SimulationOptions& options, const std::string& design_name) {
  v1::Deployment out;
  out.set_design(design_name);
  *out.mutable_options() = options;
  bool converged = true;
  int iterations = 0;
  if (without_notches) {
    out.set_rms_without_notches(without_notches->rms);
    out.set_seconds_without_notches(without_notches->seconds);
    converged = converged && without_notches->converged;
    iterations += without_notches->iterations;
    out.set_grid_vertices(without_notches->grid_vertices);
    fill_lamellas(*without_notches, out.mutable_rods_without_notches());
    fill_run(*without_notches, options, out.mutable_without_notches());
  }
  if (with_notches) {
    out.set_rms_with_notches(with_notches->rms);
    out.set_seconds_with_notches(with_notches->seconds);
    converged = converged && with_notches->converged;
    iterations += with_notches->iterations;
    out.set_grid_vertices(with_notches->grid_vertices);
    fill_lamellas(*with_notches, out.mutable_rods());
    fill_run(*with_notches, options, out.mutable_with_notches());
  }
  out.set_converged(converged);
  out.set_iterations(iterations);
  return out;
}

}  // namespace gridshell
