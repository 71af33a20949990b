// SPDX-License-Identifier: GPL-3.0-or-later
// The daemon's HTTP/JSON API (docs/api.md): POST /v1/NAME with a protobuf-JSON body, progress as
// Server-Sent Events (Accept: text/event-stream), errors as {"error": {code, status, field,
// message}}. Cancelling = aborting the fetch: the gateway sees the connection close and cancels
// the job in the kernel. Replies use the proto field names (snake_case); requests use them too.

export interface Progress {
  stage: string;
  fraction: number;
  message: string;
}

/** A failed call: the daemon's error body, or a transport failure / cancellation of our own. */
/** A feasible change to an infeasible design (ErrorDetail.suggestions, docs/api.md). */
export interface Suggestion {
  rank: number;
  kind: string; // "slope_bounds" | "corners" | "members" | "lamella_width"
  description: string;
  corners?: { vertices?: number[] };
  k_min?: number;
  k_max?: number;
  members_u?: number;
  members_v?: number;
  lamella_width?: number;
  alpha_bar_range?: number[];
  change?: number;
}

export class ApiError extends Error {
  readonly status: string;
  readonly field: string;
  readonly httpStatus: number;
  readonly suggestions: Suggestion[];
  constructor(status: string, field: string, message: string, httpStatus: number,
              suggestions: Suggestion[] = []) {
    super(message);
    this.status = status;
    this.field = field;
    this.httpStatus = httpStatus;
    this.suggestions = suggestions;
  }
  /** "field: message", as the CLI prints it. */
  describe(): string {
    return this.field ? `${this.field}: ${this.message}` : this.message;
  }
}

export function isCancelled(e: unknown): boolean {
  return e instanceof ApiError && e.status === 'CANCELLED';
}

// ---- message shapes (the subset the page reads) -----------------------------------------------

export interface MeshJson {
  name?: string;
  positions?: number[];
  indices?: number[];
  file?: string; // base64
  format?: string;
  example?: string;
}

export interface MeshReport {
  format: string;
  file_vertices: number;
  file_faces: number;
  polygons_triangulated: number;
  degenerate_faces_removed: number;
  duplicate_vertices_merged: number;
  isolated_vertices_removed: number;
  warnings: string[];
  vertices: number;
  faces: number;
  bounding_box: number[];
}

export interface LoadResult {
  mesh: MeshJson & { positions: number[]; indices: number[] };
  report: MeshReport;
  example_corners?: { vertices?: number[] };
}

export interface ExampleInfo {
  name: string;
  description: string;
  vertices: number;
  corners: number[];
}

export interface PatchReport {
  vertex_count: number;
  face_count: number;
  corners: { position: number[]; input_vertex: number; patch_vertex: number }[];
  corner_angles: number[];
  boundary_lengths: number[];
  area: number;
  gaussian_curvature_max: number;
  injectivity_ok: boolean;
  eta_before: number;
  eta_after: number;
  eta_max: number;
  smoothing_iterations: number;
  warnings: string[];
  sides: { vertices: number[]; length: number }[];
  seconds: number;
}

export interface PatchResult {
  report: PatchReport;
  patch: { positions: number[]; indices: number[] };
  gaussian_curvature: number[];
}

export type Point3 = [number, number, number];
export type Point2 = [number, number];

export interface Design {
  input: string;
  alpha: number;
  alpha_bar: number;
  alpha_bar_range: number[];
  side_lengths: number[];
  members: { family: string; index: number; boundary: boolean; surface: Point3[] }[];
  crossings: { g: number; h: number; surface_point: number[]; on_boundary: boolean }[];
  anchors: { corner: boolean; side: number; position: number[] }[];
  options: { lamella_width: number; lamella_thickness: number; members_u: number; members_v: number };
}

export interface DesignReport {
  members_g: number;
  members_h: number;
  crossings: number;
  max_notch: number;
  max_length_mismatch: number;
  seconds: number;
  distance_maps_cached: boolean;
}

export interface FileJson {
  name: string;
  content: string; // base64
}

export interface DesignResult {
  design: Design;
  report: DesignReport;
  views: FileJson[];
}

export interface Lamella {
  member: { family: string; index: number };
  boundary: boolean;
  centerline: Point3[];
  normals: Point3[];
  deviation: number[];
  max_bending_stress: number;
  max_torsion_stress: number;
  max_normal_stress: number;
}

export interface SimulationRun {
  rms: number;
  max_deviation: number;
  iterations: number;
  converged: boolean;
  seconds: number;
  termination: string;
  max_normal_stress: number;
  max_torsion_stress: number;
  bending_utilization?: number; // max_normal_stress / options.bending_strength (absent: unknown)
  shear_utilization?: number;
  overstressed_lamellas: number;
}

