// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell layout MESH --layout FILE --out DIR`: a surface in several patches that share
// corners and seams (issue 35, docs/multi-patch.md). Cuts every patch of the layout along seams
// computed once, checks each as a single patch, and writes DIR/layout.json (the report: coverage,
// per patch its checks or why it fails, per seam its length and mismatch) and DIR/layout.obj (the
// cut patches, one object each). Exit 3 when a patch fails, after writing both.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/files.h"
#include "gridshell/application/layout.h"
#include "gridshell/application/options.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::cli {
namespace {

struct LayoutArguments {
  std::string mesh;
  std::string layout;
  DescribedFlags options;    // the patch options of every patch (no --corner-angles)
  DescribedFlags automatic;  // --layout auto's options
  OutputFlags output;
};

}  // namespace

v1::Layout read_layout_file(const std::string& file, const InputMesh& input) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InvalidInput("--layout", "cannot open '" + file + "'");
  std::ostringstream text;
  text << in.rdbuf();
  v1::Layout layout;
  try {
    from_json(text.str(), layout);
  } catch (const Error& e) {
    // The layout.json of a run (a LayoutReport) holds the layout it used: it is taken too.
    v1::LayoutReport report;
    try {
      from_json(text.str(), report);
    } catch (const Error&) {
      throw InvalidInput("--layout", (e.field().empty() ? "" : e.field() + ": ") + e.message() +
                                         " (a gridshell.v1.Layout in JSON)");
    }
    layout = report.layout();
  }
  // Corner vertices are file-order indices, as --corners takes them: into the mesh as loaded.
  for (int i = 0; i < layout.corners_size(); ++i) {
    v1::Layout::Corner& c = *layout.mutable_corners(i);
    if (c.has_vertex())
      c.set_vertex(mesh_vertex(input, c.vertex(), "layout.corners[" + std::to_string(i) + "]"));
  }
  return layout;
}

LayoutChoice layout_choice(const std::string& layout, const DescribedFlags& automatic,
                           const InputMesh& input) {
  LayoutChoice out;
  if (layout == "auto") {
    set_described(automatic, out.automatic.emplace());
    return out;
  }
  check_no_layout_flags({"", automatic});
  out.layout = read_layout_file(layout, input);
  return out;
}

void write_layout_as_given(v1::LayoutReport& report, const InputMesh& input) {
  v1::Layout& written = *report.mutable_layout();
  for (int i = 0; i < written.corners_size(); ++i)
    if (written.corners(i).has_vertex())
      written.mutable_corners(i)->set_vertex(file_vertex(input, written.corners(i).vertex()));
}

void print_automatic_layout(const v1::LayoutReport& report) {
  if (!report.has_automatic()) return;
  const v1::LayoutReport::Automatic& a = report.automatic();
  // A closed surface's grid is per face of its cube: 6 x columns x rows patches.
  const char* per = a.surface() == "closed" ? "6 x " : "";
  std::string tried;
  for (const auto& t : a.trials()) {
    char buffer[96];
    if (t.checked())
      std::snprintf(buffer, sizeof buffer, "%s%s%d x %d %.1f %%", tried.empty() ? "" : ", ", per,
                    t.columns(), t.rows(), 100 * t.coverage());
    else  // cut only: its bound missed the goal
      std::snprintf(buffer, sizeof buffer, "%s%s%d x %d <= %.1f %%", tried.empty() ? "" : ", ", per,
                    t.columns(), t.rows(), 100 * t.cut_coverage());
    tried += buffer;
  }
  std::printf("  automatic       %s%d x %d patches in %.2f s; tried %s\n", per, a.columns(),
              a.rows(), a.seconds(), tried.c_str());
  if (!a.cut().empty()) std::printf("  surface         %s\n", a.cut().c_str());
}

