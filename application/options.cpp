// SPDX-License-Identifier: GPL-3.0-or-later
// The description of every request option (see gridshell/options.h): the table, the checks, the
// Options RPC and the site's material library.
#include "gridshell/application/options.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/design/auto_corners.h"
#include "gridshell/design/cladding.h"
#include "gridshell/design/coverability.h"
#include "gridshell/design/distance_map.h"
#include "gridshell/design/distance_map_copy.h"
#include "gridshell/design/layout.h"
#include "gridshell/fabrication/kit.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/mesh/mesh_io.h"
#include "gridshell/simulation/simulation.h"

// The table below names each field it sets (designated initializers) and leaves the others at
// their defaults on purpose; GCC 12 warns about that anyway (its bug 96868).
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"

namespace gridshell {
namespace {

std::string shortest(double value) {
  // Whole numbers below ten million as integers ("100000", not "1e+05").
  if (value == std::floor(value) && std::abs(value) < 1e7)
    return std::to_string(static_cast<long long>(value));
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, end);
}

std::vector<std::string> material_choices() {
  std::vector<std::string> names;
  for (const Material& m : material_presets()) names.push_back(m.name);
  names.push_back("custom");
  return names;
}

std::vector<OptionSpec> build_table() {
  using T = OptionType;
  const CoverabilityOptions coverability;
  const DistanceMapOptions maps;
  const CladdingOptions cladding;
  const AutoCornerOptions corners;
  const SimulationOptions simulation;
  const FabricationOptions fabrication;
  const AutoLayoutOptions layout;
  std::vector<OptionSpec> t;
  // The patch-stage options a design request carries too: described once, listed in both groups.
  const auto in_group = [](OptionSpec spec, const char* group) {
    spec.group = group;
    return spec;
  };
  const OptionSpec geodesic_method{.name = "geodesic_method",
                                   .flag = "--method",
                                   .type = T::Choice,
                                   .default_value = "fast",
                                   .choices = {"fast", "cgal"},
                                   .label = "Geodesics",
                                   .help = "geodesic engine (cgal: the reference)"};
  const OptionSpec eta_max{
      .name = "eta_max",
      .flag = "--eta-max",
      .type = T::Number,
      .default_value = shortest(coverability.eta_max),
      .minimum = 1,
      .maximum = 10,
      .label = "Gap factor threshold",
      .help =
          "gap factor threshold eta: the patch is smoothed until eta is below it "
          "(a ratio of path lengths, 1 on a developable surface)"};
  const OptionSpec corner_angles{.name = "auto_corner_angles",
                                 .flag = "--corner-angles",
                                 .type = T::Numbers,
                                 .default_value = shortest(corners.min_corner_angle) + "," +
                                                  shortest(corners.max_corner_angle),
                                 .minimum = 0,
                                 .maximum = std::numbers::pi,
                                 .exclusive_minimum = true,
                                 .exclusive_maximum = true,
                                 .unit = "radians",
                                 .label = "Corner angles",
                                 .help =
                                     "automatic corners: [min, max] inner corner angle of "
                                     "the patch (the CLI's --corner-angles takes degrees)",
                                 .count = 2,
                                 .note = "min < max"};
  // Patch (PatchRequest.Options) ------------------------------------------------------------
  t.push_back(in_group(geodesic_method, "patch"));
  t.push_back(in_group(eta_max, "patch"));
  t.push_back({.group = "patch",
               .name = "max_smoothing_iterations",
               .flag = "--max-smoothing-iterations",
               .type = T::Integer,
               .default_value = std::to_string(coverability.max_smoothing_iterations),
               .minimum = 0,
               .maximum = 100000,
               .label = "Smoothing cap",
               .help = "smoothing iterations at most; a patch that needs more is infeasible"});
  t.push_back({.group = "patch",
               .name = "no_smoothing",
               .flag = "--no-smoothing",
               .type = T::Boolean,
               .default_value = "false",
               .label = "No smoothing",
               .help = "report eta but do not smooth"});
  t.push_back(in_group(corner_angles, "patch"));
  // Design (DesignRequest.Options) -----------------------------------------------------------
  t.push_back({.group = "design",
               .name = "alpha",
               .flag = "--alpha",
               .type = T::Text,
               .default_value = "min",
               .label = "Planar corner angle",
               .help = "planar corner angle: min | max (of the feasible range) | radians | NNdeg"});
  t.push_back({.group = "design",
               .name = "members_u",
               .flag = "--members-u",
               .type = T::Integer,
               .default_value = "0",
               .minimum = 1,
               .maximum = 1000,
               .zero_allowed = true,
               .zero_means = "automatic",
               .label = "g-members",
               .help = "inner g-members (boundaries not counted)"});
  t.push_back({.group = "design",
               .name = "members_v",
               .flag = "--members-v",
               .type = T::Integer,
               .default_value = "0",
               .minimum = 1,
               .maximum = 1000,
               .zero_allowed = true,
               .zero_means = "automatic",
               .label = "h-members",
               .help = "inner h-members (boundaries not counted)"});
  t.push_back({.group = "design",
               .name = "lamella_width",
               .flag = "--lamella-width",
               .type = T::Number,
               .default_value = "0",
               .minimum = 0,
               .exclusive_minimum = true,
               .zero_allowed = true,
               .zero_means = "1% of the longest patch side",
               .unit = "mesh units",
               .label = "Lamella width",
               .help = "lamella width"});
  t.push_back({.group = "design",
               .name = "lamella_thickness",
               .flag = "--lamella-thickness",
               .type = T::Number,
               .default_value = "0",
               .minimum = 0,
               .exclusive_minimum = true,
               .zero_allowed = true,
               .zero_means = "width / 10",
               .unit = "mesh units",
               .label = "Lamella thickness",
               .help = "lamella thickness"});
  t.push_back({.group = "design",
               .name = "resolution",
               .flag = "--resolution",
               .type = T::Integer,
               .default_value = std::to_string(maps.resolution),
               .minimum = 8,
               .maximum = 1000,
               .zero_allowed = true,
               .zero_means = "adaptive",
               .label = "Map resolution",
               .help = "distance map resolution R"});
  t.push_back(in_group(geodesic_method, "design"));
  t.push_back(in_group(eta_max, "design"));
  t.push_back({.group = "design",
               .name = "interior_anchors",
               .flag = "--interior-anchors",
               .type = T::Integer,
               .default_value = "0",
               .minimum = 0,
               .maximum = 100,
               .label = "Inner anchors",
               .help = "also pin up to N inner crossings at the target's bumps and dips (0 = "
                       "boundary anchors only, as in the paper)"});
  t.push_back(in_group(corner_angles, "design"));
  t.push_back({.group = "design",
               .name = "suggest",
               .flag = "--suggest",
               .type = T::Integer,
               .default_value = "3",
               .minimum = 0,
               .maximum = 20,
               .label = "Suggestions",
               .help = "when the design is infeasible, compute up to N ranked feasible changes "
                       "(0 = none)"});
  t.push_back({.group = "design",
               .name = "k_min",
               .flag = "--k-min",
               .type = T::Number,
               .default_value = shortest(cladding.k_min),
               .minimum = 0,
               .maximum = 100,
               .exclusive_minimum = true,
               .exclusive_maximum = true,
               .label = "Slope bound k_min",
               .help = "lower slope bound of the cladding functions",
               .note = "k_min < k_max"});
  t.push_back({.group = "design",
               .name = "k_max",
               .flag = "--k-max",
               .type = T::Number,
               .default_value = shortest(cladding.k_max),
               .minimum = 0,
               .maximum = 100,
               .exclusive_minimum = true,
               .label = "Slope bound k_max",
               .help = "upper slope bound of the cladding functions",
               .note = "k_min < k_max"});
  t.push_back({.group = "design",
               .name = "map_vertices",
               .flag = "--map-vertices",
               .type = T::Integer,
               .default_value = "0",
               .minimum = 500,
               .zero_allowed = true,
               .zero_means = std::to_string(kDefaultMapVertices),
               .label = "Map vertices",
               .help = "distance maps of a patch with more vertices on a copy simplified to "
                       "about this many (members stay exact; a number above the patch's vertex "
                       "count gives exact maps)",
               .advanced = true});
  // Simulation (SimulationOptions) -----------------------------------------------------------
  t.push_back({.group = "simulation",
               .name = "notches",
               .flag = "--notches",
               .type = T::Choice,
               .default_value = "both",
               .choices = {"on", "off", "both"},
               .label = "Notches",
               .help = "simulate with notches (sliding connections), without, or both"});
  t.push_back({.group = "simulation",
               .name = "material",
               .flag = "--material",
               .type = T::Choice,
               .default_value = material_presets().front().name,
               .choices = material_choices(),
               .label = "Material",
               .help = "material preset (see materials); custom: give both moduli"});
  t.push_back({.group = "simulation",
               .name = "young_modulus",
               .flag = "--young",
               .type = T::Number,
               .default_value = "0",
               .minimum = 1e3,
               .maximum = 1e13,
               .zero_allowed = true,
               .zero_means = "the material's",
               .unit = "Pa",
               .label = "Young's modulus",
               .help = "Young's modulus E (overrides the material's)"});
  t.push_back({.group = "simulation",
               .name = "shear_modulus",
               .flag = "--shear",
               .type = T::Number,
               .default_value = "0",
               .minimum = 1e3,
               .maximum = 1e13,
               .zero_allowed = true,
               .zero_means = "the material's",
               .unit = "Pa",
               .label = "Shear modulus",
               .help = "shear modulus G (overrides the material's)"});
  t.push_back({.group = "simulation",
               .name = "bending_strength",
               .flag = "--bending-strength",
               .type = T::Number,
               .default_value = "0",
               .minimum = 1e3,
               .maximum = 1e11,
               .zero_allowed = true,
               .zero_means = "the material's (unknown for custom)",
               .unit = "Pa",
               .label = "Bending strength",
               .help = "bending strength f_m; stresses are reported against it"});
  t.push_back({.group = "simulation",
               .name = "shear_strength",
               .flag = "--shear-strength",
               .type = T::Number,
               .default_value = "0",
               .minimum = 1e3,
               .maximum = 1e11,
               .zero_allowed = true,
               .zero_means = "the material's (unknown for custom)",
               .unit = "Pa",
               .label = "Shear strength",
               .help = "shear strength f_v"});
  t.push_back({.group = "simulation",
               .name = "unit",
               .flag = "--unit",
               .type = T::Text,
               .default_value = "",
               .label = "Length unit",
               .help = "the model's length unit: mm | cm | m | in | ft | metres per unit "
                       "(energies in J)"});
  t.push_back({.group = "simulation",
               .name = "unit_in_meters",
               .type = T::Number,
               .default_value = "0",
               .minimum = 1e-9,
               .maximum = 1e6,
               .zero_allowed = true,
               .zero_means = "from unit, or unknown",
               .unit = "m",
               .label = "Unit in metres",
               .help = "the model's length unit in metres (the CLI sets it from --unit)",
               .advanced = true});
  t.push_back({.group = "simulation",
               .name = "friction_mu",
               .flag = "--mu",
               .type = T::Number,
               .default_value = shortest(simulation.friction_mu),
               .minimum = 0,
               .maximum = 100,
               .exclusive_minimum = true,
               .zero_allowed = true,
               .zero_means = "default",
               .label = "Friction weight",
               .help = "pseudo-friction weight mu of E_p"});
  t.push_back({.group = "simulation",
               .name = "edges_per_interval",
               .flag = "--edges-per-interval",
               .type = T::Number,
               .default_value = shortest(simulation.edges_per_interval),
               .minimum = 1,
               .maximum = 64,
               .zero_allowed = true,
               .zero_means = "default",
               .label = "Edges per interval",
               .help = "rod edges per interval between crossings"});
  t.push_back({.group = "simulation",
               .name = "max_iterations",
               .flag = "--max-iterations",
               .type = T::Integer,
               .default_value = std::to_string(simulation.max_iterations),
               .minimum = 1,
               .maximum = 1000000,
               .zero_allowed = true,
               .zero_means = "default",
               .label = "Iteration cap",
               .help = "solver iteration cap"});
  t.push_back({.group = "simulation",
               .name = "solver",
               .flag = "--solver",
               .type = T::Choice,
               .default_value = "newton",
               .choices = {"newton", "ceres"},
               .label = "Solver",
               .help = "solver (ceres: Levenberg-Marquardt, the reference)"});
  t.push_back({.group = "simulation",
               .name = "interior_anchors",
               .type = T::Choice,
               .default_value = "",
               .choices = {"", "auto"},
               .label = "Automatic inner anchors",
               .help = "auto: add inner anchors one at a time where the deployment strays "
                       "farthest while RMS falls by 5% or more (\"\": the design's anchors only)",
               .note = "the CLI sets it with --interior-anchors auto"});
  // Unset: 0.25 % of the patch diagonal, half the accuracy bar of issue 18 (0.5 %); the paper's
  // built models reached 0.22-0.55 % (Table 1 RMS2 over their patch diagonals).
  t.push_back({.group = "simulation",
               .name = "anchor_goal",
               .flag = "--anchor-goal",
               .type = T::Number,
               .default_value = "0.25",
               .minimum = 0,
               .maximum = 100,
               .unit = "%",
               .label = "Anchor goal",
               .help = "no (further) inner anchor once RMS is at most this percentage of the "
                       "patch diagonal (0: add while each lowers RMS by 5%)",
               .note = "applies to interior_anchors auto only"});
  const auto advanced = [&](const char* name, double value, double lo, double hi, bool open_lo,
                            bool open_hi, const char* label, const char* help) {
    t.push_back({.group = "simulation",
                 .name = name,
                 .type = T::Number,
                 .default_value = shortest(value),
                 .minimum = lo,
                 .maximum = hi,
                 .exclusive_minimum = open_lo,
                 .exclusive_maximum = open_hi,
                 .zero_allowed = true,
                 .zero_means = "default",
                 .label = label,
                 .help = help,
                 .advanced = true});
  };
  advanced("friction_epsilon", simulation.friction_epsilon, 0, 0.5, true, true, "Friction epsilon",
           "E_p: how far past an edge end a connection may move");
  advanced("notch_limit_weight", simulation.notch_limit_weight, 0, 1e6, true, false,
           "Notch limit weight", "E_n weight (the paper's 1/10)");
  advanced("connection_position_weight", simulation.connection_position_weight, 0, 1e6, true, false,
           "Connection position weight", "relative to EA / rest length");
  advanced("connection_direction_weight", simulation.connection_direction_weight, 0, 1e6, true,
           false, "Connection direction weight", "relative to EI_strong / rest length");
  advanced("anchor_position_weight", simulation.anchor_position_weight, 0, 1e6, true, false,
           "Anchor position weight", "anchor position penalty weight");
  advanced("anchor_direction_weight", simulation.anchor_direction_weight, 0, 1e6, true, false,
           "Anchor direction weight", "anchor direction penalty weight");
  advanced("reference_extent", simulation.reference_extent, 1e-3, 1e6, false, false,
           "Reference extent", "model scale of the energies");
  advanced("gradient_tolerance", simulation.gradient_tolerance, 0, 1, true, false,
           "Gradient tolerance", "relative to EI_weak / unit^2 of the scaled model");
  for (const char* name : {"lamella_width", "lamella_thickness"})
    t.push_back({.group = "simulation",
                 .name = name,
                 .type = T::Number,
                 .unit = "mesh units",
                 .label = name,
                 .help = "from the design (recorded in deployment.json)",
                 .output = true});
  // Automatic layouts (AutoLayoutOptions) ------------------------------------------------------
  t.push_back({.group = "layout",
               .name = "max_patches",
               .flag = "--max-patches",
               .type = T::Integer,
               .default_value = std::to_string(layout.max_patches),
               .minimum = 1,
               .maximum = 64,
               .zero_allowed = true,
               .zero_means = "default",
               .label = "Patches at most",
               .help = "an automatic layout's patches at most (fewest patches that reach the "
                       "coverage goal are chosen)"});
  t.push_back({.group = "layout",
               .name = "coverage_goal",
               .flag = "--coverage-goal",
               .type = T::Number,
               .default_value = shortest(layout.coverage_goal),
               .minimum = 0,
               .maximum = 1,
               .exclusive_minimum = true,
               .zero_allowed = true,
               .zero_means = "default",
               .label = "Coverage goal",
               .help = "an automatic layout stops growing at this fraction of the input's area "
                       "covered by checked patches"});
  // Fabrication (FabricationOptions) ---------------------------------------------------------
  t.push_back({.group = "fabrication",
               .name = "unit",
               .flag = "--unit",
               .type = T::Text,
               .label = "Design unit",
               .help = "the design's length unit: mm | cm | m | in | ft | metres per unit",
               .note = "required unless millimetres_per_unit is given"});
  t.push_back({.group = "fabrication",
               .name = "millimetres_per_unit",
               .type = T::Number,
               .default_value = "0",
               .minimum = 0,
               .maximum = 1e9,
               .exclusive_minimum = true,
               .exclusive_maximum = true,
               .zero_allowed = true,
               .zero_means = "from unit",
               .unit = "mm",
               .label = "mm per unit",
               .help = "the design's length unit in mm",
               .advanced = true});
  const auto mm = [&](const char* name, const char* flag, double value, double lo, double hi,
                      bool open_lo, bool open_hi, const char* zero, const char* label,
                      const char* help) {
    t.push_back({.group = "fabrication",
                 .name = name,
                 .flag = flag,
                 .type = T::Number,
                 .default_value = shortest(value),
                 .minimum = lo,
                 .maximum = hi,
                 .exclusive_minimum = open_lo,
                 .exclusive_maximum = open_hi,
                 .zero_allowed = *zero != '\0',
                 .zero_means = zero,
                 .unit = "mm",
                 .label = label,
                 .help = help});
  };
  mm("sheet_width", "", fabrication.sheet_width, 0, 1e6, true, true, "", "Sheet width",
     "sheet width (the CLI's --sheet takes WIDTHxHEIGHT)");
  mm("sheet_height", "", fabrication.sheet_height, 0, 1e6, true, true, "", "Sheet height",
     "sheet height");
  mm("kerf", "--kerf", fabrication.kerf, 0, 10, false, true, "", "Kerf",
     "laser kerf (outlines grow, holes shrink by half)");
  mm("hole_diameter", "--hole-diameter", fabrication.hole_diameter, 0, 1000, true, true, "default",
     "Hole diameter", "bolt hole and slot width");
  mm("end_allowance", "--end-allowance", fabrication.end_allowance, 0, 1e6, true, false,
     "the lamella width", "End allowance", "beyond the outermost crossing");
  mm("spacing", "--spacing", fabrication.spacing, 0, 1e6, false, false, "", "Spacing",
     "between parts and from the sheet's edges");
  mm("thickness", "--thickness", fabrication.thickness, 0, 1e6, true, false,
     "the design's lamella thickness", "Thickness", "lamella thickness");
  mm("min_slot", "--min-slot", fabrication.min_slot, 0, 1e6, false, false, "", "Shortest slot",
     "shorter sliding ranges get round holes");
  mm("text_height", "--text-height", fabrication.text_height, 0, 1e6, true, false,
     "0.4 x lamella width within [1, 8] mm", "Text height", "engraved label height");
  t.push_back({.group = "fabrication",
               .name = "material",
               .flag = "--material",
               .type = T::Text,
               .default_value = "lime wood",
               .label = "Material name",
               .help = "material named in bom.csv"});
  return t;
}

}  // namespace

