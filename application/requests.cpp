// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/application/requests.h"

#include <sys/resource.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <utility>

#include "gridshell/application/convert.h"
#include "gridshell/application/files.h"
#include "gridshell/application/layout.h"
#include "gridshell/application/options.h"
#include "gridshell/application/patch_cache.h"
#include "gridshell/application/patch_routing_key.h"
#include "gridshell/design/design_export.h"
#include "gridshell/design/suggestions.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/geodesic/geodesic.h"
#include "gridshell/mesh/curvature.h"

namespace gridshell {
namespace {

// The ranges of the options are in the one description (options.cpp): generous caps that keep
// one request from asking for unbounded work, far above every example.

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// CPU time of the whole process (all threads), s.
double process_cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
         1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

/// Peak resident memory of the process (VmHWM of /proc/self/status), bytes; 0 if unknown.
long long peak_resident_bytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::atoll(line.c_str() + 6) * 1024LL;
  return 0;
}

std::string indexed(const std::string& name, long long index) {
  return name + "[" + std::to_string(index) + "]";
}

/// "mesh.faces[7]" -> "mesh.indices[21]", "mesh.vertices[2]" -> "mesh.positions[6]".
std::string packed_field(const std::string& field) {
  for (const auto& [element, packed] : {std::pair{"mesh.faces[", "mesh.indices["},
                                        std::pair{"mesh.vertices[", "mesh.positions["}}) {
    const std::string prefix = element;
    if (field.rfind(prefix, 0) != 0 || field.back() != ']') continue;
    const std::string number = field.substr(prefix.size(), field.size() - prefix.size() - 1);
    long long index = 0;
    const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), index);
    if (ec != std::errc() || end != number.data() + number.size()) continue;
    return packed + std::to_string(3 * index) + "]";
  }
  return field;
}

std::string shortest(double value) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, end);
}

GeodesicMethod any_method(const std::string& text, const std::string& field) {
  try {
    return parse_geodesic_method(text.empty() ? "fast" : text);
  } catch (const Error& e) {
    rethrow_within(e, field);
  }
}

/// The exact engine a patch or design option names ("" = fast), checked against its option.
GeodesicMethod exact_method(const std::string& group, const std::string& text,
                            const std::string& field) {
  return any_method(
      check_option(option_spec(group, "geodesic_method"), text.empty() ? "fast" : text, field),
      field);
}

double eta_max_option(const std::string& group, bool has, double value, const std::string& field,
                      double fallback) {
  return has ? check_option(option_spec(group, "eta_max"), value, field) : fallback;
}

/// [min, max] corner angles of the automatic corners' search, radians (empty = default).
void auto_corner_angles(const std::string& group,
                        const google::protobuf::RepeatedField<double>& values,
                        const std::string& field, AutoCornerOptions& options) {
  if (values.empty()) return;
  const OptionSpec& spec = option_spec(group, "auto_corner_angles");
  if (values.size() != spec.count)
    throw InvalidInput(field, "expected two angles [min, max] in radians, got " +
                                  std::to_string(values.size()) + " numbers");
  for (int k = 0; k < values.size(); ++k)
    check_option(spec, values[k], field + "[" + std::to_string(k) + "]");
  const double lo = values[0], hi = values[1];
  if (!(lo < hi))
    throw InvalidInput(field, "expected min < max, got " + shortest(lo) + ", " + shortest(hi));
  options.min_corner_angle = lo;
  options.max_corner_angle = hi;
}

std::string corner_label(const v1::Corners& corners) {
  if (!corners.label().empty()) return corners.label();
  std::string label;
  if (corners.vertices_size() > 0) {
    for (int v : corners.vertices()) label += (label.empty() ? "" : ",") + std::to_string(v);
  } else if (corners.points_size() > 0) {
    for (int k = 0; k < corners.points_size(); ++k)
      label += (k == 0 ? "" : k % 3 == 0 ? ";" : ",") + shortest(corners.points(k));
  } else {
    label = "auto";
  }
  return label;
}

}  // namespace

int loaded_vertex(const LoadReport& load, int v, const std::string& field) {
  const auto& map = load.vertex_of_file_vertex;
  if (v < 0 || v >= static_cast<int>(map.size()))
    throw InvalidInput(field, "vertex index " + std::to_string(v) +
                                  " is out of range (the mesh has " + std::to_string(map.size()) +
                                  " vertices, numbered from 0)");
  if (map[v] < 0)
    throw InvalidInput(field, "vertex " + std::to_string(v) +
                                  " was removed as an isolated vertex (no face uses it)");
  return map[v];
}

