// SPDX-License-Identifier: GPL-3.0-or-later
// The patch routing key (docs/api.md, "Replicas and the patch key"): the first 16 bytes of
// SHA-256 over the mesh as loaded, the corners and the options a design's patch work depends on,
// as 32 hex digits. Sent as X-Gridshell-Patch-Key with every design, so that haproxy in front of
// several daemons sends the designs of one patch to the replica that has its work cached. The
// byte layout is application/include/gridshell/application/patch_routing_key.h's; every design result carries the
// daemon's own computation (report.patch_key), which the tests compare with this one.

export interface KeyMesh {
  positions: ArrayLike<number>;
  indices: ArrayLike<number>;
}
export interface KeyCorners {
  vertices?: number[];
  points?: number[];
}
/**
 * The values the design's patch work uses: the request's, else the daemon's defaults, which the
 * page takes from the daemon's description of the options (/v1/options) rather than a copy here.
 */
export interface KeyOptions {
  geodesic_method: string;
  eta_max: number;
  max_smoothing_iterations: number; // a design request cannot set it: the patch group's default
  resolution: number;               // 0 = adaptive
}

/** The byte string the key hashes (little-endian; f64 as IEEE 754 bits). */
export function patchKeyBytes(mesh: KeyMesh, corners: KeyCorners | undefined, options: KeyOptions): Uint8Array<ArrayBuffer> {
  const magic = new TextEncoder().encode('gridshell-patch-key-v1\n');
  const method = new TextEncoder().encode(options.geodesic_method);
  const vertices = corners?.vertices ?? [];
  const points = corners?.points ?? [];
  const cornerBytes = vertices.length === 4 ? 16 : points.length === 12 ? 96 : 0;
  const size = magic.length + 4 + 8 * mesh.positions.length + 4 + 4 * mesh.indices.length + 1 + cornerBytes +
    4 + method.length + 8 + 4 + 1 + 4;
  const bytes = new Uint8Array(size);
  const view = new DataView(bytes.buffer);
  let at = 0;
  bytes.set(magic, at);
  at += magic.length;
  view.setUint32(at, mesh.positions.length / 3, true);
  at += 4;
  for (let i = 0; i < mesh.positions.length; ++i, at += 8) view.setFloat64(at, mesh.positions[i]!, true);
  view.setUint32(at, mesh.indices.length / 3, true);
  at += 4;
  for (let i = 0; i < mesh.indices.length; ++i, at += 4) view.setUint32(at, mesh.indices[i]!, true);
  if (vertices.length === 4) {
    bytes[at++] = 1;
    for (const v of vertices) { view.setUint32(at, v, true); at += 4; }
  } else if (points.length === 12) {
    bytes[at++] = 2;
    for (const p of points) { view.setFloat64(at, p, true); at += 8; }
  } else {
    bytes[at++] = 0;
  }
  view.setUint32(at, method.length, true);
  at += 4;
  bytes.set(method, at);
  at += method.length;
  view.setFloat64(at, options.eta_max, true);
  at += 8;
  view.setUint32(at, options.max_smoothing_iterations, true);
  at += 4;
  bytes[at++] = 1; // smoothing on (a design request cannot turn it off)
  view.setUint32(at, options.resolution, true);
  return bytes;
}

/**
 * The key, or null where the browser has no WebCrypto (a page served over plain HTTP from a host
 * other than localhost): the calls then go without it, and haproxy spreads them round-robin.
 */
export async function patchKey(mesh: KeyMesh, corners: KeyCorners | undefined, options: KeyOptions): Promise<string | null> {
  const subtle = globalThis.crypto?.subtle;
  if (!subtle) return null;
  const digest = new Uint8Array(await subtle.digest('SHA-256', patchKeyBytes(mesh, corners, options)));
  return Array.from(digest.subarray(0, 16), (b) => b.toString(16).padStart(2, '0')).join('');
}