const char* to_string(OptionType type) {
  switch (type) {
    case OptionType::Number:
      return "number";
    case OptionType::Integer:
      return "integer";
    case OptionType::Boolean:
      return "boolean";
    case OptionType::Choice:
      return "choice";
    case OptionType::Text:
      return "text";
    case OptionType::Numbers:
      return "numbers";
  }
  return "text";
}

const std::vector<OptionSpec>& option_specs() {
  static std::vector<OptionSpec> table = build_table();
  // The material choices follow the presets, which a site's library extends at start-up
  // (load_site_materials, before any thread runs); the entries themselves stay where they are.
  static size_t materials = material_presets().size();
  if (materials != material_presets().size()) {
    for (OptionSpec& spec : table)
      if (spec.group == "simulation" && spec.name == "material") spec.choices = material_choices();
    materials = material_presets().size();
  }
  return table;
}

const OptionSpec& option_spec(std::string_view group, std::string_view name) {
  for (const OptionSpec& spec : option_specs())
    if (spec.group == group && spec.name == name) return spec;
  throw std::logic_error("no option " + std::string(group) + "." + std::string(name));
}

const OptionSpec* option_by_flag(std::string_view flag) {
  for (const OptionSpec& spec : option_specs())
    if (!spec.flag.empty() && spec.flag == flag) return &spec;
  return nullptr;
}

