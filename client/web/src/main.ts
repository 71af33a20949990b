// SPDX-License-Identifier: GPL-3.0-or-later
// The gridshell page: mesh in (example or file) -> four corners -> patch -> design (live ᾱ
// slider and counts) -> simulate, with progress, Cancel, errors next to their controls and
// downloads of the daemon's files. One call in flight at a time: a new one aborts the previous
// (the daemon cancels a job whose HTTP client went away). The design and simulation controls,
// the materials and the mesh formats come from the daemon's description of the options
// (/v1/options, form.ts). The layout section covers the surface with several patches instead
// (/v1/layout, /v1/runlayout; layout.ts).

import './style.css';
import {
  ApiError, base64ToBytes, bytesToBase64, call, isCancelled, setToken,
  type DesignResult, type ExampleInfo, type FileJson, type LoadResult, type MeshJson, type PatchResult,
  type Design, type OptionsResult, type Progress, type SimulateResult,
} from './api';
import { diverging, drawBar, formatNumber, sequential, symmetricRange } from './colormap';
import {
  alphaOption, decodeState, deploymentSummary, designSummary, encodeState, errorSlot, maxDeviation,
  patchSummary, sliderRange, stress, type UrlState,
} from './format';
import { OptionsForm, optionKey, tooltip } from './form';
import { fabricateRequest, kitSummary, kitZip, type FabricateResult } from './kit';
import {
  cssColour, deployedPatches, layoutFabricateRequest, layoutFiles, layoutFromJson, layoutSummary, maxDeviationOf,
  notConverged, patchAlpha, patchColour, patchDesignLine, patchRows, patchSliderPosition, runFiles, runProgress, runRows,
  runSummary, runZip, sideSegments, trialRows, uncoveredLines, type Layout, type LayoutMode, type LayoutResult,
  type LayoutRunResult,
} from './layout';
import type { Rgb } from './colormap';
import { appendSuggestions } from './suggestions';
import { Viewer, type Pick } from './viewer';
import { Zoomable } from './zoom';
import { patchKey, type KeyCorners, type KeyOptions } from './routing';

// The example list and the options' description are asked for first, so the daemon answers
// while the WebGL context is created (half a second on a software GL).
let examplesRequest: Promise<{ examples: ExampleInfo[] }> | null = call('examples', {});
let optionsRequest: Promise<OptionsResult> | null = call('options', {});

function el<T extends HTMLElement = HTMLElement>(id: string): T {
  const e = document.getElementById(id);
  if (!e) throw new Error(`missing #${id}`);
  return e as T;
}

const ui = {
  example: el<HTMLSelectElement>('example-select'),
  file: el<HTMLInputElement>('mesh-input'),
  drop: el('drop'),
  main: el('main'),
  meshInfo: el('mesh-info'),
  auto: el<HTMLButtonElement>('corners-auto'),
  suggested: el<HTMLButtonElement>('corners-example'),
  clear: el<HTMLButtonElement>('corners-clear'),
  cornersInfo: el('corners-info'),
  patchInfo: el('patch-info'),
  legend: el('legend'),
  legendTitle: el('legend-title'),
  legendBar: el<HTMLCanvasElement>('legend-bar'),
  legendMin: el('legend-min'),
  legendMid: el('legend-mid'),
  legendMax: el('legend-max'),
  meshFormats: el('mesh-formats'),
  alphaOption: el('alpha-option'),
  alpha: el<HTMLInputElement>('alpha-slider'),
  alphaValue: el<HTMLOutputElement>('alpha-value'),
  alphaMin: el('alpha-min'),
  alphaMax: el('alpha-max'),
  designOptions: el('design-options'),
  designAdvanced: el('design-advanced'),
  simulationOptions: el('simulation-options'),
  simulationAdvanced: el('simulation-advanced'),
  design: el<HTMLButtonElement>('design'),
  simulate: el<HTMLButtonElement>('simulate'),
  kit: el<HTMLButtonElement>('kit'),
  progress: el<HTMLProgressElement>('progress'),
  cancel: el<HTMLButtonElement>('cancel'),
  status: el('status'),
  error: el('error'),
  warnings: el('warnings'),
  summary: el('summary'),
  downloads: el('downloads'),
  tokenBox: el('token-box'),
  token: el<HTMLInputElement>('token'),
  devLegend: el('deviation-legend'),
  devBar: el<HTMLCanvasElement>('deviation-bar'),
  devMax: el('deviation-max'),
  devTitle: el('deviation-title'),
  colourBy: el<HTMLSelectElement>('colour-by'),
  layoutOptions: el('layout-options'),
  layoutAdvanced: el('layout-advanced'),
  layoutAuto: el<HTMLButtonElement>('layout-auto'),
  layoutFile: el<HTMLInputElement>('layout-input'),
  layoutInfo: el('layout-info'),
  layoutPatches: el<HTMLTableElement>('layout-patches'),
  layoutUncovered: el('layout-uncovered'),
  layoutTrialsBox: el<HTMLDetailsElement>('layout-trials-box'),
  layoutTrials: el<HTMLTableElement>('layout-trials'),
  layoutBuild: el<HTMLButtonElement>('layout-build'),
  layoutKit: el<HTMLButtonElement>('layout-kit'),
  layoutNonConverged: el('layout-nonconverged'),
  layoutSummary: el('layout-summary'),
  layoutRun: el<HTMLTableElement>('layout-run'),
  layoutDownloads: el('layout-downloads'),
  layoutCornerBox: el('layout-corner-box'),
  layoutCorner: el<HTMLSelectElement>('layout-corner'),
  layoutPatchBox: el('layout-patch-box'),
  layoutPatch: el<HTMLSelectElement>('layout-patch'),
  layoutPatchAlpha: el<HTMLInputElement>('layout-patch-alpha'),
  layoutPatchAlphaValue: el('layout-patch-alpha-value'),
  layoutPatchU: el<HTMLInputElement>('layout-patch-u'),
  layoutPatchV: el<HTMLInputElement>('layout-patch-v'),
  layoutPatchInfo: el('layout-patch-info'),
};

const viewer = new Viewer(el<HTMLCanvasElement>('viewer'));
const plan = new Zoomable(el('plan'), el<HTMLImageElement>('plan-img'));
const maps = new Zoomable(el('maps'), el<HTMLImageElement>('maps-img'));

// ---- state ------------------------------------------------------------------------------------

