// SPDX-License-Identifier: GPL-3.0-or-later
// Fabricate requests -> kernel (kernel/fabrication) -> kit and files (see gridshell/fabricate.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "gridshell/application/convert_deployment.h"
#include "gridshell/application/deployment_job.h"
#include "gridshell/application/fabricate.h"
#include "gridshell/application/options.h"
#include "gridshell/design/layout.h"
#include "gridshell/fabrication/kit.h"
#include "gridshell/fabrication/kit_export.h"
#include "gridshell/fabrication/layout_kit.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

std::string two_digits(int n) {
  char text[16];
  std::snprintf(text, sizeof text, "%02d", n);
  return text;
}

std::string family_name(Family f) { return f == Family::G ? "g" : "h"; }

void add_file(v1::FabricateResult& out, const std::string& name, std::string content) {
  v1::File* file = out.add_files();
  file->set_name(name);
  file->set_content(std::move(content));
}

/// What design_from_proto does not check but a kit relies on: one crossing per pair of members,
/// notch lengths equal to s - s̄ (zero on the boundary), arc lengths on their lamella.
void check_design(const Design& design) {
  const Grid& grid = design.grid;
  const size_t ng = grid.g.size(), nh = grid.h.size();
  if (grid.crossings.size() != ng * nh)
    throw InvalidInput("design.crossings",
                       "expected one crossing for each pair of g and h members (" +
                           std::to_string(ng) + " x " + std::to_string(nh) + " = " +
                           std::to_string(ng * nh) + "), got " +
                           std::to_string(grid.crossings.size()));
  std::vector<char> seen(ng * nh, 0);
  for (size_t i = 0; i < grid.crossings.size(); ++i) {
    const Crossing& c = grid.crossings[i];
    const std::string field = "design.crossings[" + std::to_string(i) + "]";
    char& s = seen[c.g * nh + c.h];
    if (s)
      throw InvalidInput(
          field, "a second crossing of g" + std::to_string(c.g) + " and h" + std::to_string(c.h));
    s = 1;
    for (int f = 0; f < 2; ++f) {
      const Member& m = f == 0 ? grid.g[c.g] : grid.h[c.h];
      const double length = m.planar_length, tolerance = 1e-6 * length + 1e-12;
      const double s_bar = f == 0 ? c.s_bar_g : c.s_bar_h, s_surface = f == 0 ? c.s_g : c.s_h;
      const char* suffix = f == 0 ? "_g" : "_h";
      const std::string name = family_name(m.family) + std::to_string(m.index);
      for (const auto& [value, what] : {std::pair{s_bar, "s_bar"}, std::pair{s_surface, "s"}})
        if (value < -tolerance || value > length + tolerance)
          throw InvalidInput(field + "." + what + suffix,
                             std::to_string(value) + " lies outside lamella " + name + " (0 to " +
                                 std::to_string(length) + ")");
    }
  }
}

void check_notches(const v1::Design& in) {
  for (int i = 0; i < in.crossings_size(); ++i) {
    const v1::Crossing& c = in.crossings(i);
    const std::string field = "design.crossings[" + std::to_string(i) + "]";
    const double expect_g = c.on_boundary() ? 0 : c.s_g() - c.s_bar_g();
    const double expect_h = c.on_boundary() ? 0 : c.s_h() - c.s_bar_h();
    const double scale = 1e-9 * (1 + std::abs(c.s_g()) + std::abs(c.s_h()));
    if (!(std::abs(c.notch_g() - expect_g) <= scale))
      throw InvalidInput(field + ".notch_g",
                         "notch length " + std::to_string(c.notch_g()) + " is not s_g - s_bar_g (" +
                             std::to_string(expect_g) +
                             (c.on_boundary() ? ", a boundary crossing has none)" : ")"));
    if (!(std::abs(c.notch_h() - expect_h) <= scale))
      throw InvalidInput(field + ".notch_h",
                         "notch length " + std::to_string(c.notch_h()) + " is not s_h - s_bar_h (" +
                             std::to_string(expect_h) +
                             (c.on_boundary() ? ", a boundary crossing has none)" : ")"));
  }
}

FabricationOptions kernel_options(const v1::FabricationOptions& o) {
  FabricationOptions k;
  k.millimetres_per_unit = o.millimetres_per_unit();
  k.sheet_width = o.sheet_width();
  k.sheet_height = o.sheet_height();
  k.kerf = o.kerf();
  k.hole_diameter = o.hole_diameter();
  k.end_allowance = o.end_allowance();
  k.spacing = o.spacing();
  k.thickness = o.thickness();
  k.min_slot = o.min_slot();
  k.text_height = o.text_height();
  return k;
}

}  // namespace

