// SPDX-License-Identifier: GPL-3.0-or-later
// The material presets: the one place they are listed. Every client reads them from here through
// the Options RPC / `gridshell options --json` (application/options.cpp); a new material is one
// entry in kBuiltIn. A site adds its own with a material library (GRIDSHELL_MATERIALS).
#include <cmath>

#include "gridshell/foundation/errors.h"
#include "gridshell/simulation/simulation.h"

namespace gridshell {
namespace {

/// Reference values along the grain / fibres, without safety factors (docs/decisions.md,
/// "Materials"): E, G, bending strength, shear strength.
Material preset(const char* name, double young, double shear, double bending, double shear_strength,
                const char* label, const char* source) {
  Material m;
  m.name = name;
  m.young_modulus = young;
  m.shear_modulus = shear;
  m.bending_strength = bending;
  m.shear_strength = shear_strength;
  m.label = label;
  m.source = source;
  return m;
}

std::vector<Material> built_in() {
  return {
      preset("lime-wood", 7.4e9, 0.46e9, 60e6, 6.8e6, "lime wood",
             "basswood (Tilia), the paper's lamellas: strengths along the grain at 12 % moisture, "
             "USDA Wood Handbook"),
      preset("birch-plywood", 9.0e9, 0.62e9, 50e6, 9.0e6, "birch plywood",
             "face grain direction, typical of Finnish birch plywood data sheets"),
      preset("beech-wood", 14.0e9, 1.08e9, 103e6, 13.9e6, "beech wood",
             "American beech along the grain, USDA Wood Handbook"),
      preset(
          "gfrp", 25.0e9, 3.5e9, 240e6, 25e6, "GFRP",
          "pultruded glass fibre, EN 13706 grade E23 minimum flexural and in-plane shear strength"),
      preset("aluminium", 70.0e9, 26.0e9, 276e6, 159e6, "aluminium",
             "6061-T6: yield, shear yield 0.577 x yield"),
      preset("steel", 210.0e9, 81.0e9, 235e6, 136e6, "steel",
             "S235: yield, shear yield 0.577 x yield"),
      preset("hdpe", 0.9e9, 0.31e9, 25e6, 14e6, "HDPE", "high-density polyethylene: yield"),
  };
}

std::vector<Material>& registry() {
  static std::vector<Material> all = built_in();
  return all;
}

bool within(double value, double lo, double hi) {
  return std::isfinite(value) && value >= lo && value <= hi;
}

}  // namespace

const std::vector<Material>& material_presets() { return registry(); }

void add_material_presets(const std::vector<Material>& materials) {
  std::vector<Material>& all = registry();
  for (size_t i = 0; i < materials.size(); ++i) {
    Material m = materials[i];
    const std::string field = "materials[" + std::to_string(i) + "]";
    if (m.name.empty() || m.name == "custom")
      throw InvalidInput(field + ".name", "a material needs a name other than custom");
    for (const Material& known : all)
      if (known.name == m.name) throw InvalidInput(field + ".name", "'" + m.name + "' is taken");
    if (!within(m.young_modulus, 1e3, 1e13))
      throw InvalidInput(field + ".young_modulus",
                         "must be a number of pascals between 1e3 and 1e13");
    if (!within(m.shear_modulus, 1e3, 1e13))
      throw InvalidInput(field + ".shear_modulus",
                         "must be a number of pascals between 1e3 and 1e13");
    if (!(m.bending_strength == 0 || within(m.bending_strength, 1e3, 1e11)))
      throw InvalidInput(field + ".bending_strength",
                         "must be a number of pascals between 1e3 and 1e11 (or 0: unknown)");
    if (!(m.shear_strength == 0 || within(m.shear_strength, 1e3, 1e11)))
      throw InvalidInput(field + ".shear_strength",
                         "must be a number of pascals between 1e3 and 1e11 (or 0: unknown)");
    if (m.label.empty()) m.label = m.name;
    m.site = true;
    all.push_back(std::move(m));
  }
}

Material material_by_name(const std::string& name) {
  std::string known;
  for (const Material& m : material_presets()) {
    if (m.name == name) return m;
    known += (known.empty() ? "" : ", ") + m.name;
  }
  throw InvalidInput("", "unknown material '" + name + "' (known: " + known + ")");
}

}  // namespace gridshell