interface State {
  source: { kind: 'example' | 'file'; name: string; hash?: string } | null;
  mesh: MeshJson | null;         // what every request sends as `mesh`
  loaded: LoadResult | null;
  corners: number[];             // vertex indices into the loaded mesh
  cornersLabel: '' | 'auto' | 'example'; // from "Auto", "Suggested" (the example's), or clicked
  selected: number | null;       // marker picked for a move
  patch: PatchResult | null;
  design: DesignResult | null;
  designWanted: boolean;         // redesign on every change once the user asked for a design
  simulation: SimulateResult | null;
  alphaDeg: number | null;       // null = the daemon's default ("min")
  layout: LayoutResult | null;   // a multi-patch layout shown instead of the single patch
  layoutRun: LayoutRunResult | null; // its patches built
}

const state: State = {
  source: null, mesh: null, loaded: null, corners: [], cornersLabel: '', selected: null,
  patch: null, design: null, designWanted: false, simulation: null, alphaDeg: null, layout: null, layoutRun: null,
};

// ---- calls: one at a time, cancellable ----------------------------------------------------------

type CallKind = 'load' | 'patch' | 'design' | 'simulate' | 'fabricate' | 'layout' | 'build' | 'layout kit' | 'patch design';
const LAYOUT_CALLS: ReadonlySet<CallKind> = new Set<CallKind>(['layout', 'build', 'layout kit']);
let current: { kind: CallKind; controller: AbortController; byUser: boolean } | null = null;

function setBusy(busy: boolean): void {
  ui.cancel.disabled = !busy;
  if (!busy) ui.progress.value = 0;
}

/**
 * Runs one call with progress; aborts the call in flight. Resolves with the result, or null
 * when it was superseded or cancelled (the status line says which) or failed (the error is shown).
 * `overall` maps a progress event to the bar's fraction (a layout run's stages are per patch).
 */
async function run<T>(kind: CallKind, method: string, request: unknown, patchKey?: string | null,
                      overall: (p: Progress) => number = (p) => p.fraction): Promise<T | null> {
  if (current) current.controller.abort();
  const job = { kind, controller: new AbortController(), byUser: false };
  current = job;
  clearErrors(kind);
  setBusy(true);
  ui.progress.removeAttribute('value');
  ui.status.textContent = `${kind}: starting…`;
  const t0 = performance.now();
  try {
    const result = await call<T>(method, request, job.controller.signal, (p: Progress) => {
      if (current !== job) return;
      const fraction = Math.max(0, Math.min(1, overall(p)));
      ui.progress.value = fraction;
      ui.status.textContent = `${kind}: ${p.stage}${p.message ? ' — ' + p.message : ''} (${Math.round(100 * fraction)}%)`;
    }, patchKey);
    if (current !== job) return null;
    ui.status.textContent = `${kind}: done in ${((performance.now() - t0) / 1000).toFixed(2)} s`;
    return result;
  } catch (e) {
    if (current !== job && !job.byUser) return null; // superseded by a newer call
    if (isCancelled(e) || job.controller.signal.aborted) {
      ui.status.textContent = `${kind}: cancelled`;
      return null;
    }
    showError(kind, e);
    return null;
  } finally {
    if (current === job) {
      current = null;
      setBusy(false);
    }
  }
}

ui.cancel.addEventListener('click', () => {
  if (!current) return;
  current.byUser = true;
  current.controller.abort();
});

// ---- errors -----------------------------------------------------------------------------------

function errorSlotElement(key: string): HTMLElement | null {
  return document.querySelector<HTMLElement>(`.field-error[data-for="${CSS.escape(key)}"]`);
}

function clearErrors(kind: CallKind): void {
  ui.error.hidden = true;
  ui.error.textContent = '';
  const slots = kind === 'patch design' ? ['layout_patch'] : kind === 'simulate' ? ['simulation'] : kind === 'load' ? ['mesh', 'corners', 'options', 'design.alpha']
    : kind === 'patch' ? ['corners', 'options', 'design.alpha'] : LAYOUT_CALLS.has(kind) ? ['mesh', 'layout', 'options', 'simulation']
    : ['options', 'design.alpha'];
  for (const s of slots) {
    const slot = errorSlotElement(s);
    if (slot) slot.textContent = '';
  }
  // Next to each control: the daemon's error goes, the description's own check stays.
  if (kind === 'layout' || kind === 'build') for (const group of ['design', 'simulation', 'layout']) form?.clearErrors(group);
  else if (kind !== 'fabricate' && kind !== 'layout kit' && kind !== 'patch design') form?.clearErrors(kind === 'simulate' ? 'simulation' : 'design');
}

function showError(kind: CallKind, e: unknown): void {
  const err = e instanceof ApiError ? e : new ApiError('INTERNAL', '', e instanceof Error ? e.message : String(e), 0);
  if (err.status === 'UNAUTHENTICATED') ui.tokenBox.hidden = false;
  ui.error.hidden = false;
  ui.error.textContent = `${kind} failed (${err.status}): ${err.describe()}`;
  appendSuggestions(ui.error, err.suggestions);
  ui.status.textContent = `${kind}: failed`;
  const slot = errorSlotElement(errorSlot(kind, err.field, (key) => errorSlotElement(key) !== null));
  if (slot) slot.textContent = err.describe();
}

window.addEventListener('unhandledrejection', (event) => {
  ui.error.hidden = false;
  ui.error.textContent = `unexpected: ${String(event.reason)}`;
});

el<HTMLFormElement>('token-form').addEventListener('submit', (e) => {
  e.preventDefault(); // never sent anywhere (the CSP has form-action 'none' anyway)
  setToken(ui.token.value.trim());
  ui.tokenBox.hidden = true;
  void (async () => {
    if (!form) await loadDescription();
    await loadExamples();
  })();
});

// ---- the options' description: the design and simulation controls ------------------------------

let form: OptionsForm | null = null;

/** Asks the daemon for its description of the options (once), then builds the controls from it. */
async function loadDescription(): Promise<void> {
  const request = optionsRequest ?? call<OptionsResult>('options', {});
  optionsRequest = null; // a retry (after a token was given) asks again
  const result = await request.catch((e: unknown) => {
    showError('load', e);
    return null;
  });
  if (!result || form) return;
  buildForm(result);
}

