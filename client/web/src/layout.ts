// SPDX-License-Identifier: GPL-3.0-or-later
// Multi-patch layouts on the page (issue 35, docs/multi-patch.md): the shapes of POST /v1/layout
// and /v1/runlayout, and the pure helpers of the layout panel: a layout file read back, the patch
// colours, the patch sides (seams and outer edges) from the cut patch meshes, the overall progress
// of a run, the tables' rows, the summaries and the files of the whole. No DOM; unit-tested by
// tests/web/unit.test.mjs.

import { zipSync } from 'fflate';
import {
  base64ToBytes, bytesToBase64, type DesignResult, type FileJson, type Lamella, type MeshJson, type Progress,
  type SimulateResult,
} from './api';
import { formatNumber, type Rgb } from './colormap';
import { stressAgainst } from './format';

// ---- message shapes (proto/gridshell/v1/layout.proto, the subset the page reads) ----------------

export interface LayoutCorner {
  vertex?: number;
  point?: number[];
}

/** A layout patch: its corners, and its own design choices over the run's options (radians or "min"/"max"). */
export interface LayoutPatch {
  name?: string;
  corners: number[];
  alpha?: string;
  members_u?: number;
  members_v?: number;
}

export interface Layout {
  corners: LayoutCorner[];
  patches: LayoutPatch[];
}

export interface LayoutPatchSummary {
  name: string;
  ok: boolean;
  problem_code?: string;
  problem_field?: string;
  problem?: string;
  vertices?: number;
  area?: number;
  corner_angles?: number[];
  side_lengths?: number[];
  eta?: number;
  alpha_range?: number[]; // [min, max] feasible planar angle (radians)
}

export interface LayoutSeam {
  corners: number[];
  patches: string[];
  length: number;
  mismatch: number;
}

export interface LayoutTrial {
  columns: number;
  rows: number;
  patches?: number;        // columns × rows; 6 × columns × rows on a closed surface
  coverage: number;
  cut_coverage?: number;   // of the patches cut alone: an upper bound of `coverage`
  checked?: boolean;       // checked in full (else only cut: its bound missed the goal)
  failing: number;
  first_problem?: string;
  seconds: number;
}

/** How an automatic layout was found: its grid, the surface ("disk", "ring", "closed") and cut. */
export interface AutomaticLayout {
  columns: number;
  rows: number;
  patches?: number;
  surface?: string;
  cut?: string;
  boundary_corners: number[];
  trials: LayoutTrial[];
  seconds: number;
}

/** A grid as the layout's surface has it: "3 × 2", "14 × 1 round the ring", "6 faces × 1 × 1". */
export function automaticGrid(surface: string | undefined, columns: number, rows: number): string {
  const grid = `${columns} × ${rows}`;
  if (surface === 'ring') return `${grid} round the ring`;
  if (surface === 'closed') return `6 faces × ${grid}`;
  return grid;
}

export interface LayoutReport {
  input: string;
  layout: Layout;
  input_area: number;
  covered_area: number;
  coverage: number;
  patches: LayoutPatchSummary[];
  seams: LayoutSeam[];
  uncovered?: { where: string; area: number; reason: string }[];
  automatic?: AutomaticLayout;
}

export type PatchMesh = MeshJson & { positions?: number[]; indices?: number[] };

export interface LayoutResult {
  report: LayoutReport;
  patches: PatchMesh[]; // per patch, in layout order; no arrays for one that could not be cut
  views: FileJson[];    // layout.svg
}

/** A patch's RunResult: {} for a patch that failed. */
export interface PatchRun {
  design?: DesignResult;
  simulation?: SimulateResult;
}

export interface LayoutDesign {
  input: string;
  layout: LayoutReport;
  patch_designs: string[];
  seams: { corners: number[]; patches: string[]; lamellas: string[]; length: number; length_difference: number;
           joints: { s: number; point: number[]; members: string[]; lamella_s: number[] }[] }[];
  seam_bolts: number;
}

export interface LayoutPatchDeployment {
  name: string;
  deployment?: string;
  rms_without_notches?: number;
  rms_with_notches?: number;
  converged?: boolean;
  grid_vertices?: number;
  max_normal_stress?: number;
  bending_utilization?: number;
}