int sent_vertex(const LoadReport& load, int v) {
  if (v < 0) return -1;
  const auto& map = load.vertex_of_file_vertex;
  const auto it = std::find(map.begin(), map.end(), v);
  return it == map.end() ? -1 : static_cast<int>(it - map.begin());
}

namespace {

/// An example surface by name, with an identity load report (nothing was repaired).
TriangleMesh example_mesh(const std::string& name, LoadReport* report,
                          std::array<int, 4>* corners) {
  ExampleSurface example;
  try {
    example = make_example(name);
  } catch (const Error& e) {
    throw InvalidInput("mesh.example", e.message());
  }
  if (report) {
    *report = LoadReport{};
    report->format = "example";
    report->file_vertices = example.mesh.vertex_count();
    report->file_faces = example.mesh.face_count();
    report->vertex_of_file_vertex.resize(example.mesh.vertex_count());
    for (int v = 0; v < example.mesh.vertex_count(); ++v) report->vertex_of_file_vertex[v] = v;
  }
  if (corners) *corners = example.corners;
  return std::move(example.mesh);
}

}  // namespace

TriangleMesh to_mesh(const v1::Mesh& mesh, LoadReport* report,
                     std::array<int, 4>* example_corners) {
  const bool arrays = mesh.positions_size() > 0 || mesh.indices_size() > 0;
  const bool file = !mesh.file().empty() || !mesh.format().empty();
  const bool example = !mesh.example().empty();
  if (arrays + file + example > 1)
    throw InvalidInput("mesh", "give one of positions and indices, file (with format) or example");
  if (example) return example_mesh(mesh.example(), report, example_corners);
  if (file) {
    const std::optional<MeshFormat> format = mesh_format_from_name(mesh.format());
    if (!format)
      throw InvalidInput("mesh.format",
                         "expected obj, off, ply, stl or a file name with one of "
                         "those extensions, got '" +
                             mesh.format() + "'");
    if (mesh.file().empty()) throw InvalidInput("mesh.file", "empty: no file bytes");
    return read_mesh(mesh.file(), *format, "mesh.file", report);
  }
  const int positions = mesh.positions_size(), indices = mesh.indices_size();
  if (positions == 0) throw InvalidInput("mesh.positions", "empty: the mesh has no vertices");
  if (positions % 3 != 0)
    throw InvalidInput(
        "mesh.positions",
        std::to_string(positions) + " numbers is not a multiple of 3 (x, y, z per vertex)");
  if (indices == 0) throw InvalidInput("mesh.indices", "empty: the mesh has no faces");
  if (indices % 3 != 0)
    throw InvalidInput("mesh.indices",
                       std::to_string(indices) +
                           " numbers is not a multiple of 3 (three vertex indices per triangle)");
  const int vertex_count = positions / 3;
  std::vector<Vec3> vertices(vertex_count);
  for (int k = 0; k < positions; ++k) {
    const double value = mesh.positions(k);
    if (!std::isfinite(value))
      throw InvalidInput(indexed("mesh.positions", k),
                         std::string(std::isnan(value) ? "NaN" : "infinite") + " coordinate (" +
                             "xyz"[k % 3] + " of vertex " + std::to_string(k / 3) + ")");
    vertices[k / 3][k % 3] = value;
  }
  std::vector<Face> faces(indices / 3);
  for (int k = 0; k < indices; ++k) {
    const int index = mesh.indices(k);
    if (index < 0 || index >= vertex_count)
      throw InvalidInput(indexed("mesh.indices", k), "vertex index " + std::to_string(index) +
                                                         " is out of range (the mesh has " +
                                                         std::to_string(vertex_count) +
                                                         " vertices, numbered from 0)");
    faces[k / 3][k % 3] = index;
  }
  try {
    return mesh_from_arrays("mesh", vertices, faces, report);
  } catch (const InvalidInput& e) {
    // The loader names faces and vertices; the request has them packed: face k is
    // mesh.indices[3k..3k+2], vertex k is mesh.positions[3k..3k+2].
    throw InvalidInput(packed_field(e.field()), e.message());
  }
}

v1::Mesh to_proto(const TriangleMesh& mesh, const std::string& name) {
  v1::Mesh out;
  out.set_name(name);
  out.mutable_positions()->Reserve(3 * mesh.vertex_count());
  for (const Vec3& p : mesh.vertices())
    for (int k = 0; k < 3; ++k) out.add_positions(p[k]);
  out.mutable_indices()->Reserve(3 * mesh.face_count());
  for (const Face& f : mesh.faces())
    for (int v : f) out.add_indices(v);
  return out;
}