export interface Deployment {
  options: {
    material: string;
    unit: string;
    young_modulus: number;
    bending_strength: number; // Pa, 0 = unknown
    shear_strength: number;
  };
  rms_without_notches?: number;
  rms_with_notches?: number;
  seconds_without_notches?: number;
  seconds_with_notches?: number;
  converged: boolean;
  iterations: number;
  grid_vertices: number;
  rods: Lamella[];
  rods_without_notches: Lamella[];
  with_notches?: SimulationRun;
  without_notches?: SimulationRun;
  /** Inner anchors the simulation added (options.interior_anchors "auto"), and the RMS of each trial. */
  added_anchors?: Design['anchors'];
  anchor_trial_rms?: number[];
  anchor_goal_rms?: number; // no anchor added once RMS is at most this (0: no goal)
}

export interface SimulateResult {
  deployment: Deployment;
  views: FileJson[];
}

/** One request option (gridshell.v1.OptionDescription, proto/gridshell/v1/options.proto). */
export interface OptionDescription {
  group: string;          // "patch" | "design" | "simulation" | "fabrication"
  name: string;           // the proto field name in that group's options message
  flag?: string;
  type: string;           // "number" | "integer" | "boolean" | "choice" | "text" | "numbers"
  default_value?: string;
  minimum?: number;
  maximum?: number;
  exclusive_minimum?: boolean;
  exclusive_maximum?: boolean;
  zero_allowed?: boolean;
  zero_means?: string;
  choices?: string[];
  unit?: string;
  help?: string;
  label?: string;
  advanced?: boolean;
  count?: number;
  note?: string;
  output?: boolean;       // recorded in results only, not a request option
}

/** A material preset (gridshell.v1.MaterialPreset): Pa, 0 = unknown strength. */
export interface MaterialPreset {
  name: string;
  label?: string;
  young_modulus?: number;
  shear_modulus?: number;
  bending_strength?: number;
  shear_strength?: number;
  source?: string;
  site?: boolean;
}

/** The Options RPC's answer (gridshell.v1.OptionsResult): every option, the materials (default first). */
export interface OptionsResult {
  options?: OptionDescription[];
  materials?: MaterialPreset[];
  mesh_formats?: string[];
  length_units?: string[];
}

// ---- transport --------------------------------------------------------------------------------

const TOKEN_KEY = 'gridshell.token';

export function getToken(): string {
  return sessionStorage.getItem(TOKEN_KEY) ?? '';
}
export function setToken(token: string): void {
  if (token) sessionStorage.setItem(TOKEN_KEY, token);
  else sessionStorage.removeItem(TOKEN_KEY);
}

function headers(sse: boolean, patchKey?: string | null): Record<string, string> {
  const h: Record<string, string> = { 'Content-Type': 'application/json' };
  if (sse) h['Accept'] = 'text/event-stream';
  const token = getToken();
  if (token) h['Authorization'] = `Bearer ${token}`;
  if (patchKey) h['X-Gridshell-Patch-Key'] = patchKey; // routing.ts
  return h;
}

async function errorFrom(response: Response): Promise<ApiError> {
  const text = await response.text().catch(() => '');
  try {
    const body = JSON.parse(text) as {
      error?: { status?: string; field?: string; message?: string; suggestions?: Suggestion[] };
    };
    if (body.error)
      return new ApiError(body.error.status ?? 'UNKNOWN', body.error.field ?? '', body.error.message ?? text,
                          response.status, body.error.suggestions ?? []);
  } catch {
    // not JSON: fall through
  }
  return new ApiError('UNKNOWN', '', `HTTP ${response.status}${text ? ': ' + text.slice(0, 200) : ''}`,
                      response.status);
}

function transportError(e: unknown, signal?: AbortSignal): ApiError {
  if (signal?.aborted) return new ApiError('CANCELLED', '', 'cancelled', 0);
  const message = e instanceof Error ? e.message : String(e);
  return new ApiError('UNAVAILABLE', '', `the daemon cannot be reached (${message})`, 0);
}

/**
 * Retries of a call the daemon could not answer (docs/api.md, "Retries"): the daemon cannot be
 * reached, a proxy in front of replicas answers 502 or 503 (no replica up, or the one serving the
 * call went away), the daemon is shutting down (503), or an event stream ends without its result.
 * Every method is idempotent, so the call is simply made again: up to `attempts` more times,
 * after 0.25 s doubling up to 4 s, each times a random factor in [0.5, 1).
 */
export const RETRY = { attempts: 5, firstMs: 250, maxMs: 4000 };

export function retryable(e: unknown): boolean {
  return e instanceof ApiError && e.status !== 'CANCELLED' &&
    (e.status === 'UNAVAILABLE' || e.httpStatus === 502 || e.httpStatus === 503);
}

export function retryDelayMs(retry: number): number {
  return Math.min(RETRY.maxMs, RETRY.firstMs * 2 ** (retry - 1)) * (0.5 + 0.5 * Math.random());
}

function sleep(ms: number, signal?: AbortSignal): Promise<void> {
  return new Promise((resolve, reject) => {
    if (signal?.aborted) { reject(new ApiError('CANCELLED', '', 'cancelled', 0)); return; }
    const timer = setTimeout(() => { signal?.removeEventListener('abort', onAbort); resolve(); }, ms);
    const onAbort = (): void => { clearTimeout(timer); reject(new ApiError('CANCELLED', '', 'cancelled', 0)); };
    signal?.addEventListener('abort', onAbort, { once: true });
  });
}

