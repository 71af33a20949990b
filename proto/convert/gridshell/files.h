// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the output files of each command, made in one place from the result messages.
//
// `gridshell patch|design --out DIR` writes exactly these bytes, whether the result came from an
// in-process run or from gridshelld; that is what makes local and remote runs byte-identical.
#pragma once

#include <google/protobuf/message.h>

#include <map>
#include <string>

#include "gridshell/v1/requests.pb.h"

namespace gridshell {

/// Output files of one command: plain file name -> contents.
using FileBundle = std::map<std::string, std::string>;

/// patch.obj (the patch mesh) and patch.json (the report).
FileBundle patch_files(const v1::PatchResult& result);

/// design.json, report.json and the views planar.svg, spatial.obj, maps.svg.
FileBundle design_files(const v1::DesignResult& result);

/// deployment.json and the views deployed.obj, deviation.ply (+ *_without_notches.*).
FileBundle simulate_files(const v1::SimulateResult& result);

/// Everything `gridshell run` writes: the design's files and the simulation's.
FileBundle run_files(const v1::RunResult& result);

/// Creates `dir` if needed and writes every file atomically (temporary file + rename). Throws
/// InvalidInput naming the path on failure, or for a file name that is not a plain name.
void write_files(const FileBundle& files, const std::string& dir);

/// A message in protobuf's JSON mapping with the proto field names (snake_case) and all primitive
/// fields, pretty-printed or on one line: the format of every JSON file gridshell writes.
/// Written by reflection with shortest round-trip numbers (json_text.cpp; protobuf's printer was
/// 11 % of a 59k-vertex design).
std::string to_json(const google::protobuf::Message& message, bool pretty = true);

/// The same text from protobuf's own JSON printer (the tests' oracle).
std::string to_json_library(const google::protobuf::Message& message, bool pretty = true);

}  // namespace gridshell