CornerSpec to_corner_spec(const v1::Corners& corners, const LoadReport& load) {
  CornerSpec spec;
  const bool vertices = corners.vertices_size() > 0, points = corners.points_size() > 0;
  if (vertices && points) throw InvalidInput("corners", "give either vertices or points, not both");
  if (vertices) {
    if (corners.vertices_size() != 4)
      throw InvalidInput("corners.vertices", "expected 4 vertex indices, got " +
                                                 std::to_string(corners.vertices_size()));
    spec.kind = CornerSpec::Kind::Vertices;
    for (int i = 0; i < 4; ++i)
      spec.vertices[i] = loaded_vertex(load, corners.vertices(i), indexed("corners.vertices", i));
  } else if (points) {
    if (corners.points_size() != 12)
      throw InvalidInput("corners.points", "expected 4 points (12 numbers x, y, z), got " +
                                               std::to_string(corners.points_size()) + " numbers");
    spec.kind = CornerSpec::Kind::Points;
    for (int k = 0; k < 12; ++k) {
      const double value = corners.points(k);
      if (!std::isfinite(value))
        throw InvalidInput(indexed("corners.points", k), "not a finite number");
      spec.points[k / 3][k % 3] = value;
    }
  } else {
    spec.kind = CornerSpec::Kind::Auto;
  }
  return spec;
}

v1::Corners to_proto(const CornerSpec& spec, const std::string& label) {
  v1::Corners out;
  if (spec.kind == CornerSpec::Kind::Vertices)
    for (int v : spec.vertices) out.add_vertices(v);
  if (spec.kind == CornerSpec::Kind::Points)
    for (const Vec3& p : spec.points)
      for (int k = 0; k < 3; ++k) out.add_points(p[k]);
  out.set_label(label);
  return out;
}

void parse_alpha(const std::string& text, DesignOptions& options) {
  if (text == "min") {
    options.alpha = DesignOptions::Alpha::Min;
    return;
  }
  if (text == "max") {
    options.alpha = DesignOptions::Alpha::Max;
    return;
  }
  std::string number = text;
  double factor = 1.0;
  if (number.size() > 3 && number.substr(number.size() - 3) == "deg") {
    number = number.substr(0, number.size() - 3);
    factor = std::numbers::pi / 180;
  }
  double value = 0;
  const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), value);
  if (number.empty() || ec != std::errc() || end != number.data() + number.size() ||
      !std::isfinite(value))
    throw InvalidInput("options.alpha",
                       "expected min, max, an angle in radians or NNdeg, got '" + text + "'");
  value *= factor;
  if (!(value > 0 && value < std::numbers::pi))
    throw InvalidInput("options.alpha", "the planar corner angle must be between 0 and pi radians");
  options.alpha = DesignOptions::Alpha::Value;
  options.alpha_value = value;
}

// Load and Examples ----------------------------------------------------------------------------

