// SPDX-License-Identifier: GPL-3.0-or-later
// Unit tests of the page's pure code (client/web/src/format.ts, colormap.ts): bundled on the fly
// with the esbuild that Vite brings (no second TypeScript toolchain), then run with node:test.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { mkdtempSync, writeFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';

const web = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../client/web');
const esbuild = createRequire(path.join(web, 'package.json'))('esbuild');

async function load(entry) {
  const out = await esbuild.build({ entryPoints: [path.join(web, entry)], bundle: true, format: 'esm', write: false, platform: 'neutral' });
  const dir = mkdtempSync(path.join(tmpdir(), 'gridshell-unit-'));
  const file = path.join(dir, 'm.mjs');
  writeFileSync(file, out.outputFiles[0].text);
  try { return await import(pathToFileURL(file).href); } finally { rmSync(dir, { recursive: true, force: true }); }
}

const f = await load('src/format.ts');
const c = await load('src/colormap.ts');

test('slider range rounds the feasible range inward', () => {
  const r = f.sliderRange([1.0, 1.5]);
  assert.deepEqual(r, [57.3, 85.9]); // 57.2958 -> 57.3, 85.9437 -> 85.9
  assert.ok(r[0] >= 1.0 * 180 / Math.PI && r[1] <= 1.5 * 180 / Math.PI);
  assert.equal(f.sliderRange([]), null);
  assert.equal(f.sliderRange([1, Number.NaN]), null);
  assert.equal(f.sliderRange([1.00001, 1.00002]), null); // narrower than a step
});

test('alpha option is degrees with the deg suffix', () => {
  assert.equal(f.alphaOption(70), '70deg');
  assert.equal(f.alphaOption(70.123456), '70.1235deg');
});

test('stresses: MPa (scale-free), against the strength when it is known', () => {
  assert.equal(f.stress(18.6e6), '18.6 MPa');
  assert.equal(f.stressAgainst(30e6, 60e6, 0.5), '30 MPa = 50% of 60 MPa');
  assert.equal(f.stressAgainst(90e6, 60e6, 1.5), '90 MPa = 150% of 60 MPa EXCEEDED');
  assert.equal(f.stressAgainst(30e6, 0, undefined), '30 MPa (strength unknown)');
});

test('deployment summary: each run with its stresses against the material', () => {
  const run = { rms: 0.2, max_deviation: 0.5, iterations: 12, converged: true, seconds: 0.4,
                termination: '', max_normal_stress: 45e6, max_torsion_stress: 2e6,
                bending_utilization: 0.75, shear_utilization: 2e6 / 6.8e6, overstressed_lamellas: 0 };
  const dep = { options: { material: 'lime-wood', unit: '', young_modulus: 7.4e9,
                           bending_strength: 60e6, shear_strength: 6.8e6 },
                rms_with_notches: 0.2, seconds_with_notches: 0.4, converged: true, iterations: 12,
                grid_vertices: 100, rods: [], rods_without_notches: [], with_notches: run };
  const text = f.deploymentSummary(dep);
  assert.match(text, /max normal stress 45 MPa = 75% of 60 MPa, max torsion stress 2 MPa = 29% of 6\.8 MPa/);
  assert.match(text, /material lime-wood: E = 7\.4 GPa, bending strength 60 MPa, shear strength 6\.8 MPa/);
  assert.doesNotMatch(text, /EXCEEDED|overstressed/);
  const over = f.deploymentSummary({ ...dep, with_notches: { ...run, bending_utilization: 1.2,
                                                             overstressed_lamellas: 3 } });
  assert.match(over, /= 120% of 60 MPa EXCEEDED.*3 lamellas overstressed/);
  assert.doesNotMatch(text, /inner anchors/); // no search asked
  const anchor = { corner: false, side: -1, position: [0, 0, 1] };
  const searched = f.deploymentSummary({ ...dep, added_anchors: [anchor], anchor_trial_rms: [3.332, 0.2867, 0.2886] });
  assert.match(searched, /inner anchors: 1 added automatically \(RMS of the trials 3\.33 → 0\.287 → 0\.289; kept while it fell by 5% or more\)/);
  const goal = f.deploymentSummary({ ...dep, added_anchors: [anchor], anchor_trial_rms: [3.332, 0.2867], anchor_goal_rms: 0.355 });
  assert.match(goal, /RMS of the trials 3\.33 → 0\.287; kept while it fell by 5% or more, until RMS ≤ 0\.355\)/);
  const none = f.deploymentSummary({ ...dep, added_anchors: [], anchor_trial_rms: [0.2, 0.199] });
  assert.match(none, /inner anchors: none added \(RMS of the trials 0\.2 → 0\.199;/);
});

