// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the output files of each command, made in one place from the result messages.
//
// `gridshell patch|design --out DIR` writes exactly these bytes, whether the result came from an
// in-process run or from gridshelld; that is what makes local and remote runs byte-identical.
#pragma once

#include <google/protobuf/message.h>

#include <cstddef>
#include <map>
#include <string>
#include <string_view>

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

/// The deepest nesting of JSON objects and arrays from_json accepts (documented in docs/api.md).
inline constexpr int kJsonMaxDepth = 32;

/// What from_json does with a member that names no field.
enum class UnknownFields {
  Refuse,  ///< an error naming it (the API's and the CLI's input files)
  Skip,    ///< ignored with its value, and so are unknown enum value names (files written by a
           ///< newer gridshell; protobuf's ignore_unknown_fields)
};

/// Reads `text` in protobuf's JSON mapping into `message` (cleared first), strictly: only what
/// the mapping allows for each field's type (protobuf.dev/programming-guides/proto3/#json) in
/// strict JSON (RFC 8259, UTF-8) — true/false for a bool, integral numbers in range or decimal
/// strings for integers, numbers or "NaN"/"Infinity"/"-Infinity" for floating point, base64 for
/// bytes, an enum value's name or number, an array for a repeated field (no nested arrays, no
/// null elements), an object for a message or map; each field once (by its proto or its JSON
/// name), one member of a oneof; null as a field's default; objects and arrays nested at most
/// `max_depth` deep. The text is checked in one pass first (json_read.cpp), then protobuf's
/// parser fills the message. Throws InvalidInput(field path, reason): the path in proto field
/// names with indices ("design.options.files", "mesh.positions[12]", "stage_seconds["grid"]"),
/// the reason what was expected and what came; "" for text that is not JSON at all.
/// `max_string_bytes` > 0: a string field (not bytes, not inside google.protobuf values) longer
/// than that is refused in the checking pass ("mesh.name: too long: N bytes, at most M"), before
/// protobuf copies it (the daemon passes its text limit: a 31 MiB name peaked at +212 MiB).
void from_json(std::string_view text, google::protobuf::Message& message,
               int max_depth = kJsonMaxDepth, UnknownFields unknown = UnknownFields::Refuse,
               std::size_t max_string_bytes = 0);

}  // namespace gridshell
