// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell fabricate DIR/design.json --unit cm --out KIT`: the fabrication kit of a design
// (nested DXF/SVG cut sheets, kit.json, assembly.svg, supports.csv, bom.csv), in process or on a
// daemon (--server). docs/fabrication.md explains the files.
#include <CLI/CLI.hpp>
#include <charconv>
#include <cstdio>
#include <filesystem>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/fabricate.h"
#include "gridshell/application/options.h"
#include "gridshell/foundation/errors.h"
#include "remote.h"

namespace gridshell::cli {
namespace {

struct FabricateArguments {
  std::string design;
  OutputFlags output;
  std::string unit;
  std::string sheet;       // WIDTHxHEIGHT mm; "" = the default sheet
  DescribedFlags options;  // every described fabrication option with a flag but --unit
};

/// "1200x600" -> {1200, 600} (mm).
std::pair<double, double> parse_sheet(const std::string& text) {
  const size_t x = text.find_first_of("xX");
  double w = 0, h = 0;
  const auto number = [](std::string_view part, double& out) {
    const auto [ptr, ec] = std::from_chars(part.data(), part.data() + part.size(), out);
    return ec == std::errc() && ptr == part.data() + part.size();
  };
  if (x == std::string::npos || !number(std::string_view(text).substr(0, x), w) ||
      !number(std::string_view(text).substr(x + 1), h) || !(w > 0) || !(h > 0))
    throw InvalidInput("--sheet", "expected WIDTHxHEIGHT in mm (1200x600), got '" + text + "'");
  return {w, h};
}

int run_fabricate(const FabricateArguments& args) {
  v1::FabricateRequest request;
  // A layout run's design.json: one kit for all its patches (docs/multi-patch.md).
  if (std::optional<LayoutDesignFiles> layout = read_layout_design_file(args.design)) {
    *request.mutable_layout() = std::move(layout->layout);
    for (v1::Design& design : layout->patches) *request.add_patches() = std::move(design);
  } else {
    *request.mutable_design() = read_design_file(args.design);
  }
  request.set_design_name(std::filesystem::path(args.design).filename().string());
  v1::FabricationOptions& o = *request.mutable_options();
  o.set_unit(args.unit);
  if (!args.sheet.empty()) {
    const auto [w, h] = parse_sheet(args.sheet);
    o.set_sheet_width(w);
    o.set_sheet_height(h);
  }
  set_described(args.options, o);
  prepare_fabrication_options(o);  // checked here, before anything runs or is sent
  prepare_output_folder(args.output.out);
  const Progress progress = make_progress(args.output.quiet);
  field_context().design = args.design;
  v1::FabricateResult result;
  if (args.output.remote.remote())
    result = RemoteClient(args.output.remote).fabricate(request, progress);
  else
    result = gridshell::run_fabricate(request, progress);
  finish_progress();
  write_kit_files(fabricate_files(result), args.output.out);
  print_heading("fabricate", args.design, args.output);
  const v1::Kit& kit = result.kit();
  std::printf("  lamellas        %d (%d crossings: %d holes, %d slots), %.1f x %.2f mm\n",
              kit.parts_size(), kit.crossings(), kit.holes(), kit.slots(), kit.lamella_width(),
              kit.thickness());
  std::printf(
      "  sheets          %d of %.0f x %.0f mm, %d rows; utilisation %.1f %% (one lamella "
      "per row: %d sheets, %.1f %%)\n",
      kit.sheets_size(), kit.options().sheet_width(), kit.options().sheet_height(), kit.rows(),
      100 * kit.utilisation(), kit.baseline_sheets(), 100 * kit.baseline_utilisation());
  if (request.has_layout()) {
    std::printf("  patches         %d, parts named by patch (P2-g7); seam bolts in bom.csv\n",
                request.patches_size());
    std::printf(
        "  wrote           kit.json assembly-<patch>.svg joining.svg supports.csv bom.csv "
        "sheets/ (%d x .dxf .svg)\n",
        kit.sheets_size());
    return 0;
  }
  std::printf("  on top          %s lamellas (as drawn in assembly.svg)\n",
              kit.top_family().c_str());
  std::printf(
      "  wrote           kit.json assembly.svg supports.csv bom.csv sheets/ (%d x .dxf "
      ".svg)\n",
      kit.sheets_size());
  return 0;
}

}  // namespace

Command add_fabricate_command(CLI::App& app) {
  auto args = std::make_shared<FabricateArguments>();
  CLI::App* sub = app.add_subcommand(
      "fabricate", "Fabrication kit of a design: nested DXF/SVG cut sheets, assembly, supports");
  sub->add_option("DESIGN", args->design,
                  "design.json written by 'gridshell design' or 'gridshell run' (of a layout: one "
                  "kit for all its patches)")
      ->required();
  sub->add_option("--unit", args->unit, described_help("fabrication", "unit"));
  sub->add_option("--sheet", args->sheet,
                  "sheet size WIDTHxHEIGHT in mm; default " +
                      option_spec("fabrication", "sheet_width").default_value + "x" +
                      option_spec("fabrication", "sheet_height").default_value);
  add_described_flags(sub, "fabrication", args->options, {"unit"});
  add_output_flags(sub, args->output, false);
  return [args] { return run_fabricate(*args); };
}

}  // namespace gridshell::cli
