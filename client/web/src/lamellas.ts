// SPDX-License-Identifier: GPL-3.0-or-later
// Deployed lamellas as one merged triangle mesh in typed arrays (issue 36: a 100 x 100-member grid
// is 204 lamellas, 41k rod vertices, 350k mesh vertices). Each lamella is a box of the design's
// width and thickness along its centreline: the cross-section spanned by `normal × tangent` times
// the width and the material normal times the thickness, four side faces with outward normals
// and winding (so back faces can be culled) and a cap at each end, coloured per rod vertex by
// `value(rod, vertex)` in [0, max] on the sequential map. No DOM, no three.js: the viewer wraps
// the arrays in one BufferGeometry, and the unit tests count them.

import type { Lamella } from './api';
import { sequential } from './colormap';

export interface LamellaGroup {
  rods: Lamella[];
  width: number;
  thickness: number;
}

export interface LamellaMesh {
  positions: Float32Array<ArrayBuffer>;
  normals: Float32Array<ArrayBuffer>;
  colors: Float32Array<ArrayBuffer>;
  indices: Uint16Array<ArrayBuffer> | Uint32Array<ArrayBuffer>;
  /** Lamellas drawn (those with at least two centreline points). */
  lamellas: number;
  vertices: number;
  triangles: number;
  /**
   * The light version drawn while the camera moves (LIGHT_ABOVE): the two wide faces only, over
   * every `lightStep`-th centreline point (and the last), on the same vertices; null when the boxes
   * have at most LIGHT_ABOVE triangles.
   */
  light: Uint16Array<ArrayBuffer> | Uint32Array<ArrayBuffer> | null;
  lightStep: number;
}

/**
 * Above this many triangles the view draws the light version while the camera moves: with a
 * software renderer (SwiftShader) the frame time grows with the triangles; a 100 x 100 grid's
 * 330k take 0.3-0.6 s a frame on 2 cores; the light version has about LIGHT_TRIANGLES.
 */
export const LIGHT_ABOVE = 150000;
export const LIGHT_TRIANGLES = 20000;

/** Mesh vertices and triangles of one lamella with `points` centreline points (≥ 2). */
export function lamellaCounts(points: number): { vertices: number; triangles: number } {
  return { vertices: 8 * points + 8, triangles: 8 * (points - 1) + 4 };
}

// The cross-section's corners as (±b, ±h), counter-clockwise seen from the end (+t); face f joins
// corners f and f + 1, its outward normal is FACE_NORMAL[f] (±h, ±b).
const SIGNS: [number, number][] = [[1, 1], [-1, 1], [-1, -1], [1, -1]];
const FACE_NORMAL: [number, number][] = [[0, 1], [-1, 0], [0, -1], [1, 0]];

/**
 * The boxes of every group's rods, relative to `offset` (subtracted in double precision before
 * the Float32 arrays, as the rest of the view).
 */
