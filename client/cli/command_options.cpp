// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell options [--json] [--group G]`: the one description of every request option and of
// the material presets (gridshell.v1.OptionsResult, the daemon's Options RPC), as a table or as
// JSON for scripts and clients that do not talk to a daemon.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "commands.h"
#include "gridshell/application/files.h"
#include "gridshell/application/options.h"
#include "gridshell/application/requests.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::cli {
namespace {
struct OptionsArguments {
  bool json = false;
  std::string group;
};
}  // namespace

Command add_options_command(CLI::App& app) {
  auto args = std::make_shared<OptionsArguments>();
  CLI::App* sub = app.add_subcommand(
      "options", "Describe every request option (type, default, range, unit) and the materials");
  sub->add_flag("--json", args->json, "print gridshell.v1.OptionsResult as JSON");
  sub->add_option("--group", args->group,
                  "only this group: patch | design | simulation | layout | fabrication");
  return [args]() -> int {
    v1::OptionsResult all = run_options({}, {}, {});
    if (!args->group.empty()) {
      v1::OptionsResult picked = all;
      picked.clear_options();
      for (const v1::OptionDescription& d : all.options())
        if (d.group() == args->group) *picked.add_options() = d;
      if (picked.options_size() == 0)
        throw InvalidInput(
            "--group",
            "expected patch, design, simulation, layout or fabrication, got '" + args->group + "'");
      all = std::move(picked);
    }
    if (args->json) {
      std::fputs(to_json(all).c_str(), stdout);
      return 0;
    }
    std::string group;
    for (const v1::OptionDescription& d : all.options()) {
      if (d.output()) continue;
      if (d.group() != group) {
        group = d.group();
        std::printf("%s%s options\n", &d == &all.options(0) ? "" : "\n", group.c_str());
      }
      std::string range;
      for (const OptionSpec& spec : option_specs())
        if (spec.group == d.group() && spec.name == d.name()) range = allowed_text(spec);
      std::printf("  %-28s %-28s %-8s default %-10s %s%s\n", d.name().c_str(),
                  d.flag().empty() ? "(request only)" : d.flag().c_str(), d.type().c_str(),
                  d.default_value().empty() ? "-" : d.default_value().c_str(), range.c_str(),
                  d.advanced() ? " [advanced]" : "");
    }
    std::printf("\nmaterials (E, G, f_m, f_v in GPa / MPa)\n");
    for (const v1::MaterialPreset& m : all.materials())
      std::printf("  %-16s E %6.1f  G %5.2f  f_m %5.0f  f_v %5.1f  %s%s\n", m.name().c_str(),
                  m.young_modulus() / 1e9, m.shear_modulus() / 1e9, m.bending_strength() / 1e6,
                  m.shear_strength() / 1e6, m.source().c_str(), m.site() ? " [site]" : "");
    return 0;
  };
}

}  // namespace gridshell::cli