function buildForm(d: OptionsResult): void {
  form = new OptionsForm(d, {
    design: { main: ui.designOptions, advanced: ui.designAdvanced },
    simulation: { main: ui.simulationOptions, advanced: ui.simulationAdvanced },
    layout: { main: ui.layoutOptions, advanced: ui.layoutAdvanced },
  });
  // One patch's member counts take the design options' bounds, as described.
  for (const [input, key] of [[ui.layoutPatchU, 'design.members_u'], [ui.layoutPatchV, 'design.members_v']] as const) {
    const o = form.option(key);
    if (o?.maximum !== undefined) input.max = String(o.maximum);
    if (o?.help) input.title = o.help;
  }
  form.onChange = (_key, option, settled) => {
    saveUrl();
    if (option.group !== 'design') return; // a simulation or layout option: the next call takes it
    if (patchOptionNames().has(option.name)) repatchSoon(settled ? 0 : 350);
    else redesignSoon(settled ? 0 : 350);
  };
  // The ᾱ slider is the page's own control of design.alpha: its help and default are the description's.
  const alpha = form.option('design.alpha');
  ui.alphaOption.hidden = !alpha; // an option the daemon no longer describes: no control for it
  if (alpha) {
    ui.alphaOption.dataset['option'] = optionKey(alpha);
    ui.alphaOption.title = tooltip(alpha);
    if (state.alphaDeg === null) ui.alphaValue.textContent = alpha.default_value ?? '';
  }
  const formats = d.mesh_formats ?? [];
  ui.file.accept = formats.map((f) => `.${f}`).join(',');
  ui.meshFormats.textContent = formats.length ? `(${formats.map((f) => f.toUpperCase()).join(', ')})` : '';
  document.body.dataset['options'] = String(form.controls.size);
}

/** Names of the design options a patch request takes too (the patch preview uses them). */
function patchOptionNames(): Set<string> {
  const patch = new Set((form?.description.options ?? []).filter((o) => o.group === 'patch' && !o.output).map((o) => o.name));
  return new Set([...(form?.names('design') ?? [])].filter((n) => patch.has(n)));
}

// ---- mesh in ------------------------------------------------------------------------------------

async function loadExamples(): Promise<void> {
  const request = examplesRequest ?? call<{ examples: ExampleInfo[] }>('examples', {});
  examplesRequest = null; // a retry (after a token was given) asks again
  const result = await request.catch((e: unknown) => {
    showError('load', e);
    return null;
  });
  if (!result) return;
  ui.example.length = 1;
  for (const ex of result.examples) {
    const o = document.createElement('option');
    o.value = ex.name;
    o.textContent = `${ex.name} (${ex.vertices} vertices)`;
    o.title = ex.description;
    ui.example.append(o);
  }
  ui.example.dataset['loaded'] = String(result.examples.length);
  ui.example.dataset['loadedMs'] = performance.now().toFixed(0); // since navigation start
}

/** Everything derived from the mesh forgotten (corners, patch, design, simulation, views). */
function resetFromMesh(): void {
  state.corners = [];
  state.cornersLabel = '';
  state.selected = null;
  state.patch = null;
  state.design = null;
  state.designWanted = false;
  state.simulation = null;
  state.alphaDeg = null;
  ui.alpha.disabled = ui.design.disabled = ui.simulate.disabled = ui.kit.disabled = true;
  ui.alphaValue.textContent = form?.option('design.alpha')?.default_value ?? '';
  ui.alphaMin.textContent = ui.alphaMax.textContent = '';
  ui.patchInfo.textContent = '';
  ui.summary.textContent = '';
  ui.warnings.textContent = '';
  ui.legend.hidden = true;
  ui.devLegend.hidden = true;
  setDownloads([]);
  plan.clear();
  maps.clear();
  clearLayout();
  updateCorners();
}

async function loadMesh(mesh: MeshJson, source: NonNullable<State['source']>): Promise<boolean> {
  const result = await run<LoadResult>('load', 'load', { mesh });
  if (!result) return false;
  state.loaded = result;
  state.source = source;
  // An example is sent by name, labelled as the CLI labels it (example:NAME, recorded as the
  // design's `input`); a file as the arrays the loader returned, labelled with its file name.
  state.mesh = source.kind === 'example' ? { name: `example:${source.name}`, example: source.name }
    : { name: source.name, positions: result.mesh.positions, indices: result.mesh.indices };
  resetFromMesh();
  viewer.setMesh(result.mesh.positions, result.mesh.indices);
  const r = result.report;
  const box = r.bounding_box;
  const extent = box.length === 6 ? `; extent ${[0, 1, 2].map((i) => formatNumber(box[i + 3]! - box[i]!)).join(' × ')}` : '';
  const repairs = [
    [r.polygons_triangulated, 'polygons triangulated'], [r.duplicate_vertices_merged, 'duplicate vertices merged'],
    [r.degenerate_faces_removed, 'degenerate faces removed'], [r.isolated_vertices_removed, 'isolated vertices removed'],
  ].filter(([k]) => Number(k) > 0).map(([k, what]) => `${k} ${what}`);
  ui.meshInfo.textContent = `${source.name}: ${r.vertices} vertices, ${r.faces} faces (${r.format})${extent}` +
    (repairs.length ? `\nloader: ${repairs.join(', ')}` : '');
  ui.warnings.textContent = r.warnings.length ? `loader: ${r.warnings.join('\n')}` : '';
  ui.meshInfo.dataset['ready'] = '1';
  ui.meshInfo.dataset['readyMs'] = performance.now().toFixed(0); // since navigation start
  ui.auto.disabled = ui.clear.disabled = false;
  ui.suggested.disabled = (result.example_corners?.vertices ?? []).length !== 4;
  ui.layoutAuto.disabled = ui.layoutFile.disabled = false;
  saveUrl();
  return true;
}

ui.example.addEventListener('change', () => {
  const name = ui.example.value;
  if (name) void loadMesh({ example: name }, { kind: 'example', name });
});

async function sha256(bytes: Uint8Array<ArrayBuffer>): Promise<string> {
  const digest = new Uint8Array(await crypto.subtle.digest('SHA-256', bytes));
  return Array.from(digest.slice(0, 8), (b) => b.toString(16).padStart(2, '0')).join('');
}

/** The state of a reload whose mesh was an uploaded file: applied when that file is opened again. */
let pendingFileState: UrlState | null = null;

async function loadFile(file: File): Promise<void> {
  const format = file.name.split('.').pop()?.toLowerCase() ?? '';
  const bytes = new Uint8Array(await file.arrayBuffer());
  const hash = await sha256(bytes);
  ui.example.value = '';
  const pending = pendingFileState;
  const same = pending?.file?.hash === hash;
  if (same) restoring = true;
  try {
    if (!(await loadMesh({ name: file.name, file: bytesToBase64(bytes), format }, { kind: 'file', name: file.name, hash })))
      return;
    pendingFileState = null;
    if (same && pending) await applyState(pending);
  } finally {
    if (same) {
      restoring = false;
      saveUrl();
    }
  }
}

