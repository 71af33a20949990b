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
#include "gridshell/foundation/errors.h"

namespace gridshell::cli {
namespace {

struct LayoutArguments {
  std::string mesh;
  std::string layout;
  DescribedFlags options;  // the patch options of every patch (no --corner-angles)
  std::string out;
  bool quiet = false;
  int threads = 0;
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
    throw InvalidInput("--layout", (e.field().empty() ? "" : e.field() + ": ") + e.message() +
                                       " (a gridshell.v1.Layout in JSON)");
  }
  // Corner vertices are file-order indices, as --corners takes them: into the mesh as loaded.
  for (int i = 0; i < layout.corners_size(); ++i) {
    v1::Layout::Corner& c = *layout.mutable_corners(i);
    if (c.has_vertex())
      c.set_vertex(mesh_vertex(input, c.vertex(), "layout.corners[" + std::to_string(i) + "]"));
  }
  return layout;
}

void write_layout_as_given(v1::LayoutReport& report, const InputMesh& input) {
  v1::Layout& written = *report.mutable_layout();
  for (int i = 0; i < written.corners_size(); ++i)
    if (written.corners(i).has_vertex())
      written.mutable_corners(i)->set_vertex(file_vertex(input, written.corners(i).vertex()));
}

const v1::LayoutReport::PatchSummary* print_layout_report(const v1::LayoutReport& r) {
  const double deg = 180 / std::numbers::pi;
  std::printf("  coverage        %.1f %% of the input's area (%.4g of %.4g), %d patches\n",
              100 * r.coverage(), r.covered_area(), r.input_area(), r.patches_size());
  const v1::LayoutReport::PatchSummary* failed = nullptr;
  for (const auto& p : r.patches()) {
    if (p.ok())
      std::printf("  %-6s ok       area %.4g, eta %.5f, corners %.0f %.0f %.0f %.0f deg\n",
                  p.name().c_str(), p.area(), p.eta(), p.corner_angles(0) * deg,
                  p.corner_angles(1) * deg, p.corner_angles(2) * deg, p.corner_angles(3) * deg);
    else
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
  return failed;
}

namespace {

int run_layout_command(const LayoutArguments& args) {
  const InputMesh input = load_input(args.mesh);
  v1::LayoutRequest request;
  *request.mutable_layout() = read_layout_file(args.layout, input);
  *request.mutable_mesh() = request_mesh(input);
  set_described(args.options, *request.mutable_options());
  prepare_output_folder(args.out);
  const Progress progress = make_progress(args.quiet);
  v1::LayoutResult result = run_layout(request, progress, {args.threads});
  finish_progress();
  write_layout_as_given(*result.mutable_report(), input);  // file-order vertices, names filled
  write_files(layout_files(result), args.out);
  std::printf("layout %s (%s) -> %s\n", args.mesh.c_str(), args.layout.c_str(), args.out.c_str());
  const v1::LayoutReport::PatchSummary* failed = print_layout_report(result.report());
  const std::filesystem::path out(args.out);
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
  sub->add_option("--layout", args->layout,
                  "layout file: gridshell.v1.Layout in JSON (corners by file-order vertex index "
                  "or point; patches of four corners, all in the same turning sense)")
      ->required();
  add_described_flags(sub, "patch", args->options, {"auto_corner_angles", "no_smoothing"});
  sub->add_option("--out", args->out, "output folder")->required();
  sub->add_option("--threads", args->threads, "worker threads (0 = all cores)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  sub->add_flag("--quiet", args->quiet, "no progress line");
  return [args] { return run_layout_command(*args); };
}

}  // namespace gridshell::cli