export interface LayoutDeployment {
  options?: { material?: string; unit?: string; bending_strength?: number };
  rms_without_notches?: number;
  rms_with_notches?: number;
  converged?: boolean;
  grid_vertices?: number;
  diagonal?: number;
  patches: LayoutPatchDeployment[];
  seams_joined?: boolean;
  seams: { corners: number[]; patches: string[]; gaps: number[]; max_gap: number; rms_gap: number;
           gaps_before_joining?: number[]; max_gap_before_joining?: number; forces?: number[]; max_force?: number }[];
  max_seam_gap?: number;
  /** The patches deployed alone, each to its own patch (main mode). */
  rms_before_joining?: number;
  max_seam_gap_before_joining?: number;
  max_bolt_force?: number;
  force_unit?: string;
  joined_with_notches?: JoinedRun;
  joined_without_notches?: JoinedRun;
  /** The joined whole's lamellas (main run), every patch's in layout order, and each one's patch. */
  rods?: Lamella[];
  rod_patches?: string[];
  max_normal_stress?: number;
  bending_utilization?: number;
  seconds?: number;
}

/** The whole in one equilibrium, its seams bolted (deployment.json of a layout run). */
export interface JoinedRun {
  notches?: boolean;
  rms?: number;
  converged?: boolean;
  iterations?: number;
  termination?: string;
  anchors?: number;
  seconds?: number;
}

export interface LayoutRunResult {
  layout: LayoutResult;
  patches: PatchRun[];
  design: LayoutDesign;
  deployment: LayoutDeployment;
  views: FileJson[]; // deployed.obj, deviation.ply of the whole
}

// ---- requests ---------------------------------------------------------------------------------

/** How the layout is chosen: computed (the automatic options, {} = defaults) or given. */
export type LayoutMode = { automatic: Record<string, unknown> } | { layout: Layout };

/**
 * A layout file read back: a `Layout` ({corners, patches}), or a file that holds one as its
 * `layout` (layout.json, a LayoutReport; design.json of a layout run, a LayoutDesign, whose
 * `layout` is a LayoutReport). Throws an Error saying what is wrong.
 */
export function layoutFromJson(text: string): Layout {
  let value: unknown;
  try {
    value = JSON.parse(text);
  } catch (e) {
    throw new Error(`not JSON (${e instanceof Error ? e.message : String(e)})`);
  }
  for (let depth = 0; depth < 3 && value && typeof value === 'object'; ++depth) {
    const o = value as Record<string, unknown>;
    if (Array.isArray(o['corners']) && Array.isArray(o['patches'])) return o as unknown as Layout;
    value = o['layout'];
  }
  throw new Error('no layout in it: expected {"corners": [...], "patches": [...]}, or a layout.json / design.json that holds one');
}

// ---- drawing ----------------------------------------------------------------------------------

function hsl(h: number, s: number, l: number): Rgb {
  const f = (n: number): number => {
    const k = (n + h * 12) % 12;
    return l - s * Math.min(l, 1 - l) * Math.max(-1, Math.min(k - 3, 9 - k, 1));
  };
  return [f(0), f(8), f(4)];
}

/** The colour of patch `i`: hues a golden angle apart (neighbours in layout order differ), light enough for black seams. */
export function patchColour(i: number): Rgb {
  const h = (i * 0.381966011250105 + 0.58) % 1;
  return hsl(h, 0.55, i % 2 ? 0.72 : 0.62);
}

/** CSS colour of an Rgb in [0, 1]. */
export function cssColour(c: Rgb): string {
  return `rgb(${c.map((x) => Math.round(255 * Math.min(1, Math.max(0, x)))).join(',')})`;
}

/** The boundary edges of a triangle mesh (used by one triangle), as vertex pairs. */
export function boundaryEdges(indices: ArrayLike<number>): [number, number][] {
  const count = new Map<string, [number, number, number]>();
  for (let t = 0; t + 2 < indices.length; t += 3)
    for (let k = 0; k < 3; ++k) {
      const a = indices[t + k]!, b = indices[t + (k + 1) % 3]!;
      const key = a < b ? `${a},${b}` : `${b},${a}`;
      const e = count.get(key);
      if (e) ++e[2];
      else count.set(key, [a, b, 1]);
    }
  const out: [number, number][] = [];
  for (const [a, b, n] of count.values()) if (n === 1) out.push([a, b]);
  return out;
}

/**
 * The patches' sides as line segments (flat xyz, two points each): `seams`, the boundary edges two
 * patches share (both patches are cut along one geodesic, so they have the same points there),
 * and `outer`, the rest.
 */