export function lamellaMesh(groups: LamellaGroup[], offset: readonly [number, number, number], max: number,
                            value: (rod: Lamella, vertex: number) => number, lightAbove = LIGHT_ABOVE): LamellaMesh {
  let vertices = 0, triangles = 0, lamellas = 0, wide = 0;
  for (const { rods } of groups)
    for (const rod of rods) {
      if (rod.centerline.length < 2) continue;
      const c = lamellaCounts(rod.centerline.length);
      vertices += c.vertices;
      triangles += c.triangles;
      wide += 4 * (rod.centerline.length - 1);
      ++lamellas;
    }
  const lightStep = triangles > lightAbove ? Math.max(1, Math.ceil(wide / LIGHT_TRIANGLES)) : 0;
  const lightIndices: number[] = [];
  const positions = new Float32Array(3 * vertices);
  const normals = new Float32Array(3 * vertices);
  const colors = new Float32Array(3 * vertices);
  const indices = vertices > 65535 ? new Uint32Array(3 * triangles) : new Uint16Array(3 * triangles);
  let v = 0, k = 0; // next vertex, next index
  const put = (x: number, y: number, z: number, nx: number, ny: number, nz: number, rgb: readonly number[]): void => {
    const o = 3 * v++;
    positions[o] = x; positions[o + 1] = y; positions[o + 2] = z;
    normals[o] = nx; normals[o + 1] = ny; normals[o + 2] = nz;
    colors[o] = rgb[0]!; colors[o + 1] = rgb[1]!; colors[o + 2] = rgb[2]!;
  };
  const tri = (a: number, b: number, c: number): void => {
    indices[k++] = a; indices[k++] = b; indices[k++] = c;
  };
  for (const { rods, width, thickness } of groups)
    for (const rod of rods) {
      const line = rod.centerline;
      const m = line.length;
      if (m < 2) continue;
      // Per centreline point: the centre (local), the half-width and half-thickness vectors b and
      // h, the unit normals bu of the b faces and hu of the h faces, and the unit tangent t.
      const frame = new Float64Array(18 * m); // p, b, h, bu, hu, t
      for (let i = 0; i < m; ++i) {
        const p = line[i]!, prev = line[Math.max(0, i - 1)]!, next = line[Math.min(m - 1, i + 1)]!;
        let tx = next[0] - prev[0], ty = next[1] - prev[1], tz = next[2] - prev[2];
        const tl = Math.hypot(tx, ty, tz);
        tx /= tl; ty /= tl; tz /= tl;
        const nn = rod.normals[i];
        let nx = nn?.[0] ?? 0, ny = nn?.[1] ?? 0, nz = nn?.[2] ?? 1;
        const nl = Math.hypot(nx, ny, nz);
        nx /= nl; ny /= nl; nz /= nl;
        // bu = t × n normalised; hu = bu × t (n made orthogonal to t): the faces' normals.
        let bx = ty * nz - tz * ny, by = tz * nx - tx * nz, bz = tx * ny - ty * nx;
        const bl = Math.hypot(bx, by, bz);
        bx /= bl; by /= bl; bz /= bl;
        let hx = by * tz - bz * ty, hy = bz * tx - bx * tz, hz = bx * ty - by * tx;
        const hl = Math.hypot(hx, hy, hz);
        hx /= hl; hy /= hl; hz /= hl;
        const f = 18 * i;
        frame[f] = p[0] - offset[0]; frame[f + 1] = p[1] - offset[1]; frame[f + 2] = p[2] - offset[2];
        const bOk = Number.isFinite(bx) && Number.isFinite(by) && Number.isFinite(bz);
        const nOk = Number.isFinite(nx) && Number.isFinite(ny) && Number.isFinite(nz);
        const hOk = Number.isFinite(hx) && Number.isFinite(hy) && Number.isFinite(hz);
        const w = width / 2, d = thickness / 2;
        if (bOk) { frame[f + 3] = bx * w; frame[f + 4] = by * w; frame[f + 5] = bz * w; }
        if (nOk) { frame[f + 6] = nx * d; frame[f + 7] = ny * d; frame[f + 8] = nz * d; }
        if (bOk) { frame[f + 9] = bx; frame[f + 10] = by; frame[f + 11] = bz; }
        if (hOk) { frame[f + 12] = hx; frame[f + 13] = hy; frame[f + 14] = hz; }
        else if (nOk) { frame[f + 12] = nx; frame[f + 13] = ny; frame[f + 14] = nz; }
        if (Number.isFinite(tx)) { frame[f + 15] = tx; frame[f + 16] = ty; frame[f + 17] = tz; }
      }
      const rgb: number[][] = [];
      for (let i = 0; i < m; ++i) rgb.push(sequential(value(rod, i), max));
      const corner = (i: number, c: number): [number, number, number] => {
        const f = 18 * i, [sb, sh] = SIGNS[c]!;
        return [frame[f]! + sb * frame[f + 3]! + sh * frame[f + 6]!, frame[f + 1]! + sb * frame[f + 4]! + sh * frame[f + 7]!,
                frame[f + 2]! + sb * frame[f + 5]! + sh * frame[f + 8]!];
      };
      // The four side faces: two vertices per point (corners f and f + 1), a quad per segment.
      for (let face = 0; face < 4; ++face) {
        const base = v;
        if (lightStep && face % 2 === 0) // the wide faces (±h) over every lightStep-th point
          for (let i = 0; i + 1 < m;) {
            const j = Math.min(m - 1, i + lightStep), qi = base + 2 * i, qj = base + 2 * j;
            lightIndices.push(qi, qj, qi + 1, qi + 1, qj, qj + 1);
            i = j;
          }
        const [cb, ch] = FACE_NORMAL[face]!;
        for (let i = 0; i < m; ++i) {
          const f = 18 * i;
          const nx = cb * frame[f + 9]! + ch * frame[f + 12]!, ny = cb * frame[f + 10]! + ch * frame[f + 13]!,
                nz = cb * frame[f + 11]! + ch * frame[f + 14]!;
          const a = corner(i, face), b = corner(i, (face + 1) % 4);
          put(a[0], a[1], a[2], nx, ny, nz, rgb[i]!);
          put(b[0], b[1], b[2], nx, ny, nz, rgb[i]!);
          if (i + 1 < m) {
            const q = base + 2 * i;
            tri(q, q + 2, q + 1);
            tri(q + 1, q + 2, q + 3);
          }
        }
      }
      // The end caps: the cross-section at the first point facing -t, at the last facing +t.
      for (const [i, s] of [[0, -1], [m - 1, 1]] as const) {
        const base = v, f = 18 * i;
        for (let c = 0; c < 4; ++c) {
          const a = corner(i, c);
          put(a[0], a[1], a[2], s * frame[f + 15]!, s * frame[f + 16]!, s * frame[f + 17]!, rgb[i]!);
        }
        if (s < 0) {
          tri(base, base + 1, base + 2);
          tri(base, base + 2, base + 3);
        } else {
          tri(base, base + 2, base + 1);
          tri(base, base + 3, base + 2);
        }
      }
    }
  const light = !lightStep ? null : vertices > 65535 ? Uint32Array.from(lightIndices) : Uint16Array.from(lightIndices);
  return { positions, normals, colors, indices, lamellas, vertices, triangles, light, lightStep };
}