const v1::LayoutReport::PatchSummary* print_layout_report(const v1::LayoutReport& r) {
  const double deg = 180 / std::numbers::pi;
  std::printf("  coverage        %.1f %% of the input's area (%.4g of %.4g), %d patches\n",
              100 * r.coverage(), r.covered_area(), r.input_area(), r.patches_size());
  const v1::LayoutReport::PatchSummary* failed = nullptr;
  for (const auto& p : r.patches()) {
    if (p.ok()) {
      // The feasible planar angles, from which a layout patch's own "alpha" may choose.
      char range[64] = "";
      if (p.alpha_range_size() == 2)
        std::snprintf(range, sizeof range, ", alpha %.1f..%.1f deg", p.alpha_range(0) * deg,
                      p.alpha_range(1) * deg);
      std::printf("  %-6s ok       area %.4g, eta %.5f, corners %.0f %.0f %.0f %.0f deg%s\n",
                  p.name().c_str(), p.area(), p.eta(), p.corner_angles(0) * deg,
                  p.corner_angles(1) * deg, p.corner_angles(2) * deg, p.corner_angles(3) * deg,
                  range);
    } else
      std::printf("  %-6s FAILS    %s: %s\n", p.name().c_str(), p.problem_field().c_str(),
                  p.problem().c_str());
    if (!p.ok() && !failed) failed = &p;
  }
  int seams = 0;
  double mismatch = 0;
  for (const auto& s : r.seams())
    if (s.patches_size() == 2) {
      ++seams;
      mismatch = std::max(mismatch, s.mismatch());
    }
  std::printf("  seams           %d shared (largest mismatch %.1e), %d outer edges\n", seams,
              mismatch, r.seams_size() - seams);
  for (const auto& u : r.uncovered())
    std::printf("  uncovered       %.4g (%.1f %%) %s: %s\n", u.area(),
                r.input_area() > 0 ? 100 * u.area() / r.input_area() : 0.0, u.where().c_str(),
                u.reason().c_str());
  return failed;
}

namespace {

int run_layout_command(const LayoutArguments& args) {
  const InputMesh input = load_input(args.mesh);
  v1::LayoutRequest request;
  LayoutChoice choice = layout_choice(args.layout, args.automatic, input);
  *request.mutable_layout() = std::move(choice.layout);
  if (choice.automatic) *request.mutable_automatic() = *choice.automatic;
  *request.mutable_mesh() = request_mesh(input);
  set_described(args.options, *request.mutable_options());
  prepare_output_folder(args.output.out);
  const Progress progress = make_progress(args.output.quiet);
  v1::LayoutResult result = args.output.remote.remote()
                                ? RemoteClient(args.output.remote).layout(request, progress)
                                : run_layout(request, progress, {args.output.threads});
  finish_progress();
  write_layout_as_given(*result.mutable_report(), input);  // file-order vertices, names filled
  write_files(layout_files(result), args.output.out);
  std::printf("layout %s (%s) -> %s\n", args.mesh.c_str(), args.layout.c_str(),
              args.output.out.c_str());
  print_automatic_layout(result.report());
  const v1::LayoutReport::PatchSummary* failed = print_layout_report(result.report());
  const std::filesystem::path out(args.output.out);
  std::printf("  wrote           %s, %s, %s\n", (out / "layout.json").c_str(),
              (out / "layout.obj").c_str(), (out / "layout.svg").c_str());
  if (failed)
    throw Infeasible(failed->problem_field(), failed->problem() + " (patch " + failed->name() +
                                                  "; every patch's checks: layout.json)");
  return 0;
}

}  // namespace

Command add_layout_command(CLI::App& app) {
  auto args = std::make_shared<LayoutArguments>();
  CLI::App* sub = app.add_subcommand(
      "layout",
      "Cut a surface into several patches that share corners and seams (layout.json), check "
      "each, report the coverage");
  sub->add_option("MESH", args->mesh, "input mesh (.obj .off .ply .stl) or example:NAME")
      ->required();
  sub->add_option("--layout", args->layout, kLayoutHelp)->required();
  add_described_flags(sub, "layout", args->automatic);
  add_described_flags(sub, "patch", args->options, {"auto_corner_angles", "no_smoothing"});
  add_output_flags(sub, args->output);
  return [args] { return run_layout_command(*args); };
}

}  // namespace gridshell::cli
