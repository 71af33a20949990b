// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell examples list` and `gridshell examples write NAME FILE`.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"

namespace gridshell::cli {
namespace {
struct ExamplesArguments {
  std::string name;
  std::string file;
  double scale = 1.0;
};
}  // namespace

Command add_examples_command(CLI::App& app) {
  auto args = std::make_shared<ExamplesArguments>();
  CLI::App* sub = app.add_subcommand("examples", "Built-in example surfaces");
  sub->require_subcommand(1);
  CLI::App* list = sub->add_subcommand("list", "List the examples with size and vertex count");
  CLI::App* write = sub->add_subcommand("write", "Write an example surface as OBJ");
  write->add_option("NAME", args->name, "example name (see 'examples list')")->required();
  write->add_option("FILE", args->file, "output .obj file")->required();
  write->add_option("--scale", args->scale, "resolution scale (vertex count grows with its square)")
      ->capture_default_str();
  return [args, list, write]() -> int {
    if (list->parsed()) {
      std::printf("%-14s %8s  %-22s %s\n", "name", "vertices", "size (w x d x h)", "description");
      for (const std::string& name : example_names()) {
        const ExampleSurface example = make_example(name);
        const Vec3 size = bounding_box_size(example.mesh);
        char dims[64];
        std::snprintf(dims, sizeof dims, "%.1f x %.1f x %.1f", size.x(), size.y(), size.z());
        std::printf("%-14s %8d  %-22s %s\n", name.c_str(), example.mesh.vertex_count(), dims,
                    example.description.c_str());
      }
      return 0;
    }
    if (write->parsed()) {
      if (!(args->scale >= 0.05 && args->scale <= 20))
        throw InvalidInput("--scale", "must be between 0.05 and 20");
      const std::string& f = args->file;
      if (f.size() < 4 || f.substr(f.size() - 4) != ".obj")
        throw InvalidInput("FILE", "only .obj output is supported, got '" + f + "'");
      const ExampleSurface example = make_example(args->name, args->scale);
      save_obj(example.mesh, f);
      std::printf("wrote %s: %d vertices, %d faces; corners %d,%d,%d,%d\n", f.c_str(),
                  example.mesh.vertex_count(), example.mesh.face_count(), example.corners[0],
                  example.corners[1], example.corners[2], example.corners[3]);
      return 0;
    }
    return 2;
  };
}

}  // namespace gridshell::cli
