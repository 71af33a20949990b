// SPDX-License-Identifier: GPL-3.0-or-later
// How the CLI shows a kernel or API error: its field in the CLI's own terms (flags, file names),
// then the message. The kernel and the converters name request fields ("options.lamella_width",
// "corners.vertices[2]", "mesh.indices[21]", "design.members[3]"); only this file knows that the
// CLI calls them --lamella-width, --corners, the MESH argument or the design file.
#include <algorithm>
#include <array>
#include <charconv>
#include <iostream>
#include <sstream>
#include <utility>

#include "cli_support.h"
#include "gridshell/application/options.h"
#include "gridshell/application/requests.h"

namespace gridshell::cli {
namespace {

/// "name[12]" -> {"name", 12}; {field, -1} without a trailing index.
std::pair<std::string, long long> split_index(const std::string& field) {
  if (field.empty() || field.back() != ']') return {field, -1};
  const size_t open = field.rfind('[');
  if (open == std::string::npos) return {field, -1};
  long long index = -1;
  const char* begin = field.data() + open + 1;
  const char* end = field.data() + field.size() - 1;
  const auto [ptr, ec] = std::from_chars(begin, end, index);
  if (ec != std::errc() || ptr != end) return {field, -1};
  return {field.substr(0, open), index};
}

/// An option of a request ("members_u") as the CLI flag that sets it: the flag of its
/// description (options.cpp); --unit sets unit_in_meters too, and design.json's map_resolution
/// is the --resolution it was designed with.
std::string flag_of(const std::string& option) {
  for (const OptionSpec& spec : option_specs())
    if (spec.name == option && !spec.flag.empty()) return spec.flag;
  if (option == "unit_in_meters") return "--unit";
  if (option == "map_resolution") return "--resolution";
  std::string flag = "--" + option;
  for (char& c : flag)
    if (c == '_') c = '-';
  return flag;
}

std::string corners_field(const std::string& rest) {
  // rest: "", "[i]", ".vertices[i]", ".points[k]" (k counts numbers, three per corner)
  const auto [name, index] = split_index(rest);
  if (index < 0) return "--corners";
  const long long corner = name == ".points" ? index / 3 : index;
  return "--corners (corner " + std::to_string(corner + 1) + ")";
}

std::string mesh_field(const std::string& rest, const FieldContext& context) {
  const std::string file = context.mesh.empty() ? "MESH" : context.mesh;
  const auto [name, index] = split_index(rest);
  if (index >= 0 && name == ".indices") return file + " (face " + std::to_string(index / 3) + ")";
  if (index >= 0 && name == ".positions")
    return file + " (vertex " + std::to_string(index / 3) + ")";
  return file;
}

bool starts_with(const std::string& text, const std::string& prefix) {
  return text.rfind(prefix, 0) == 0;
}

}  // namespace

FieldContext& field_context() {
  static FieldContext context;
  return context;
}

std::string cli_field(const std::string& field, const FieldContext& context) {
  if (field.empty()) return field;
  if (field == "corners" || starts_with(field, "corners.") || starts_with(field, "corners["))
    return corners_field(field.substr(7));
  if (field == "mesh" || starts_with(field, "mesh.")) return mesh_field(field.substr(4), context);
  for (const std::string prefix : {"options.", "simulation.", "automatic."})
    if (starts_with(field, prefix)) {
      const std::string option = field.substr(prefix.size());
      return option.find_first_of(".[") == std::string::npos ? flag_of(option) : field;
    }
  if (starts_with(field, "design.")) {
    const std::string inner = field.substr(7);
    // gridshell run: the design half of the request; gridshell simulate: the design file.
    if (context.design.empty()) return cli_field(inner, context);
    return context.design + " (" + inner + ")";
  }
  for (const char* option : {"source", "method", "compare", "repeat"})
    if (field == option) return flag_of(option);
  return field;  // a flag or a file name already
}

void print_suggestions(const std::vector<v1::Suggestion>& suggestions) {
  const FieldContext& context = field_context();
  for (const v1::Suggestion& s : suggestions) {
    std::ostringstream flags;
    if (s.kind() == "slope_bounds") flags << "--k-min " << s.k_min() << " --k-max " << s.k_max();
    if (s.kind() == "corners") {
      flags << "--corners ";
      for (int i = 0; i < s.corners().vertices_size(); ++i) {
        const int v = s.corners().vertices(i);
        // As sent -> as in the file (the loader may have welded or dropped vertices).
        const auto& map = context.vertex_of_file_vertex;
        const auto it = std::find(map.begin(), map.end(), v);
        flags << (i ? "," : "") << (it == map.end() ? v : static_cast<int>(it - map.begin()));
      }
    }
    if (s.kind() == "members") {
      if (s.members_u() > 0) flags << "--members-u " << s.members_u() << " ";
      if (s.members_v() > 0) flags << "--members-v " << s.members_v();
    }
    if (s.kind() == "lamella_width") flags << "--lamella-width " << s.lamella_width();
    std::cerr << "suggestion " << s.rank() << ": " << s.description() << "  [" << flags.str()
              << "]\n";
  }
}

int report_error(const Error& error) {
  finish_progress();
  remove_unused_output_folder();
  const std::string field = cli_field(error.field(), field_context());
  std::string line = "error: ";
  if (error.code() == ErrorCode::Infeasible) line += "infeasible: ";
  if (error.code() == ErrorCode::Internal) line += "internal: ";
  if (!field.empty()) line += field + ": ";
  std::cerr << line << error.message() << "\n";
  if (const auto* with = dynamic_cast<const InfeasibleWithSuggestions*>(&error))
    print_suggestions(with->suggestions());
  switch (error.code()) {
    case ErrorCode::InvalidInput:
      return 2;
    case ErrorCode::Infeasible:
      return 3;
    case ErrorCode::Cancelled:
      return 130;
    case ErrorCode::Internal:
      return 1;
  }
  return 1;
}

}  // namespace gridshell::cli
