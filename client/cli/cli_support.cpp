// SPDX-License-Identifier: GPL-3.0-or-later
#include "cli_support.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <mutex>
#include <numbers>
#include <sstream>

#include "gridshell/application/files.h"
#include "gridshell/application/options.h"
#include "gridshell/application/requests.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::cli {

std::string described_help(const char* group, const char* name) {
  const OptionSpec& spec = option_spec(group, name);
  std::string help = spec.help;
  if (!spec.unit.empty() && (spec.type == OptionType::Text || spec.type == OptionType::Choice))
    help += ", " + spec.unit;
  if (spec.type == OptionType::Choice) {
    std::string choices;
    for (const std::string& choice : spec.choices)
      if (!choice.empty()) choices += (choices.empty() ? "" : " | ") + choice;
    help += ": " + choices;
  } else if (spec.type == OptionType::Number || spec.type == OptionType::Integer) {
    help += "; " + allowed_text(spec);
  }
  if (!spec.default_value.empty()) help += "; default " + spec.default_value;
  if (!spec.note.empty()) help += " (" + spec.note + ")";
  return help;
}

void add_described_flags(CLI::App* sub, const char* group, DescribedFlags& flags,
                         const std::set<std::string>& except) {
  flags.group = group;
  for (const OptionSpec& spec : option_specs()) {
    if (spec.group != group || spec.flag.empty() || spec.output || except.count(spec.name))
      continue;
    const std::string help = described_help(group, spec.name.c_str());
    if (spec.type == OptionType::Boolean)
      sub->add_flag(spec.flag, flags.switches[spec.name], help);
    else
      sub->add_option(spec.flag, flags.values[spec.name], help)
          ->type_name(spec.type == OptionType::Number    ? "FLOAT"
                      : spec.type == OptionType::Integer ? "INT"
                                                         : "TEXT");
  }
}

namespace {

/// `text` as a double, whole (strict); nullopt if it is not one.
std::optional<double> number_of(const std::string& text) {
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

}  // namespace

void set_described(const DescribedFlags& flags, google::protobuf::Message& options) {
  using google::protobuf::FieldDescriptor;
  const google::protobuf::Reflection& reflection = *options.GetReflection();
  for (const auto& [name, on] : flags.switches)
    if (on) reflection.SetBool(&options, options.GetDescriptor()->FindFieldByName(name), true);
  for (const auto& [name, value] : flags.values) {
    if (!value) continue;
    const OptionSpec& spec = option_spec(flags.group, name);
    const FieldDescriptor* field = options.GetDescriptor()->FindFieldByName(name);
    const std::string& text = *value;
    switch (spec.type) {
      case OptionType::Number: {
        const std::optional<double> number = number_of(text);
        if (!number) throw InvalidInput(spec.flag, "expected a number, got '" + text + "'");
        reflection.SetDouble(&options, field, *number);
        break;
      }
      case OptionType::Integer: {
        int number = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), number);
        if (text.empty() || ec != std::errc() || end != text.data() + text.size())
          throw InvalidInput(spec.flag, "expected a whole number, got '" + text + "'");
        reflection.SetInt32(&options, field, number);
        break;
      }
      case OptionType::Numbers: {
        reflection.ClearField(&options, field);
        std::stringstream items(text);
        for (std::string item; std::getline(items, item, ',');) {
          const std::optional<double> number = number_of(trim(item));
          if (!number)
            throw InvalidInput(spec.flag, "expected numbers a,b,..., got '" + text + "'");
          reflection.AddDouble(&options, field, *number);
        }
        break;
      }
      default:
        reflection.SetString(&options, field, text);
    }
  }
}

InputMesh load_input(const std::string& name) {
  InputMesh input;
  input.name = name;
  field_context().mesh = name;  // errors about the request's mesh name the MESH argument
  const std::string prefix = "example:";
  if (name.rfind(prefix, 0) == 0) {
    ExampleSurface example = make_example(name.substr(prefix.size()));
    input.mesh = std::move(example.mesh);
    input.example_corners = example.corners;
    input.report.format = "example";
    input.report.file_vertices = input.mesh.vertex_count();
    input.report.file_faces = input.mesh.face_count();
    input.report.vertex_of_file_vertex.resize(input.mesh.vertex_count());
    for (int v = 0; v < input.mesh.vertex_count(); ++v) input.report.vertex_of_file_vertex[v] = v;
    return input;
  }
  input.mesh = load_mesh(name, &input.report);
  for (const std::string& warning : input.report.warnings) std::cerr << warning << "\n";
  field_context().vertex_of_file_vertex = input.report.vertex_of_file_vertex;
  return input;
}