std::string allowed_text(const OptionSpec& spec) {
  if (spec.type == OptionType::Choice) {
    std::string text = "one of ";
    for (size_t i = 0; i < spec.choices.size(); ++i)
      text += (i ? ", " : "") + (spec.choices[i].empty() ? "\"\"" : spec.choices[i]);
    return text;
  }
  std::string text;
  const std::string lo = spec.minimum ? shortest(*spec.minimum) : "",
                    hi = spec.maximum ? shortest(*spec.maximum) : "";
  if (spec.minimum && spec.maximum && !spec.exclusive_minimum && !spec.exclusive_maximum)
    text = "between " + lo + " and " + hi;
  else if (spec.minimum && spec.maximum)
    text = "in " + std::string(spec.exclusive_minimum ? "(" : "[") + lo + ", " + hi +
           (spec.exclusive_maximum ? ")" : "]");
  else if (spec.minimum && *spec.minimum == 0 && spec.exclusive_minimum)
    text = "positive";
  else if (spec.minimum)
    text = (spec.exclusive_minimum ? "above " : "at least ") + lo;
  else if (spec.maximum)
    text = (spec.exclusive_maximum ? "below " : "at most ") + hi;
  if (!spec.unit.empty() && !text.empty() && spec.unit != "%")
    text += text == "positive" ? ", in " + spec.unit : " " + spec.unit;
  if (spec.unit == "%") text += " %";
  if (spec.zero_allowed) text += " (or 0: " + spec.zero_means + ")";
  return text;
}