v1::LoadResult run_load(const v1::LoadRequest& request, const Progress& progress,
                        const RunSettings&) {
  progress.check();
  LoadReport load;
  std::array<int, 4> corners{-1, -1, -1, -1};
  const TriangleMesh mesh = to_mesh(request.mesh(), &load, &corners);
  v1::LoadResult out;
  *out.mutable_mesh() = to_proto(
      mesh, request.mesh().name().empty() ? request.mesh().example() : request.mesh().name());
  v1::MeshReport& report = *out.mutable_report();
  report.set_format(load.format);
  report.set_file_vertices(load.file_vertices);
  report.set_file_faces(load.file_faces);
  report.set_polygons_triangulated(load.polygons_triangulated);
  report.set_degenerate_faces_removed(load.degenerate_faces_removed);
  report.set_duplicate_vertices_merged(load.duplicate_vertices_merged);
  report.set_isolated_vertices_removed(load.isolated_vertices_removed);
  for (const std::string& warning : load.warnings) report.add_warnings(warning);
  report.set_vertices(mesh.vertex_count());
  report.set_faces(mesh.face_count());
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  if (mesh.vertex_count() > 0) {
    lo = hi = mesh.vertices().front();
    for (const Vec3& p : mesh.vertices()) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  for (int k = 0; k < 3; ++k) report.add_bounding_box(lo[k]);
  for (int k = 0; k < 3; ++k) report.add_bounding_box(hi[k]);
  if (corners[0] >= 0)
    for (int v : corners) out.mutable_example_corners()->add_vertices(v);
  const std::vector<int>& map = load.vertex_of_file_vertex;
  bool identity = static_cast<int>(map.size()) == mesh.vertex_count();
  for (size_t v = 0; identity && v < map.size(); ++v) identity = map[v] == static_cast<int>(v);
  if (!identity) out.mutable_vertex_map()->Add(map.begin(), map.end());
  return out;
}

v1::ExamplesResult run_examples(const v1::ExamplesRequest&, const Progress& progress,
                                const RunSettings&) {
  progress.check();
  // Generating all examples takes ~50 ms; they never change, so once per process.
  static const v1::ExamplesResult all = [] {
    v1::ExamplesResult out;
    for (const std::string& name : example_names()) {
      const ExampleSurface example = make_example(name);
      v1::ExamplesResult::Example* entry = out.add_examples();
      entry->set_name(example.name);
      entry->set_description(example.description);
      entry->set_vertices(example.mesh.vertex_count());
      for (int v : example.corners) entry->add_corners(v);
    }
    return out;
  }();
  return all;
}

// Patch ------------------------------------------------------------------------------------------

PatchInputs prepare_patch(const v1::PatchRequest& request) {
  PatchInputs in;
  in.mesh = to_mesh(request.mesh(), &in.load);
  in.corners = to_corner_spec(request.corners(), in.load);
  const v1::PatchRequest::Options& o = request.options();
  in.options.geodesic.method =
      exact_method("patch", o.geodesic_method(), "options.geodesic_method");
  in.options.coverability.eta_max = eta_max_option(
      "patch", o.has_eta_max(), o.eta_max(), "options.eta_max", in.options.coverability.eta_max);
  if (o.has_max_smoothing_iterations())
    in.options.coverability.max_smoothing_iterations = static_cast<int>(
        check_option(option_spec("patch", "max_smoothing_iterations"), o.max_smoothing_iterations(),
                     "options.max_smoothing_iterations"));
  in.options.smooth = !o.no_smoothing();
  auto_corner_angles("patch", o.auto_corner_angles(), "options.auto_corner_angles",
                     in.options.auto_corners);
  return in;
}

v1::PatchResult run_patch(const v1::PatchRequest& request, const Progress& progress,
                          const RunSettings& settings) {
  {
    const auto start = std::chrono::steady_clock::now();
    PatchInputs in = prepare_patch(request);
    in.options.coverability.threads = settings.threads;
    const TargetPatch result = make_target_patch(in.mesh, in.corners, in.options, progress);

    v1::PatchResult out;
    v1::PatchReport& report = *out.mutable_report();
    report.set_input(request.mesh().name());
    report.set_input_vertex_count(in.mesh.vertex_count());
    report.set_vertex_count(result.patch.mesh.vertex_count());
    report.set_face_count(result.patch.mesh.face_count());
    for (int i = 0; i < 4; ++i) {
      v1::Corner* corner = report.add_corners();
      const int pv = result.patch.corners[i];
      const Vec3& p = result.patch.mesh.vertices()[pv];
      for (int k = 0; k < 3; ++k) corner->add_position(p[k]);
      corner->set_patch_vertex(pv);
      // Indices as sent, so the caller can pass them back as corners.
      corner->set_input_vertex(sent_vertex(in.load, result.patch.input_vertex[pv]));
      report.add_corner_angles(result.corner_angles[i]);
      report.add_boundary_lengths(result.boundary_lengths[i]);
    }
    report.set_area(result.area);
    const CoverabilityReport& cov = result.coverability;
    report.set_gaussian_curvature_max(cov.gaussian_curvature_max);
    report.set_gaussian_curvature_max_vertex(cov.gaussian_curvature_max_vertex);
    report.set_injectivity_bound(cov.injectivity_bound);
    report.set_longest_member_distance(cov.longest_member_distance);
    report.set_injectivity_ok(cov.injectivity_ok);
    report.set_eta_before(result.smoothing.eta_before);
    report.set_eta_after(result.smoothing.eta_after);
    report.set_eta_max(in.options.coverability.eta_max);
    report.set_smoothing_iterations(result.smoothing.iterations);
    report.set_max_smoothing_displacement(result.smoothing.max_displacement);
    report.set_geodesic_method(to_string(in.options.geodesic.method));
    for (const std::string& w : request.mesh().warnings()) report.add_warnings(w);
    for (const std::string& w : in.load.warnings) report.add_warnings(w);
    if (result.patch.corners_reversed)
      report.add_warnings("corners were given clockwise; the patch uses them counter-clockwise");
    if (!cov.injectivity_ok)
      report.add_warnings("longest member distance exceeds the injectivity bound pi/sqrt(Kmax)");
    for (const std::string& w : result.warnings) report.add_warnings(w);
    for (double e : result.boundary_excess) report.add_boundary_geodesic_excess(e);
    report.set_recuts(result.smoothing.recuts);
    if (result.auto_corners)
      *report.mutable_auto_corners() =
          to_proto(*result.auto_corners, in.mesh, [&](int v) { return sent_vertex(in.load, v); });
    for (int i = 0; i < 4; ++i) {
      v1::Side* side = report.add_sides();
      for (int v : result.patch.sides[i]) side->add_vertices(v);
      side->set_length(result.boundary_lengths[i]);
    }
    for (const auto& [stage, s] : result.stage_seconds)
      (*report.mutable_stage_seconds())[stage] = s;
    *out.mutable_patch() = to_proto(result.patch.mesh, "patch");
    for (double k : gaussian_curvature(result.patch.mesh)) out.add_gaussian_curvature(k);
    report.set_seconds(seconds_since(start));
    return out;
  }
}

// Design -----------------------------------------------------------------------------------------

namespace {

/// The patch work of a layout's patch: from the cache, else the layout cut (every patch's work
/// kept in the cache, so that a redesign of any other patch of it skips the cut too).
std::shared_ptr<const PatchWork> layout_patch_work(const RunSettings& settings,
                                                   const DesignInputs& in, const Progress& progress,
                                                   bool* cached, double* patch_seconds) {
  const PatchLayout& layout = *in.layout;
  auto compute = [&] {
    const auto start = std::chrono::steady_clock::now();
    const LayoutResult cut = cut_layout(in.mesh, layout, patch_options(in.options), progress);
    *patch_seconds = seconds_since(start);
    std::optional<PatchWork> wanted;
    for (size_t j = 0; j < cut.patches.size(); ++j) {
      const LayoutPatch& p = cut.patches[j];
      const bool asked = static_cast<int>(j) == in.layout_patch;
      if (!asked && !settings.patch_cache) continue;  // nowhere to keep the others' work
      if (!p.target || p.problem) {
        if (!asked) continue;
        const Error problem = p.problem ? *p.problem : Infeasible("", "the patch could not be cut");
        throw Error(problem.code(), "layout_patch.patch",
                    p.name + ": " + (problem.field().empty() ? "" : problem.field() + ": ") +
                        problem.message(),
                    problem.reason());
      }
      PatchWork work = prepare_patch_work(*p.target, in.options, progress);
      if (settings.patch_cache) work.members = member_memo_for(work);
      if (asked) {
        wanted = std::move(work);
      } else if (settings.patch_cache) {
        settings.patch_cache->put(
            layout_patch_key(in.mesh, layout, static_cast<int>(j), in.options),
            std::make_shared<const PatchWork>(std::move(work)));
      }
    }
    return std::move(*wanted);
  };
  if (!settings.patch_cache) return std::make_shared<const PatchWork>(compute());
  return settings.patch_cache->get(layout_patch_key(in.mesh, layout, in.layout_patch, in.options),
                                   compute, cached, progress);
}

/// The patch work of a design: from (or into) the cache when there is one. `patch_seconds` is
/// the patch stage's time (0 from the cache).
std::shared_ptr<const PatchWork> patch_work(const RunSettings& settings, const DesignInputs& in,
                                            const Progress& progress, bool* cached,
                                            double* patch_seconds) {
  auto compute = [&] {
    const auto start = std::chrono::steady_clock::now();
    TargetPatch target =
        make_target_patch(in.mesh, in.corners, patch_options(in.options), progress);
    *patch_seconds = seconds_since(start);
    PatchWork work = prepare_patch_work(std::move(target), in.options, progress);
    if (settings.patch_cache) work.members = member_memo_for(work);
    return work;
  };
  *cached = false;
  if (in.layout) return layout_patch_work(settings, in, progress, cached, patch_seconds);
  if (!settings.patch_cache) return std::make_shared<const PatchWork>(compute());
  return settings.patch_cache->get(patch_key(in.mesh, in.corners, in.options), compute, cached,
                                   progress);
}

/// Ranked feasible suggestions for a design that failed with `failure` on `work`, as the API's
/// messages (corners as sent).
std::vector<v1::Suggestion> suggestions_for(const DesignInputs& in, const PatchWork& work,
                                            const DesignOptions& options, const Error& failure,
                                            const Progress& progress) {
  SuggestionOptions limits;
  limits.count = in.suggest;
  std::vector<v1::Suggestion> out;
  int rank = 0;
  for (const DesignSuggestion& s :
       suggest_feasible_designs(in.mesh, work, options, failure, limits, progress)) {
    // A layout's patch keeps the layout's corners (its neighbours share them).
    if (in.layout && s.kind == DesignSuggestion::Kind::Corners) continue;
    v1::Suggestion& m = out.emplace_back();
    m.set_rank(++rank);
    m.set_kind(to_string(s.kind));
    m.set_description(s.description);
    if (s.kind == DesignSuggestion::Kind::Corners)
      for (int v : s.corners) m.mutable_corners()->add_vertices(sent_vertex(in.load, v));
    m.set_k_min(s.k_min > 0 ? s.k_min : options.cladding.k_min);
    m.set_k_max(s.k_max > 0 ? s.k_max : options.cladding.k_max);
    m.set_members_u(s.members_g);
    m.set_members_v(s.members_h);
    m.set_lamella_width(s.lamella_width);
    m.add_alpha_bar_range(s.alpha.min);
    m.add_alpha_bar_range(s.alpha.max);
    m.set_change(s.change);
  }
  return out;
}

/// make_design through patch_work, so that a failing design's patch work can be searched for
/// feasible suggestions.
Design design_with_suggestions(const DesignInputs& in, const Progress& progress,
                               const RunSettings& settings, bool* cached) {
  double patch_seconds = 0;
  const std::shared_ptr<const PatchWork> work =
      patch_work(settings, in, progress, cached, &patch_seconds);
  DesignOptions options = in.options;
  if (*cached && settings.redesign_threads >= 0) options.grid.threads = settings.redesign_threads;
  Design design;
  try {
    design = design_on_patch(*work, options, progress);
  } catch (const Cancelled&) {
    throw;
  } catch (const Infeasible& e) {
    if (in.suggest <= 0) throw;
    std::vector<v1::Suggestion> suggestions = suggestions_for(in, *work, in.options, e, progress);
    if (suggestions.empty()) throw;
    throw InfeasibleWithSuggestions(e.field(), e.message(), std::move(suggestions));
  }
  design.stage_seconds["patch"] = patch_seconds;
  design.stage_seconds["distance_maps"] = *cached ? 0.0 : work->maps_seconds;
  if (*cached)
    for (auto& [stage, seconds] : design.target.stage_seconds) seconds = 0;  // not spent now
  return design;
}

}  // namespace

v1::DesignResult design_result(const Design& design, v1::DesignOptions record,
                               const std::string& name, int mesh_vertices, double seconds) {
  record.set_lamella_width(design.lamella_width);
  record.set_lamella_thickness(design.lamella_thickness);
  record.set_map_resolution(design.maps.g.resolution());
  v1::DesignResult out;
  *out.mutable_design() = to_proto(design, record, name);
  auto add_view = [&](const char* file, std::string content) {
    v1::File* view = out.add_views();
    view->set_name(file);
    view->set_content(std::move(content));
  };
  add_view("planar.svg", planar_svg(design, design.lamella_width));
  add_view("spatial.obj", spatial_obj(design));
  add_view("maps.svg", maps_svg(design));
  *out.mutable_report() = to_report(design, name, mesh_vertices, seconds);
  return out;
}

DesignInputs prepare_design(const v1::DesignRequest& request) {
  DesignInputs in;
  in.mesh = to_mesh(request.mesh(), &in.load);
  if (request.has_layout_patch()) {
    const v1::Corners& c = request.corners();
    if (c.vertices_size() > 0 || c.points_size() > 0)
      throw InvalidInput("corners", "give corners or a layout_patch, not both");
    try {
      in.layout = layout_from_proto(request.layout_patch().layout(), in.load);
    } catch (const Error& e) {
      rethrow_within(e, "layout_patch");
    }
    std::string names;
    for (size_t j = 0; j < in.layout->patches.size(); ++j) {
      std::string& name = in.layout->patches[j].name;
      if (name.empty()) name = "P" + std::to_string(j + 1);
      if (name == request.layout_patch().patch()) in.layout_patch = static_cast<int>(j);
      names += (j ? ", " : "") + name;
    }
    if (in.layout_patch < 0)
      throw InvalidInput(
          "layout_patch.patch",
          "'" + request.layout_patch().patch() + "' is not a patch of the layout (" + names + ")");
  } else {
    in.corners = to_corner_spec(request.corners(), in.load);
  }
  prepare_design_options(request.options(), in);
  if (in.layout)  // the patch's own design choices in the layout, over the request's options
    apply_patch_design(request.layout_patch().layout().patches(in.layout_patch),
                       "layout_patch.layout.patches[" + std::to_string(in.layout_patch) + "]",
                       in.options, in.record);
  in.record.set_corners(in.layout ? "layout patch " + request.layout_patch().patch()
                                  : corner_label(request.corners()));
  return in;
}

void prepare_design_options(const v1::DesignRequest::Options& o, DesignInputs& in) {
  DesignOptions& options = in.options;
  // Each option against its description (options.cpp), named by its field.
  const auto check = [](const char* name, double value) {
    return check_option(option_spec("design", name), value, std::string("options.") + name);
  };
  options.patch.geodesic.method =
      exact_method("design", o.geodesic_method(), "options.geodesic_method");
  options.patch.coverability.eta_max =
      eta_max_option("design", o.has_eta_max(), o.eta_max(), "options.eta_max",
                     options.patch.coverability.eta_max);
  const std::string alpha = o.has_alpha() ? o.alpha() : "min";
  parse_alpha(alpha, options);
  options.members_g = static_cast<int>(check("members_u", o.members_u()));
  options.members_h = static_cast<int>(check("members_v", o.members_v()));
  options.members.lamella_width = check("lamella_width", o.lamella_width());
  options.members.lamella_thickness = check("lamella_thickness", o.lamella_thickness());
  options.anchors.interior = static_cast<int>(check("interior_anchors", o.interior_anchors()));
  if (o.has_resolution())
    options.maps.resolution = static_cast<int>(check("resolution", o.resolution()));
  auto_corner_angles("design", o.auto_corner_angles(), "options.auto_corner_angles",
                     options.patch.auto_corners);
  if (o.has_k_min()) options.cladding.k_min = check("k_min", o.k_min());
  if (o.has_k_max()) options.cladding.k_max = check("k_max", o.k_max());
  if (!(options.cladding.k_min < options.cladding.k_max))
    throw InvalidInput(o.has_k_min() && !o.has_k_max() ? "options.k_min" : "options.k_max",
                       "slope bounds must satisfy k_min < k_max, got k_min " +
                           shortest(options.cladding.k_min) + ", k_max " +
                           shortest(options.cladding.k_max));
  in.suggest = o.has_suggest() ? static_cast<int>(check("suggest", o.suggest()))
                               : std::stoi(option_spec("design", "suggest").default_value);
  check("map_vertices", o.map_vertices());
  options.maps.max_vertices = options.patch.coverability.max_vertices =
      o.map_vertices() != 0 ? o.map_vertices() : kDefaultMapVertices;

  v1::DesignOptions& record = in.record;
  record.set_alpha(alpha);
  record.set_members_u(o.members_u());
  record.set_members_v(o.members_v());
  record.set_eta_max(options.patch.coverability.eta_max);
  record.set_max_smoothing_iterations(options.patch.coverability.max_smoothing_iterations);
  record.set_k_min(options.cladding.k_min);
  record.set_k_max(options.cladding.k_max);
  record.set_max_spacing(options.members.max_spacing);
  record.set_min_members(options.members.min_members);
  record.set_max_members(options.members.max_members);
  record.set_geodesic_method(to_string(options.patch.geodesic.method));
  record.set_length_tolerance(options.grid.length_tolerance);
  record.set_interior_anchors(options.anchors.interior);
  record.set_map_vertices(options.maps.max_vertices);
}

v1::DesignResult run_design(const v1::DesignRequest& request, const Progress& progress,
                            const RunSettings& settings) {
  {
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = process_cpu_seconds();
    DesignInputs in = prepare_design(request);
    in.options.maps.threads = in.options.grid.threads = settings.threads;
    in.options.patch.coverability.threads = settings.threads;
    bool cached = false;
    const Design design = design_with_suggestions(in, progress, settings, &cached);

    const std::string& name = request.mesh().name();
    v1::DesignResult out =
        design_result(design, in.record, name, in.mesh.vertex_count(), seconds_since(start));
    auto add_view = [&](const char* file, std::string content) {
      v1::File* view = out.add_views();
      view->set_name(file);
      view->set_content(std::move(content));
    };
    out.mutable_report()->set_distance_maps_cached(cached);
    out.mutable_report()->set_cpu_seconds(process_cpu_seconds() - cpu_start);
    out.mutable_report()->set_peak_memory_bytes(peak_resident_bytes());
    out.mutable_report()->set_patch_key(patch_routing_key(in.mesh, in.corners, in.options));
    if (design.target.auto_corners)
      *out.mutable_report()->mutable_auto_corners() = to_proto(
          *design.target.auto_corners, in.mesh, [&](int v) { return sent_vertex(in.load, v); });
    if (request.files())  // the files the CLI writes, for clients that offer downloads
      for (auto& [file, content] : design_files(out))
        if (file == "design.json" || file == "report.json") add_view(file.c_str(), content);
    return out;
  }
}

}  // namespace gridshell

