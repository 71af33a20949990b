// SPDX-License-Identifier: GPL-3.0-or-later
// Pure helpers of the page (no DOM): angles, the slider's feasible range, the summary text, the
// URL state, where an error belongs. Unit-tested by tests/web/unit.test.mjs.

import type { Deployment, DesignResult, PatchReport } from './api';
import { formatNumber } from './colormap';

export const DEG = 180 / Math.PI;

/** The slider's [min, max] in degrees for a feasible range in radians, rounded inward to `step`. */
export function sliderRange(rangeRad: number[], step = 0.1): [number, number] | null {
  if (rangeRad.length !== 2 || !rangeRad.every(Number.isFinite)) return null;
  const k = 1 / step;
  const lo = Math.ceil(rangeRad[0]! * DEG * k - 1e-9) / k;
  const hi = Math.floor(rangeRad[1]! * DEG * k + 1e-9) / k;
  return lo <= hi ? [lo, hi] : null;
}

/** DesignRequest.options.alpha for a slider value in degrees ("70.5deg"). */
export function alphaOption(deg: number): string {
  return `${Number(deg.toFixed(4))}deg`;
}

export function degrees(rad: number): string {
  return `${(rad * DEG).toFixed(1)}°`;
}

export function patchSummary(r: PatchReport): string {
  const lines = [
    `η = ${r.eta_after.toFixed(5)} (before smoothing ${r.eta_before.toFixed(5)}, limit ${r.eta_max})`,
    `corner angles: ${r.corner_angles.map(degrees).join(', ')}`,
    `sides: ${r.boundary_lengths.map(formatNumber).join(', ')}; area ${formatNumber(r.area)}`,
    `patch: ${r.vertex_count} vertices, ${r.face_count} faces; ${r.smoothing_iterations} smoothing iterations`,
    `injectivity: ${r.injectivity_ok ? 'ok' : 'NOT ok (members may cross)'}`,
  ];
  return lines.join('\n');
}

export function designSummary(d: DesignResult): string {
  const g = d.design, r = d.report;
  const range = g.alpha_bar_range.length === 2
    ? ` (feasible ${degrees(g.alpha_bar_range[0]!)}–${degrees(g.alpha_bar_range[1]!)})` : '';
  return [
    `ᾱ = ${degrees(g.alpha_bar)}${range}`,
    `α = ${degrees(g.alpha)} (spatial angle at corner 1)`,
    `members: ${r.members_g} g × ${r.members_h} h inner, ${r.crossings} crossings, ${g.anchors.length} anchors`,
    `lamella: ${formatNumber(g.options.lamella_width)} × ${formatNumber(g.options.lamella_thickness)}`,
    `max notch ${formatNumber(r.max_notch)}; max length mismatch ${(100 * r.max_length_mismatch).toFixed(2)}%`,
    `design ${r.seconds.toFixed(3)} s; distance maps cached: ${r.distance_maps_cached ? 'yes' : 'no'}`,
  ].join('\n');
}

/** A stress in MPa: kappa t is scale-free, so stresses need no length unit (docs/decisions.md). */
export function stress(pa: number): string {
  return `${formatNumber(pa / 1e6)} MPa`;
}

/** "41.2 MPa = 69% of 60 MPa" (or "... (strength unknown)"); EXCEEDED above the strength. */
export function stressAgainst(pa: number, strength: number, utilization: number | undefined): string {
  if (utilization === undefined || !(strength > 0)) return `${stress(pa)} (strength unknown)`;
  const percent = `${Math.round(100 * utilization)}%`;
  return `${stress(pa)} = ${percent} of ${stress(strength)}${utilization > 1 ? ' EXCEEDED' : ''}`;
}