ui.file.addEventListener('change', () => {
  const f = ui.file.files?.[0];
  if (f) void loadFile(f);
  ui.file.value = '';
});

for (const target of [ui.drop, ui.main]) {
  target.addEventListener('dragover', (e) => {
    e.preventDefault();
    target.classList.add('over');
  });
  target.addEventListener('dragleave', () => target.classList.remove('over'));
  target.addEventListener('drop', (e) => {
    e.preventDefault();
    target.classList.remove('over');
    const f = e.dataTransfer?.files[0];
    if (f) void loadFile(f);
  });
}

// ---- corners and patch ------------------------------------------------------------------------

function updateCorners(): void {
  viewer.setCorners(state.corners, state.selected);
  const n = state.corners.length;
  ui.cornersInfo.textContent = n === 0 ? (state.loaded ? 'No corners yet.' : '')
    : `corners${state.cornersLabel ? ` (${state.cornersLabel})` : ''}: ${state.corners.map((v, i) => `${i + 1}→v${v}`).join(', ')}` +
      (state.selected !== null ? `\nmoving corner ${state.selected + 1}: click the surface` : n < 4 ? `\nclick to place corner ${n + 1}` : '');
  ui.cornersInfo.dataset['count'] = String(n);
}

viewer.onPick = (pick: Pick) => {
  if (!state.loaded) return;
  if (state.layout) {
    // A layout corner chosen under "Move corner": it goes to the picked vertex and the layout is
    // cut again, so every patch at that corner follows.
    if (ui.layoutCorner.value !== '' && pick.kind === 'surface' && current?.kind !== 'build') {
      const k = Number(ui.layoutCorner.value);
      const layout: Layout = structuredClone(state.layout.report.layout);
      layout.corners[k] = { vertex: pick.vertex };
      ui.layoutCorner.value = '';
      ui.status.textContent = `corner ${k} moved to vertex ${pick.vertex}: cutting the layout again`;
      void computeLayout({ layout });
      return;
    }
    ui.status.textContent = 'A layout is shown: choose a corner under "Move corner" to move it, or Clear (section 2) to place corners of a single patch.';
    return;
  }
  if (pick.kind === 'marker') {
    state.selected = state.selected === pick.index ? null : pick.index;
    updateCorners();
    return;
  }
  if (state.selected !== null) {
    state.corners[state.selected] = pick.vertex;
    state.selected = null;
  } else if (state.corners.length < 4) {
    state.corners.push(pick.vertex);
  } else {
    ui.status.textContent = 'Four corners are set: click a marker to move it.';
    return;
  }
  state.cornersLabel = '';
  state.alphaDeg = null; // a new patch has its own feasible range: start again from its minimum
  updateCorners();
  ui.status.textContent = `picked vertex ${pick.vertex} in ${viewer.lastPickMs.toFixed(1)} ms`;
  ui.cornersInfo.dataset['pickMs'] = viewer.lastPickMs.toFixed(2);
  if (state.corners.length === 4) void computePatch();
  else saveUrl();
};

ui.auto.addEventListener('click', () => {
  state.corners = [];
  state.cornersLabel = 'auto';
  state.selected = null;
  state.alphaDeg = null;
  updateCorners();
  void computePatch();
});

ui.suggested.addEventListener('click', () => {
  const suggested = state.loaded?.example_corners?.vertices ?? [];
  if (suggested.length !== 4) return;
  state.corners = [...suggested];
  state.cornersLabel = 'example';
  state.selected = null;
  state.alphaDeg = null;
  updateCorners();
  void computePatch();
});

ui.clear.addEventListener('click', () => {
  if (current && current.kind !== 'load') current.controller.abort();
  resetFromMesh(); // keeps the mesh
  viewer.clearPatch();
  saveUrl();
});

function cornersJson(): { vertices?: number[]; label?: string } {
  if (state.cornersLabel === 'auto' && state.corners.length !== 4) return {}; // neither: automatic
  // The label is what design.json records as options.corners, as the CLI does ("auto", "example").
  return state.cornersLabel ? { vertices: state.corners, label: state.cornersLabel } : { vertices: state.corners };
}

async function computePatch(): Promise<void> {
  if (!state.mesh) return;
  if (state.layout) { // a single patch instead of the layout
    clearLayout();
    viewer.clearPatch();
  }
  state.patch = state.design = state.simulation = null;
  ui.design.disabled = ui.simulate.disabled = ui.kit.disabled = true;
  // The design options a patch takes too (geodesics, eta_max, the automatic corners' angles), so
  // that the patch shown is the one the design will use.
  const options = form?.requestOptions('design', patchOptionNames()) ?? {};
  const result = await run<PatchResult>('patch', 'patch', { mesh: state.mesh, corners: cornersJson(), options });
  if (!result) {
    if (!current) { // failed or cancelled (not superseded): no stale patch
      viewer.clearPatch();
      ui.patchInfo.textContent = '';
      delete ui.patchInfo.dataset['ready'];
      ui.legend.hidden = true;
    }
    return;
  }
  state.patch = result;
  const r = result.report;
  if (state.cornersLabel === 'auto') {
    state.corners = r.corners.map((c) => c.input_vertex);
    // Other corners, another feasible range: ᾱ starts again from the default.
    if (repickedFrom && repickedFrom.join() !== state.corners.join()) state.alphaDeg = null;
    updateCorners();
  }
  repickedFrom = null;
  const range = symmetricRange(result.gaussian_curvature);
  viewer.setPatch(result.patch.positions, result.patch.indices, result.gaussian_curvature, range,
                  r.sides.map((s) => s.vertices));
  ui.patchInfo.textContent = patchSummary(r);
  ui.patchInfo.dataset['ready'] = '1';
  ui.legend.hidden = false;
  ui.legendTitle.textContent = 'Gaussian curvature K (1/length²)';
  drawBar(ui.legendBar, (t) => diverging(2 * t - 1, 1));
  ui.legendMin.textContent = formatNumber(-range);
  ui.legendMid.textContent = '0';
  ui.legendMax.textContent = formatNumber(range);
  ui.warnings.textContent = r.warnings.length ? `patch: ${r.warnings.join('\n')}` : '';
  ui.design.disabled = false;
  saveUrl();
  if (state.designWanted) void computeDesign();
}

// ---- design -------------------------------------------------------------------------------------

/**
 * The design request's options, by field name: each control whose value is not the default (bad
 * values too: the daemon names them), and ᾱ once the slider moved.
 */
function designOptions(): Record<string, unknown> {
  const o = form?.requestOptions('design') ?? {};
  if (state.alphaDeg !== null) o['alpha'] = alphaOption(state.alphaDeg);
  return o;
}