/**
 * One call: the result message, with progress events passed to onProgress. Rejects with ApiError
 * (status CANCELLED when `signal` aborted it). `patchKey` (routing.ts) routes a design to the
 * replica that has its patch cached; calls the daemon could not answer are retried (RETRY).
 */
export async function call<T>(method: string, request: unknown, signal?: AbortSignal,
                              onProgress?: (p: Progress) => void, patchKey?: string | null): Promise<T> {
  for (let retry = 1; ; ++retry) {
    try {
      return await callOnce<T>(method, request, signal, onProgress, patchKey);
    } catch (e) {
      if (!retryable(e) || signal?.aborted || retry > RETRY.attempts) throw e;
      onProgress?.({ stage: `daemon unavailable, retry ${retry} of ${RETRY.attempts}`, fraction: 0,
                     message: (e as ApiError).message });
      await sleep(retryDelayMs(retry), signal);
    }
  }
}

async function callOnce<T>(method: string, request: unknown, signal?: AbortSignal,
                           onProgress?: (p: Progress) => void, patchKey?: string | null): Promise<T> {
  const sse = onProgress !== undefined;
  let response: Response;
  try {
    response = await fetch(`v1/${method}`, {
      method: 'POST', headers: headers(sse, patchKey), body: JSON.stringify(request), signal,
      cache: 'no-store',
    });
  } catch (e) {
    throw transportError(e, signal);
  }
  if (!response.ok) throw await errorFrom(response);
  const type = response.headers.get('Content-Type') ?? '';
  try {
    if (!type.startsWith('text/event-stream') || !response.body) return (await response.json()) as T;
    return await readEvents<T>(response.body, onProgress ?? (() => {}));
  } catch (e) {
    if (e instanceof ApiError) throw e;
    throw transportError(e, signal);
  }
}

/**
 * Parses the SSE stream: progress events to the callback, then the result or the error. A
 * result can be tens of MB (a 100 x 100 deployment with its files): the chunks are kept as they
 * come and only the new text is searched for the end of an event, so the stream is read in
 * linear time (searching the whole buffer after every chunk was quadratic).
 */
export async function readEvents<T>(body: ReadableStream<Uint8Array>, onProgress: (p: Progress) => void): Promise<T> {
  const reader = body.getReader();
  const decoder = new TextDecoder();
  let pieces: string[] = []; // the text of the event being received
  let tail = '';             // the last character of `pieces`
  const handle = (block: string): T | undefined => {
    let event = 'message';
    let data = '';
    for (const line of block.split('\n')) {
      if (line.startsWith('event:')) event = line.slice(6).trim();
      else if (line.startsWith('data:')) data += line.slice(5).trimStart();
    }
    if (event === 'progress') onProgress(JSON.parse(data) as Progress);
    else if (event === 'result') return JSON.parse(data) as T;
    else if (event === 'error') {
      const e = (JSON.parse(data) as {
        error: { status: string; field: string; message: string; suggestions?: Suggestion[] };
      }).error;
      throw new ApiError(e.status, e.field, e.message, 200, e.suggestions ?? []);
    }
    return undefined;
  };
  for (;;) {
    const { done, value } = await reader.read();
    let text = value ? decoder.decode(value, { stream: true }) : '';
    if (done) text += decoder.decode();
    const blocks: string[] = [];
    let from = 0; // the start of `text` not yet in a block or in `pieces`
    if (tail === '\n' && text.startsWith('\n')) { // "\n\n" across the chunks
      blocks.push(pieces.join('').slice(0, -1));
      pieces = [];
      from = 1;
    }
    for (let end = text.indexOf('\n\n', from); end >= 0; end = text.indexOf('\n\n', from)) {
      blocks.push(pieces.join('') + text.slice(from, end));
      pieces = [];
      from = end + 2;
    }
    if (from < text.length) pieces.push(text.slice(from));
    tail = pieces.length ? pieces[pieces.length - 1]!.slice(-1) : '';
    for (const block of blocks) {
      const result = handle(block);
      if (result !== undefined) {
        void reader.cancel().catch(() => {});
        return result;
      }
    }
    if (done) throw new ApiError('UNAVAILABLE', '', 'the daemon closed the stream without a result', 0);
  }
}

// ---- helpers ----------------------------------------------------------------------------------

export function bytesToBase64(bytes: Uint8Array): string {
  let binary = '';
  const chunk = 0x8000;
  for (let i = 0; i < bytes.length; i += chunk)
    binary += String.fromCharCode(...bytes.subarray(i, i + chunk));
  return btoa(binary);
}

/** Base64 decoded: the browser's own decoder where there is one (Chromium 140+: tens of MB of files per result), else atob. */
export function base64ToBytes(text: string): Uint8Array<ArrayBuffer> {
  const u8 = Uint8Array as unknown as { fromBase64?: (s: string) => Uint8Array<ArrayBuffer> };
  if (u8.fromBase64) return u8.fromBase64(text);
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes;
}