int mesh_vertex(const InputMesh& input, int file_vertex, const std::string& field) {
  const auto& map = input.report.vertex_of_file_vertex;
  if (file_vertex < 0 || file_vertex >= static_cast<int>(map.size()))
    throw InvalidInput(field, "vertex index " + std::to_string(file_vertex) + " is out of range (" +
                                  input.name + " has " + std::to_string(map.size()) +
                                  " vertices, numbered from 0)");
  if (map[file_vertex] < 0)
    throw InvalidInput(field, "vertex " + std::to_string(file_vertex) + " of " + input.name +
                                  " was removed as an isolated vertex");
  return map[file_vertex];
}

CornerSpec resolve_corners(const InputMesh& input, const std::string& text, std::string* used) {
  CornerSpec spec;
  if (!text.empty()) {
    spec = parse_corners(text);
    if (spec.kind == CornerSpec::Kind::Vertices)
      for (int& v : spec.vertices) v = mesh_vertex(input, v, "--corners");
    if (used) *used = text;
  } else if (input.example_corners) {
    spec.kind = CornerSpec::Kind::Vertices;
    spec.vertices = *input.example_corners;
    if (used) *used = "example";
  } else {
    spec.kind = CornerSpec::Kind::Auto;
    if (used) *used = "auto";
  }
  return spec;
}

namespace {
std::atomic<bool> interrupted{false};
}  // namespace

const std::atomic<bool>* cancel_flag() { return &interrupted; }
void on_interrupt(int) { interrupted.store(true, std::memory_order_relaxed); }

namespace {
std::mutex progress_mutex;
bool progress_line_open = false;
}  // namespace

Progress make_progress(bool quiet) {
  if (quiet) return Progress(nullptr, cancel_flag());
  const bool tty = isatty(STDERR_FILENO);
  auto last =
      std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now());
  auto last_stage = std::make_shared<std::string>();
  return Progress(
      [tty, last, last_stage](std::string_view stage, double fraction) {
        std::lock_guard lock(progress_mutex);
        const auto now = std::chrono::steady_clock::now();
        const bool new_stage = *last_stage != stage;
        if (tty) {
          if (!new_stage && now - *last < std::chrono::milliseconds(100)) return;
          std::fprintf(stderr, "\r\033[K%.*s %3.0f%%", static_cast<int>(stage.size()), stage.data(),
                       100 * std::clamp(fraction, 0.0, 1.0));
          std::fflush(stderr);
          progress_line_open = true;
        } else {
          if (now - *last < std::chrono::seconds(2)) return;  // logs: a line every 2 s at most
          std::fprintf(stderr, "progress: %.*s %.0f%%\n", static_cast<int>(stage.size()),
                       stage.data(), 100 * std::clamp(fraction, 0.0, 1.0));
        }
        *last = now;
        *last_stage = std::string(stage);
      },
      cancel_flag());
}

void finish_progress() {
  std::lock_guard lock(progress_mutex);
  if (progress_line_open) std::fprintf(stderr, "\r\033[K");
  progress_line_open = false;
}

std::string to_json(const google::protobuf::Message& message, bool pretty) {
  return gridshell::to_json(message, pretty);
}

v1::Mesh request_mesh(const InputMesh& input) {
  v1::Mesh mesh = to_proto(input.mesh, std::filesystem::path(input.name).filename().string());
  for (const std::string& warning : input.report.warnings) mesh.add_warnings(warning);
  return mesh;
}

int file_vertex(const InputMesh& input, int mesh_vertex) {
  if (mesh_vertex < 0) return -1;
  const auto& map = input.report.vertex_of_file_vertex;
  const auto it = std::find(map.begin(), map.end(), mesh_vertex);
  return it == map.end() ? -1 : static_cast<int>(it - map.begin());
}

void add_corner_angles_flag(CLI::App* sub, std::string& text) {
  // The default from the description, which is in radians.
  const std::string radians = option_spec("design", "auto_corner_angles").default_value;
  const double lo = std::strtod(radians.c_str(), nullptr),
               hi = std::strtod(radians.c_str() + radians.find(',') + 1, nullptr);
  char degrees[64];
  std::snprintf(degrees, sizeof degrees, "%g,%g", lo * 180 / std::numbers::pi,
                hi * 180 / std::numbers::pi);
  sub->add_option("--corner-angles", text,
                  "automatic corners: MIN,MAX inner corner angles of the patch in degrees "
                  "(default " +
                      std::string(degrees) + ")");
}