/** The values the routing key hashes: the controls', else the description's defaults. */
function keyOptions(): KeyOptions | null {
  if (!form) return null;
  const method = form.effective('design.geodesic_method') ?? form.effective('patch.geodesic_method');
  const eta = form.effective('design.eta_max') ?? form.effective('patch.eta_max');
  const iterations = form.effective('patch.max_smoothing_iterations');
  const resolution = form.effective('design.resolution');
  if (typeof method !== 'string' || typeof eta !== 'number' || typeof iterations !== 'number' || typeof resolution !== 'number')
    return null;
  return { geodesic_method: method, eta_max: eta, max_smoothing_iterations: iterations, resolution };
}

/** The patch routing key of the designs on this mesh, corners and options (the slider keeps it). */
let keyMemo: { loaded: LoadResult; input: string; key: Promise<string | null> } | null = null;
function designKey(loaded: LoadResult, corners: KeyCorners | undefined): Promise<string | null> {
  const options = keyOptions();
  if (!options) return Promise.resolve(null); // the call goes without it
  const input = JSON.stringify([corners ?? null, options]);
  if (keyMemo?.loaded !== loaded || keyMemo.input !== input)
    keyMemo = { loaded, input, key: patchKey(loaded.mesh, corners, options).catch(() => null) };
  return keyMemo.key;
}

async function computeDesign(): Promise<void> {
  if (!state.mesh || !state.patch) return;
  state.designWanted = true;
  ui.simulate.disabled = true; // simulate the design on screen, not one being replaced
  const corners = cornersJson();
  const key = state.loaded ? await designKey(state.loaded, corners) : null;
  const result = await run<DesignResult>('design', 'design', {
    mesh: state.mesh, corners, options: designOptions(), files: true,
  }, key);
  if (!result) {
    if (!current) ui.simulate.disabled = !state.design; // failed or cancelled: the old one stays
    return;
  }
  state.design = result;
  state.simulation = null;
  const g = result.design;
  const range = sliderRange(g.alpha_bar_range);
  if (range) {
    ui.alpha.min = String(range[0]);
    ui.alpha.max = String(range[1]);
    ui.alphaMin.textContent = `${range[0]}°`;
    ui.alphaMax.textContent = `${range[1]}°`;
    ui.alpha.disabled = false;
  }
  ui.alpha.value = String(Math.round(g.alpha_bar * 1800 / Math.PI) / 10);
  ui.alphaValue.textContent = `${(g.alpha_bar * 180 / Math.PI).toFixed(1)}°`;
  viewer.setDesign(g);
  ui.devLegend.hidden = true;
  ui.summary.textContent = designSummary(result);
  ui.summary.dataset['cached'] = String(result.report.distance_maps_cached);
  ui.summary.dataset['designs'] = String(Number(ui.summary.dataset['designs'] ?? '0') + 1);
  setDownloads(result.views);
  const svg = (name: string) => result.views.find((f) => f.name === name);
  const p = svg('planar.svg'), m = svg('maps.svg');
  if (p) plan.show(blobUrl(p));
  if (m) maps.show(blobUrl(m));
  ui.simulate.disabled = false;
  ui.kit.disabled = false;
  saveUrl();
}

ui.design.addEventListener('click', () => void computeDesign());

let redesignTimer = 0;
function redesignSoon(ms: number): void {
  window.clearTimeout(redesignTimer);
  if (!state.designWanted || !state.patch) return;
  redesignTimer = window.setTimeout(() => void computeDesign(), ms);
}

/**
 * After a change of an option the patch depends on too: the patch again (and the design, if one
 * is wanted). Automatic corners are chosen again (their angles may have changed).
 */
let repatchTimer = 0;
let repickedFrom: number[] | null = null; // the automatic corners before they were chosen again
function repatchSoon(ms: number): void {
  window.clearTimeout(repatchTimer);
  window.clearTimeout(redesignTimer);
  if (!state.mesh || !(state.patch || state.corners.length === 4 || state.cornersLabel === 'auto')) return;
  repatchTimer = window.setTimeout(() => {
    if (state.cornersLabel === 'auto') {
      repickedFrom = state.corners.length === 4 ? [...state.corners] : null;
      state.corners = [];
      updateCorners();
    }
    void computePatch();
  }, ms);
}

ui.alpha.addEventListener('input', () => {
  state.alphaDeg = Number(ui.alpha.value);
  ui.alphaValue.textContent = `${state.alphaDeg.toFixed(1)}°`;
  redesignSoon(120);
});

// ---- simulate -----------------------------------------------------------------------------------

ui.simulate.addEventListener('click', () => void simulate());

async function simulate(): Promise<void> {
  const d = state.design;
  if (!d) return;
  // By field name, each control not at its default (what is left out takes the daemon's default).
  const options = form?.requestOptions('simulation') ?? {};
  const result = await run<SimulateResult>('simulate', 'simulate', {
    design: d.design, options, design_name: 'design.json', files: true,
  });
  if (!result) return;
  state.simulation = result;
  const dep = result.deployment;
  showDeployment();
  ui.summary.textContent = `${designSummary(d)}\n\n${deploymentSummary(dep)}`;
  setDownloads([...d.views, ...result.views]);
}

/** The deployment in 3D (a single patch's, or a layout's patches'), coloured as the panel says, with its legend. */
function showDeployment(): void {
  if (state.layoutRun) {
    showLayoutDeployment();
    return;
  }
  const d = state.design, sim = state.simulation;
  if (!d || !sim) return;
  const dep = sim.deployment;
  const bending = ui.colourBy.value === 'bending';
  const max = bending ? Math.max(0, ...dep.rods.map((r) => r.max_bending_stress)) : maxDeviation(dep);
  viewer.setDeployment(dep, d.design.options.lamella_width, d.design.options.lamella_thickness, max,
                       bending ? (rod) => rod.max_bending_stress : (rod, i) => rod.deviation[i] ?? 0);
  showDeploymentLegend(bending, max);
}

function showDeploymentLegend(bending: boolean, max: number): void {
  ui.devLegend.hidden = false;
  ui.devTitle.textContent = bending ? 'largest bending stress per lamella' : 'deviation from the target';
  drawBar(ui.devBar, (t) => sequential(t, 1));
  ui.devMax.textContent = bending ? stress(max) : formatNumber(max);
}

ui.colourBy.addEventListener('change', () => showDeployment());

// ---- fabricate ----------------------------------------------------------------------------------

ui.kit.addEventListener('click', () => void downloadKit());

