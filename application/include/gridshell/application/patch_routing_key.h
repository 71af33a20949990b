// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the patch routing key: what a client sends (header x-gridshell-patch-key) so that
// a proxy in front of several gridshelld replicas sends every design on one patch to the same
// replica, whose per-patch cache (patch_cache.h) then has the patch's work (docs/api.md,
// "Replicas and the patch key"; docs/deploy.md).
//
// The key is a function of the request's values only, so that any client computes it before its
// first call, with a standard hash every platform has (SHA-256: OpenSSL, WebCrypto, hashlib):
// the first 16 bytes of SHA-256 over this byte string, as 32 lowercase hex digits:
//
//   "gridshell-patch-key-v1\n"
//   u32 V, then V x 3 f64       the mesh as loaded (after the loader's repairs): positions
//   u32 F, then F x 3 u32       faces (vertex indices)
//   u8 corners                  0 automatic, 1 vertex indices, 2 points; then
//                               4 x u32 (vertices of the loaded mesh) or 12 x f64 (points)
//   u32 n, n bytes              geodesic engine ("fast" or "cgal")
//   f64                         eta_max
//   u32                         the smoothing iteration cap
//   u8                          smoothing on (1) or off (0)
//   u32                         distance map resolution (0 = adaptive)
//
// All numbers little-endian, f64 as IEEE 754 bits. These are exactly the request values the
// daemon's cache key (patch_key) depends on; the cache key also hashes internal constants that
// no request sets, so two requests with the same routing key share a cache entry.
#pragma once

#include <string>

#include "gridshell/design/design.h"
#include "gridshell/v1/requests.pb.h"

namespace gridshell {

/// The routing key of a design on `mesh` (as loaded) with these corners and options.
std::string patch_routing_key(const TriangleMesh& mesh, const CornerSpec& corners,
                              const DesignOptions& options);

/// The routing key of a design request (checked and converted like run_design does; throws
/// InvalidInput as prepare_design).
std::string patch_routing_key(const v1::DesignRequest& request);

}  // namespace gridshell
