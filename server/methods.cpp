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
                      {}};
  methods.fabricate = {"Fabricate",
                       [settings](const v1::FabricateRequest& request, const Progress& progress) {
                         return run_fabricate(request, progress, settings);
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

std::pair<int, int> mesh_size(const google::protobuf::Message& request) {
  const v1::Mesh* mesh = find_mesh(request, 3);
  if (!mesh) return {0, 0};
  return {mesh->positions_size() / 3, mesh->indices_size() / 3};
}

}  // namespace gridshell::server