/** Fabricate the design on screen and hand the kit over as kit.zip. */
async function downloadKit(): Promise<void> {
  const d = state.design;
  if (!d) return;
  // Inner anchors that the simulation added need supports too: the kit is then cut for the
  // anchored design the daemon returned with the deployment (design-anchored.json).
  const anchored = state.simulation?.views.find((f) => f.name === 'design-anchored.json');
  const design = anchored ? JSON.parse(new TextDecoder().decode(base64ToBytes(anchored.content))) as Design : d.design;
  const unit = form?.value('simulation.unit') ?? '';
  const result = await run<FabricateResult>('fabricate', 'fabricate', fabricateRequest(design, unit));
  if (!result) return;
  const a = document.createElement('a');
  a.href = URL.createObjectURL(new Blob([kitZip(result.files)], { type: 'application/zip' }));
  urls.push(a.href);
  a.download = 'kit.zip';
  a.textContent = 'kit.zip';
  a.dataset['testid'] = 'download-kit';
  ui.downloads.querySelector('[data-testid="download-kit"]')?.remove();
  ui.downloads.append(a);
  ui.summary.textContent = `${ui.summary.textContent ?? ''}\n\n${kitSummary(result.kit)}`;
  a.click();
}

// ---- layout: several patches ---------------------------------------------------------------------

/** A table's rows (its caption stays): a header, then one row per item, `num` columns right-aligned. */
function fillTable(table: HTMLTableElement, header: string[], rows: string[][], num: number[] = [],
                   decorate: (tr: HTMLTableRowElement, i: number) => void = () => {}): void {
  for (const child of [...table.children]) if (!(child instanceof HTMLTableCaptionElement)) child.remove();
  const head = table.createTHead().insertRow();
  for (const h of header) {
    const th = document.createElement('th');
    th.scope = 'col';
    th.textContent = h;
    head.append(th);
  }
  const body = table.createTBody();
  rows.forEach((cells, i) => {
    const tr = body.insertRow();
    cells.forEach((c, k) => {
      const td = tr.insertCell();
      td.textContent = c;
      if (num.includes(k)) td.className = 'num';
    });
    decorate(tr, i);
  });
  table.hidden = false;
}

function swatch(colour: Rgb): HTMLElement {
  const span = document.createElement('span');
  span.className = 'swatch';
  span.style.background = cssColour(colour); // the CSSOM: allowed by the CSP
  span.setAttribute('aria-hidden', 'true');
  return span;
}

/** Forgets the built patches: the run's summary, table, downloads, kit and lamellas. */
function clearLayoutRun(): void {
  state.layoutRun = null;
  ui.layoutKit.disabled = true;
  ui.layoutNonConverged.hidden = true;
  ui.layoutNonConverged.textContent = '';
  ui.layoutSummary.textContent = '';
  delete ui.layoutSummary.dataset['ready'];
  ui.layoutRun.hidden = true;
  if (state.layout) setLayoutDownloads(layoutFiles(state.layout));
  viewer.setLayoutDeployment(null);
  ui.devLegend.hidden = true;
}

/** Forgets the layout and what was built on it (the view is the caller's). */
function clearLayout(): void {
  clearLayoutRun();
  state.layout = null;
  ui.layoutBuild.disabled = true;
  ui.layoutInfo.textContent = '';
  delete ui.layoutInfo.dataset['ready'];
  ui.layoutPatches.hidden = true;
  ui.layoutUncovered.textContent = '';
  ui.layoutTrialsBox.hidden = true;
  ui.layoutPatchBox.hidden = true;
  ui.layoutCornerBox.hidden = true;
  ui.layoutPatchInfo.textContent = '';
  delete ui.layoutPatchInfo.dataset['ready'];
  setLayoutDownloads([]);
  const slot = errorSlotElement('layout');
  if (slot) slot.textContent = '';
}

/**
 * A layout (automatic, or a layout file) for the loaded surface. It replaces the single patch:
 * corners, patch, design and simulation are cleared, the patches drawn in their colours.
 */
async function computeLayout(mode: LayoutMode): Promise<void> {
  if (!state.mesh) return;
  resetFromMesh(); // keeps the mesh
  viewer.clearPatch();
  saveUrl();
  // The patch options of the design section (geodesics, eta_max) hold for every patch.
  const options = form?.requestOptions('design', patchOptionNames()) ?? {};
  const result = await run<LayoutResult>('layout', 'layout', { mesh: state.mesh, ...mode, options });
  if (result) showLayout(result);
}

function showLayout(result: LayoutResult): void {
  state.layout = result;
  const r = result.report;
  const colours = r.patches.map((_, i) => patchColour(i));
  const drawn = result.patches.map((p, i) => ({ positions: p.positions ?? [], indices: p.indices ?? [], colour: colours[i] ?? patchColour(i) }))
    .filter((p) => p.indices.length > 0);
  const sides = sideSegments(result.patches);
  viewer.setLayout(drawn, sides.seams, sides.outer);
  ui.layoutInfo.textContent = layoutSummary(r);
  ui.layoutInfo.dataset['ready'] = '1';
  ui.layoutInfo.dataset['patches'] = String(r.patches.length);
  fillTable(ui.layoutPatches, ['patch', 'ok or problem', 'area', 'η'], patchRows(r), [2, 3], (tr, i) => {
    const p = r.patches[i]!;
    tr.dataset['patch'] = p.name;
    tr.cells[0]?.prepend(swatch(colours[i]!));
    if (!p.ok) tr.classList.add('bad');
  });
  const uncovered = uncoveredLines(r);
  ui.layoutUncovered.textContent = uncovered.length ? `not covered:\n${uncovered.join('\n')}` : 'not covered: nothing';
  const trials = trialRows(r);
  ui.layoutTrialsBox.hidden = trials.length === 0;
  if (trials.length) fillTable(ui.layoutTrials, ['grid', 'patches', 'coverage', 'failing', 's'], trials, [1, 2, 4]);
  ui.layoutBuild.disabled = !r.patches.some((p) => p.ok);
  // One patch's own ᾱ and counts: the patches that meet the checks.
  const chosen = ui.layoutPatch.value;
  ui.layoutPatch.replaceChildren(...r.patches.filter((p) => p.ok).map((p) => new Option(p.name, p.name)));
  if (chosen && r.patches.some((p) => p.ok && p.name === chosen)) ui.layoutPatch.value = chosen;
  ui.layoutPatchBox.hidden = ui.layoutPatch.options.length === 0;
  ui.layoutCorner.replaceChildren(new Option('—', ''), ...r.layout.corners.map((_, k) => new Option(String(k), String(k))));
  ui.layoutCornerBox.hidden = false;
  showPatchChoices();
  setLayoutDownloads(layoutFiles(result));
  const svg = result.views.find((f) => f.name === 'layout.svg');
  if (svg) plan.show(blobUrl(svg));
}

