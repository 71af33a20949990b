// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — `gridshell compare`: a scan of the built grid against a design folder
// (design.json + deployment.json), into compare.json and compare.ply.
#pragma once

#include <string>
#include <vector>

#include "gridshell/fabrication/compare.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/v1/deployment.pb.h"
#include "gridshell/v1/design.pb.h"
#include "gridshell/v1/fabrication.pb.h"

namespace gridshell {

/// The deployed lamellas of deployment.json (the run with notches, else the one without).
/// InvalidInput naming "deployment.<field>".
std::vector<SimulatedLamella> lamellas_from_proto(const v1::Deployment& deployment);

struct CompareJob {
  v1::CompareReport report;  ///< compare.json (without `seconds`, which the caller measures)
  std::string ply;           ///< compare.ply
};

/// Registers `scan` to the deployment and measures it against the deployment and the design's
/// target patch.
CompareJob run_compare_job(const std::vector<Vec3>& scan, const v1::Design& design,
                           const v1::Deployment& deployment, const CompareOptions& options = {},
                           const Progress& progress = {});

}  // namespace gridshell
