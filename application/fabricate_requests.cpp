// SPDX-License-Identifier: GPL-3.0-or-later
// Fabricate requests -> kernel (kernel/fabrication) -> kit and files (see gridshell/fabricate.h).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "gridshell/application/convert_deployment.h"
#include "gridshell/application/deployment_job.h"
#include "gridshell/application/fabricate.h"
#include "gridshell/application/options.h"
#include "gridshell/fabrication/kit.h"
#include "gridshell/fabrication/kit_export.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

std::string two_digits(int n) {
  char text[16];
  std::snprintf(text, sizeof text, "%02d", n);
  return text;
}

std::string family_name(Family f) { return f == Family::G ? "g" : "h"; }

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

v1::FabricateResult run_fabricate(const v1::FabricateRequest& request, const Progress& progress,
                                  const RunSettings&) {
  v1::FabricationOptions options = prepare_fabrication_options(request.options());
  check_notches(request.design());
  Design design;
  try {
    design = design_from_proto(request.design());
  } catch (const Error& e) {
    rethrow_within(e, "design");
  }
  check_design(design);
  const Kit kit = make_kit(design, kernel_options(options), progress);
  const FabricationOptions& k = kit.options;
  options.set_end_allowance(k.end_allowance);
  options.set_thickness(k.thickness);
  options.set_text_height(k.text_height);
  const double mm = k.millimetres_per_unit;

  v1::FabricateResult out;
  v1::Kit& kj = *out.mutable_kit();
  kj.set_design(request.design_name().empty() ? "design.json" : request.design_name());
  *kj.mutable_options() = options;
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
      feature->set_partner(family_name(f.partner_family) + std::to_string(f.partner));
      feature->set_s_bar(f.s_bar);
      feature->set_s(f.s);
      feature->add_x(f.x0);
      if (f.kind == FeatureKind::Slot) feature->add_x(f.x1);
      feature->set_diameter(f.diameter);
      feature->set_length(f.length());
    }
  }
  auto add_file = [&](const std::string& name, std::string content) {
    v1::File* file = out.add_files();
    file->set_name(name);
    file->set_content(std::move(content));
  };
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
    add_file(base + ".dxf", sheet_dxf(drawing));
    add_file(base + ".svg", sheet_svg(drawing));
  }
  kj.set_utilisation(kit.utilisation);
  kj.set_rows(kit.rows);
  kj.set_rows_per_sheet(kit.rows_per_sheet);
  kj.set_baseline_sheets(kit.baseline_sheets);
  kj.set_baseline_utilisation(kit.baseline_utilisation);
  kj.set_crossings(static_cast<int>(design.grid.crossings.size()));
  kj.set_holes(kit.holes);
  kj.set_slots(kit.slots);
  kj.set_top_family(family_name(kit.top_family));
  kj.set_lamella_width(design.lamella_width * mm);
  kj.set_thickness(k.thickness);
  const CornerAngles angles = corner_angles(design);
  for (double a : angles.planar) kj.add_planar_corner_angles(a);
  for (double a : angles.target) kj.add_target_corner_angles(a);

  // Supports in the design's unit when it has a name, else in mm.
  const bool named = options.unit() == "mm" || options.unit() == "cm" || options.unit() == "m" ||
                     options.unit() == "in" || options.unit() == "ft";
  add_file("supports.csv", supports_csv(design, named ? 1 : mm, named ? options.unit() : "mm"));
  add_file("bom.csv", bom_csv(design, kit, options.material()));
  add_file("assembly.svg", assembly_svg(design, kit, options.unit()));
  add_file("kit.json", to_json(out.kit()) + "\n");
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