export function deploymentSummary(dep: Deployment): string {
  const lines: string[] = [];
  const run = (name: string, rms: number | undefined, s: number | undefined, r: Deployment['with_notches']) => {
    if (rms === undefined || !r) return;
    lines.push(`${name}: RMS ${formatNumber(rms)}, max deviation ${formatNumber(r.max_deviation)}, ` +
               `${r.iterations} iterations, ${r.converged ? 'converged' : 'NOT converged'}, ${(s ?? r.seconds).toFixed(2)} s`);
    const over = r.overstressed_lamellas > 0 ? `; ${r.overstressed_lamellas} lamellas overstressed` : '';
    lines.push(`  max normal stress ${stressAgainst(r.max_normal_stress, dep.options.bending_strength, r.bending_utilization)}, ` +
               `max torsion stress ${stressAgainst(r.max_torsion_stress, dep.options.shear_strength, r.shear_utilization)}${over}`);
  };
  run('with notches', dep.rms_with_notches, dep.seconds_with_notches, dep.with_notches);
  run('without notches', dep.rms_without_notches, dep.seconds_without_notches, dep.without_notches);
  lines.push(`material ${dep.options.material}: E = ${formatNumber(dep.options.young_modulus / 1e9)} GPa` +
             (dep.options.bending_strength > 0 ? `, bending strength ${stress(dep.options.bending_strength)}` : '') +
             (dep.options.shear_strength > 0 ? `, shear strength ${stress(dep.options.shear_strength)}` : '') +
             (dep.options.unit ? `; unit ${dep.options.unit}` : ''));
  const trials = dep.anchor_trial_rms ?? [];
  if (trials.length) {
    const added = dep.added_anchors?.length ?? 0;
    lines.push(`inner anchors: ${added ? `${added} added automatically` : 'none added'} ` +
               `(RMS of the trials ${trials.map(formatNumber).join(' → ')}; kept while it fell by 5% or more` +
               `${dep.anchor_goal_rms ? `, until RMS ≤ ${formatNumber(dep.anchor_goal_rms)}` : ''})`);
  }
  lines.push(`grid vertices ${dep.grid_vertices}; ${dep.converged ? 'every run converged' : 'a run did NOT converge'}`);
  return lines.join('\n');
}

/** Largest deviation over the rods (the colour map's top). */
export function maxDeviation(dep: Deployment): number {
  let m = 0;
  for (const rod of dep.rods) for (const d of rod.deviation) if (Number.isFinite(d)) m = Math.max(m, d);
  return m;
}

/**
 * Which control an error concerns: the daemon's field path (`mesh.indices[3]`,
 * `corners.vertices[2]`, `options.lamella_width`, `options.auto_corner_angles[1]`,
 * `design.members[4]`) mapped to the page's `data-for` slots, given the call it came from. An
 * option's error goes next to its own control (`design.NAME`, `simulation.NAME`) when
 * `hasSlot` says the page has one, else under its section.
 */
export function errorSlot(call: 'load' | 'patch' | 'design' | 'simulate' | 'fabricate' | 'layout' | 'build' | 'layout kit' | 'patch design',
                          field: string, hasSlot: (slot: string) => boolean = () => false): string {
  if (call === 'fabricate') return 'fabricate';
  // One patch of a layout redesigned: its options next to theirs, the rest under the patch's controls.
  if (call === 'patch design') return field.startsWith('options.') ? layoutErrorSlot(field, hasSlot) : 'layout_patch';
  if (call === 'layout kit') return 'layout'; // the whole's Fabricate: under the layout section
  if (call === 'layout' || call === 'build') return layoutErrorSlot(field, hasSlot);
  const name = /^options\.([A-Za-z0-9_]+)/.exec(field)?.[1];
  if (call === 'simulate') {
    if (field.startsWith('design')) return 'options';
    return name && hasSlot(`simulation.${name}`) ? `simulation.${name}` : 'simulation';
  }
  if (field.startsWith('mesh')) return 'mesh';
  if (field.startsWith('corners')) return 'corners';
  if (name && hasSlot(`design.${name}`)) return `design.${name}`; // a patch sends design options too
  if (field.startsWith('options')) return call === 'patch' ? 'corners' : 'options';
  return call === 'load' ? 'mesh' : call === 'patch' ? 'corners' : 'options';
}