void set_corner_angles(const std::string& text, google::protobuf::RepeatedField<double>* out) {
  if (text.empty()) return;
  const size_t comma = text.find(',');
  if (comma == std::string::npos)
    throw InvalidInput("--corner-angles", "expected MIN,MAX in degrees, got '" + text + "'");
  double values[2];
  const std::string parts[2] = {trim(text.substr(0, comma)), trim(text.substr(comma + 1))};
  for (int k = 0; k < 2; ++k) {
    const auto [end, ec] =
        std::from_chars(parts[k].data(), parts[k].data() + parts[k].size(), values[k]);
    if (parts[k].empty() || ec != std::errc() || end != parts[k].data() + parts[k].size() ||
        !std::isfinite(values[k]))
      throw InvalidInput("--corner-angles", "'" + parts[k] + "' is not a number of degrees");
  }
  if (!(values[0] > 0 && values[0] < values[1] && values[1] < 180))
    throw InvalidInput("--corner-angles",
                       "expected 0 < MIN < MAX < 180 degrees, got '" + text + "'");
  out->Clear();
  for (double v : values) out->Add(v * std::numbers::pi / 180);
}

void auto_corners_to_file_order(const InputMesh& input, v1::AutoCornerSearch* search) {
  for (v1::AutoCornerCandidate& candidate : *search->mutable_candidates())
    for (int& v : *candidate.mutable_input_vertices()) v = file_vertex(input, v);
}

void print_auto_corners(const v1::AutoCornerSearch& search) {
  if (search.candidates_size() == 0 || search.chosen() < 0) return;
  const v1::AutoCornerCandidate& c = search.candidates(search.chosen());
  std::printf(
      "  auto corners    %d,%d,%d,%d (%s): candidate %d of %d, area %.4g; %d cut, %d "
      "evaluated, %.2f s\n",
      c.input_vertices(0), c.input_vertices(1), c.input_vertices(2), c.input_vertices(3),
      c.kind().c_str(), search.chosen() + 1, search.candidates_size(), c.area(), search.cuts(),
      search.evaluations(), search.seconds());
  if (search.simplified_vertices() > 0)
    std::printf(
        "                  ranked on a copy simplified to %d vertices (areas within %.2g %% of "
        "the input's); the patch is cut exactly\n",
        search.simplified_vertices(), 100 * search.area_error());
}

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

namespace {
/// The outermost folder prepare_output_folder created ("" if --out existed).
std::string created_output_folder;
}  // namespace

void prepare_output_folder(const std::string& out) {
  namespace fs = std::filesystem;
  if (out.empty()) throw InvalidInput("--out", "empty: give the output folder");
  std::error_code ec;
  fs::path missing;
  for (fs::path p = fs::absolute(out, ec); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    missing = p;
    if (p == p.parent_path()) break;
  }
  fs::create_directories(out, ec);
  if (!ec && !missing.empty()) created_output_folder = missing.string();
  if (ec)
    throw InvalidInput("--out", "cannot create the output folder " + out + ": " + ec.message());
  if (!fs::is_directory(out, ec)) throw InvalidInput("--out", out + " exists and is not a folder");
  // Writable? (results are written atomically: a temporary file beside the final one)
  const fs::path probe = fs::path(out) / (".gridshell-write-test-" + std::to_string(::getpid()));
  std::FILE* f = std::fopen(probe.c_str(), "w");
  if (!f) throw InvalidInput("--out", "cannot write into " + out + ": " + std::strerror(errno));
  std::fclose(f);
  fs::remove(probe, ec);
}

void remove_unused_output_folder() {
  namespace fs = std::filesystem;
  if (created_output_folder.empty()) return;
  std::error_code ec;
  // Only what this run created, and only if nothing was written into it.
  for (fs::recursive_directory_iterator it(created_output_folder, ec), end; !ec && it != end;
       it.increment(ec))
    if (!it->is_directory(ec)) return;
  if (!ec) fs::remove_all(created_output_folder, ec);
  created_output_folder.clear();
}

namespace {

std::string read_json_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidInput(path, "cannot open the design file");
  std::stringstream text;
  text << in.rdbuf();
  std::string json = text.str();
  if (json.rfind("\xEF\xBB\xBF", 0) == 0) json.erase(0, 3);  // a UTF-8 byte order mark
  return json;
}

}  // namespace

v1::Design read_design_file(const std::string& path) {
  v1::Design design;
  try {
    from_json(read_json_file(path), design);  // strict: unknown fields, "yes" for a bool, ...
  } catch (const InvalidInput& e) {
    throw InvalidInput(path, "not a gridshell design file: " + std::string(e.what()));
  }
  return design;
}

std::optional<LayoutDesignFiles> read_layout_design_file(const std::string& path) {
  const std::string json = read_json_file(path);
  LayoutDesignFiles out;
  try {
    from_json(json, out.layout);
  } catch (const InvalidInput&) {
    return std::nullopt;  // not a layout run's design.json
  }
  if (out.layout.patch_designs_size() == 0) return std::nullopt;
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  for (const std::string& file : out.layout.patch_designs())
    if (!file.empty()) out.patches.push_back(read_design_file((folder / file).string()));
  return out;
}

}  // namespace gridshell::cli
