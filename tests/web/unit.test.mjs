// SPDX-License-Identifier: GPL-3.0-or-later
// Unit tests of the page's pure code (client/web/src/format.ts, colormap.ts, form.ts, ...): bundled on the fly
// with the esbuild that Vite brings (no second TypeScript toolchain), then run with node:test.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { existsSync, mkdtempSync, writeFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';

const web = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../client/web');
const esbuild = createRequire(path.join(web, 'package.json'))('esbuild');

async function load(entry) {
  const out = await esbuild.build({ entryPoints: [path.join(web, entry)], bundle: true, format: 'esm', write: false, platform: 'neutral',
                                    mainFields: ['module', 'main'] }); // fflate (layout.ts) names its entry so
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
  const slots = new Set(['design.alpha', 'design.members_u', 'design.eta_max', 'design.auto_corner_angles', 'simulation.material']);
  const has = (k) => slots.has(k);
  assert.equal(f.errorSlot('load', 'mesh.indices[3]', has), 'mesh');
  assert.equal(f.errorSlot('load', '', has), 'mesh');
  assert.equal(f.errorSlot('patch', 'corners.vertices[2]', has), 'corners');
  assert.equal(f.errorSlot('patch', 'options.eta_max', has), 'design.eta_max'); // a patch sends design options too
  assert.equal(f.errorSlot('patch', 'options.no_smoothing', has), 'corners');
  assert.equal(f.errorSlot('design', 'options.alpha', has), 'design.alpha');
  assert.equal(f.errorSlot('design', 'options.members_u', has), 'design.members_u');
  assert.equal(f.errorSlot('design', 'options.auto_corner_angles[1]', has), 'design.auto_corner_angles');
  assert.equal(f.errorSlot('design', 'options.members_u'), 'options'); // no such control: under the section
  assert.equal(f.errorSlot('design', 'options.k_max', has), 'options');
  assert.equal(f.errorSlot('simulate', 'options.material', has), 'simulation.material');
  assert.equal(f.errorSlot('simulate', 'options.solver', has), 'simulation');
  assert.equal(f.errorSlot('simulate', 'design.members[4]', has), 'options');
  assert.equal(f.errorSlot('fabricate', 'options.unit', has), 'fabricate');
  // Layout calls: the automatic options next to the layout controls, design and simulation options
  // next to theirs, the layout itself under its section.
  const layoutSlots = new Set([...slots, 'layout.max_patches']);
  const lhas = (k) => layoutSlots.has(k);
  assert.equal(f.errorSlot('layout', 'automatic.max_patches', lhas), 'layout.max_patches');
  assert.equal(f.errorSlot('layout', 'automatic.coverage_goal', lhas), 'layout');
  assert.equal(f.errorSlot('layout', 'layout.patches[1].corners[2]', lhas), 'layout');
  assert.equal(f.errorSlot('layout', 'mesh.indices[3]', lhas), 'mesh');
  assert.equal(f.errorSlot('build', 'design.options.members_u', lhas), 'design.members_u');
  assert.equal(f.errorSlot('build', 'design.members_u', lhas), 'design.members_u');
  assert.equal(f.errorSlot('build', 'simulation.material', lhas), 'simulation.material');
  assert.equal(f.errorSlot('build', 'simulation.solver', lhas), 'layout');
  assert.equal(f.errorSlot('layout', 'options.eta_max', lhas), 'design.eta_max'); // the patch options of the design section
  assert.equal(f.errorSlot('layout kit', 'options.unit', lhas), 'layout');
});