/**
 * Where an error of a layout call (/v1/layout, /v1/runlayout) goes:
 * `automatic.max_patches` next to that layout control, `design.options.members_u` (or
 * `design.members_u`) and `simulation.material` next to theirs, `mesh.*` under the file input,
 * the rest (`layout.patches[1].corners[2]`, `patches[k].…`) under the layout section.
 */
function layoutErrorSlot(field: string, hasSlot: (slot: string) => boolean): string {
  if (field.startsWith('mesh')) return 'mesh';
  const m = /^(automatic|design(?:\.options)?|simulation|options)\.([A-Za-z0-9_]+)/.exec(field);
  if (m) {
    const group = m[1] === 'automatic' ? 'layout' : m[1]!.startsWith('design') || m[1] === 'options' ? 'design' : 'simulation';
    if (hasSlot(`${group}.${m[2]}`)) return `${group}.${m[2]}`;
  }
  return 'layout';
}

/** The page's state in the URL hash: example, corners, options (`design.NAME`, `simulation.NAME`). */
export interface UrlState {
  example?: string;
  file?: { name: string; hash: string }; // an uploaded mesh: its name and SHA-256 (hex, 16 digits)
  corners?: number[];
  auto?: boolean;
  suggested?: boolean; // the example's suggested corners
  alpha?: number;
  design?: boolean;
  options: Record<string, string>; // control key -> its text, for the controls not at their default
}

const STATE_KEYS = new Set(['example', 'file', 'sha256', 'corners', 'auto', 'suggested', 'alpha', 'design']);

/** Option keys of URLs written before the form was built from the daemon's description. */
const LEGACY_KEYS: Record<string, string> = {
  mu: 'design.members_u', mv: 'design.members_v', w: 'design.lamella_width', t: 'design.lamella_thickness',
  ia: 'design.interior_anchors', unit: 'simulation.unit', mat: 'simulation.material', aa: 'simulation.interior_anchors',
};

export function encodeState(s: UrlState): string {
  const p = new URLSearchParams();
  if (s.example) p.set('example', s.example);
  if (s.file) {
    p.set('file', s.file.name);
    p.set('sha256', s.file.hash);
  }
  if (s.corners && s.corners.length) p.set('corners', s.corners.join(','));
  if (s.auto) p.set('auto', '1');
  if (s.suggested) p.set('suggested', '1');
  if (s.alpha !== undefined) p.set('alpha', String(s.alpha));
  if (s.design) p.set('design', '1');
  for (const [k, v] of Object.entries(s.options)) if (v !== '' && !STATE_KEYS.has(k)) p.set(k, v);
  return p.toString();
}

export function decodeState(hash: string): UrlState {
  const p = new URLSearchParams(hash.replace(/^#/, ''));
  const s: UrlState = { options: {} };
  const example = p.get('example');
  if (example) s.example = example;
  const file = p.get('file'), digest = p.get('sha256');
  if (file && digest && /^[0-9a-f]{16}$/.test(digest)) s.file = { name: file, hash: digest };
  const corners = (p.get('corners') ?? '').split(',').filter((x) => x !== '').map(Number);
  if (corners.length && corners.length <= 4 && corners.every((x) => Number.isInteger(x) && x >= 0)) s.corners = corners;
  if (p.get('auto') === '1') s.auto = true;
  if (p.get('suggested') === '1') s.suggested = true;
  const alpha = Number(p.get('alpha'));
  if (p.has('alpha') && Number.isFinite(alpha)) s.alpha = alpha;
  if (p.get('design') === '1') s.design = true;
  for (const [k, v] of p) {
    if (STATE_KEYS.has(k)) continue;
    const legacy = LEGACY_KEYS[k];
    if (legacy) s.options[legacy] = k === 'aa' ? (v === '1' ? 'auto' : '') : v;
    else if (/^[a-z]+\.[A-Za-z0-9_]+$/.test(k)) s.options[k] = v;
  }
  return s;
}
