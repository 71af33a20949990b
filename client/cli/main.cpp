// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — command-line front end. Runs the kernel in-process, or on gridshelld (--server).
//
// Exit codes (docs/decisions.md): 0 success, 1 internal error, 2 invalid input, 3 infeasible
// design, 130 cancelled (Ctrl-C). Errors are one line on stderr starting with "error:".
#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <map>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/options.h"
#include "gridshell/foundation/errors.h"
#include "remote.h"

int main(int argc, char** argv) {
  using namespace gridshell;
  CLI::App app{"gridshell: design and simulate elastic geodesic gridshells"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "gridshell 0.1.0");
  // A site's materials (GRIDSHELL_MATERIALS) before the flags that list them.
  try {
    load_site_materials();
  } catch (const Error& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  std::map<CLI::App*, cli::Command> commands;
  auto add = [&](cli::Command (*adder)(CLI::App&)) {
    const size_t before = app.get_subcommands({}).size();
    cli::Command command = adder(app);
    commands[app.get_subcommands({})[before]] = std::move(command);
  };
  add(cli::add_patch_command);
  add(cli::add_design_command);
  add(cli::add_geodesic_command);
  add(cli::add_examples_command);
  add(cli::add_bench_command);
  add(cli::add_simulate_command);
  add(cli::add_run_command);
  add(cli::add_health_command);
  add(cli::add_sweep_command);
  add(cli::add_fabricate_command);
  add(cli::add_compare_command);
  add(cli::add_options_command);
  add(cli::add_layout_command);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "error: " << e.what() << "\n(run 'gridshell --help' for usage)\n";
    return 2;
  }
  std::signal(SIGINT, cli::on_interrupt);
  std::signal(SIGTERM, cli::on_interrupt);
  try {
    for (CLI::App* sub : app.get_subcommands())
      if (commands.count(sub)) return commands[sub]();
    std::cerr << "error: no command given\n";
    return 2;
  } catch (const Cancelled&) {
    cli::finish_progress();
    cli::remove_unused_output_folder();
    std::cerr << "error: cancelled\n";
    return 130;
  } catch (const Error& e) {
    return cli::report_error(e);  // the field in the CLI's terms (cli_errors.cpp)
  } catch (const cli::RemoteError& e) {
    cli::finish_progress();
    cli::remove_unused_output_folder();
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    cli::finish_progress();
    std::cerr << "error: internal: " << e.what() << "\n";
    return 1;
  }
}