v1::FabricationOptions prepare_fabrication_options(const v1::FabricationOptions& in) {
  v1::FabricationOptions o = in;
  const FabricationOptions defaults;
  if (o.unit().empty() && o.millimetres_per_unit() == 0)
    throw InvalidInput("options.unit",
                       "the design's length unit is needed to cut it: mm, cm, m, in, ft or a "
                       "number of metres");
  if (!o.unit().empty()) {
    const double metres = parse_length_unit(o.unit(), "options.unit");
    if (!(metres >= 1e-9 && metres <= 1e6))
      throw InvalidInput("options.unit", "must be between 1e-9 and 1e6 metres");
    o.set_millimetres_per_unit(1000 * metres);
  }
  if (o.sheet_width() == 0 && o.sheet_height() == 0) {
    o.set_sheet_width(defaults.sheet_width);
    o.set_sheet_height(defaults.sheet_height);
  }
  if (!o.has_kerf()) o.set_kerf(defaults.kerf);
  if (o.hole_diameter() == 0) o.set_hole_diameter(defaults.hole_diameter);
  if (!o.has_spacing()) o.set_spacing(defaults.spacing);
  if (!o.has_min_slot()) o.set_min_slot(defaults.min_slot);
  if (o.material().empty()) o.set_material(option_spec("fabrication", "material").default_value);
  // Each number against its description (options.cpp); then the checks that relate two options
  // (the hole larger than the kerf, ...), by the kernel (the lamella size is not known here: 1
  // mm stands in for it).
  for (const OptionSpec& spec : option_specs())
    if (spec.group == "fabrication" && spec.type == OptionType::Number && !spec.output)
      check_option(spec,
                   o.GetReflection()->GetDouble(o, o.GetDescriptor()->FindFieldByName(spec.name)),
                   "options." + spec.name);
  resolve_fabrication_options(kernel_options(o), 1, 1);
  return o;
}