// Geodesic -----------------------------------------------------------------------------------

namespace gridshell {
namespace {

constexpr int kMaxRepeat = 1000;

struct TimedField {
  std::vector<double> distances;
  double ms = 0;
};

TimedField timed_field(const TriangleMesh& mesh, GeodesicMethod method, const SurfacePoint& source,
                       int repeat, const Progress& progress) {
  const GeodesicSolver solver(mesh, GeodesicOptions{method});
  std::vector<double> times;
  TimedField out;
  for (int r = 0; r < repeat; ++r) {
    const auto start = std::chrono::steady_clock::now();
    out.distances = solver.distances(source, progress);
    times.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  }
  std::sort(times.begin(), times.end());
  const size_t n = times.size();
  out.ms = n % 2 ? times[n / 2] : 0.5 * (times[n / 2 - 1] + times[n / 2]);
  return out;
}

}  // namespace

GeodesicInputs prepare_geodesic(const v1::GeodesicRequest& request) {
  {
    GeodesicInputs in;
    LoadReport load;
    in.mesh = to_mesh(request.mesh(), &load);
    in.source = loaded_vertex(load, request.source(), "source");
    in.method = any_method(request.method(), "method");
    if (!request.compare().empty()) in.reference = any_method(request.compare(), "compare");
    in.repeat = request.repeat() == 0 ? 1 : request.repeat();
    if (in.repeat < 1 || in.repeat > kMaxRepeat)
      throw InvalidInput("repeat",
                         "must be between 1 and " + std::to_string(kMaxRepeat) + " (0 = 1)");
    return in;
  }
}

v1::GeodesicResult run_geodesic(const v1::GeodesicRequest& request, const Progress& progress,
                                const RunSettings& /*settings: one solve runs on one thread*/) {
  {
    const GeodesicInputs in = prepare_geodesic(request);
    const TriangleMesh& mesh = in.mesh;
    const SurfacePoint source = SurfacePoint::at_vertex(mesh, in.source);
    const TimedField main = timed_field(mesh, in.method, source, in.repeat, progress);
    v1::GeodesicResult out;
    v1::GeodesicReport& report = *out.mutable_report();
    report.set_input(request.mesh().name());
    report.set_vertices(mesh.vertex_count());
    report.set_source(request.source());
    report.set_method(to_string(in.method));
    report.set_ms_per_source(main.ms);
    report.set_repeats(in.repeat);
    double max_distance = 0;
    for (double d : main.distances)
      if (std::isfinite(d)) max_distance = std::max(max_distance, d);
    report.set_max_distance(max_distance);
    if (in.reference) {
      const TimedField ref = timed_field(mesh, *in.reference, source, in.repeat, progress);
      const double floor = 1e-12 * std::max(1.0, bounding_box_size(mesh).norm());
      double max_abs = 0, max_rel = 0;
      for (size_t v = 0; v < main.distances.size(); ++v) {
        const double a = main.distances[v], b = ref.distances[v];
        if (std::isinf(a) && std::isinf(b)) continue;
        const double diff = std::abs(a - b);
        max_abs = std::max(max_abs, diff);
        max_rel = std::max(max_rel, diff / std::max(std::abs(b), floor));
      }
      report.set_reference(to_string(*in.reference));
      report.set_reference_ms_per_source(ref.ms);
      report.set_max_abs_diff(max_abs);
      report.set_max_rel_diff(max_rel);
      report.set_speedup(main.ms > 0 ? ref.ms / main.ms : 0);
    }
    if (request.distances())
      out.mutable_distances()->Add(main.distances.begin(), main.distances.end());
    return out;
  }
}

}  // namespace gridshell
