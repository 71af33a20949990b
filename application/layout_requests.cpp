// SPDX-License-Identifier: GPL-3.0-or-later
// Layout requests -> kernel -> results (see gridshell/application/layout.h).
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

#include "gridshell/application/convert.h"
#include "gridshell/application/layout.h"
#include "gridshell/application/options.h"
#include "gridshell/design/layout.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"

namespace gridshell {

PatchLayout layout_from_proto(const v1::Layout& in, const LoadReport& load) {
  PatchLayout out;
  for (int i = 0; i < in.corners_size(); ++i) {
    const v1::Layout::Corner& c = in.corners(i);
    const std::string field = "layout.corners[" + std::to_string(i) + "]";
    LayoutCorner corner;
    if (c.has_vertex() == (c.point_size() > 0))
      throw InvalidInput(field, "give either vertex or point (3 numbers)");
    if (c.has_vertex()) {
      corner.vertex = loaded_vertex(load, c.vertex(), field + ".vertex");
    } else {
      if (c.point_size() != 3)
        throw InvalidInput(field + ".point",
                           "expected 3 numbers x, y, z, got " + std::to_string(c.point_size()));
      for (int k = 0; k < 3; ++k) {
        if (!std::isfinite(c.point(k)) || std::abs(c.point(k)) > kMaxCoordinate)
          throw InvalidInput(field + ".point[" + std::to_string(k) + "]",
                             "not a finite number within +-1e15");
        corner.point[k] = c.point(k);
      }
    }
    out.corners.push_back(corner);
  }
  for (int j = 0; j < in.patches_size(); ++j) {
    const v1::Layout::Patch& p = in.patches(j);
    if (p.corners_size() != 4)
      throw InvalidInput("layout.patches[" + std::to_string(j) + "].corners",
                         "expected 4 corner indices, got " + std::to_string(p.corners_size()));
    PatchLayout::Quad quad;
    quad.name = p.name();
    // A name names a folder (patches/<name>/) and the parts ("P2-g7"): plain and short.
    const bool plain =
        quad.name.size() <= 64 && std::all_of(quad.name.begin(), quad.name.end(), [](char ch) {
          return std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_';
        });
    if (!plain)
      throw InvalidInput("layout.patches[" + std::to_string(j) + "].name",
                         "'" + quad.name +
                             "': use up to 64 letters, digits, '-' and '_' (it names a folder "
                             "and the parts)");
    for (int k = 0; k < 4; ++k) quad.corners[k] = p.corners(k);
    out.patches.push_back(quad);
  }
  return out;
}

v1::LayoutResult run_layout(const v1::LayoutRequest& request, const Progress& progress,
                            const RunSettings& settings) {
  // The mesh and the patch options as a patch request checks them.
  v1::PatchRequest patch_request;
  *patch_request.mutable_mesh() = request.mesh();
  *patch_request.mutable_options() = request.options();
  PatchInputs in = prepare_patch(patch_request);
  in.options.coverability.threads = settings.threads;
  const RequestedLayout layout = cut_requested_layout(
      request.layout(), request.has_automatic() ? &request.automatic() : nullptr, in.mesh, in.load,
      in.options, progress);
  return layout_result(layout, in.mesh, mesh_label(request.mesh()));
}

void apply_patch_design(const v1::Layout::Patch& patch, const std::string& field,
                        DesignOptions& options, v1::DesignOptions& record) {
  if (patch.has_alpha()) {
    try {
      parse_alpha(patch.alpha(), options);
    } catch (const Error& e) {
      throw InvalidInput(field + ".alpha", e.message());
    }
    record.set_alpha(patch.alpha());
  }
  for (const auto& [name, value, count, set] :
       {std::tuple{"members_u", patch.members_u(), &options.members_g,
                   &v1::DesignOptions::set_members_u},
        std::tuple{"members_v", patch.members_v(), &options.members_h,
                   &v1::DesignOptions::set_members_v}}) {
    if (value == 0) continue;
    *count = static_cast<int>(
        check_option(option_spec("design", name), value, field + "." + std::string(name)));
    (record.*set)(value);
  }
}

AutoLayoutOptions prepare_auto_layout_options(const v1::AutoLayoutOptions& options,
                                              const std::string& prefix) {
  AutoLayoutOptions out;
  const auto check = [&](const char* name, double value) {
    return check_option(option_spec("layout", name), value, prefix + "." + name);
  };
  if (options.max_patches() != 0)
    out.max_patches = static_cast<int>(check("max_patches", options.max_patches()));
  if (options.coverage_goal() != 0)
    out.coverage_goal = check("coverage_goal", options.coverage_goal());
  return out;
}

RequestedLayout cut_requested_layout(const v1::Layout& layout,
                                     const v1::AutoLayoutOptions* automatic,
                                     const TriangleMesh& mesh, const LoadReport& load,
                                     const TargetPatchOptions& options, const Progress& progress) {
  RequestedLayout out;
  if (!automatic) {
    out.cut = cut_layout(mesh, layout_from_proto(layout, load), options, progress);
    out.given = layout;
    return out;
  }
  const AutoLayoutOptions auto_options = prepare_auto_layout_options(*automatic);
  if (layout.corners_size() > 0 || layout.patches_size() > 0)
    throw InvalidInput("layout", "give a layout or ask for an automatic one, not both");
  const auto start = std::chrono::steady_clock::now();
  AutoLayout found;
  try {
    found = auto_layout(mesh, options, auto_options, progress);
  } catch (const InvalidInput& e) {
    rethrow_within(e, "automatic");  // its options: "automatic.max_patches"
  }
  v1::LayoutReport::Automatic& report = out.automatic.emplace();
  report.set_columns(found.columns);
  report.set_rows(found.rows);
  report.set_patches(found.patches);
  report.set_surface(found.surface);
  report.set_cut(found.cut);
  for (const Vec3& p : found.cut_path)
    for (int k = 0; k < 3; ++k) report.add_cut_path(p[k]);
  for (int v : found.boundary_corners) report.add_boundary_corners(sent_vertex(load, v));
  for (const AutoLayoutTrial& t : found.trials) {
    v1::LayoutReport::Automatic::Trial& m = *report.add_trials();
    m.set_columns(t.columns);
    m.set_rows(t.rows);
    m.set_patches(t.patches);
    m.set_coverage(t.coverage);
    m.set_cut_coverage(t.cut_coverage);
    m.set_checked(t.checked);
    m.set_failing(t.failing);
    m.set_first_problem(t.first_problem);
    m.set_seconds(t.seconds);
  }
  report.set_seconds(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  // The layout found, as a file would give it: boundary corners as vertices, the others as
  // points on the surface.
  for (const LayoutCorner& c : found.result.layout.corners) {
    v1::Layout::Corner& m = *out.given.add_corners();
    if (c.vertex >= 0) {
      m.set_vertex(sent_vertex(load, c.vertex));
    } else {
      for (int k = 0; k < 3; ++k) m.add_point(c.point[k]);
    }
  }
  for (const PatchLayout::Quad& quad : found.result.layout.patches) {
    v1::Layout::Patch& m = *out.given.add_patches();
    for (int c : quad.corners) m.add_corners(c);
  }
  out.cut = std::move(found.result);
  return out;
}

std::string mesh_label(const v1::Mesh& mesh) {
  return mesh.name().empty() ? mesh.example() : mesh.name();
}

v1::LayoutResult layout_result(const RequestedLayout& requested, const TriangleMesh& mesh,
                               const std::string& input) {
  const LayoutResult& cut = requested.cut;
  v1::LayoutResult out;
  v1::LayoutReport& report = *out.mutable_report();
  report.set_input(input);
  *report.mutable_layout() = requested.given;
  if (requested.automatic) *report.mutable_automatic() = *requested.automatic;
  for (size_t j = 0; j < cut.layout.patches.size(); ++j)
    report.mutable_layout()
        ->mutable_patches(static_cast<int>(j))
        ->set_name(cut.layout.patches[j].name);
  report.set_input_area(cut.input_area);
  report.set_covered_area(cut.covered_area);
  report.set_coverage(cut.coverage());
  for (const LayoutPatch& p : cut.patches) {
    v1::LayoutReport::PatchSummary& s = *report.add_patches();
    s.set_name(p.name);
    s.set_ok(p.target.has_value() && !p.problem);
    if (p.problem) {
      s.set_problem_code(to_string(p.problem->code()));
      s.set_problem_field(p.problem->field());
      s.set_problem(p.problem->message());
    }
    v1::Mesh* mesh = out.add_patches();
    mesh->set_name(p.name);
    if (!p.target) continue;
    const TargetPatch& t = *p.target;
    s.set_vertices(t.patch.mesh.vertex_count());
    s.set_area(t.area);
    for (double a : t.corner_angles) s.add_corner_angles(a);
    for (double l : t.boundary_lengths) s.add_side_lengths(l);
    s.set_eta(t.coverability.gap.eta);
    if (p.alpha_range && !p.problem) {
      s.add_alpha_range((*p.alpha_range)[0]);
      s.add_alpha_range((*p.alpha_range)[1]);
    }
    *mesh = to_proto(t.patch.mesh, p.name);
  }
  // What is not covered, and why.
  double cut_area = 0;
  for (const LayoutPatch& p : cut.patches) {
    if (p.target) cut_area += p.target->area;
    if (!p.problem) continue;
    v1::LayoutReport::Uncovered& u = *report.add_uncovered();
    u.set_where(p.name);
    u.set_area(p.target ? p.target->area : 0);
    u.set_reason(p.problem->message());
  }
  if (cut.input_area - cut_area > 1e-9 * cut.input_area) {
    v1::LayoutReport::Uncovered& u = *report.add_uncovered();
    u.set_where("outside the patches");
    u.set_area(cut.input_area - cut_area);
    u.set_reason(
        "between the outer patch sides and the input's boundary: a side is an exact shortest "
        "geodesic and cuts across where the boundary bends away; more corners along the boundary "
        "cover more of it");
  }
  v1::File& svg = *out.add_views();
  svg.set_name("layout.svg");
  svg.set_content(layout_svg(mesh, cut));
  for (const LayoutSeam& seam : cut.seams) {
    v1::LayoutReport::Seam& s = *report.add_seams();
    s.add_corners(seam.corners[0]);
    s.add_corners(seam.corners[1]);
    for (const auto& [j, k] : seam.uses) s.add_patches(cut.layout.patches[j].name);
    s.set_length(seam.length);
    s.set_mismatch(seam.mismatch);
  }
  return out;
}

std::string merge_obj(const std::string& heading,
                      const std::vector<std::pair<std::string, std::string>>& parts) {
  std::ostringstream obj;
  obj << "# " << heading << "\n";
  int offset = 0;
  for (const auto& [prefix, text] : parts) {
    std::istringstream lines(text);
    int vertices = 0;
    bool named = false;
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("o ", 0) == 0) {
        obj << "o " << prefix << "-" << line.substr(2) << "\n";
        named = true;
      } else if (line.rfind("v ", 0) == 0) {
        if (!named) {
          obj << "o " << prefix << "\n";
          named = true;
        }
        obj << line << "\n";
        ++vertices;
      } else if (line.rfind("f ", 0) == 0) {
        std::istringstream f(line.substr(2));
        obj << "f";
        for (int v; f >> v;) obj << " " << v + offset;
        obj << "\n";
      }
    }
    offset += vertices;
  }
  return obj.str();
}

FileBundle layout_files(const v1::LayoutResult& result) {
  // One OBJ object per cut patch, vertices numbered on through the file.
  std::vector<std::pair<std::string, std::string>> parts;
  for (const v1::Mesh& mesh : result.patches()) {
    if (mesh.indices().empty()) continue;
    std::vector<Vec3> vertices;
    for (int k = 0; k + 2 < mesh.positions_size(); k += 3)
      vertices.emplace_back(mesh.positions(k), mesh.positions(k + 1), mesh.positions(k + 2));
    std::vector<Face> faces;
    for (int k = 0; k + 2 < mesh.indices_size(); k += 3)
      faces.push_back({mesh.indices(k), mesh.indices(k + 1), mesh.indices(k + 2)});
    parts.emplace_back(mesh.name(), obj_text(vertices, faces));
  }
  const std::string obj = merge_obj("gridshell layout: " + result.report().input() + ", " +
                                        std::to_string(result.report().patches_size()) + " patches",
                                    parts);
  FileBundle files{{"layout.json", to_json(result.report()) + "\n"}, {"layout.obj", obj}};
  for (const v1::File& view : result.views()) files[view.name()] = view.content();
  return files;
}

}  // namespace gridshell