export function sideSegments(patches: { positions?: number[]; indices?: number[] }[]): { seams: number[]; outer: number[] } {
  const point = (p: number[], v: number): string => `${p[3 * v]},${p[3 * v + 1]},${p[3 * v + 2]}`;
  const edges: { key: string; xyz: number[] }[] = [];
  const patchesOf = new Map<string, number>();
  for (const patch of patches) {
    const p = patch.positions ?? [], seen = new Set<string>();
    for (const [a, b] of boundaryEdges(patch.indices ?? [])) {
      const pa = point(p, a), pb = point(p, b);
      const key = pa < pb ? `${pa};${pb}` : `${pb};${pa}`;
      edges.push({ key, xyz: [p[3 * a]!, p[3 * a + 1]!, p[3 * a + 2]!, p[3 * b]!, p[3 * b + 1]!, p[3 * b + 2]!] });
      if (!seen.has(key)) patchesOf.set(key, (patchesOf.get(key) ?? 0) + 1);
      seen.add(key);
    }
  }
  const seams: number[] = [], outer: number[] = [], drawn = new Set<string>();
  for (const e of edges) {
    if (drawn.has(e.key)) continue; // a seam once
    drawn.add(e.key);
    ((patchesOf.get(e.key) ?? 0) > 1 ? seams : outer).push(...e.xyz);
  }
  return { seams, outer };
}

/** The largest finite deviation over the rods drawn (the one colour scale's top). */
export function maxDeviationOf(groups: { rods: Lamella[] }[]): number {
  let m = 0;
  for (const group of groups)
    for (const rod of group.rods)
      for (const d of rod.deviation) if (Number.isFinite(d)) m = Math.max(m, d);
  return m;
}

/**
 * What the view draws of a run, each built patch's deployed rods with the lamella's
 * cross-section: the whole joined in one equilibrium when its seams were (the deployment's
 * `rods`, grouped by `rod_patches`), else each patch as it deployed alone.
 */
export function deployedPatches(run: { patches: PatchRun[]; deployment?: LayoutDeployment }):
    { name?: string; rods: Lamella[]; width: number; thickness: number }[] {
  const built = run.patches.filter((r) => r.design && r.simulation);
  const d = run.deployment;
  if (d?.seams_joined && d.rods?.length && d.rod_patches?.length === d.rods.length && built.length > 0) {
    // One cross-section per layout: every patch's design has it.
    const { lamella_width: width, lamella_thickness: thickness } = built[0].design!.design.options;
    const groups = new Map<string, Lamella[]>();
    d.rods.forEach((rod, i) => {
      const name = d.rod_patches![i];
      if (!groups.has(name)) groups.set(name, []);
      groups.get(name)!.push(rod);
    });
    return [...groups].map(([name, rods]) => ({ name, rods, width, thickness }));
  }
  return built.map((r) => ({
    rods: r.simulation!.deployment.rods,
    width: r.design!.design.options.lamella_width,
    thickness: r.design!.design.options.lamella_thickness,
  }));
}

// ---- progress ---------------------------------------------------------------------------------

/**
 * The overall fraction of a run's progress events: finding and cutting the layout is the first
 * tenth ("layout: 3 x 2", "layout"), the patches the rest ("layout: patches designed and
 * simulated" counts the patches done; the per-patch stages, "P3: simulate with notches", keep it).
 */
export function runProgress(): (p: Progress) => number {
  let done = 0;
  return (p) => {
    const f = Math.max(0, Math.min(1, Number.isFinite(p.fraction) ? p.fraction : 0));
    if (p.stage.startsWith('layout: patches')) {
      done = Math.max(done, f);
      return 0.1 + 0.9 * done;
    }
    if (done === 0 && (p.stage === 'layout' || p.stage.startsWith('layout:'))) return 0.1 * f;
    return 0.1 + 0.9 * done;
  };
}

// ---- text -------------------------------------------------------------------------------------

/** A fraction as a percentage: "95.4 %". */
export function percent(fraction: number, digits = 1): string {
  return `${(100 * fraction).toFixed(digits)} %`;
}

/** A length and its share of the diagonal: "0.0337 (0.066 % of the diagonal)". */
export function ofDiagonal(length: number | undefined, diagonal: number | undefined): string {
  if (length === undefined || !Number.isFinite(length)) return '—';
  return diagonal && diagonal > 0 ? `${formatNumber(length)} (${percent(length / diagonal, 3)} of the diagonal)` : formatNumber(length);
}

export function layoutSummary(r: LayoutReport): string {
  const ok = r.patches.filter((p) => p.ok).length;
  const seams = r.seams.filter((s) => s.patches.length > 1);
  const mismatch = Math.max(0, ...seams.map((s) => s.mismatch));
  const lines = [
    `coverage ${percent(r.coverage)}: ${formatNumber(r.covered_area)} of ${formatNumber(r.input_area)}`,
    `${r.patches.length} patches (${ok} ok${ok < r.patches.length ? `, ${r.patches.length - ok} failing` : ''}), ` +
      `${seams.length} seams (largest mismatch ${formatNumber(mismatch)}), ${r.layout.corners.length} corners`,
  ];
  const a = r.automatic;
  if (a) {
    lines.push(`automatic: ${automaticGrid(a.surface, a.columns, a.rows)} grid, ${a.trials.length} trials in ${a.seconds.toFixed(2)} s`);
    if (a.cut) lines.push(`surface: ${a.cut}`);
  }
  return lines.join('\n');
}