test('URL state round-trips; option keys are the controls\' (older short keys still read)', () => {
  const s = { example: 'double-vault', corners: [1, 20, 300, 4000], alpha: 71.5, design: true,
              options: { 'design.members_u': '5', 'simulation.material': 'steel', 'simulation.interior_anchors': 'auto',
                         'design.test_extra': '2.5' } };
  const back = f.decodeState('#' + f.encodeState(s));
  assert.deepEqual(back, s);
  assert.deepEqual(f.decodeState('#example=x&mu=5&w=0.5&mat=steel&aa=1&unit=cm').options,
                   { 'design.members_u': '5', 'design.lamella_width': '0.5', 'simulation.material': 'steel',
                     'simulation.interior_anchors': 'auto', 'simulation.unit': 'cm' });
  assert.deepEqual(f.decodeState('#bogus=1&design.x=2').options, { 'design.x': '2' });
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

test('SSE: every cut (also between the two newlines that end an event), byte by byte, and a big result', async () => {
  const text = 'event: progress\ndata: {"stage":"a","fraction":0.5}\n\n' + 'event: result\ndata: {"x":[1,2,3]}\n\n';
  for (let cut = 1; cut < text.length; ++cut) {
    const seen = [];
    const result = await api.readEvents(streamOf([text.slice(0, cut), text.slice(cut)]), (p) => seen.push(p.stage));
    assert.deepEqual(result, { x: [1, 2, 3] }, `cut at ${cut}`);
    assert.deepEqual(seen, ['a'], `cut at ${cut}`);
  }
  assert.deepEqual(await api.readEvents(streamOf([...text]), () => {}), { x: [1, 2, 3] });
  // A 20 MB result in 64 KiB chunks: read in linear time (the old reader searched the whole
  // buffer after every chunk); the bound is loose, a quadratic reader took tens of seconds.
  const big = `event: result\ndata: {"s":"${'x'.repeat(20e6)}"}\n\n`;
  const chunks = [];
  for (let i = 0; i < big.length; i += 65536) chunks.push(big.slice(i, i + 65536));
  const t0 = performance.now();
  assert.equal((await api.readEvents(streamOf(chunks), () => {})).s.length, 20e6);
  assert.ok(performance.now() - t0 < 10000);
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
  // The values come from the description's defaults on the page (routing.ts keeps no copy).
  const defaults = { geodesic_method: 'fast', eta_max: 1.0015, max_smoothing_iterations: 60, resolution: 100 };
  const b = routing.patchKeyBytes(mesh, { vertices: [0, 1, 2, 0] }, { ...defaults, resolution: 16 });
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
  const auto = routing.patchKeyBytes(mesh, {}, defaults);
  assert.equal(auto[27 + 72 + 16], 0); // automatic corners: nothing follows the kind
  assert.equal(new DataView(auto.buffer).getUint32(auto.length - 4, true), 100); // default resolution
});

// ---- the form built from the daemon's description of the options (form.ts, issue 34) ------------

const form = await load('src/form.ts');

/** A description as /v1/options answers it (a part of the real one), plus a made-up option and material. */
function description({ extra = true } = {}) {
  const options = [
    { group: 'patch', name: 'eta_max', type: 'number', default_value: '1.0015', minimum: 1, maximum: 10, label: 'Gap factor threshold', help: 'gap factor threshold eta' },
    { group: 'patch', name: 'max_smoothing_iterations', type: 'integer', default_value: '60', minimum: 0, maximum: 1e5, label: 'Smoothing cap', help: 'smoothing iterations at most' },
    { group: 'design', name: 'alpha', type: 'text', default_value: 'min', label: 'Planar corner angle', help: 'planar corner angle: min | max | radians | NNdeg' },
    { group: 'design', name: 'members_u', flag: '--members-u', type: 'integer', default_value: '0', minimum: 1, maximum: 1000, zero_allowed: true, zero_means: 'automatic', label: 'g-members', help: 'inner g-members' },
    { group: 'design', name: 'lamella_width', type: 'number', default_value: '0', minimum: 0, maximum: 1e15, exclusive_minimum: true, zero_allowed: true, zero_means: '1% of the longest patch side', unit: 'mesh units', label: 'Lamella width', help: 'lamella width' },
    { group: 'design', name: 'resolution', type: 'integer', default_value: '100', minimum: 8, maximum: 1000, zero_allowed: true, zero_means: 'adaptive', label: 'Map resolution', help: 'distance map resolution R' },
    { group: 'design', name: 'geodesic_method', type: 'choice', default_value: 'fast', choices: ['fast', 'cgal'], label: 'Geodesics', help: 'geodesic engine' },
    { group: 'design', name: 'eta_max', type: 'number', default_value: '1.0015', minimum: 1, maximum: 10, label: 'Gap factor threshold', help: 'gap factor threshold eta' },
    { group: 'design', name: 'interior_anchors', type: 'integer', default_value: '0', minimum: 0, maximum: 100, label: 'Inner anchors', help: 'inner anchors' },
    { group: 'design', name: 'auto_corner_angles', type: 'numbers', count: 2, default_value: '0.7853981633974483,2.356194490192345', minimum: 0, maximum: Math.PI, exclusive_minimum: true, exclusive_maximum: true, unit: 'radians', label: 'Corner angles', help: 'automatic corners', note: 'min < max' },
    { group: 'simulation', name: 'notches', type: 'choice', default_value: 'both', choices: ['on', 'off', 'both'], label: 'Notches', help: 'notches' },
    { group: 'simulation', name: 'material', type: 'choice', default_value: 'lime-wood', choices: ['lime-wood', 'steel', 'custom'], label: 'Material', help: 'material preset; custom: give both moduli' },
    { group: 'simulation', name: 'unit', type: 'text', default_value: '', label: 'Length unit', help: 'the model\'s length unit' },
    { group: 'simulation', name: 'interior_anchors', type: 'choice', default_value: '', choices: ['', 'auto'], label: 'Automatic inner anchors', help: 'add inner anchors' },
    { group: 'simulation', name: 'friction_epsilon', type: 'number', default_value: '1e-04', minimum: 0, maximum: 0.5, exclusive_minimum: true, exclusive_maximum: true, zero_allowed: true, zero_means: 'default', advanced: true, label: 'Friction epsilon', help: 'E_p' },
    { group: 'simulation', name: 'lamella_width', type: 'number', default_value: '', unit: 'mesh units', label: 'lamella_width', help: 'from the design', output: true },
    { group: 'layout', name: 'max_patches', flag: '--max-patches', type: 'integer', default_value: '36', minimum: 1, maximum: 64, zero_allowed: true, zero_means: 'default', label: 'Patches at most', help: "an automatic layout's patches at most" },
    { group: 'layout', name: 'coverage_goal', flag: '--coverage-goal', type: 'number', default_value: '0.95', minimum: 0, maximum: 1, exclusive_minimum: true, zero_allowed: true, zero_means: 'default', label: 'Coverage goal', help: 'an automatic layout stops growing at this fraction' },
    { group: 'fabrication', name: 'kerf', type: 'number', default_value: '0.15', minimum: 0, maximum: 10, exclusive_maximum: true, unit: 'mm', label: 'Kerf', help: 'laser kerf' },
  ];
  const materials = [
    { name: 'lime-wood', label: 'lime wood', young_modulus: 7.4e9, shear_modulus: 4.6e8, bending_strength: 6e7, shear_strength: 6.8e6, source: 'USDA', site: false },
    { name: 'steel', label: 'steel', young_modulus: 2.1e11, shear_modulus: 8.1e10, bending_strength: 2.35e8, shear_strength: 1.36e8, source: 'S235', site: false },
  ];
  if (extra) {
    options.splice(10, 0, { group: 'design', name: 'test_extra', flag: '--test-extra', type: 'number', default_value: '7', minimum: 2, maximum: 50,
                            exclusive_maximum: true, unit: 'mm', label: 'Test extra', help: 'a made-up option' });
    options.push({ group: 'simulation', name: 'test_switch', type: 'boolean', default_value: 'false', advanced: true, label: 'Test switch', help: 'a made-up advanced switch' });
    materials.push({ name: 'test-larch', label: 'test larch', young_modulus: 1.1e10, shear_modulus: 0.7e9, bending_strength: 7e7, shear_strength: 8e6, source: 'test', site: true });
  }
  return { options, materials, mesh_formats: ['obj', 'off', 'ply', 'stl'], length_units: ['mm', 'cm', 'm', 'in', 'ft'] };
}

test('form: a control for every design, simulation and layout option of the description, none for output or other groups', () => {
  const keys = form.controlSpecs(description()).map((c) => c.key);
  assert.deepEqual(keys, ['design.members_u', 'design.lamella_width', 'design.resolution', 'design.geodesic_method',
    'design.eta_max', 'design.interior_anchors', 'design.auto_corner_angles', 'design.test_extra', 'simulation.notches',
    'simulation.material', 'simulation.unit', 'simulation.interior_anchors', 'simulation.friction_epsilon',
    'layout.max_patches', 'layout.coverage_goal', 'simulation.test_switch']);
  // design.alpha is the page's own slider; the rest is exactly the description's, so an option added
  // to it is a control more, with no other change.
  const without = form.controlSpecs(description({ extra: false })).map((c) => c.key);
  assert.deepEqual(keys.filter((k) => !without.includes(k)), ['design.test_extra', 'simulation.test_switch']);
});

test('form: the layout options (automatic layouts) get their range and default; a request sends only what differs', () => {
  const specs = new Map(form.controlSpecs(description()).map((c) => [c.key, c]));
  const max = specs.get('layout.max_patches'), goal = specs.get('layout.coverage_goal');
  assert.deepEqual([max.kind, max.testid, max.min, max.max, max.step, max.value], ['number', 'max-patches', '0', '64', '1', '36']);
  assert.deepEqual([goal.kind, goal.testid, goal.min, goal.max, goal.value], ['number', 'coverage-goal', '0', '1', '0.95']);
  assert.match(max.title, /^an automatic layout's patches at most\nallowed: integer \[1, 64\] \(or 0: default\)\ndefault: 36\nCLI: --max-patches$/);
  assert.equal(form.checkValue(max.option, '100'), 'must be in [1, 64] (or 0: default)');
  assert.equal(form.checkValue(goal.option, '0'), '');
  const values = new Map([['layout.max_patches', '36'], ['layout.coverage_goal', '0.9']]);
  assert.deepEqual(form.requestOptions(values, form.formOptions(description()), 'layout'), { coverage_goal: 0.9 });
  assert.equal(form.REQUEST_FIELD.layout, 'automatic'); // the daemon's errors name automatic.max_patches
});

test('form: a made-up number option gets its range, default, label and help', () => {
  const spec = form.controlSpecs(description()).find((c) => c.key === 'design.test_extra');
  assert.equal(spec.kind, 'number');
  assert.equal(spec.testid, 'test-extra');
  assert.deepEqual([spec.min, spec.max, spec.step, spec.value, spec.label, spec.unit], ['2', '50', 'any', '7', 'Test extra', 'mm']);
  assert.equal(spec.title, 'a made-up option\nallowed: [2, 50) mm\ndefault: 7\nCLI: --test-extra');
  const o = spec.option;
  assert.equal(form.checkValue(o, '49.5'), '');
  assert.equal(form.checkValue(o, '50'), 'must be in [2, 50) mm'); // exclusive maximum
  assert.equal(form.checkValue(o, '1'), 'must be in [2, 50) mm');
  assert.equal(form.checkValue(o, ''), ''); // empty: the default
});

test('form: integer, zero-allowed, exclusive and list ranges; choices; what a request sends', () => {
  const specs = new Map(form.controlSpecs(description()).map((c) => [c.key, c]));
  const mu = specs.get('design.members_u');
  assert.deepEqual([mu.kind, mu.min, mu.max, mu.step, mu.value, mu.testid], ['number', '0', '1000', '1', '0', 'members-u']);
  assert.match(mu.title, /allowed: integer \[1, 1000\] \(or 0: automatic\)\ndefault: 0 \(automatic\)/);
  assert.equal(form.checkValue(mu.option, '0'), '');
  assert.equal(form.checkValue(mu.option, '2.5'), 'must be an integer in [1, 1000] (or 0: automatic)');
  const res = specs.get('design.resolution');
  assert.deepEqual([res.min, res.max], ['0', '1000']); // 0 or 8..1000: the input reaches 0, the check says the rest
  assert.equal(form.checkValue(res.option, '5'), 'must be in [8, 1000] (or 0: adaptive)');
  const w = specs.get('design.lamella_width');
  assert.equal(form.checkValue(w.option, '0'), '');
  assert.equal(form.checkValue(w.option, '-1'), 'must be in (0, 1e+15] mesh units (or 0: 1% of the longest patch side)');
  const eps = specs.get('simulation.friction_epsilon');
  assert.equal(eps.advanced, true);
  assert.equal(form.checkValue(eps.option, '0.5'), 'must be in (0, 0.5) (or 0: default)');
  const angles = specs.get('design.auto_corner_angles');
  assert.deepEqual([angles.kind, angles.count, angles.min, angles.max], ['numbers', 2, '0', String(Math.PI)]);
  assert.equal(form.checkValue(angles.option, '0.5,2.5'), '');
  assert.match(form.checkValue(angles.option, '0.5'), /needs 2 numbers/);
  assert.match(form.checkValue(angles.option, '0,2'), /^0: must be in \(0, 3\.14159\) radians/);
  assert.deepEqual(specs.get('design.geodesic_method').items.map((i) => i.value), ['fast', 'cgal']);
  const aa = specs.get('simulation.interior_anchors');
  assert.deepEqual([aa.kind, aa.checked, aa.testid], ['checkbox', 'auto', 'auto-anchors']);
  const unit = specs.get('simulation.unit');
  assert.deepEqual(unit.items.map((i) => i.value), ['', 'mm', 'cm', 'm', 'in', 'ft']); // the description's length units
  // Only values other than the default go into a request, typed by the option's type.
  const d = description();
  const values = new Map(form.controlSpecs(d).map((c) => [c.key, c.value]));
  assert.deepEqual(form.requestOptions(values, form.formOptions(d), 'design'), {});
  assert.deepEqual(form.requestOptions(values, form.formOptions(d), 'simulation'), {});
  values.set('design.test_extra', '9').set('design.members_u', '6').set('design.eta_max', '1.0015')
    .set('design.auto_corner_angles', '0.5,2.5').set('simulation.interior_anchors', 'auto').set('simulation.material', 'test-larch');
  assert.deepEqual(form.requestOptions(values, form.formOptions(d), 'design'),
                   { members_u: 6, test_extra: 9, auto_corner_angles: [0.5, 2.5] });
  assert.deepEqual(form.requestOptions(values, form.formOptions(d), 'design', new Set(['eta_max', 'auto_corner_angles'])),
                   { auto_corner_angles: [0.5, 2.5] });
  assert.deepEqual(form.requestOptions(values, form.formOptions(d), 'simulation'), { material: 'test-larch', interior_anchors: 'auto' });
});

test('form: the material select lists the description\'s materials (E and G in each title), then the other choices', () => {
  const spec = form.controlSpecs(description()).find((c) => c.key === 'simulation.material');
  assert.equal(spec.kind, 'select');
  assert.equal(spec.value, 'lime-wood');
  assert.deepEqual(spec.items.map((i) => [i.value, i.label]),
                   [['lime-wood', 'lime wood'], ['steel', 'steel'], ['test-larch', 'test larch'], ['custom', 'custom']]);
  assert.match(spec.items[2].title, /^E = 11 GPa, G = 0\.7 GPa; bending strength 70 MPa, shear strength 8 MPa\ntest\n\(this site's material library\)$/);
  assert.match(spec.items[0].title, /^E = 7\.4 GPa, G = 0\.46 GPa/);
});

// The DOM builder in real Chromium (the e2e tests' browser), on an empty page with no network.
const chromiumPath = process.env.CHROMIUM ?? '/usr/bin/chromium';
test('form: the built controls in Chromium (a made-up option and material appear with their range)',
     { timeout: 60000, skip: !existsSync(chromiumPath) && `no Chromium at ${chromiumPath}` }, async () => {
  const { chromium } = createRequire(path.join(web, 'package.json'))('playwright-core');
  const bundle = await esbuild.build({ entryPoints: [path.join(web, 'src/form.ts')], bundle: true, format: 'iife',
                                       globalName: 'gridshellForm', write: false, platform: 'browser' });
  const browser = await chromium.launch({ executablePath: chromiumPath, timeout: 30000,
    args: ['--no-sandbox', '--headless', '--disable-background-networking', '--disable-component-update', '--no-first-run'] });
  try {
    const page = await browser.newPage();
    page.setDefaultTimeout(10000);
    await page.route('**/*', (route) => route.abort()); // nothing leaves the page
    const errors = [];
    page.on('pageerror', (e) => errors.push(e.message));
    await page.setContent(`<div id="dm"></div><details><summary>Advanced</summary><div id="da"></div></details>
      <div id="sm"></div><details id="sd"><summary>Advanced</summary><div id="sa"></div></details>
      <div id="lm"></div><details id="ld"><summary>Advanced</summary><div id="la"></div></details>`);
    await page.addScriptTag({ content: bundle.outputFiles[0].text });
    await page.evaluate((d) => {
      const $ = (id) => document.getElementById(id);
      window.form = new window.gridshellForm.OptionsForm(d, { design: { main: $('dm'), advanced: $('da') },
                                                              simulation: { main: $('sm'), advanced: $('sa') },
                                                              layout: { main: $('lm'), advanced: $('la') } });
      window.changes = [];
      window.form.onChange = (key, o, settled) => window.changes.push([key, settled]);
    }, description());
    const extra = page.locator('[data-option="design.test_extra"]');
    const input = page.getByTestId('test-extra');
    assert.deepEqual(await input.evaluate((i) => [i.type, i.min, i.max, i.step, i.value]), ['number', '2', '50', 'any', '7']);
    assert.equal(await extra.locator('label').textContent(), 'Test extra (mm)');
    assert.match(await extra.getAttribute('title'), /^a made-up option\nallowed: \[2, 50\) mm/);
    assert.ok(await extra.evaluate((e) => e.parentElement.id === 'dm'), 'in the design grid, not under Advanced');
    // Immediate feedback from the description: the exclusive maximum, next to the control.
    await input.fill('50');
    assert.equal(await input.evaluate((i) => i.validity.valid), false);
    assert.equal(await extra.locator('.field-error').textContent(), 'options.test_extra: must be in [2, 50) mm');
    await input.fill('9');
    assert.equal(await input.evaluate((i) => i.validity.valid), true);
    assert.equal(await extra.locator('.field-error').textContent(), '');
    assert.deepEqual(await page.evaluate(() => window.form.requestOptions('design')), { test_extra: 9 });
    assert.deepEqual(await page.evaluate(() => window.changes.at(-1)), ['design.test_extra', false]);
    // The material select: every material of the description, the first selected.
    const material = page.getByTestId('material');
    assert.deepEqual(await material.locator('option').evaluateAll((os) => os.map((o) => [o.value, o.textContent])),
                     [['lime-wood', 'lime wood'], ['steel', 'steel'], ['test-larch', 'test larch'], ['custom', 'custom']]);
    assert.equal(await material.inputValue(), 'lime-wood');
    assert.match(await material.locator('option[value="test-larch"]').getAttribute('title'), /E = 11 GPa, G = 0\.7 GPa/);
    await material.selectOption('test-larch');
    assert.deepEqual(await page.evaluate(() => window.form.requestOptions('simulation')), { material: 'test-larch' });
    // An advanced option goes under the collapsed "Advanced"; an output field and other groups get nothing.
    assert.ok(await page.locator('#sa [data-option="simulation.test_switch"] input[type=checkbox]').count() === 1);
    assert.equal(await page.locator('#sd').evaluate((d) => d.open || d.hidden), false);
    assert.equal(await page.locator('[data-option="simulation.lamella_width"], [data-option^="fabrication."], [data-option^="patch."]').count(), 0);
    assert.equal(await page.locator('[data-option="design.alpha"]').count(), 0); // the page's own slider
    await page.getByTestId('auto-anchors').check();
    assert.deepEqual(await page.evaluate(() => window.form.changed()),
                     { 'design.test_extra': '9', 'simulation.material': 'test-larch', 'simulation.interior_anchors': 'auto' });
    // The layout controls: the immediate check names the request's field (LayoutRequest.automatic).
    const patches = page.getByTestId('max-patches');
    assert.ok(await patches.evaluate((i) => i.closest('#lm') !== null));
    await patches.fill('100');
    assert.equal(await patches.evaluate((i) => i.validity.valid), false);
    assert.equal(await page.locator('[data-option="layout.max_patches"] .field-error').textContent(),
                 'automatic.max_patches: must be in [1, 64] (or 0: default)');
    assert.deepEqual(await page.evaluate(() => window.form.requestOptions('layout')), { max_patches: 100 });
    await patches.fill('36');
    assert.equal(await page.locator('#ld').evaluate((d) => d.hidden), true); // no advanced layout option
    assert.equal(await page.evaluate(() => window.form.set('design.test_extra', '51')), true);
    assert.equal(await input.evaluate((i) => i.validity.valid), false);
    assert.deepEqual(errors, []);
  } finally {
    await browser.close();
  }
});

// ---- multi-patch layouts (layout.ts, issue 35) ----------------------------------------------------

const lay = await load('src/layout.ts');
const { unzipSync } = createRequire(path.join(web, 'package.json'))('fflate');

/** A 2 x 1 strip of unit squares as two patches (two triangles each) sharing the edge x = 1. */
function twoPatches() {
  return [
    { name: 'P1', positions: [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0], indices: [0, 1, 2, 0, 2, 3] },
    { name: 'P2', positions: [1, 0, 0, 2, 0, 0, 2, 1, 0, 1, 1, 0], indices: [0, 1, 2, 0, 2, 3] },
  ];
}

test('layout: a layout file read back (a Layout, layout.json, a layout run\'s design.json); what is not one', () => {
  const layout = { corners: [{ vertex: 0 }, { vertex: 1 }, { point: [1, 2, 3] }, { vertex: 4 }], patches: [{ corners: [0, 1, 2, 3] }] };
  assert.deepEqual(lay.layoutFromJson(JSON.stringify(layout)), layout);
  assert.deepEqual(lay.layoutFromJson(JSON.stringify({ input: 'x', coverage: 1, layout })), layout);            // LayoutReport
  assert.deepEqual(lay.layoutFromJson(JSON.stringify({ input: 'x', layout: { coverage: 1, layout } })), layout); // LayoutDesign
  assert.throws(() => lay.layoutFromJson('{"corners": ['), /^Error: not JSON/);
  assert.throws(() => lay.layoutFromJson('{"members": []}'), /no layout in it/);
  assert.throws(() => lay.layoutFromJson('[1, 2]'), /no layout in it/);
});

test('layout: boundary edges and the patch sides, seams (shared) apart from outer edges', () => {
  const [a] = twoPatches();
  const edges = lay.boundaryEdges(a.indices).map(([x, y]) => [Math.min(x, y), Math.max(x, y)].join('-')).sort();
  assert.deepEqual(edges, ['0-1', '0-3', '1-2', '2-3']); // the diagonal 0-2 is inner
  const { seams, outer } = lay.sideSegments(twoPatches());
  const points = (flat) => Array.from({ length: flat.length / 6 }, (_, i) => flat.slice(6 * i, 6 * i + 6));
  assert.equal(points(seams).length, 1, 'one seam segment, drawn once');
  assert.deepEqual(points(seams)[0].filter((_, k) => k % 3 === 0).sort(), [1, 1]); // on x = 1
  assert.equal(points(outer).length, 6);
  assert.ok(points(outer).every((s) => !(s[0] === 1 && s[3] === 1)), 'the seam is not an outer edge');
  // A patch that could not be cut (no arrays) adds nothing.
  assert.deepEqual(lay.sideSegments([...twoPatches(), { name: 'P3' }]).outer.length, outer.length);
});

test('layout: patch colours are distinct, valid, and neighbours differ', () => {
  const colours = Array.from({ length: 64 }, (_, i) => lay.patchColour(i));
  for (const c of colours) assert.ok(c.every((x) => x >= 0 && x <= 1), String(c));
  const keys = new Set(colours.map((c) => c.map((x) => x.toFixed(3)).join()));
  assert.equal(keys.size, 64);
  for (let i = 1; i < 64; ++i) {
    const d = colours[i].reduce((s, x, k) => s + Math.abs(x - colours[i - 1][k]), 0);
    assert.ok(d > 0.15, `patches ${i - 1} and ${i} too alike (${d})`);
  }
  assert.equal(lay.cssColour([1, 0.5, 0]), 'rgb(255,128,0)');
});

test('layout: a run\'s overall progress: the layout the first tenth, then the patches done', () => {
  const p = lay.runProgress();
  const at = (stage, fraction) => Math.round(1000 * p({ stage, fraction, message: '' })) / 1000;
  assert.equal(at('layout: 1 x 1', 0), 0);
  assert.equal(at('layout: 3 x 2', 0.5), 0.05);
  assert.equal(at('layout', 1), 0.1);
  assert.equal(at('P1: distance maps', 0.5), 0.1);            // a patch's own stage keeps the overall
  assert.equal(at('layout: patches designed and simulated', 0.25), 0.325);
  assert.equal(at('P3: simulate with notches', 1), 0.325);
  assert.equal(at('layout: patches designed and simulated', 0.2), 0.325); // never backwards
  assert.equal(at('layout: patches designed and simulated', 1), 1);
  assert.equal(at('layout: patches designed and simulated', Number.NaN), 1);
});

function report() {
  return {
    input: 'knet1.obj', layout: { corners: [{ vertex: 1 }, { vertex: 2 }, { vertex: 3 }, { vertex: 4 }, { vertex: 5 }, { vertex: 6 }],
                                  patches: [{ name: 'P1', corners: [0, 1, 4, 3] }, { name: 'P2', corners: [1, 2, 5, 4] }] },
    input_area: 200, covered_area: 150, coverage: 0.75,
    patches: [{ name: 'P1', ok: true, area: 150, eta: 1.0000123, vertices: 40 },
              { name: 'P2', ok: false, problem_code: 'infeasible', problem_field: 'layout.patches[1]', problem: 'corner angle 3.1 rad too large', area: 0 }],
    seams: [{ corners: [1, 4], patches: ['P1', 'P2'], length: 5, mismatch: 0 }, { corners: [0, 1], patches: ['P1'], length: 5, mismatch: 0 }],
    uncovered: [{ where: 'P2', area: 40, reason: 'corner angle 3.1 rad too large' },
                { where: 'outside the patches', area: 10, reason: 'between the outer patch sides and the boundary' }],
    automatic: { columns: 2, rows: 1, boundary_corners: [1, 3, 4, 6], seconds: 0.25,
                 trials: [{ columns: 1, rows: 1, coverage: 0.4378, failing: 0, first_problem: '', seconds: 0.0054 },
                          { columns: 2, rows: 1, coverage: 0.75, failing: 1, first_problem: 'P2: corner angle', seconds: 0.011 }] },
  };
}

test('layout: the summary, the patches\' table, what is not covered and the trials', () => {
  const r = report();
  assert.equal(lay.layoutSummary(r), 'coverage 75.0 %: 150 of 200\n2 patches (1 ok, 1 failing), 1 seams (largest mismatch 0), 6 corners\n' +
                                      'automatic: 2 × 1 grid, 2 trials in 0.25 s');
  assert.deepEqual(lay.patchRows(r), [['P1', 'ok', '150', '1.00001'],
                                      ['P2', 'layout.patches[1]: corner angle 3.1 rad too large', '—', '—']]);
  assert.deepEqual(lay.uncoveredLines(r), ['P2: 40 (20.00 %) — corner angle 3.1 rad too large',
                                           'outside the patches: 10 (5.00 %) — between the outer patch sides and the boundary']);
  assert.deepEqual(lay.trialRows(r), [['1 × 1', '1', '43.8 %', '0', '0.005'], ['2 × 1', '2', '75.0 %', '1: P2: corner angle', '0.011']]);
  assert.deepEqual(lay.trialRows({ ...r, automatic: undefined }), []); // a layout file: no trials
  // A ring is laid out round it, a closed surface on the six faces of a cube; a trial only cut
  // shows the bound of its coverage.
  const closed = { ...r, automatic: { ...r.automatic, surface: 'closed', columns: 1, rows: 1, patches: 6,
                                        cut: 'a closed surface: split along the edges of a cube',
                                        trials: [{ columns: 1, rows: 1, patches: 6, coverage: 1, checked: true, failing: 0, seconds: 0.07 },
                                                 { columns: 2, rows: 2, patches: 24, coverage: 0, cut_coverage: 0.5, checked: false, failing: 0, seconds: 0.1 }] } };
  assert.equal(lay.layoutSummary(closed).split('\n').slice(2).join('\n'),
               'automatic: 6 faces × 1 × 1 grid, 2 trials in 0.25 s\nsurface: a closed surface: split along the edges of a cube');
  assert.deepEqual(lay.trialRows(closed), [['6 faces × 1 × 1', '6', '100.0 %', '0', '0.070'], ['6 faces × 2 × 2', '24', '≤ 50.0 %', '0', '0.100']]);
  assert.equal(lay.automaticGrid('ring', 14, 1), '14 × 1 round the ring');
});

test('layout: one patch\'s own ᾱ on a slider over its feasible range, and the line after its redesign', () => {
  const range = [0.5, 0.9];
  assert.equal(lay.patchAlpha(range, 0), 0.5);
  assert.ok(Math.abs(lay.patchAlpha(range, 0.25) - 0.6) < 1e-15);
  assert.equal(lay.patchAlpha(range, 2), 0.9); // clamped
  assert.equal(lay.patchAlpha(undefined, 0.5), null);
  assert.equal(lay.patchSliderPosition(range, undefined), 0);
  assert.equal(lay.patchSliderPosition(range, 'max'), 1);
  assert.ok(Math.abs(lay.patchSliderPosition(range, '0.8') - 0.75) < 1e-12);
  assert.equal(lay.patchSliderPosition(range, 'wide'), 0);
  const member = (family, boundary) => ({ family, index: 0, boundary, surface: [] });
  const result = {
    design: { alpha_bar: Math.PI / 3, members: [member('g', true), member('g', false), member('g', false), member('h', false), member('h', true)],
              crossings: [{}, {}, {}] },
    report: { distance_maps_cached: true },
  };
  assert.equal(lay.patchDesignLine('P2', result, 31.4), 'P2: ᾱ 60.00°, 2 × 1 inner members, 3 crossings — 31 ms, patch work cached');
  assert.equal(lay.patchDesignLine('P2', { ...result, report: { distance_maps_cached: false } }, 800),
               'P2: ᾱ 60.00°, 2 × 1 inner members, 3 crossings — 800 ms');
  assert.equal(lay.percent(0.9537766652778353), '95.4 %');
  assert.equal(lay.ofDiagonal(0.0337, 50), '0.0337 (0.067 % of the diagonal)');
  assert.equal(lay.ofDiagonal(undefined, 50), '—');
});

function runResult({ converged = true } = {}) {
  const rod = (dev) => ({ member: { family: 'g', index: 0 }, boundary: false, centerline: [[0, 0, 0], [1, 0, 0]], normals: [[0, 0, 1], [0, 0, 1]],
                          deviation: dev, max_bending_stress: 1e6, max_torsion_stress: 0, max_normal_stress: 1e6 });
  const file = (name, text) => ({ name, content: Buffer.from(text).toString('base64') });
  const patch = (dev) => ({
    design: { design: { options: { lamella_width: 0.5, lamella_thickness: 0.05 } }, report: {}, views: [file('planar.svg', '<svg/>')] },
    simulation: { deployment: { rods: [rod(dev)] }, views: [file('deployed.obj', 'o x\n')] },
  });
  return {
    layout: { report: report(), patches: twoPatches(), views: [file('layout.svg', '<svg/>')] },
    patches: [patch([0.1, 0.7]), {}],
    design: { input: 'knet1.obj', layout: report(), patch_designs: ['patches/P1/design.json', ''], seams: [], seam_bolts: 0 },
    deployment: {
      options: { bending_strength: 60e6 }, rms_with_notches: 0.0337437107135822, rms_without_notches: 0.25, converged,
      grid_vertices: 90, diagonal: 51.1, max_seam_gap: 0, seams_joined: false, max_normal_stress: 30e6, bending_utilization: 0.5,
      seconds: 1.25, seams: [],
      patches: [{ name: 'P1', rms_with_notches: 0.0337, rms_without_notches: 0.25, converged, grid_vertices: 90 }],
    },
    views: [file('deployed.obj', 'o P1-g0\n'), file('deviation.ply', 'ply\n')],
  };
}

test('layout run: the per-patch table, the whole\'s summary (seams not joined), non-convergence', () => {
  const run = runResult();
  assert.deepEqual(lay.runRows(run.deployment), [['P1', '90', '0.0337', '0.25', 'yes']]);
  const text = lay.runSummary(run);
  assert.match(text, /^1 of 2 patches built; 90 grid vertices$/m);
  assert.match(text, /^whole RMS with notches 0\.0337 \(0\.066 % of the diagonal\)$/m);
  assert.match(text, /^whole RMS without notches 0\.25 \(0\.489 % of the diagonal\)$/m);
  assert.match(text, /^largest seam gap 0 \(0\.000 % of the diagonal\) — before joining: the seams are not joined, each patch deployed on its own$/m);
  assert.match(text, /^max normal stress 30 MPa = 50% of 60 MPa$/m);
  assert.match(text, /^every run of every patch converged$/m);
  // Joined: the gaps after and before, the bolts' force, the joined run, the patches alone.
  const joined = runResult();
  Object.assign(joined.deployment, {
    seams_joined: true, max_seam_gap: 0.0511, max_seam_gap_before_joining: 0.511, max_bolt_force: 4332, force_unit: 'Pa*unit^2',
    rms_before_joining: 0.0255, joined_with_notches: { notches: true, rms: 0.0337, converged: true, iterations: 27, anchors: 36 },
  });
  const joinedText = lay.runSummary(joined);
  assert.match(joinedText, /^largest seam gap 0\.0511 \(0\.100 % of the diagonal\) after joining, 0\.511 \(1\.000 % of the diagonal\) before$/m);
  assert.match(joinedText, /^largest bolt force 4330 Pa\*unit\^2$/m);
  assert.match(joinedText, /^whole joined with notches: 27 iterations, 36 anchors$/m);
  assert.match(joinedText, /^patches alone RMS 0\.0255 \(0\.050 % of the diagonal\), each deployed on its own$/m);
  assert.match(joinedText, /^every run of every patch and of the whole converged$/m);
  joined.deployment.joined_with_notches.converged = false;
  joined.deployment.joined_with_notches.termination = 'iteration limit';
  assert.match(lay.runSummary(joined), /^whole joined with notches: 27 iterations, 36 anchors, NOT converged: iteration limit$/m);
  assert.deepEqual(lay.notConverged(run.deployment), []);
  const bad = runResult({ converged: false });
  assert.match(lay.runSummary(bad), /^NOT converged/m);
  assert.deepEqual(lay.runRows(bad.deployment)[0].at(-1), 'NO');
  assert.deepEqual(lay.notConverged(bad.deployment), ['P1']);
  const drawn = lay.deployedPatches(run);
  assert.equal(lay.maxDeviationOf(drawn), 0.7);
  assert.equal(drawn.length, 1); // the patch without a result draws nothing
  assert.deepEqual([drawn[0].width, drawn[0].thickness, drawn[0].rods.length], [0.5, 0.05, 1]);
  // Joined: the whole's rods, grouped by patch, on their own deviation scale.
  const whole = runResult();
  const lam = (dev) => ({ member: { family: 'g', index: 0 }, boundary: false, centerline: dev.map((_, i) => [i, 0, 0]),
                          normals: dev.map(() => [0, 0, 1]), deviation: dev, max_bending_stress: 0, max_torsion_stress: 0, max_normal_stress: 0 });
  Object.assign(whole.deployment, {
    seams_joined: true, rod_patches: ['P1', 'P1', 'P2'],
    rods: [lam([0.2, 0.3]), lam([0.9, 0.1]), lam([0.4, 0.4])],
  });
  const joinedDrawn = lay.deployedPatches(whole);
  assert.deepEqual(joinedDrawn.map((g) => [g.name, g.rods.length, g.width, g.thickness]), [['P1', 2, 0.5, 0.05], ['P2', 1, 0.5, 0.05]]);
  assert.equal(lay.maxDeviationOf(joinedDrawn), 0.9);
});

test('layout run: the files of the whole (JSON that parses back) and run.zip with each patch\'s folder', () => {
  const run = runResult();
  const files = lay.runFiles(run);
  assert.deepEqual(files.map((f) => f.name), ['layout.json', 'design.json', 'deployment.json', 'layout.svg', 'deployed.obj', 'deviation.ply']);
  const json = (name) => JSON.parse(Buffer.from(files.find((f) => f.name === name).content, 'base64').toString('utf8'));
  assert.deepEqual(json('layout.json'), run.layout.report);
  assert.deepEqual(json('deployment.json'), run.deployment);
  assert.equal(json('design.json').seam_bolts, 0);
  assert.deepEqual(lay.layoutFromJson(JSON.stringify(json('layout.json'))), run.layout.report.layout); // it reads back as a layout
  assert.deepEqual(lay.layoutFiles(run.layout).map((f) => f.name), ['layout.json', 'layout.svg']);
  const zip = unzipSync(lay.runZip(run));
  assert.deepEqual(Object.keys(zip).sort(), ['run/deployed.obj', 'run/deployment.json', 'run/design.json', 'run/deviation.ply',
    'run/layout.json', 'run/layout.svg', 'run/patches/P1/deployed.obj', 'run/patches/P1/deployment.json',
    'run/patches/P1/design.json', 'run/patches/P1/planar.svg']);
  assert.equal(Buffer.from(zip['run/deployed.obj']).toString(), 'o P1-g0\n');
  assert.deepEqual(JSON.parse(Buffer.from(zip['run/patches/P1/design.json']).toString()), run.patches[0].design.design);
  const kit = lay.layoutFabricateRequest(run, 'cm');
  assert.deepEqual([kit.layout, kit.patches.length, kit.options], [run.design, 1, { unit: 'cm' }]);
});

const lm = await load('src/lamellas.ts');

/** A synthetic n x n grid's deployment on a dome: 2n + 4 rods of `points` centreline points each. */
function syntheticRods(n, points) {
  const rods = [];
  for (const family of ['g', 'h'])
    for (let k = 0; k < n + 2; ++k) {
      const centerline = [], normals = [], deviation = [];
      for (let i = 0; i < points; ++i) {
        const u = i / (points - 1) * 100 - 50, v = k / (n + 1) * 100 - 50;
        const [x, y] = family === 'g' ? [u, v] : [v, u];
        centerline.push([x + 3e5, y + 5e6, 30 - (x * x + y * y) / 400]);
        normals.push([x / 200, y / 200, 1]);
        deviation.push((i % 7) / 70);
      }
      rods.push({ member: { family, index: k }, boundary: k === 0 || k === n + 1, centerline, normals, deviation,
                  max_bending_stress: k, max_torsion_stress: 0, max_normal_stress: 0 });
    }
  return rods;
}

test('lamella boxes: a synthetic 100 x 100 grid in one mesh, the counts, outward faces, the light version', () => {
  const rods = syntheticRods(100, 203); // 204 lamellas, 41412 rod vertices as the real 100 x 100 run
  rods.push({ ...rods[0], centerline: [[0, 0, 0]], normals: [[0, 0, 1]], deviation: [0] }); // one point: not drawn
  const offset = [3e5, 5e6, 0];
  const t0 = performance.now();
  const m = lm.lamellaMesh([{ rods, width: 0.1, thickness: 0.01 }], offset, 0.1, (rod, i) => rod.deviation[i]);
  const ms = performance.now() - t0;
  assert.equal(m.lamellas, 204);
  assert.equal(m.vertices, 204 * lm.lamellaCounts(203).vertices);
  assert.equal(m.vertices, 204 * (8 * 203 + 8));
  assert.equal(m.triangles, 204 * (8 * 202 + 4));
  assert.equal(m.positions.length, 3 * m.vertices);
  assert.equal(m.indices.length, 3 * m.triangles);
  assert.ok(m.indices instanceof Uint32Array);
  assert.ok(m.indices.every((i) => i < m.vertices));
  // Relative to the offset, the box half a width / thickness off the centreline.
  const first = rods[0].centerline[0];
  assert.ok(Math.abs(m.positions[0] - (first[0] - offset[0])) < 0.06);
  assert.ok(m.positions.every(Number.isFinite) && m.normals.every(Number.isFinite));
  // Every triangle faces out: its winding's normal along the vertex normals, away from the centreline.
  for (let t = 0; t < m.triangles; t += 997) {
    const [a, b, c] = [0, 1, 2].map((j) => m.indices[3 * t + j]);
    const p = (v) => [m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]];
    const [pa, pb, pc] = [p(a), p(b), p(c)];
    const e1 = pb.map((x, k) => x - pa[k]), e2 = pc.map((x, k) => x - pa[k]);
    const cross = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
    const dot = cross[0] * m.normals[3 * a] + cross[1] * m.normals[3 * a + 1] + cross[2] * m.normals[3 * a + 2];
    assert.ok(dot > 0, `triangle ${t} faces in`);
  }
  // Colours: the sequential map of each rod vertex's deviation.
  assert.deepEqual([...m.colors.slice(0, 3)].map((x) => x.toFixed(4)), c.sequential(0, 0.1).map((x) => x.toFixed(4)));
  // Above LIGHT_ABOVE triangles a light version for camera moves: the wide faces, fewer points.
  assert.ok(m.triangles > lm.LIGHT_ABOVE && m.light !== null && m.lightStep > 1);
  assert.ok(m.light.length / 3 <= 1.1 * lm.LIGHT_TRIANGLES + 204 * 4, `${m.light.length / 3} light triangles`);
  assert.ok(m.light.every((i) => i < m.vertices));
  // A small one has none, 16-bit indices.
  const small = lm.lamellaMesh([{ rods: syntheticRods(4, 20), width: 1, thickness: 0.1 }], [0, 0, 0], 1, () => 0);
  assert.equal(small.lamellas, 12);
  assert.equal(small.light, null);
  assert.ok(small.indices instanceof Uint16Array);
  console.log(`# lamella boxes of a synthetic 100 x 100 grid: ${m.vertices} vertices, ${m.triangles} triangles in ${ms.toFixed(0)} ms`);
});
