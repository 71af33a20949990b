// SPDX-License-Identifier: GPL-3.0-or-later
// The one description of the options (application/options.cpp): it covers every field of the
// options messages with its type, each default passes its own check, and the request checks
// refuse every out-of-range value by that option's field path, as described; site materials join
// the presets everywhere the description is read.
#include <google/protobuf/descriptor.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <set>

#include "gridshell/application/deployment_job.h"
#include "gridshell/application/fabricate.h"
#include "gridshell/application/layout.h"
#include "gridshell/application/options.h"
#include "gridshell/application/requests.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/simulation/simulation.h"
#include "gridshell/v1/fabrication.pb.h"
#include "support.h"

namespace gridshell {
namespace {

using google::protobuf::Descriptor;
using google::protobuf::FieldDescriptor;
using google::protobuf::Message;

const std::map<std::string, const Descriptor*>& groups() {
  static const std::map<std::string, const Descriptor*> all{
      {"patch", v1::PatchRequest::Options::descriptor()},
      {"design", v1::DesignRequest::Options::descriptor()},
      {"simulation", v1::SimulationOptions::descriptor()},
      {"fabrication", v1::FabricationOptions::descriptor()},
      {"layout", v1::AutoLayoutOptions::descriptor()},
  };
  return all;
}

std::string type_of(const FieldDescriptor* field) {
  if (field->is_repeated())
    return field->cpp_type() == FieldDescriptor::CPPTYPE_DOUBLE ? "numbers" : "?";
  switch (field->cpp_type()) {
    case FieldDescriptor::CPPTYPE_DOUBLE:
      return "number";
    case FieldDescriptor::CPPTYPE_INT32:
      return "integer";
    case FieldDescriptor::CPPTYPE_BOOL:
      return "boolean";
    case FieldDescriptor::CPPTYPE_STRING:
      return "text";  // or choice
    default:
      return "?";
  }
}

TEST(Options, DescribeEveryFieldOfEveryOptionsMessageOnceWithItsType) {
  std::set<std::pair<std::string, std::string>> described;
  for (const OptionSpec& spec : option_specs()) {
    SCOPED_TRACE(spec.group + "." + spec.name);
    ASSERT_TRUE(groups().count(spec.group));
    EXPECT_TRUE(described.insert({spec.group, spec.name}).second) << "described twice";
    const FieldDescriptor* field = groups().at(spec.group)->FindFieldByName(spec.name);
    ASSERT_NE(field, nullptr) << "no such field";
    const std::string type = to_string(spec.type);
    EXPECT_EQ(type == "choice" ? "text" : type, type_of(field));
    EXPECT_FALSE(spec.label.empty());
    EXPECT_FALSE(spec.help.empty());
    if (spec.type == OptionType::Choice) {
      EXPECT_FALSE(spec.choices.empty());
    }
  }
  for (const auto& [group, descriptor] : groups())
    for (int i = 0; i < descriptor->field_count(); ++i)
      EXPECT_TRUE(described.count({group, descriptor->field(i)->name()}))
          << group << "." << descriptor->field(i)->name() << " has no description";
  // Flags are unique within a command's groups (design and simulation share `gridshell run`).
  std::map<std::string, std::string> flags;
  for (const OptionSpec& spec : option_specs()) {
    if (spec.flag.empty() || spec.group == "patch" || spec.group == "fabrication") continue;
    EXPECT_TRUE(flags.emplace(spec.flag, spec.name).second) << spec.flag;
  }
}

TEST(Options, EveryDefaultPassesItsOwnCheck) {
  for (const OptionSpec& spec : option_specs()) {
    SCOPED_TRACE(spec.group + "." + spec.name);
    if (spec.type == OptionType::Number || spec.type == OptionType::Integer) {
      if (spec.output) continue;
      ASSERT_FALSE(spec.default_value.empty());
      char* end = nullptr;
      const double value = std::strtod(spec.default_value.c_str(), &end);
      EXPECT_EQ(*end, '\0');
      EXPECT_NO_THROW(check_option(spec, value, "x"));
    } else if (spec.type == OptionType::Choice) {
      EXPECT_NO_THROW(check_option(spec, spec.default_value, "x"));
    }
  }
}

/// Sets field `name` of `message` to `value` (a number option).
void set_number(Message& message, const std::string& name, double value) {
  const FieldDescriptor* field = message.GetDescriptor()->FindFieldByName(name);
  if (field->cpp_type() == FieldDescriptor::CPPTYPE_DOUBLE)
    message.GetReflection()->SetDouble(&message, field, value);
  else
    message.GetReflection()->SetInt32(&message, field, static_cast<int>(value));
}

/// Runs the request check of `spec`'s group with the option set to `value`; the error's field, or
/// "" when it passed.
std::string check_in_request(const OptionSpec& spec, double value) {
  try {
    if (spec.group == "patch") {
      v1::PatchRequest request;
      request.mutable_mesh()->set_example("plane");
      set_number(*request.mutable_options(), spec.name, value);
      prepare_patch(request);
    } else if (spec.group == "design") {
      v1::DesignRequest request;
      request.mutable_mesh()->set_example("plane");
      set_number(*request.mutable_options(), spec.name, value);
      prepare_design(request);
    } else if (spec.group == "simulation") {
      v1::SimulationOptions options;
      if (spec.name == "anchor_goal") options.set_interior_anchors("auto");
      set_number(options, spec.name, value);
      prepare_simulation_options(options, "options");
    } else if (spec.group == "layout") {
      v1::AutoLayoutOptions options;
      set_number(options, spec.name, value);
      prepare_auto_layout_options(options, "options");
    } else {
      v1::FabricationOptions options;
      options.set_unit("mm");
      // The sheet is given whole (WIDTHxHEIGHT): the other side at its default.
      for (const char* side : {"sheet_width", "sheet_height"})
        set_number(options, side,
                   std::strtod(option_spec("fabrication", side).default_value.c_str(), nullptr));
      set_number(options, spec.name, value);
      prepare_fabrication_options(options);
    }
  } catch (const InvalidInput& e) {
    return e.field();
  }
  return "";
}

// One check per option, in the request layer, naming the option's field: a value just outside
// each described bound is refused, a value inside passes.
TEST(Options, RequestChecksRefuseWhatTheDescriptionRefuses) {
  const double inf = std::numeric_limits<double>::infinity();
  int checked = 0;
  for (const OptionSpec& spec : option_specs()) {
    if (spec.output || (spec.type != OptionType::Number && spec.type != OptionType::Integer))
      continue;
    if (spec.name == "millimetres_per_unit") continue;  // replaced by `unit` when both are given
    SCOPED_TRACE(spec.group + "." + spec.name);
    const std::string field = "options." + spec.name;
    const bool integer = spec.type == OptionType::Integer;
    std::vector<double> outside;
    if (spec.minimum) {
      const double below = spec.exclusive_minimum ? *spec.minimum : *spec.minimum - 1;
      if (!(spec.zero_allowed && below == 0)) outside.push_back(below);
      outside.push_back(std::min(below, -1.0) * 2);
    }
    if (spec.maximum && *spec.maximum < 2e9)
      outside.push_back(spec.exclusive_maximum ? *spec.maximum : *spec.maximum + 1);
    else if (spec.maximum && !integer)
      outside.push_back(*spec.maximum * 10);
    if (!integer) outside.push_back(inf);
    for (double value : outside) {
      if (spec.zero_allowed && value == 0) continue;
      EXPECT_EQ(check_in_request(spec, value), field) << value;
      ++checked;
    }
    EXPECT_EQ(check_in_request(spec, std::strtod(spec.default_value.c_str(), nullptr)), "");
  }
  EXPECT_GT(checked, 60);
}

TEST(Options, DescriptionListsTheMaterialsAndTheirChoice) {
  const v1::OptionsResult all = describe_options();
  ASSERT_EQ(all.materials_size(), static_cast<int>(material_presets().size()));
  EXPECT_EQ(all.materials(0).name(), option_spec("simulation", "material").default_value);
  for (const v1::MaterialPreset& m : all.materials()) {
    EXPECT_GT(m.young_modulus(), 0) << m.name();
    EXPECT_FALSE(m.source().empty()) << m.name();
  }
  EXPECT_EQ(all.mesh_formats_size(), 4);
  for (const std::string& format : all.mesh_formats())
    EXPECT_TRUE(mesh_format_from_name(format).has_value()) << format;
  for (const std::string& unit : all.length_units()) EXPECT_GT(parse_length_unit(unit), 0);
}

// A site material (as GRIDSHELL_MATERIALS adds it) joins the presets: the simulation accepts it
// by name and takes its moduli and strengths.
TEST(Options, SiteMaterialsAreAddedAfterTheBuiltInOnes) {
  const std::string dir = testing::temp_dir();
  const std::string path = testing::write_text(
      dir, "materials.json",
      R"({"materials": [{"name": "test-larch", "label": "test larch", "young_modulus": 1.1e10,
          "shear_modulus": 0.7e9, "bending_strength": 7e7, "shear_strength": 8e6,
          "source": "a test"}]})");
  ::setenv("GRIDSHELL_MATERIALS", path.c_str(), 1);
  load_site_materials();
  ::unsetenv("GRIDSHELL_MATERIALS");
  const Material& added = material_presets().back();
  EXPECT_EQ(added.name, "test-larch");
  EXPECT_TRUE(added.site);
  v1::SimulationOptions options;
  options.set_material("test-larch");
  const v1::SimulationOptions resolved = resolve_simulation_options(options);
  EXPECT_EQ(resolved.young_modulus(), 1.1e10);
  EXPECT_EQ(resolved.bending_strength(), 7e7);
  // A name taken, a modulus out of range, a file that is not a library: errors naming the place.
  const auto error_of = [&](const std::string& text) {
    ::setenv("GRIDSHELL_MATERIALS", testing::write_text(dir, "bad.json", text).c_str(), 1);
    std::string field;
    try {
      load_site_materials();
    } catch (const InvalidInput& e) {
      field = e.field();
    }
    ::unsetenv("GRIDSHELL_MATERIALS");
    return field;
  };
  EXPECT_EQ(
      error_of(
          R"({"materials": [{"name": "steel", "young_modulus": 2e11, "shear_modulus": 8e10}]})"),
      dir + "/bad.json.materials[0].name");
  EXPECT_EQ(
      error_of(R"({"materials": [{"name": "jelly", "young_modulus": 1, "shear_modulus": 1}]})"),
      dir + "/bad.json.materials[0].young_modulus");
  EXPECT_EQ(error_of(R"({"materials": [{"nme": "x"}]})"), dir + "/bad.json.materials[0].nme");
}

}  // namespace
}  // namespace gridshell
