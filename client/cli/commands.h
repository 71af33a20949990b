// Subcommands of the gridshell CLI; each registers itself on the CLI11 app and returns the
// function that runs it (exit code).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace gridshell::cli {

using Command = std::function<int()>;

Command add_patch_command(CLI::App& app);
Command add_geodesic_command(CLI::App& app);
Command add_design_command(CLI::App& app);
Command add_examples_command(CLI::App& app);
Command add_bench_command(CLI::App& app);
Command add_health_command(CLI::App& app);

/// `gridshell bench service` (bench_service.cpp): `repeats` scales the requests per client
/// count; `write_section` replaces a marked section of the benchmarks file.
using SectionWriter = void (*)(const std::string& path, const std::string& name,
                               const std::string& body);
int bench_service(const std::string& out, bool no_write, int repeats, SectionWriter write_section);

}  // namespace gridshell::cli