test('errors go next to the control their field names', () => {
  assert.equal(f.errorSlot('load', 'mesh.indices[3]'), 'mesh');
  assert.equal(f.errorSlot('load', ''), 'mesh');
  assert.equal(f.errorSlot('patch', 'corners.vertices[2]'), 'corners');
  assert.equal(f.errorSlot('design', 'options.alpha'), 'options.alpha');
  assert.equal(f.errorSlot('design', 'options.members_u'), 'options');
  assert.equal(f.errorSlot('simulate', 'options.material'), 'simulation');
  assert.equal(f.errorSlot('simulate', 'design.members[4]'), 'options');
});

test('URL state round-trips', () => {
  const s = { example: 'double-vault', corners: [1, 20, 300, 4000], alpha: 71.5, design: true, options: { mu: '5', mat: 'steel', aa: '1' } };
  const back = f.decodeState('#' + f.encodeState(s));
  assert.deepEqual(back, s);
  const up = { file: { name: 'my mesh.obj', hash: '0123456789abcdef' }, corners: [1, 2, 3, 4], options: {} };
  assert.deepEqual(f.decodeState('#' + f.encodeState(up)), up);
  assert.deepEqual(f.decodeState('#file=x.obj&sha256=nothex'), { options: {} });
  assert.deepEqual(f.decodeState('#corners=1,x,3'), { options: {} });
  assert.deepEqual(f.decodeState(''), { options: {} });
});

test('colour maps: ends, middle, clamping, robust range', () => {
  assert.deepEqual(c.diverging(0, 1).map((x) => x.toFixed(2)), ['0.97', '0.97', '0.97']);
  assert.ok(c.diverging(-1, 1)[2] > c.diverging(-1, 1)[0]); // blue for negative
  assert.ok(c.diverging(1, 1)[0] > c.diverging(1, 1)[2]); // red for positive
  assert.deepEqual(c.diverging(5, 1), c.diverging(1, 1));
  assert.deepEqual(c.sequential(Number.NaN, 1), c.sequential(0, 1));
  const values = Array.from({ length: 100 }, (_, i) => (i % 2 ? 1 : -1) * 0.01);
  values.push(1e6); // one spike must not flatten the map
  assert.equal(c.symmetricRange(values), 0.01);
  assert.equal(c.symmetricRange([0, 0]), 1e-12);
  assert.equal(c.formatNumber(0.000123), '1.23e-4');
  assert.equal(c.formatNumber(12.5), '12.5');
  assert.equal(c.formatNumber(1.5), '1.5');
  assert.equal(c.formatNumber(100), '100');
  assert.equal(c.formatNumber(2000), '2000');
  assert.equal(c.formatNumber(-0.25), '-0.25');
});

const api = await load('src/api.ts');

function streamOf(chunks) {
  const enc = new TextEncoder();
  return new ReadableStream({ start(c) { for (const x of chunks) c.enqueue(enc.encode(x)); c.close(); } });
}

test('SSE: progress events, then the result, across arbitrary chunk boundaries', async () => {
  const text = 'event: progress\ndata: {"stage":"distance maps","fraction":0.5,"message":""}\n\n' +
               'event: progress\ndata: {"stage":"grid: crossings","fraction":1,"message":"x"}\n\n' +
               'event: result\ndata: {"design":{"alpha":1.5}}\n\n';
  for (const cut of [1, 7, 50, 90, text.length - 3]) {
    const seen = [];
    const result = await api.readEvents(streamOf([text.slice(0, cut), text.slice(cut)]), (p) => seen.push(p.stage));
    assert.deepEqual(result, { design: { alpha: 1.5 } });
    assert.deepEqual(seen, ['distance maps', 'grid: crossings']);
  }
});