namespace {

/// A kit's parts, sheets and figures into kit.json's message, and its sheet files into `out`.
void add_kit(const Kit& kit, v1::Kit& kj, v1::FabricateResult& out, const Progress& progress) {
  for (const Part& p : kit.parts) {
    v1::KitPart* part = kj.add_parts();
    part->set_name(p.name);
    part->set_family(family_name(p.family));
    part->set_index(p.index);
    part->set_boundary(p.boundary);
    part->set_sheet(p.sheet + 1);
    part->set_row(p.row + 1);
    part->set_rotation(p.rotation);
    part->add_translation(p.translation.x());
    part->add_translation(p.translation.y());
    part->set_length(p.length);
    part->set_width(p.width);
    part->set_start(p.start);
    for (const PartFeature& f : p.features) {
      v1::KitFeature* feature = part->add_features();
      feature->set_kind(f.kind == FeatureKind::Hole ? "hole" : "slot");
      feature->set_crossing(f.crossing);
      feature->set_partner(f.partner_name);
      feature->set_s_bar(f.s_bar);
      feature->set_s(f.s);
      feature->add_x(f.x0);
      if (f.kind == FeatureKind::Slot) feature->add_x(f.x1);
      feature->set_diameter(f.diameter);
      feature->set_length(f.length());
    }
  }
  for (size_t s = 0; s < kit.sheets.size(); ++s) {
    progress.report("fabricate: sheets", static_cast<double>(s) / kit.sheets.size());
    const std::string base = "sheets/sheet-" + two_digits(static_cast<int>(s) + 1);
    v1::KitSheet* sheet = kj.add_sheets();
    sheet->set_index(static_cast<int>(s) + 1);
    sheet->set_dxf(base + ".dxf");
    sheet->set_svg(base + ".svg");
    for (int p : kit.sheets[s].parts) sheet->add_parts(kit.parts[p].name);
    sheet->set_rows(kit.sheets[s].rows);
    sheet->set_utilisation(kit.sheets[s].utilisation);
    const SheetDrawing drawing = sheet_drawing(kit, static_cast<int>(s));
    add_file(out, base + ".dxf", sheet_dxf(drawing));
    add_file(out, base + ".svg", sheet_svg(drawing));
  }
  kj.set_utilisation(kit.utilisation);
  kj.set_rows(kit.rows);
  kj.set_rows_per_sheet(kit.rows_per_sheet);
  kj.set_baseline_sheets(kit.baseline_sheets);
  kj.set_baseline_utilisation(kit.baseline_utilisation);
  kj.set_holes(kit.holes);
  kj.set_slots(kit.slots);
  kj.set_top_family(family_name(kit.top_family));
  kj.set_thickness(kit.options.thickness);
}

/// The effective lamella end allowance, thickness and text height in the options recorded.
void record_resolved(const FabricationOptions& k, v1::FabricationOptions& options) {
  options.set_end_allowance(k.end_allowance);
  options.set_thickness(k.thickness);
  options.set_text_height(k.text_height);
}

/// Supports in the design's unit when it has a name, else in mm: (scale, unit).
std::pair<double, std::string> support_unit(const v1::FabricationOptions& options, double mm) {
  const bool named = options.unit() == "mm" || options.unit() == "cm" || options.unit() == "m" ||
                     options.unit() == "in" || options.unit() == "ft";
  return named ? std::pair{1.0, options.unit()} : std::pair{mm, std::string("mm")};
}

/// A design message of a kit request checked and converted; errors name `field`.
Design checked_design(const v1::Design& message, const std::string& field) {
  try {
    check_notches(message);
    Design design = design_from_proto(message);
    check_design(design);
    return design;
  } catch (const Cancelled&) {
    throw;
  } catch (const Error& e) {
    // The checks name "design.<...>" (or "<...>"): the same place under `field`.
    const std::string inner = e.field().rfind("design", 0) == 0 ? e.field().substr(6) : e.field();
    throw Error(e.code(),
                field + (inner.empty() || inner[0] == '.' || inner[0] == '[' ? "" : ".") + inner,
                e.message(), e.reason());
  }
}

/// The kit of a layout run (FabricateRequest.layout and .patches).
v1::FabricateResult layout_fabricate(const v1::FabricateRequest& request,
                                     v1::FabricationOptions options, const Progress& progress) {
  const v1::LayoutDesign& layout = request.layout();
  const auto& quads = layout.layout().layout().patches();
  std::vector<std::string> names;
  for (int j = 0; j < layout.patch_designs_size(); ++j)
    if (!layout.patch_designs(j).empty())
      names.push_back(j < quads.size() && !quads[j].name().empty() ? quads[j].name()
                                                                   : "P" + std::to_string(j + 1));
  if (static_cast<int>(names.size()) != request.patches_size())
    throw InvalidInput("patches", "expected " + std::to_string(names.size()) +
                                      " designs (one per designed patch of the layout), got " +
                                      std::to_string(request.patches_size()));
  if (names.empty()) throw InvalidInput("layout", "the layout has no designed patch");
  std::vector<Design> designs;
  for (int k = 0; k < request.patches_size(); ++k)
    designs.push_back(checked_design(request.patches(k), "patches[" + std::to_string(k) + "]"));
  std::vector<LayoutKitPatch> patches;
  for (size_t k = 0; k < designs.size(); ++k) patches.push_back({names[k], &designs[k], {}});
  std::vector<KitSeam> seams;
  for (int i = 0; i < layout.seams_size(); ++i) {
    const v1::SeamDesign& m = layout.seams(i);
    const std::string field = "layout.seams[" + std::to_string(i) + "]";
    if (m.patches_size() != 2 || m.lamellas_size() != 2 || m.corners_size() != 2)
      throw InvalidInput(field, "a seam has two patches, two lamellas and two corners");
    KitSeam seam;
    seam.patches = {m.patches(0), m.patches(1)};
    seam.corners = {m.corners(0), m.corners(1)};
    for (int k = 0; k < m.joints_size(); ++k) {
      const v1::SeamJoint& j = m.joints(k);
      if (j.lamella_s_size() != 2 || j.point_size() != 3)
        throw InvalidInput(field + ".joints[" + std::to_string(k) + "]",
                           "a seam bolt has an arc length on each lamella and a point");
      SeamBolt bolt;
      bolt.lamellas = {m.lamellas(0), m.lamellas(1)};
      bolt.along = {j.lamella_s(0), j.lamella_s(1)};
      bolt.members.assign(j.members().begin(), j.members().end());
      bolt.point = Vec3(j.point(0), j.point(1), j.point(2));
      seam.bolts.push_back(std::move(bolt));
    }
    seams.push_back(std::move(seam));
  }
  // The supports: the anchors that hold the whole, as its simulation has them.
  {
    std::vector<SeamMember> members;
    for (int i = 0; i < layout.seams_size(); ++i)
      for (int k = 0; k < 2; ++k) {
        const std::string field =
            "layout.seams[" + std::to_string(i) + "].lamellas[" + std::to_string(k) + "]";
        const auto at = std::find(names.begin(), names.end(), layout.seams(i).patches(k));
        const std::string& lamella = layout.seams(i).lamellas(k);
        if (at == names.end())
          throw InvalidInput(
              "layout.seams[" + std::to_string(i) + "].patches[" + std::to_string(k) + "]",
              "'" + layout.seams(i).patches(k) + "' is not a designed patch");
        const auto parsed = parse_layout_part_name(lamella, *at);
        if (!parsed)
          throw InvalidInput(field, "'" + lamella + "' is not a lamella of patch " + *at +
                                        " (expected " + *at + "-g<i> or " + *at + "-h<i>)");
        SeamMember m;
        m.patch = static_cast<int>(at - names.begin());
        m.family = parsed->first;
        m.member = parsed->second;
        members.push_back(m);
      }
    std::vector<const std::vector<Anchor>*> anchors;
    std::vector<const Grid*> grids;
    for (const Design& d : designs) anchors.push_back(&d.anchors), grids.push_back(&d.grid);
    const WholeAnchors held = whole_anchors(anchors, grids, members);
    for (size_t k = 0; k < patches.size(); ++k) patches[k].supports = held.patches[k];
  }
  const LayoutKit kit = make_layout_kit(patches, seams, kernel_options(options), progress);
  record_resolved(kit.kit.options, options);
  v1::FabricateResult out;
  v1::Kit& kj = *out.mutable_kit();
  kj.set_design(request.design_name().empty() ? "design.json" : request.design_name());
  *kj.mutable_options() = options;
  add_kit(kit.kit, kj, out, progress);
  int crossings = 0;
  for (const Design& d : designs) crossings += static_cast<int>(d.grid.crossings.size());
  kj.set_crossings(crossings);
  const double mm = kit.kit.options.millimetres_per_unit;
  kj.set_lamella_width(designs.front().lamella_width * mm);
  const auto [scale, unit] = support_unit(options, mm);
  for (size_t k = 0; k < designs.size(); ++k)
    add_file(out, "assembly-" + names[k] + ".svg",
             assembly_svg(designs[k], kit.patch_kits[k], options.unit(), names[k]));
  add_file(out, "supports.csv", layout_supports_csv(patches, scale, unit));
  add_file(out, "bom.csv", layout_bom_csv(patches, kit, options.material()));
  add_file(out, "joining.svg", joining_svg(patches, seams));
  add_file(out, "kit.json", to_json(out.kit()) + "\n");
  progress.report("fabricate: sheets", 1);
  return out;
}

}  // namespace

