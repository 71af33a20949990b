// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/application/files.h"

#include <filesystem>
#include <memory>
#include <stdexcept>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"

namespace gridshell {

FileBundle patch_files(const v1::PatchResult& result) {
  // The patch as it arrived: no repairs, only the arrays turned back into OBJ text.
  const v1::Mesh& m = result.patch();
  std::vector<Vec3> vertices(m.positions_size() / 3);
  for (int k = 0; k + 2 < m.positions_size(); k += 3)
    vertices[k / 3] = Vec3(m.positions(k), m.positions(k + 1), m.positions(k + 2));
  std::vector<Face> faces(m.indices_size() / 3);
  for (int k = 0; k + 2 < m.indices_size(); k += 3)
    faces[k / 3] = {m.indices(k), m.indices(k + 1), m.indices(k + 2)};
  return {{"patch.obj", obj_text(vertices, faces)},
          {"patch.json", to_json(result.report()) + "\n"}};
}

FileBundle design_files(const v1::DesignResult& result) {
  FileBundle files{{"design.json", to_json(result.design()) + "\n"},
                   {"report.json", to_json(result.report()) + "\n"}};
  for (const v1::File& view : result.views()) files[view.name()] = view.content();
  return files;
}

FileBundle simulate_files(const v1::SimulateResult& result) {
  FileBundle files{{"deployment.json", to_json(result.deployment()) + "\n"}};
  for (const v1::File& view : result.views()) files[view.name()] = view.content();
  return files;
}

FileBundle run_files(const v1::RunResult& result) {
  FileBundle files = design_files(result.design());
  for (auto& [name, contents] : simulate_files(result.simulation())) files[name] = contents;
  return files;
}

void write_files(const FileBundle& files, const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InvalidInput(dir, "cannot create the output folder: " + ec.message());
  for (const auto& [name, contents] : files) {
    // Names come from result messages, possibly from a daemon: never let one leave `dir`.
    const fs::path file(name);
    if (name.empty() || file.has_parent_path() || file.is_absolute() || name == "." || name == "..")
      throw InvalidInput(dir, "result file name '" + name + "' is not a plain file name");
    write_file_atomically((fs::path(dir) / file).string(), contents);
  }
}

}  // namespace gridshell