double check_option(const OptionSpec& spec, double value, const std::string& field) {
  bool ok = std::isfinite(value);
  if (ok && spec.type == OptionType::Integer) ok = value == std::floor(value);
  if (ok && !(spec.zero_allowed && value == 0)) {
    if (spec.minimum) ok = spec.exclusive_minimum ? value > *spec.minimum : value >= *spec.minimum;
    if (ok && spec.maximum)
      ok = spec.exclusive_maximum ? value < *spec.maximum : value <= *spec.maximum;
  }
  if (!ok) throw InvalidInput(field, "must be " + allowed_text(spec) + ", got " + shortest(value));
  return value;
}

const std::string& check_option(const OptionSpec& spec, const std::string& value,
                                const std::string& field) {
  for (const std::string& choice : spec.choices)
    if (value == choice) return value;
  throw InvalidInput(field, "expected " + allowed_text(spec) + ", got '" + value + "'");
}

v1::OptionsResult describe_options() {
  v1::OptionsResult out;
  for (const OptionSpec& spec : option_specs()) {
    v1::OptionDescription& d = *out.add_options();
    d.set_group(spec.group);
    d.set_name(spec.name);
    d.set_flag(spec.flag);
    d.set_type(to_string(spec.type));
    d.set_default_value(spec.default_value);
    if (spec.minimum) d.set_minimum(*spec.minimum);
    if (spec.maximum) d.set_maximum(*spec.maximum);
    d.set_exclusive_minimum(spec.exclusive_minimum);
    d.set_exclusive_maximum(spec.exclusive_maximum);
    d.set_zero_allowed(spec.zero_allowed);
    d.set_zero_means(spec.zero_means);
    for (const std::string& choice : spec.choices) d.add_choices(choice);
    d.set_unit(spec.unit);
    d.set_help(spec.help);
    d.set_label(spec.label);
    d.set_advanced(spec.advanced);
    d.set_count(spec.count);
    d.set_note(spec.note);
    d.set_output(spec.output);
  }
  for (const Material& m : material_presets()) {
    v1::MaterialPreset& p = *out.add_materials();
    p.set_name(m.name);
    p.set_label(m.label);
    p.set_young_modulus(m.young_modulus);
    p.set_shear_modulus(m.shear_modulus);
    p.set_bending_strength(m.bending_strength);
    p.set_shear_strength(m.shear_strength);
    p.set_source(m.source);
    p.set_site(m.site);
  }
  for (MeshFormat format : {MeshFormat::Obj, MeshFormat::Off, MeshFormat::Ply, MeshFormat::Stl})
    out.add_mesh_formats(to_string(format));
  for (const char* unit : {"mm", "cm", "m", "in", "ft"}) out.add_length_units(unit);
  return out;
}

v1::OptionsResult run_options(const v1::OptionsRequest&, const Progress& progress,
                              const RunSettings&) {
  progress.check();
  return describe_options();
}

void load_site_materials() {
  const char* path = std::getenv("GRIDSHELL_MATERIALS");
  if (path == nullptr || *path == '\0') return;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidInput(path, "cannot read the material library (GRIDSHELL_MATERIALS)");
  std::ostringstream text;
  text << in.rdbuf();
  v1::MaterialLibrary library;
  std::vector<Material> materials;
  try {
    from_json(text.str(), library);
    for (const v1::MaterialPreset& p : library.materials()) {
      Material& m = materials.emplace_back();
      m.name = p.name();
      m.young_modulus = p.young_modulus();
      m.shear_modulus = p.shear_modulus();
      m.bending_strength = p.bending_strength();
      m.shear_strength = p.shear_strength();
      m.label = p.label();
      m.source = p.source();
    }
    add_material_presets(materials);
  } catch (const Error& e) {
    throw InvalidInput(join_field(path, e.field()), e.message());
  }
}

}  // namespace gridshell