test('SSE: an error event becomes an ApiError with its field; a cut stream is UNAVAILABLE', async () => {
  const err = 'event: error\ndata: {"error":{"code":9,"status":"FAILED_PRECONDITION","field":"options.alpha","message":"no feasible angle"}}\n\n';
  await assert.rejects(api.readEvents(streamOf([err]), () => {}), (e) => {
    assert.ok(e instanceof api.ApiError);
    assert.equal(e.status, 'FAILED_PRECONDITION');
    assert.equal(e.describe(), 'options.alpha: no feasible angle');
    return true;
  });
  await assert.rejects(api.readEvents(streamOf(['event: progress\ndata: {"stage":"a","fraction":0}\n\n']), () => {}),
                       (e) => e.status === 'UNAVAILABLE');
});

test('base64 both ways, also past one 32 KiB chunk', () => {
  const bytes = new Uint8Array(100000).map((_, i) => (i * 7919) & 255);
  const text = api.bytesToBase64(bytes);
  assert.equal(text, Buffer.from(bytes).toString('base64'));
  assert.deepEqual(api.base64ToBytes(text), bytes);
});

const routing = await load('src/routing.ts');

test('retries: only calls the daemon did not answer, after a bounded, jittered back-off', () => {
  const e = (status, http) => new api.ApiError(status, '', 'x', http);
  assert.equal(api.retryable(e('UNAVAILABLE', 0)), true);        // refused, cut stream
  assert.equal(api.retryable(e('UNKNOWN', 502)), true);          // haproxy: the replica went away
  assert.equal(api.retryable(e('UNKNOWN', 503)), true);          // haproxy: no replica up
  assert.equal(api.retryable(e('UNAVAILABLE', 503)), true);      // a daemon shutting down
  for (const [status, http] of [['INVALID_ARGUMENT', 400], ['FAILED_PRECONDITION', 422], ['CANCELLED', 0],
                                ['DEADLINE_EXCEEDED', 504], ['RESOURCE_EXHAUSTED', 429], ['INTERNAL', 500],
                                ['UNAUTHENTICATED', 401]])
    assert.equal(api.retryable(e(status, http)), false, status);
  assert.equal(api.retryable(new Error('x')), false);
  let total = [0, 0];
  for (let k = 1; k <= api.RETRY.attempts; ++k) {
    const base = Math.min(api.RETRY.maxMs, api.RETRY.firstMs * 2 ** (k - 1));
    for (let i = 0; i < 200; ++i) {
      const d = api.retryDelayMs(k);
      assert.ok(d >= 0.5 * base && d < base, `retry ${k}: ${d} ms`);
    }
    total = [total[0] + 0.5 * base, total[1] + base];
  }
  assert.deepEqual(total, [3875, 7750]); // docs/api.md: 3.9 to 7.75 s of waiting in all
});

test('patch key bytes: the layout of docs/api.md', () => {
  const mesh = { positions: [0, 0, 0, 1, 0, 0, 0, 1, 0.5], indices: [0, 1, 2] };
  const b = routing.patchKeyBytes(mesh, { vertices: [0, 1, 2, 0] }, { resolution: 16 });
  const v = new DataView(b.buffer);
  const magic = new TextDecoder().decode(b.subarray(0, 23));
  assert.equal(magic, 'gridshell-patch-key-v1\n');
  assert.equal(v.getUint32(23, true), 3);
  assert.equal(v.getFloat64(27 + 8 * 8, true), 0.5);
  let at = 27 + 72;
  assert.equal(v.getUint32(at, true), 1);
  assert.deepEqual([0, 1, 2].map((k) => v.getUint32(at + 4 + 4 * k, true)), [0, 1, 2]);
  at += 16;
  assert.equal(b[at], 1); // vertex corners
  at += 1 + 16;
  assert.equal(v.getUint32(at, true), 4);
  assert.equal(new TextDecoder().decode(b.subarray(at + 4, at + 8)), 'fast');
  at += 8;
  assert.equal(v.getFloat64(at, true), 1.0015);
  assert.equal(v.getUint32(at + 8, true), 60);
  assert.equal(b[at + 12], 1);
  assert.equal(v.getUint32(at + 13, true), 16);
  assert.equal(b.length, at + 17);
  const auto = routing.patchKeyBytes(mesh, {}, {});
  assert.equal(auto[27 + 72 + 16], 0); // automatic corners: nothing follows the kind
  assert.equal(new DataView(auto.buffer).getUint32(auto.length - 4, true), 100); // default resolution
});