ui.layoutAuto.addEventListener('click', () => void computeLayout({ automatic: form?.requestOptions('layout') ?? {} }));

/** The selected patch's index in the layout shown, or -1. */
function selectedPatch(): number {
  return state.layout ? state.layout.report.layout.patches.findIndex((p, i) => (p.name || `P${i + 1}`) === ui.layoutPatch.value) : -1;
}

/** The selected patch's own choices (from the layout) on its controls. */
function showPatchChoices(): void {
  const i = selectedPatch();
  if (!state.layout || i < 0) return;
  const patch = state.layout.report.layout.patches[i]!;
  const range = state.layout.report.patches[i]?.alpha_range;
  ui.layoutPatchAlpha.disabled = !range;
  ui.layoutPatchAlpha.value = String(Math.round(1000 * patchSliderPosition(range, patch.alpha)));
  ui.layoutPatchU.value = String(patch.members_u ?? 0);
  ui.layoutPatchV.value = String(patch.members_v ?? 0);
  showPatchAlpha();
}

function showPatchAlpha(): void {
  const i = selectedPatch();
  const range = i >= 0 ? state.layout?.report.patches[i]?.alpha_range : undefined;
  const alpha = patchAlpha(range, Number(ui.layoutPatchAlpha.value) / 1000);
  ui.layoutPatchAlphaValue.textContent = alpha === null ? '—'
    : `${(alpha * 180 / Math.PI).toFixed(2)}° (${(range![0]! * 180 / Math.PI).toFixed(2)}°–${(range![1]! * 180 / Math.PI).toFixed(2)}°)`;
}

/**
 * The selected patch's ᾱ and counts into the layout, then that patch redesigned alone (Design with
 * layout_patch: the daemon keeps each patch's work, so this skips the cut and the maps). Built, it
 * takes the run's cross-section; Build all patches then simulates the whole with the choices.
 */
async function redesignPatch(): Promise<void> {
  const i = selectedPatch();
  const layout = state.layout;
  if (!layout || i < 0 || !state.mesh) return;
  if (current?.kind === 'build') {
    ui.layoutPatchInfo.textContent = 'the layout is being built: change the patch when it is done';
    return;
  }
  const patch = layout.report.layout.patches[i]!;
  const alpha = patchAlpha(layout.report.patches[i]?.alpha_range, Number(ui.layoutPatchAlpha.value) / 1000);
  if (alpha !== null) patch.alpha = String(alpha);
  const u = Math.max(0, Math.round(Number(ui.layoutPatchU.value) || 0)), v = Math.max(0, Math.round(Number(ui.layoutPatchV.value) || 0));
  if (u > 0) patch.members_u = u; else delete patch.members_u;
  if (v > 0) patch.members_v = v; else delete patch.members_v;
  const options: Record<string, unknown> = { ...(form?.requestOptions('design') ?? {}) };
  const built = state.layoutRun?.patches.find((p) => p.design?.design)?.design?.design;
  if (built) options['lamella_width'] = built.options.lamella_width; // the layout's cross-section
  const name = ui.layoutPatch.value;
  delete ui.layoutPatchInfo.dataset['ready'];
  const t0 = performance.now();
  const result = await run<DesignResult>('patch design', 'design', {
    mesh: state.mesh, layout_patch: { layout: layout.report.layout, patch: name }, options,
  });
  if (!result) return;
  ui.layoutPatchInfo.textContent = `${patchDesignLine(name, result, performance.now() - t0)}` +
    (state.layoutRun ? '; Build all patches to simulate the whole with it' : '');
  ui.layoutPatchInfo.dataset['ready'] = '1';
  ui.layoutPatchInfo.dataset['alphaBar'] = String(result.design.alpha_bar);
}

ui.layoutPatch.addEventListener('change', showPatchChoices);
ui.layoutPatchAlpha.addEventListener('input', showPatchAlpha);
ui.layoutPatchAlpha.addEventListener('change', () => void redesignPatch());
ui.layoutPatchU.addEventListener('change', () => void redesignPatch());
ui.layoutPatchV.addEventListener('change', () => void redesignPatch());

ui.layoutFile.addEventListener('change', () => {
  const f = ui.layoutFile.files?.[0];
  ui.layoutFile.value = '';
  if (f) void openLayoutFile(f);
});

async function openLayoutFile(file: File): Promise<void> {
  try {
    const layout = layoutFromJson(await file.text());
    await computeLayout({ layout });
  } catch (e) {
    showError('layout', new ApiError('INVALID_ARGUMENT', 'layout', `${file.name}: ${e instanceof Error ? e.message : String(e)}`, 0));
  }
}

ui.layoutBuild.addEventListener('click', () => void buildLayout());

/** Every patch of the layout shown designed and simulated with the options of sections 3 and 4, the whole measured. */
async function buildLayout(): Promise<void> {
  const layout = state.layout;
  if (!layout || !state.mesh) return;
  clearLayoutRun();
  const result = await run<LayoutRunResult>('build', 'runlayout', {
    mesh: state.mesh, layout: layout.report.layout,
    design: form?.requestOptions('design') ?? {}, simulation: form?.requestOptions('simulation') ?? {},
  }, null, runProgress());
  if (!result) return;
  showLayout(result.layout); // the layout as built (the same, with the options sent)
  state.layoutRun = result;
  const d = result.deployment;
  showLayoutDeployment();
  ui.layoutSummary.textContent = runSummary(result);
  ui.layoutSummary.dataset['ready'] = '1';
  const failing = notConverged(d);
  ui.layoutNonConverged.hidden = d.converged === true;
  ui.layoutNonConverged.textContent = d.converged ? ''
    : `NOT converged: ${failing.length ? `${failing.join(', ')} did not reach equilibrium` : 'a run did not reach equilibrium'}; ` +
      'their deviations and the whole RMS are not those of a deployed structure.';
  fillTable(ui.layoutRun, ['patch', 'grid vertices', 'RMS with notches', 'RMS without', 'converged'], runRows(d), [1, 2, 3], (tr, i) => {
    const p = d.patches[i]!;
    tr.dataset['patch'] = p.name;
    const k = result.layout.report.patches.findIndex((q) => q.name === p.name);
    if (k >= 0) tr.cells[0]?.prepend(swatch(patchColour(k)));
    if (!p.converged) tr.classList.add('bad');
  });
  setLayoutDownloads(runFiles(result));
  layoutDownload('run.zip', new Blob([runZip(result)], { type: 'application/zip' }));
  ui.layoutKit.disabled = false;
}

