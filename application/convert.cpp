// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/application/convert.h"

#include <cmath>

namespace gridshell {
namespace {

using google::protobuf::ListValue;

void add_point(ListValue* list, std::initializer_list<double> values) {
  ListValue* point = list->add_values()->mutable_list_value();
  for (double v : values) point->add_values()->set_number_value(v);
}

}  // namespace

void to_proto(const Anchor& a, v1::Anchor* anchor) {
  anchor->set_g(a.g);
  anchor->set_h(a.h);
  anchor->set_corner(a.corner);
  anchor->set_side(a.side);
  for (int k = 0; k < 3; ++k) anchor->add_position(a.position[k]);
  for (int k = 0; k < 3; ++k) anchor->add_normal(a.normal[k]);
  anchor->set_boundary_curvature(a.boundary_curvature);
}

v1::Design to_proto(const Design& design, const v1::DesignOptions& options,
                    const std::string& input_name) {
  v1::Design out;
  out.set_input(input_name);
  out.set_alpha(design.alpha);
  out.set_alpha_bar(design.alpha_bar);
  out.add_alpha_bar_range(design.alpha_range.min);
  out.add_alpha_bar_range(design.alpha_range.max);
  for (double l : design.planar.side_lengths) out.add_side_lengths(l);
  for (const Vec2& c : design.planar.corners)
    add_point(out.mutable_planar_corners(), {c.x(), c.y()});
  for (const auto* family : {&design.grid.g, &design.grid.h})
    for (const Member& m : *family) {
      v1::Member* member = out.add_members();
      member->set_family(m.family == Family::G ? "g" : "h");
      member->set_index(m.index);
      member->set_boundary(m.boundary);
      member->set_u_start(m.u_start);
      member->set_u_end(m.u_end);
      for (const Vec3& p : m.surface) add_point(member->mutable_surface(), {p.x(), p.y(), p.z()});
      for (const Vec2& p : m.planar) add_point(member->mutable_planar(), {p.x(), p.y()});
      member->set_length(m.length);
      member->set_planar_length(m.planar_length);
    }
  for (const Crossing& x : design.grid.crossings) {
    v1::Crossing* c = out.add_crossings();
    c->set_g(x.g);
    c->set_h(x.h);
    for (int k = 0; k < 3; ++k) c->add_surface_point(x.surface_point[k]);
    for (int k = 0; k < 2; ++k) c->add_planar_point(x.planar_point[k]);
    c->set_s_g(x.s_g);
    c->set_s_bar_g(x.s_bar_g);
    c->set_s_h(x.s_h);
    c->set_s_bar_h(x.s_bar_h);
    c->set_notch_g(x.notch_g());
    c->set_notch_h(x.notch_h());
    c->set_on_boundary(x.on_boundary);
  }
  for (const Anchor& a : design.anchors) to_proto(a, out.add_anchors());
  const Patch& patch = design.target.patch;
  for (const Vec3& v : patch.mesh.vertices())
    add_point(out.mutable_patch()->mutable_vertices(), {v.x(), v.y(), v.z()});
  for (const Face& f : patch.mesh.faces())
    add_point(out.mutable_patch()->mutable_faces(), {double(f[0]), double(f[1]), double(f[2])});
  for (int c : patch.corners) out.mutable_patch()->add_corners(c);
  for (const Vec2& p : design.cladding_g.points)
    add_point(out.mutable_cladding_u(), {p.x(), p.y()});
  for (const Vec2& p : design.cladding_h.points)
    add_point(out.mutable_cladding_v(), {p.x(), p.y()});
  *out.mutable_options() = options;
  return out;
}

v1::DesignReport to_report(const Design& design, const std::string& input_name, int mesh_vertices,
                           double seconds) {
  v1::DesignReport report;
  report.set_input(input_name);
  report.set_mesh_vertices(mesh_vertices);
  report.set_patch_vertices(design.target.patch.mesh.vertex_count());
  report.set_members_g(static_cast<int>(design.grid.g.size()) - 2);
  report.set_members_h(static_cast<int>(design.grid.h.size()) - 2);
  report.set_crossings(static_cast<int>(design.grid.crossings.size()));
  double max_notch = 0, mismatch = 0;
  for (const Crossing& x : design.grid.crossings)
    max_notch = std::max({max_notch, std::abs(x.notch_g()), std::abs(x.notch_h())});
  for (const auto* family : {&design.grid.g, &design.grid.h})
    for (const Member& m : *family)
      mismatch = std::max(mismatch, std::abs(m.length - m.planar_length) / m.length);
  report.set_max_notch(max_notch);
  report.set_max_length_mismatch(mismatch);
  report.set_seconds(seconds);
  const auto& st = design.target.stage_seconds;
  report.set_t_smooth(st.count("smoothing") ? st.at("smoothing") : 0.0);
  double t_grid = 0;
  for (const auto& [stage, s] : design.stage_seconds) {
    (*report.mutable_stage_seconds())[stage] = s;
    if (stage != "patch") t_grid += s;
  }
  for (const auto& [stage, s] : st) (*report.mutable_stage_seconds())["patch_" + stage] = s;
  report.set_t_grid(t_grid);
  report.set_eta_before(design.target.smoothing.eta_before);
  report.set_eta_after(design.target.smoothing.eta_after);
  report.set_smoothing_iterations(design.target.smoothing.iterations);
  for (const std::string& w : design.target.warnings) report.add_warnings(w);
  report.set_recuts(design.target.smoothing.recuts);
  for (double e : design.target.boundary_excess) report.add_boundary_geodesic_excess(e);
  report.set_map_vertices(design.maps.mesh_vertices);
  report.set_map_error(design.map_error);
  report.set_member_end_shift(design.member_end_shift);
  return report;
}

v1::AutoCornerSearch to_proto(const AutoCornerReport& report, const TriangleMesh& mesh,
                              const std::function<int(int)>& sent_vertex) {
  v1::AutoCornerSearch out;
  for (const AutoCornerCandidate& c : report.candidates) {
    v1::AutoCornerCandidate* candidate = out.add_candidates();
    for (int v : c.vertices) {
      for (int k = 0; k < 3; ++k) candidate->add_positions(mesh.vertices()[v][k]);
      candidate->add_input_vertices(sent_vertex(v));
    }
    candidate->set_kind(c.kind);
    candidate->set_area(c.area);
    candidate->set_coarse_area(c.coarse_area);
    for (double a : c.corner_angles) candidate->add_corner_angles(a);
    candidate->set_eta(c.eta);
    if (c.alpha_range)
      for (double a : *c.alpha_range) candidate->add_alpha_bar_range(a);
    candidate->set_accepted(c.accepted);
    candidate->set_reason(c.reason);
  }
  out.set_chosen(report.chosen);
  out.set_rule(report.rule);
  out.set_cuts(report.cuts);
  out.set_evaluations(report.evaluations);
  out.set_seconds(report.seconds);
  out.set_min_corner_angle(report.min_corner_angle);
  out.set_max_corner_angle(report.max_corner_angle);
  out.set_simplified_vertices(report.simplified_vertices);
  out.set_area_error(report.area_error);
  return out;
}

}  // namespace gridshell