/** A patch's planar angle (radians) at slider position `t` in [0, 1] of its feasible range; null without one. */
export function patchAlpha(range: number[] | undefined, t: number): number | null {
  if (!range || range.length !== 2 || !(range[1]! >= range[0]!)) return null;
  const f = Math.max(0, Math.min(1, t));
  return range[0]! + f * (range[1]! - range[0]!);
}

/** The slider position (0..1) of a patch's own ᾱ choice in its range: "min" 0, "max" 1, radians between. */
export function patchSliderPosition(range: number[] | undefined, alpha: string | undefined): number {
  if (!range || range.length !== 2 || alpha === undefined || alpha === 'min') return 0;
  if (alpha === 'max') return 1;
  const value = Number(alpha);
  const span = range[1]! - range[0]!;
  return Number.isFinite(value) && span > 0 ? Math.max(0, Math.min(1, (value - range[0]!) / span)) : 0;
}

/** After one patch's redesign: "P2: ᾱ 52.6°, 5 × 4 inner members, 36 crossings — 31 ms, patch work cached". */
export function patchDesignLine(name: string, r: DesignResult, ms: number): string {
  const d = r.design;
  const inner = (family: string): number => d.members.filter((m) => m.family === family && !m.boundary).length;
  return `${name}: ᾱ ${(d.alpha_bar * 180 / Math.PI).toFixed(2)}°, ${inner('g')} × ${inner('h')} inner members, ` +
    `${d.crossings.length} crossings — ${Math.round(ms)} ms${r.report.distance_maps_cached ? ', patch work cached' : ''}`;
}

/** The patches' table: name, ok or its problem, area, eta. */
export function patchRows(r: LayoutReport): string[][] {
  return r.patches.map((p) => [
    p.name,
    p.ok ? 'ok' : `${p.problem_field ? `${p.problem_field}: ` : ''}${p.problem || p.problem_code || 'failed'}`,
    p.area !== undefined && p.area > 0 ? formatNumber(p.area) : '—',
    p.eta !== undefined && p.eta > 0 ? p.eta.toFixed(5) : '—',
  ]);
}

/** What no checked patch covers: "outside the patches: 16.6 (4.62 %) — why". */
export function uncoveredLines(r: LayoutReport): string[] {
  return (r.uncovered ?? []).map((u) =>
    `${u.where}: ${formatNumber(u.area)} (${percent(r.input_area > 0 ? u.area / r.input_area : 0, 2)}) — ${u.reason}`);
}

/** The automatic trials' table: grid, patches, coverage (the bound of one only cut: "≤ 80 %"),
 * failing (first problem), seconds. */
export function trialRows(r: LayoutReport): string[][] {
  const surface = r.automatic?.surface;
  return (r.automatic?.trials ?? []).map((t) => [
    automaticGrid(surface, t.columns, t.rows), String(t.patches ?? t.columns * t.rows),
    t.checked === false ? `≤ ${percent(t.cut_coverage ?? 0)}` : percent(t.coverage),
    t.failing ? `${t.failing}${t.first_problem ? `: ${t.first_problem}` : ''}` : '0', t.seconds.toFixed(3),
  ]);
}

/** The per-patch table of a run: name, grid vertices, RMS with and without notches, converged. */
export function runRows(d: LayoutDeployment): string[][] {
  const rms = (v: number | undefined): string => (v === undefined ? '—' : formatNumber(v));
  return d.patches.map((p) => [p.name, String(p.grid_vertices ?? 0), rms(p.rms_with_notches), rms(p.rms_without_notches),
                               p.converged ? 'yes' : 'NO']);
}