/** The built patches' deployed lamellas on one colour scale (deviation, or bending stress per lamella). */
function showLayoutDeployment(): void {
  const r = state.layoutRun;
  if (!r) return;
  const bending = ui.colourBy.value === 'bending';
  const groups = deployedPatches(r);
  const max = bending ? Math.max(0, ...groups.flatMap((g) => g.rods.map((rod) => rod.max_bending_stress))) : maxDeviationOf(groups);
  viewer.setLayoutDeployment(groups, max, bending ? (rod) => rod.max_bending_stress : (rod, i) => rod.deviation[i] ?? 0);
  showDeploymentLegend(bending, max);
}

ui.layoutKit.addEventListener('click', () => void downloadLayoutKit());

/** The kit of the whole (one Fabricate of the run's design.json and its patches' designs) as kit.zip. */
async function downloadLayoutKit(): Promise<void> {
  const built = state.layoutRun;
  if (!built) return;
  const result = await run<FabricateResult>('layout kit', 'fabricate', layoutFabricateRequest(built, form?.value('simulation.unit') ?? ''));
  if (!result) return;
  ui.layoutDownloads.querySelector('[data-testid="layout-download-kit-zip"]')?.remove();
  const a = layoutDownload('kit.zip', new Blob([kitZip(result.files)], { type: 'application/zip' }));
  ui.layoutSummary.textContent = `${ui.layoutSummary.textContent ?? ''}\n${kitSummary(result.kit)}`;
  a.click();
}

// ---- downloads, views -----------------------------------------------------------------------

const urls: string[] = [];
const TYPES: Record<string, string> = { json: 'application/json', svg: 'image/svg+xml', obj: 'text/plain', ply: 'application/octet-stream' };

/** A blob URL of a file's bytes; the caller revokes it (downloads: setDownloads, views: Zoomable). */
function blobUrl(file: FileJson): string {
  const ext = file.name.split('.').pop() ?? '';
  return URL.createObjectURL(new Blob([base64ToBytes(file.content)], { type: TYPES[ext] ?? 'application/octet-stream' }));
}

function setDownloads(files: FileJson[]): void {
  for (const u of urls.splice(0)) URL.revokeObjectURL(u);
  ui.downloads.replaceChildren();
  for (const f of files) {
    const a = document.createElement('a');
    a.href = blobUrl(f);
    urls.push(a.href);
    a.download = f.name;
    a.textContent = f.name;
    const id = f.name === 'design.json' ? 'download-design' : f.name === 'deployment.json' ? 'download-deployment'
      : `download-${f.name.replace(/[^a-z0-9]+/gi, '-')}`;
    a.dataset['testid'] = id;
    ui.downloads.append(a);
  }
}

/** The layout's downloads (`layout-download-NAME`, e.g. layout-download-layout-json), its own blob URLs. */
const layoutUrls: string[] = [];
function layoutDownload(name: string, blob: Blob): HTMLAnchorElement {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  layoutUrls.push(a.href);
  a.download = name;
  a.textContent = name;
  a.dataset['testid'] = `layout-download-${name.replace(/[^a-z0-9]+/gi, '-')}`;
  ui.layoutDownloads.append(a);
  return a;
}

function setLayoutDownloads(files: FileJson[]): void {
  for (const u of layoutUrls.splice(0)) URL.revokeObjectURL(u);
  ui.layoutDownloads.replaceChildren();
  for (const f of files) {
    const ext = f.name.split('.').pop() ?? '';
    layoutDownload(f.name, new Blob([base64ToBytes(f.content)], { type: TYPES[ext] ?? 'application/octet-stream' }));
  }
}

for (const tab of document.querySelectorAll<HTMLButtonElement>('.tab')) {
  tab.addEventListener('click', () => {
    for (const t of document.querySelectorAll('.tab')) t.classList.toggle('active', t === tab);
    for (const p of document.querySelectorAll('.pane')) p.classList.toggle('active', p.id === tab.dataset['tab']);
    if (tab.dataset['tab'] === 'plan') plan.fit();
    if (tab.dataset['tab'] === 'maps') maps.fit();
    viewer.requestRender();
  });
}

// ---- state in the URL -------------------------------------------------------------------------

let restoring = false;
function saveUrl(): void {
  if (restoring) return;
  const s: UrlState = { options: form?.changed() ?? {} };
  if (state.source?.kind === 'example') s.example = state.source.name;
  if (state.source?.kind === 'file' && state.source.hash) s.file = { name: state.source.name, hash: state.source.hash };
  if (state.corners.length) s.corners = state.corners;
  if (state.cornersLabel === 'auto') s.auto = true;
  if (state.cornersLabel === 'example') s.suggested = true;
  if (state.alphaDeg !== null) s.alpha = state.alphaDeg;
  if (state.designWanted) s.design = true;
  history.replaceState(null, '', `#${encodeState(s)}`);
}

async function restore(): Promise<void> {
  const s = decodeState(location.hash);
  for (const [key, value] of Object.entries(s.options)) form?.set(key, value); // an option gone is skipped
  if (s.file && !s.example) {
    // The bytes of an uploaded file are not in the URL: ask for the file, restore when it comes.
    pendingFileState = s;
    ui.status.textContent = `Open ${s.file.name} again to restore its corners and options.`;
    return;
  }
  if (!s.example) return;
  restoring = true;
  try {
    ui.example.value = s.example;
    if (!(await loadMesh({ example: s.example }, { kind: 'example', name: s.example }))) return;
    await applyState(s);
  } finally {
    restoring = false;
    saveUrl();
  }
}

/** Corners, ᾱ and the design of a restored state, on the mesh just loaded. */
async function applyState(s: UrlState): Promise<void> {
  if (s.corners?.length === 4 || s.auto) {
    state.corners = s.corners ?? [];
    state.cornersLabel = s.auto ? 'auto' : s.suggested ? 'example' : '';
    updateCorners();
    if (s.alpha !== undefined) state.alphaDeg = s.alpha;
    state.designWanted = s.design ?? false;
    await computePatch();
  } else if (s.corners) {
    state.corners = s.corners;
    updateCorners();
  }
}

// ---- start ------------------------------------------------------------------------------------

void (async () => {
  await Promise.all([loadDescription(), loadExamples()]);
  await restore();
  document.body.dataset['ready'] = '1';
})();
