// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the Fabricate request (`gridshell fabricate`, the daemon's Fabricate): design.json
// and options in, the kit (kit.json and every file of the kit folder) out. Shared by the CLI and
// the daemon, so both write the same bytes.
#pragma once

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/v1/fabrication.pb.h"

namespace gridshell {

/// The options with their defaults filled in and checked (InvalidInput naming
/// "options.<field>"); the unit is required.
v1::FabricationOptions prepare_fabrication_options(const v1::FabricationOptions& options);

/// Checks the design (InvalidInput naming "design.<field>": missing members or crossings, notch
/// lengths that are not s - s̄, arc lengths outside their lamella, zero width), builds the kit
/// and renders every file.
v1::FabricateResult run_fabricate(const v1::FabricateRequest& request,
                                  const Progress& progress = {}, const RunSettings& settings = {});

/// The kit folder: kit.json, assembly.svg, supports.csv, bom.csv and sheets/sheet-NN.{dxf,svg}
/// (names relative to the folder).
FileBundle fabricate_files(const v1::FabricateResult& result);

/// write_files for bundles whose names may hold one folder level ("sheets/sheet-01.dxf").
void write_kit_files(const FileBundle& files, const std::string& dir);

}  // namespace gridshell
