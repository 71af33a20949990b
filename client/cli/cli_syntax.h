// SPDX-License-Identifier: GPL-3.0-or-later
// The text syntaxes of the CLI's own flags (not CLI11's): --corners. A library of its own
// (gridshell_cli_syntax) that needs only the kernel, so that its fuzz target and the sanitized
// tree (scripts/build-sanitized.sh) do not build the whole CLI.
#pragma once

#include <string>
#include <vector>

#include "gridshell/design/patch.h"

namespace gridshell::cli {

/// Parses --corners: "i,j,k,l" (vertex indices), "x,y,z;x,y,z;x,y,z;x,y,z" (points) or "auto".
/// Throws InvalidInput (field "--corners").
CornerSpec parse_corners(const std::string& text);

/// `text` without leading and trailing spaces and tabs.
std::string trim(const std::string& text);

/// `text` split at every `separator` (empty parts kept).
std::vector<std::string> split(const std::string& text, char separator);

}  // namespace gridshell::cli
