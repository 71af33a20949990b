// SPDX-License-Identifier: GPL-3.0-or-later
#include "methods.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/reflection.h>

namespace gridshell::server {

Methods make_methods(const RunSettings& settings) {
  Methods methods;
  methods.patch = {"Patch",
                   [settings](const v1::PatchRequest& request, const Progress& progress) {
                     return run_patch(request, progress, settings);
                   },
                   {}};
  methods.design = {"Design",
                    [settings](const v1::DesignRequest& request, const Progress& progress) {
                      return run_design(request, progress, settings);
                    },
                    {}};
  methods.simulate = {"Simulate",
                      [settings](const v1::SimulateRequest& request, const Progress& progress) {
                        return run_simulate(request, progress, settings);
                      },
                      {}};
  methods.run = {"Run",
                 [settings](const v1::RunRequest& request, const Progress& progress) {
                   return run_run(request, progress, settings);
                 },
                 {}};
  methods.geodesic = {"Geodesic",
                      [settings](const v1::GeodesicRequest& request, const Progress& progress) {
                        return run_geodesic(request, progress, settings);
                      },
                      {}};
  methods.load = {"Load",
                  [settings](const v1::LoadRequest& request, const Progress& progress) {
                    return run_load(request, progress, settings);
                  },
                  {}};
  methods.examples = {"Examples",
                      [settings](const v1::ExamplesRequest& request, const Progress& progress) {
                        return run_examples(request, progress, settings);
                      },
                      {},
                      true};
  methods.fabricate = {"Fabricate",
                       [settings](const v1::FabricateRequest& request, const Progress& progress) {
                         return run_fabricate(request, progress, settings);
                       },
                       {}};
  methods.options = {"Options",
                     [settings](const v1::OptionsRequest& request, const Progress& progress) {
                       return run_options(request, progress, settings);
                     },
                     {},
                     true};
  methods.layout = {"Layout",
                    [settings](const v1::LayoutRequest& request, const Progress& progress) {
                      return run_layout(request, progress, settings);
                    },
                    {}};
  methods.run_layout = {"RunLayout",
                        [settings](const v1::LayoutRunRequest& request, const Progress& progress) {
                          return run_layout_run(request, progress, settings);
                        },
                        {}};
  return methods;
}

namespace {

const v1::Mesh* find_mesh(const google::protobuf::Message& message, int depth) {
  if (const auto* mesh = dynamic_cast<const v1::Mesh*>(&message)) return mesh;
  if (depth == 0) return nullptr;
  const google::protobuf::Reflection* reflection = message.GetReflection();
  std::vector<const google::protobuf::FieldDescriptor*> fields;
  reflection->ListFields(message, &fields);
  for (const auto* field : fields)
    if (field->cpp_type() == google::protobuf::FieldDescriptor::CPPTYPE_MESSAGE &&
        !field->is_repeated())
      if (const v1::Mesh* mesh = find_mesh(reflection->GetMessage(message, field), depth - 1))
        return mesh;
  return nullptr;
}

}  // namespace

namespace {

void check_text(const google::protobuf::Message& message, const std::string& path, int depth) {
  using google::protobuf::FieldDescriptor;
  if (depth > 64) return;  // protobuf refuses deeper messages when it parses them
  const google::protobuf::Reflection* reflection = message.GetReflection();
  std::vector<const FieldDescriptor*> fields;
  reflection->ListFields(message, &fields);
  std::string scratch;
  for (const FieldDescriptor* field : fields) {
    const std::string name = path.empty() ? field->name() : path + "." + field->name();
    if (field->type() == FieldDescriptor::TYPE_STRING) {
      const auto too_long = [&](const std::string& text, const std::string& where) {
        if (text.size() > kMaxTextBytes)
          throw InvalidInput(where, "too long: " + std::to_string(text.size()) +
                                        " bytes, at most " + std::to_string(kMaxTextBytes));
      };
      if (!field->is_repeated()) {
        too_long(reflection->GetStringReference(message, field, &scratch), name);
        continue;
      }
      const int count = reflection->FieldSize(message, field);
      if (count > kMaxTextEntries)
        throw InvalidInput(name, "too many entries: " + std::to_string(count) + ", at most " +
                                     std::to_string(kMaxTextEntries));
      for (int i = 0; i < count; ++i)
        too_long(reflection->GetRepeatedStringReference(message, field, i, &scratch),
                 name + "[" + std::to_string(i) + "]");
    } else if (field->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE &&
               field->message_type()->file()->package() != "google.protobuf") {
      if (!field->is_repeated()) {
        check_text(reflection->GetMessage(message, field), name, depth + 1);
        continue;
      }
      const int count = reflection->FieldSize(message, field);
      for (int i = 0; i < count; ++i)
        check_text(reflection->GetRepeatedMessage(message, field, i),
                   name + "[" + std::to_string(i) + "]", depth + 1);
    }
  }
}

}  // namespace

void check_text_limits(const google::protobuf::Message& request) { check_text(request, "", 0); }

std::pair<int, int> mesh_size(const google::protobuf::Message& request) {
  const v1::Mesh* mesh = find_mesh(request, 3);
  if (!mesh) return {0, 0};
  return {mesh->positions_size() / 3, mesh->indices_size() / 3};
}

}  // namespace gridshell::server