export function runSummary(run: LayoutRunResult): string {
  const d = run.deployment, diagonal = d.diagonal;
  const built = run.patches.filter((p) => p.design && p.simulation).length;
  const lines = [`${built} of ${run.patches.length} patches built; ${d.grid_vertices ?? 0} grid vertices`];
  if (d.rms_with_notches !== undefined) lines.push(`whole RMS with notches ${ofDiagonal(d.rms_with_notches, diagonal)}`);
  if (d.rms_without_notches !== undefined) lines.push(`whole RMS without notches ${ofDiagonal(d.rms_without_notches, diagonal)}`);
  if (d.rms_before_joining !== undefined)
    lines.push(`patches alone RMS ${ofDiagonal(d.rms_before_joining, diagonal)}, each deployed on its own`);
  lines.push(`seam bolts ${run.design.seam_bolts} on ${run.design.seams.length} seams`);
  const joined = [d.joined_with_notches, d.joined_without_notches].filter((j): j is JoinedRun => j !== undefined);
  if (d.seams_joined) {
    lines.push(`largest seam gap ${ofDiagonal(d.max_seam_gap ?? 0, diagonal)} after joining, ` +
               `${ofDiagonal(d.max_seam_gap_before_joining ?? 0, diagonal)} before`);
    lines.push(`largest bolt force ${formatNumber(d.max_bolt_force ?? 0)} ${d.force_unit ?? ''}`.trimEnd());
  } else {
    const why = joined.map((j) => j.termination).filter((t) => t).join('; ');
    lines.push(`largest seam gap ${ofDiagonal(d.max_seam_gap ?? 0, diagonal)}` +
               ` — before joining: the seams are not joined${why ? ` (${why})` : ''}, each patch deployed on its own`);
  }
  for (const j of joined)
    if (j.iterations)
      lines.push(`whole joined ${j.notches ? 'with' : 'without'} notches: ${j.iterations} iterations, ` +
                 `${j.anchors ?? 0} anchors${j.converged ? '' : `, NOT converged: ${j.termination ?? ''}`}`);
  if (d.max_normal_stress !== undefined)
    lines.push(`max normal stress ${stressAgainst(d.max_normal_stress, d.options?.bending_strength ?? 0, d.bending_utilization)}`);
  lines.push(d.converged ? `every run of every patch${d.seams_joined ? ' and of the whole' : ''} converged`
                         : 'NOT converged: a run of a patch or of the whole did not converge');
  if (d.seconds !== undefined) lines.push(`built in ${d.seconds.toFixed(2)} s`);
  return lines.join('\n');
}

/** The patches whose runs did not converge ("P3, P7"). */
export function notConverged(d: LayoutDeployment): string[] {
  return d.patches.filter((p) => !p.converged).map((p) => p.name);
}

// ---- files ------------------------------------------------------------------------------------

function jsonFile(name: string, value: unknown): FileJson {
  return { name, content: bytesToBase64(new TextEncoder().encode(`${JSON.stringify(value, null, 2)}\n`)) };
}

/** The files of a layout: layout.json (the LayoutReport, which `--layout FILE` takes back) and the daemon's layout.svg. */
export function layoutFiles(result: LayoutResult): FileJson[] {
  return [jsonFile('layout.json', result.report), ...result.views];
}

/** The files of the whole run: layout.json, design.json, deployment.json, layout.svg, then deployed.obj and deviation.ply. */
export function runFiles(run: LayoutRunResult): FileJson[] {
  return [jsonFile('layout.json', run.layout.report), jsonFile('design.json', run.design),
          jsonFile('deployment.json', run.deployment), ...run.layout.views, ...run.views];
}

/**
 * run.zip: the whole's files under `run/`, and each built patch's in `run/patches/NAME/` (its
 * design.json and deployment.json, then the daemon's views) as `gridshell run --layout` lays them out.
 */
export function runZip(run: LayoutRunResult): Uint8Array<ArrayBuffer> {
  const entries: Record<string, Uint8Array> = {};
  for (const f of runFiles(run)) entries[`run/${f.name}`] = base64ToBytes(f.content);
  run.patches.forEach((p, i) => {
    const name = run.layout.report.patches[i]?.name ?? `P${i + 1}`;
    const files = [
      ...(p.design ? [jsonFile('design.json', p.design.design), ...p.design.views] : []),
      ...(p.simulation ? [jsonFile('deployment.json', p.simulation.deployment), ...p.simulation.views] : []),
    ];
    for (const f of files) entries[`run/patches/${name.replace(/[^A-Za-z0-9_.-]+/g, '_')}/${f.name}`] = base64ToBytes(f.content);
  });
  return zipSync(entries, { level: 6, mtime: new Date(2026, 0, 1) }) as Uint8Array<ArrayBuffer>;
}

/** The Fabricate request of the whole: the run's design.json and each designed patch's design, in layout order. */
export function layoutFabricateRequest(run: LayoutRunResult, unit: string): unknown {
  return {
    layout: run.design, patches: run.patches.filter((p) => p.design).map((p) => p.design!.design),
    options: { unit }, design_name: 'design.json',
  };
}
