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
#include "gridshell/v1/layout.pb.h"

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

/// The same for a layout run's whole: its joined lamellas (deployment.json's `rods`) and the
/// union of its patches' target patches (`designs`: each built patch's design.json; their
/// cross-section is the layout's one). InvalidInput naming "deployment.rods" when the seams were
/// not joined (no whole to compare with: a patch's folder is).
CompareJob run_compare_layout_job(const std::vector<Vec3>& scan,
                                  const std::vector<v1::Design>& designs,
                                  const v1::LayoutDeployment& deployment,
                                  const CompareOptions& options = {},
                                  const Progress& progress = {});

}  // namespace gridshell