v1::FabricateResult run_fabricate(const v1::FabricateRequest& request, const Progress& progress,
                                  const RunSettings&) {
  v1::FabricationOptions options = prepare_fabrication_options(request.options());
  if (request.has_layout()) {
    if (request.has_design())
      throw InvalidInput("design", "give a design or a layout's (layout and patches), not both");
    return layout_fabricate(request, options, progress);
  }
  if (request.patches_size() > 0)
    throw InvalidInput("patches", "patch designs belong to a layout: give the layout too");
  const Design design = checked_design(request.design(), "design");
  const Kit kit = make_kit(design, kernel_options(options), progress);
  record_resolved(kit.options, options);
  const double mm = kit.options.millimetres_per_unit;

  v1::FabricateResult out;
  v1::Kit& kj = *out.mutable_kit();
  kj.set_design(request.design_name().empty() ? "design.json" : request.design_name());
  *kj.mutable_options() = options;
  add_kit(kit, kj, out, progress);
  kj.set_crossings(static_cast<int>(design.grid.crossings.size()));
  kj.set_lamella_width(design.lamella_width * mm);
  const CornerAngles angles = corner_angles(design);
  for (double a : angles.planar) kj.add_planar_corner_angles(a);
  for (double a : angles.target) kj.add_target_corner_angles(a);
  const auto [scale, unit] = support_unit(options, mm);
  add_file(out, "supports.csv", supports_csv(design, scale, unit));
  add_file(out, "bom.csv", bom_csv(design, kit, options.material()));
  add_file(out, "assembly.svg", assembly_svg(design, kit, options.unit()));
  add_file(out, "kit.json", to_json(out.kit()) + "\n");
  progress.report("fabricate: sheets", 1);
  return out;
}

FileBundle fabricate_files(const v1::FabricateResult& result) {
  FileBundle files;
  for (const v1::File& file : result.files()) files[file.name()] = file.content();
  files["kit.json"] = to_json(result.kit()) + "\n";
  return files;
}

void write_kit_files(const FileBundle& files, const std::string& dir) {
  namespace fs = std::filesystem;
  std::map<std::string, FileBundle> by_folder;
  for (const auto& [name, content] : files) {
    const fs::path path(name);
    const std::string folder = path.parent_path().string();
    // One level below `dir` at most, never upwards; write_files checks the plain names.
    if (folder.find('/') != std::string::npos || folder == ".." || folder == "." ||
        path.is_absolute())
      throw InvalidInput(dir, "result file name '" + name + "' is not a kit file name");
    by_folder[folder][path.filename().string()] = content;
  }
  for (const auto& [folder, bundle] : by_folder)
    write_files(bundle, folder.empty() ? dir : (fs::path(dir) / folder).string());
}

}  // namespace gridshell
