// SPDX-License-Identifier: GPL-3.0-or-later
// The sweep's row check in `gridshell run`'s terms (sweep::RowChecker): a row's columns are the
// long names of `gridshell run`'s design and simulation flags, which come from the options
// description; a row is parsed as that command line and its requests are checked as `gridshell
// run` checks them before its work starts (the mesh is loaded, corners and options checked).
#include <CLI/CLI.hpp>
#include <map>
#include <memory>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/requests.h"
#include "gridshell/batch/sweep.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::cli {
namespace {

/// The flags of `gridshell run` that describe a design (not where or how it runs).
struct RunFlags {
  DesignFlags design;
  LayoutFlags layout;
  SimulationFlags simulation;
  CLI::App app{"row"};
  RunFlags() {
    add_design_flags(&app, design);
    add_layout_flags(&app, layout);
    add_simulation_flags(&app, simulation);
  }
  /// Parses `gridshell run` arguments (without the command name).
  void parse(const std::vector<std::string>& arguments) {
    std::vector<std::string> reversed(arguments.rbegin(), arguments.rend());
    app.parse(reversed);
  }
};

class RunRowChecker final : public sweep::RowChecker {
 public:
  std::vector<std::string> columns() override {
    RunFlags flags;
    std::vector<std::string> columns;
    for (const CLI::Option* option : flags.app.get_options())
      for (const std::string& name : option->get_lnames())
        if (name != "help") columns.push_back(name);
    return columns;
  }

  std::vector<std::pair<std::string, std::string>> check(const sweep::Row& row) override {
    std::vector<std::pair<std::string, std::string>> problems;
    // Each value alone, so that a value CLI11 rejects is reported in its own column.
    for (const auto& [column, value] : row.values) {
      if (column == "mesh") continue;
      try {
        RunFlags flags;
        flags.parse({row.mesh, "--" + column + "=" + value});
      } catch (const CLI::ParseError& e) {
        std::string message = e.what();
        const std::string prefix = "--" + column + ": ";
        if (message.rfind(prefix, 0) == 0) message = message.substr(prefix.size());
        problems.emplace_back(column, message);
      }
    }
    if (!problems.empty()) return problems;
    // The row as `gridshell run` checks it before its work: mesh, corners, design and
    // simulation options.
    try {
      RunFlags flags;
      flags.parse(row.run_arguments());
      field_context().mesh = row.mesh;
      auto& input = meshes_[row.mesh];
      if (mesh_errors_.count(row.mesh)) throw mesh_errors_.at(row.mesh);
      if (!input) {
        try {
          input = std::make_shared<InputMesh>(load_input(row.mesh));
        } catch (const Error& e) {
          mesh_errors_.emplace(row.mesh, e);
          throw;
        }
      }
      if (!flags.layout.layout.empty()) {
        layout_run_request(flags.layout, flags.design, flags.simulation, *input);
      } else {
        check_no_layout_flags(flags.layout);
        SimulationFlags simulation = flags.simulation;
        if (automatic_interior_anchors(flags.design)) simulation.interior_anchors = "auto";
        prepare_design(design_request(flags.design, *input));
        prepare_simulation_options(simulation_options_from_flags(simulation));
      }
    } catch (const CLI::ParseError& e) {
      problems.emplace_back("", e.what());
    } catch (const Error& e) {
      const std::string field = cli_field(e.field(), field_context());
      std::string column, detail;
      if (field.rfind("--", 0) == 0) {
        const size_t space = field.find(' ');
        column = field.substr(2, space == std::string::npos ? std::string::npos : space - 2);
        if (space != std::string::npos) detail = field.substr(space + 1);
      } else {
        column = "mesh";
        if (!field.empty() && field != row.mesh) detail = field;
      }
      problems.emplace_back(column, (detail.empty() ? "" : detail + ": ") + e.message());
    }
    return problems;
  }

 private:
  std::map<std::string, std::shared_ptr<InputMesh>> meshes_;  // each mesh loaded once
  std::map<std::string, Error> mesh_errors_;
};

}  // namespace

std::unique_ptr<sweep::RowChecker> run_row_checker() { return std::make_unique<RunRowChecker>(); }

}  // namespace gridshell::cli
