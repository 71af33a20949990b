// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the one description of every request option: its name, type, default, range,
// unit and help, and the check of a value against it. The request converters check every option
// here (one check per option, one field path); the CLI builds its flags and help from it; the
// daemon answers it as the Options RPC (gridshell.v1.OptionsResult), which the web page, the
// Blender and FreeCAD panels and the Python client read; the sweep manifest check takes its
// columns from it. A new option is one entry in options.cpp (and its field in the .proto).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gridshell/v1/options.pb.h"

namespace gridshell {

enum class OptionType { Number, Integer, Boolean, Choice, Text, Numbers };

/// "number" | "integer" | "boolean" | "choice" | "text" | "numbers".
const char* to_string(OptionType type);

struct OptionSpec {
  std::string group;  ///< "patch" | "design" | "simulation" | "layout" | "fabrication"
  std::string name;   ///< proto field name in the group's options message
  std::string flag;   ///< CLI flag ("--lamella-width"), "" = request only
  OptionType type = OptionType::Number;
  std::string default_value;  ///< as text; "" = none
  std::optional<double> minimum, maximum;
  bool exclusive_minimum = false, exclusive_maximum = false;
  bool zero_allowed = false;  ///< 0 is allowed besides the range and means `zero_means`
  std::string zero_means;
  std::vector<std::string> choices;
  std::string unit;
  std::string label;
  std::string help;
  bool advanced = false;
  int count = 0;        ///< Numbers: how many (0 = any)
  std::string note;     ///< a dependency on other options, in words
  bool output = false;  ///< recorded in results, ignored in requests
};

/// Every option, grouped, in the order forms show them.
const std::vector<OptionSpec>& option_specs();

/// The option `name` of `group`; throws std::logic_error (a bug) if there is none.
const OptionSpec& option_spec(std::string_view group, std::string_view name);

/// The option whose CLI flag is `flag` (first match), or null.
const OptionSpec* option_by_flag(std::string_view flag);

/// "between 1 and 64", "at least 500 (or 0: 4000)", "one of on, off, both": what `spec` allows.
std::string allowed_text(const OptionSpec& spec);

/// Checks `value` against a Number or Integer option; throws InvalidInput(field, "must be ...,
/// got X") if it is outside (NaN and infinities are always outside). Returns `value`.
double check_option(const OptionSpec& spec, double value, const std::string& field);
/// The same for a Choice option.
const std::string& check_option(const OptionSpec& spec, const std::string& value,
                                const std::string& field);

/// The whole description: options, material presets (built in, then the site's), mesh formats
/// and length units.
v1::OptionsResult describe_options();

/// The Options RPC.
class Progress;
struct RunSettings;
v1::OptionsResult run_options(const v1::OptionsRequest& request, const Progress& progress,
                              const RunSettings& settings);

/// Reads the site's material library (gridshell.v1.MaterialLibrary in JSON) named by the
/// environment variable GRIDSHELL_MATERIALS, if set, and adds its materials to the presets.
/// Call once at start-up, before any thread runs. Throws InvalidInput naming the file and field.
void load_site_materials();

}  // namespace gridshell
