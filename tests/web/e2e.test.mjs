// SPDX-License-Identifier: GPL-3.0-or-later
// End-to-end tests of the web page: a real gridshelld (started here on free loopback ports,
// serving client/web/dist) and real headless Debian Chromium driven by playwright-core. One
// browser page walks the whole flow in order, as a user would. Every wait is bounded; the
// daemon and the browser are stopped at the end, also when a test fails.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, spawnSync } from 'node:child_process';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { createHash } from 'node:crypto';
import path from 'node:path';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const web = path.join(root, 'client/web');
const { chromium } = createRequire(path.join(web, 'package.json'))('playwright-core');
const daemonPath = process.env.GRIDSHELLD ?? path.join(root, 'build/gridshelld');
const cliPath = process.env.GRIDSHELL ?? path.join(root, 'build/gridshell');
const outDir = path.join(root, 'tests/web/out'); // screenshot, kept out of git

let daemon, daemonLog = () => '', address, base, browser, page;
const daemons = [];        // every gridshelld started, stopped in after()
const allowedHosts = new Set();
const consoleErrors = [];
const foreignRequests = [];
let allowHttpErrors = false; // while a test provokes a 4xx on purpose

/** Waits until `predicate()` is truthy (polling), at most `ms`. */
async function until(predicate, ms, what) {
  const end = Date.now() + ms;
  for (;;) {
    const v = await predicate();
    if (v) return v;
    if (Date.now() > end) throw new Error(`timed out after ${ms} ms waiting for ${what}`);
    await new Promise((r) => setTimeout(r, 50));
  }
}

/** Starts gridshelld on free loopback ports serving the page; resolves when it listens. */
async function startDaemon(extra, http = '127.0.0.1:0', env = {}) {
  const proc = spawn(daemonPath, ['--listen', '127.0.0.1:0', '--http', http, '--static', path.join(web, 'dist'),
                                  '--workers', '2', ...extra],
                     { stdio: ['ignore', 'ignore', 'pipe'], env: { ...process.env, ...env } });
  let log = '';
  proc.stderr.setEncoding('utf8');
  proc.stderr.on('data', (d) => { log += d; });
  const address = await until(() => {
    const m = log.match(/"event":\s*"listening"[^\n]*?"http":\s*"([^"]+)"/) ??
              log.match(/"http":\s*"([^"]+)"[^\n]*"event":\s*"listening"/);
    if (proc.exitCode !== null) throw new Error(`gridshelld exited: ${log}`);
    return m?.[1];
  }, 20000, 'gridshelld to listen');
  allowedHosts.add(address);
  return { proc, address, log: () => log };
}

async function stopDaemon(proc) {
  if (proc.exitCode !== null || proc.signalCode !== null) return;
  proc.kill('SIGTERM');
  const exited = await Promise.race([new Promise((r) => proc.once('exit', () => r(true))),
                                     new Promise((r) => setTimeout(() => r(false), 5000))]);
  if (!exited) proc.kill('SIGKILL');
}

const byId = (id) => page.getByTestId(id);
const text = (id) => byId(id).textContent();

/** The daemon's description of every option (POST /v1/options), which the page's form is built from. */
async function describedOptions(url = base) {
  const r = await fetch(url + 'v1/options', { method: 'POST', body: '{}', headers: { 'Content-Type': 'application/json' },
                                              signal: AbortSignal.timeout(10000) });
  assert.equal(r.status, 200);
  return r.json();
}
const FORM_GROUPS = ['design', 'simulation', 'layout'];
const formOptions = (d) => d.options.filter((o) => !o.output && FORM_GROUPS.includes(o.group));

before(async () => {
  assert.ok(existsSync(daemonPath), `no daemon at ${daemonPath} (build it: bash scripts/build.sh)`);
  assert.ok(existsSync(path.join(web, 'dist/index.html')), 'no client/web/dist (bash scripts/build-web.sh)');
  ({ proc: daemon, address, log: daemonLog } = await startDaemon([]));
  daemons.push(daemon);
  base = `http://${address}/`;
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--no-sandbox', '--headless',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--no-first-run', '--disable-quic'], // Playwright gives it a fresh temporary profile
    timeout: 30000,
  });
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 }, acceptDownloads: true });
  // Traffic only to the daemon on loopback: anything else is recorded and refused.
  await context.route('**/*', (route) => {
    const url = new URL(route.request().url());
    if (url.protocol === 'blob:' || url.protocol === 'data:' || allowedHosts.has(url.host)) return route.continue();
    foreignRequests.push(url.href);
    return route.abort();
  });
  page = await context.newPage();
  page.setDefaultTimeout(20000);
  page.on('console', (m) => {
    if (m.type() !== 'error') return;
    if (allowHttpErrors && /Failed to load resource: the server responded with a status of 4\d\d/.test(m.text())) return;
    consoleErrors.push(m.text());
  });
  page.on('pageerror', (e) => consoleErrors.push(`pageerror: ${e.message}`));
});

after(async () => {
  await browser?.close().catch(() => {});
  await Promise.all(daemons.map(stopDaemon));
});

let exampleName;

test('page loads, lists the examples, shows one (page-ready time)', async () => {
  const t0 = Date.now();
  await page.goto(base, { waitUntil: 'load' });
  await until(() => page.evaluate(() => Number(document.querySelector('[data-testid=example-select]')?.dataset.loaded ?? 0)),
              10000, 'the example list');
  const options = await byId('example-select').locator('option').evaluateAll((os) => os.map((o) => o.value).filter(Boolean));
  assert.ok(options.length >= 3, `examples: ${options}`);
  // The daemon's own list, for comparison: the page shows all of them.
  const listed = await (await fetch(base + 'v1/examples', { method: 'POST', body: '{}', headers: { 'Content-Type': 'application/json' } })).json();
  assert.deepEqual(options, listed.examples.map((e) => e.name));
  const smallest = listed.examples.reduce((a, b) => (b.vertices < a.vertices ? b : a));
  exampleName = process.env.GRIDSHELL_WEB_EXAMPLE ?? (options.includes('double-vault') ? 'double-vault' : smallest.name);
  await byId('example-select').selectOption(exampleName);
  await page.waitForFunction(() => document.querySelector('[data-testid=mesh-info]')?.dataset.ready === '1', null, { timeout: 15000 });
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  const ms = Date.now() - t0;
  const inPage = await page.evaluate(() => ({
    dom: Math.round(performance.getEntriesByType('navigation')[0].domContentLoadedEventEnd),
    examples: document.querySelector('[data-testid=example-select]').dataset.loadedMs,
    shown: document.querySelector('[data-testid=mesh-info]').dataset.readyMs,
  }));
  console.log(`# page ready (navigation -> example ${exampleName} shown): ${ms} ms; in the page: bundle ` +
              `loaded ${inPage.dom} ms, examples listed ${inPage.examples} ms, example shown ${inPage.shown} ms`);
  assert.match(await text('mesh-info'), new RegExp(`${exampleName}: \\d+ vertices, \\d+ faces`));
});

test('the form is the daemon\'s description (/v1/options): one control per option, its range and default, the materials, the mesh formats', async () => {
  const d = await describedOptions();
  const described = formOptions(d).map((o) => `${o.group}.${o.name}`);
  assert.ok(described.includes('design.lamella_width') && described.includes('simulation.material'), described.join(' '));
  // One to one, by name: a list of its own in the page would fail here once the description changes.
  const onPage = await page.locator('#panel [data-option]').evaluateAll((es) => es.map((e) => e.dataset.option));
  assert.equal(new Set(onPage).size, onPage.length, `a control twice: ${onPage}`);
  assert.deepEqual([...onPage].sort(), [...described].sort());
  assert.equal(await page.evaluate(() => document.body.dataset.options), String(described.length - 1)); // all but the ᾱ slider
  // Each control: the description's help as its tooltip, its default, advanced ones under a collapsed
  // "Advanced", and number inputs whose own validity follows the range (exclusive bounds and
  // "0 allowed besides the range" included): the immediate feedback.
  const shown = await page.evaluate((options) => options.map((o) => {
    const root = document.querySelector(`[data-option="${o.group}.${o.name}"]`);
    const inputs = [...root.querySelectorAll('input, select')];
    const input = inputs[0];
    const r = { key: `${o.group}.${o.name}`, title: root.title, advanced: root.closest('details') !== null,
                closed: root.closest('details')?.open === false, kind: input?.type ?? '',
                value: inputs.map((i) => (i.type === 'checkbox' ? (i.checked ? 'on' : 'off') : i.value)).join(','),
                choices: input?.tagName === 'SELECT' ? [...input.options].map((x) => x.value) : null, valid: {} };
    if (input?.type === 'number' && o.type !== 'numbers') {
      const probe = (v) => { input.value = String(v); input.dispatchEvent(new Event('input')); return input.validity.valid; };
      const candidates = [0];
      if (o.minimum !== undefined) candidates.push(o.minimum, o.minimum - 1);
      if (o.maximum !== undefined) candidates.push(o.maximum, o.maximum * 2 + 1);
      if (o.minimum !== undefined && o.maximum !== undefined) candidates.push(o.type === 'integer' ? Math.ceil((o.minimum + o.maximum) / 2) : (o.minimum + o.maximum) / 2);
      for (const v of candidates) r.valid[String(v)] = probe(v);
      input.value = o.default_value;
      input.dispatchEvent(new Event('input'));
    }
    return r;
  }), formOptions(d));
  for (const o of formOptions(d)) {
    const c = shown.find((x) => x.key === `${o.group}.${o.name}`);
    assert.ok(c.title.startsWith(o.help), `${c.key}: title ${JSON.stringify(c.title)}`);
    assert.equal(c.advanced, o.advanced, `${c.key} under Advanced`);
    if (o.advanced) assert.ok(c.closed, `${c.key}: Advanced is collapsed`);
    if (c.key === 'design.alpha') continue; // the slider: its range is the design's feasible range
    if (o.type === 'number' || o.type === 'integer') {
      assert.equal(c.kind, 'number', c.key);
      assert.equal(Number(c.value), Number(o.default_value), `${c.key} default`);
      for (const [v, valid] of Object.entries(c.valid)) {
        const x = Number(v);
        const inRange = (o.minimum === undefined || x > o.minimum || (x === o.minimum && !o.exclusive_minimum)) &&
                        (o.maximum === undefined || x < o.maximum || (x === o.maximum && !o.exclusive_maximum)) &&
                        (o.type !== 'integer' || Number.isInteger(x));
        assert.equal(valid, inRange || (x === 0 && o.zero_allowed), `${c.key} = ${v}: valid ${valid}`);
      }
    } else if (o.type === 'choice' && c.choices) {
      assert.equal(c.value, o.default_value || c.choices[0], `${c.key} default`);
      for (const choice of o.choices) assert.ok(c.choices.includes(choice), `${c.key}: ${choice} offered`);
    } else if (o.type === 'boolean' || (o.type === 'choice' && c.kind === 'checkbox')) {
      assert.equal(c.kind, 'checkbox', c.key);
      assert.equal(c.value, o.default_value === 'true' || (o.default_value !== '' && o.default_value !== 'false') ? 'on' : 'off', c.key);
    } else if (o.type === 'numbers') {
      assert.deepEqual(c.value.split(',').map(Number), o.default_value.split(',').map(Number), `${c.key} default`);
    } else if (c.choices === null) {
      assert.equal(c.value, o.default_value, `${c.key} default`);
    }
  }
  // The materials, in the description's order, the first selected; E and G in each title.
  const material = byId('material');
  const listed = await material.locator('option').evaluateAll((os) => os.map((o) => ({ value: o.value, label: o.textContent, title: o.title })));
  assert.deepEqual(listed.slice(0, d.materials.length).map((m) => [m.value, m.label]), d.materials.map((m) => [m.name, m.label]));
  assert.equal(await material.inputValue(), d.materials[0].name);
  for (const m of listed.slice(0, d.materials.length)) assert.match(m.title, /^E = [\d.e+]+ GPa, G = [\d.e+]+ GPa/);
  assert.deepEqual(await byId('unit').locator('option').evaluateAll((os) => os.map((o) => o.value).filter(Boolean)), d.length_units);
  assert.equal(await byId('mesh-input').getAttribute('accept'), d.mesh_formats.map((f) => `.${f}`).join(','));
  // The probes above are undone: nothing but the defaults, so no option in the URL.
  assert.equal(await page.locator('#panel input:invalid').count(), 0);
  assert.doesNotMatch(new URL(page.url()).hash, /(design|simulation)\./);
});

/** Fraction of canvas pixels that differ from the background colour. */
async function canvasCoverage() {
  return page.evaluate(() => {
    const src = document.querySelector('[data-testid=viewer]');
    const c = document.createElement('canvas');
    c.width = 160; c.height = 100;
    const ctx = c.getContext('2d');
    ctx.drawImage(src, 0, 0, c.width, c.height);
    const d = ctx.getImageData(0, 0, c.width, c.height).data;
    const bg = [d[0], d[1], d[2]];
    let differ = 0;
    for (let i = 0; i < d.length; i += 4)
      if (Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]) > 30) ++differ;
    return differ / (d.length / 4);
  });
}

test('the mesh is drawn (canvas not blank)', async () => {
  const coverage = await until(async () => { const v = await canvasCoverage(); return v > 0.05 ? v : 0; }, 5000, 'a drawn mesh');
  assert.ok(coverage < 0.98, `coverage ${coverage}`);
});

test('Auto corners: the patch with η, corner angles, legend', async () => {
  await byId('corners-auto').click();
  await page.waitForFunction(() => document.querySelector('[data-testid=patch-info]')?.dataset.ready === '1', null, { timeout: 30000 });
  const info = await text('patch-info');
  assert.match(info, /η = \d\.\d{5}/);
  assert.match(info, /corner angles: (\d+\.\d°(, )?){4}/);
  assert.ok(await byId('legend').isVisible());
  assert.match(await byId('legend').textContent(), /Gaussian curvature/);
  assert.equal(await byId('corners-info').getAttribute('data-count'), '4');
  assert.match(await text('corners-info'), /\(auto\)/);
});

async function designCount() {
  return Number(await byId('summary').getAttribute('data-designs') ?? 0);
}

let firstSummary;
test('Design, then the ᾱ slider redesigns with the cached distance maps', async () => {
  await byId('design').click();
  await until(async () => (await designCount()) === 1, 60000, 'the first design');
  firstSummary = await text('summary');
  assert.match(firstSummary, /ᾱ = \d+\.\d°/);
  const slider = byId('alpha-slider');
  assert.ok(await slider.isEnabled());
  const [min, max] = [Number(await slider.getAttribute('min')), Number(await slider.getAttribute('max'))];
  assert.ok(min < max, `range ${min}..${max}`);
  const target = Math.round((min + 0.5 * (max - min)) * 10) / 10;
  await slider.fill(String(target));
  await until(async () => (await designCount()) === 2, 60000, 'the redesign');
  const summary = await text('summary');
  assert.match(summary, new RegExp(`ᾱ = ${target.toFixed(1).replace('.', '\\.')}°`));
  assert.match(summary, /distance maps cached: yes/);
  assert.equal(await byId('summary').getAttribute('data-cached'), 'true');
  assert.notEqual(summary, firstSummary);
  await page.getByRole('button', { name: 'Plan (2D)' }).click();
  await until(() => page.locator('#plan-img').evaluate((i) => i.complete && i.naturalWidth > 0), 5000, 'planar.svg shown');
  const scale = () => page.locator('#plan-img').evaluate((i) => Number(/scale\(([\d.e+-]+)\)/.exec(i.style.transform)?.[1]));
  await until(async () => (await scale()) > 0, 5000, 'the plan fitted');
  const fitted = await scale();
  const box = await byId('plan').boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.wheel(0, -300); // zoom in about the cursor
  await until(async () => (await scale()) > fitted * 1.2, 5000, 'the plan zoomed in');
  await page.getByRole('button', { name: '3D' }).click();
});

test('a redesign sends the patch key the daemon computes (X-Gridshell-Patch-Key = report.patch_key)', async () => {
  // The key routes designs of one patch to one replica behind haproxy (docs/api.md); the page
  // computes it with WebCrypto (routing.ts), the daemon in C++, from the same bytes. The page's
  // request is sent again without event stream, and its report names the daemon's key.
  const seen = [];
  const onRequest = (request) => {
    if (request.url().endsWith('/v1/design'))
      seen.push({ key: request.headers()['x-gridshell-patch-key'], body: request.postData() });
  };
  page.on('request', onRequest);
  try {
    const n = await designCount();
    const slider = byId('alpha-slider');
    const [min, max] = [Number(await slider.getAttribute('min')), Number(await slider.getAttribute('max'))];
    await slider.fill(String(Math.round((min + 0.25 * (max - min)) * 10) / 10));
    await until(async () => (await designCount()) === n + 1, 60000, 'the redesign');
  } finally {
    page.off('request', onRequest);
  }
  const last = seen.at(-1);
  assert.match(last.key ?? '', /^[0-9a-f]{32}$/);
  const reply = await (await fetch(base + 'v1/design', {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: last.body,
  })).json();
  assert.equal(last.key, reply.report.patch_key);
});

test('the state is in the URL: a reload restores the design, a second tab is independent', async () => {
  const summary = await text('summary');
  const hash = new URL(page.url()).hash;
  assert.match(hash, new RegExp(`example=${exampleName}.*corners=\\d+%2C\\d+%2C\\d+%2C\\d+.*alpha=`));
  const other = await page.context().newPage();
  try {
    await other.goto(base);
    await until(() => other.evaluate(() => document.body.dataset.ready === '1'), 10000, 'the second tab');
    assert.equal(await other.getByTestId('example-select').inputValue(), '');
    assert.equal(await other.getByTestId('summary').textContent(), '');
  } finally {
    await other.close();
  }
  await page.reload();
  await until(async () => (await designCount()) === 1, 60000, 'the restored design');
  assert.equal(await byId('example-select').inputValue(), exampleName);
  assert.equal(await byId('corners-info').getAttribute('data-count'), '4');
  const restored = await text('summary');
  assert.equal(restored.split('\n')[0], summary.split('\n')[0]); // the same ᾱ line
  assert.match(restored, /distance maps cached: yes/); // the daemon still has this patch's maps
});

/** design.json as `gridshell design MESH` writes it with the page's current options (corners
 *  given as CLI flags, [] = the CLI's default: an example's own corners). */
async function cliDesign(mesh, alphaDeg, cwd, corners = ['--corners', 'auto']) {
  const flags = [];
  for (const [id, flag] of [['members-u', '--members-u'], ['members-v', '--members-v'], ['lamella-width', '--lamella-width'],
                            ['lamella-thickness', '--lamella-thickness'], ['interior-anchors', '--interior-anchors']])
    flags.push(flag, await byId(id).inputValue());
  const dir = mkdtempSync(path.join(tmpdir(), 'gridshell-cli-'));
  try {
    const alpha = alphaDeg === null ? [] : ['--alpha', `${alphaDeg}deg`]; // null: the default (min)
    const r = spawnSync(cliPath, ['design', mesh, ...corners, ...alpha, ...flags, '--out', dir, '--quiet'],
                        { cwd, encoding: 'utf8', timeout: 60000 });
    assert.equal(r.status, 0, r.stderr);
    return readFileSync(path.join(dir, 'design.json'));
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
}

/** Asserts the page's and the CLI's design.json are the same bytes (both kept in out/ if not). */
function assertSameBytes(page, cli, name) {
  if (!cli.equals(page)) {
    mkdirSync(outDir, { recursive: true });
    writeFileSync(path.join(outDir, `${name}.page.json`), page);
    writeFileSync(path.join(outDir, `${name}.cli.json`), cli);
  }
  assert.ok(cli.equals(page), `design.json differs from the CLI's (${cli.length} vs ${page.length} bytes; see tests/web/out/${name}.*.json)`);
}

async function downloadJson(testid, on = page) {
  const [download] = await Promise.all([on.waitForEvent('download', { timeout: 10000 }), on.getByTestId(testid).click()]);
  const file = await download.path();
  return { name: download.suggestedFilename(), bytes: readFileSync(file) };
}

test('design.json downloads, the same bytes as the CLI writes for the same inputs', async () => {
  const { name, bytes } = await downloadJson('download-design');
  assert.equal(name, 'design.json');
  const design = JSON.parse(bytes.toString('utf8'));
  assert.ok(Array.isArray(design.members) && design.members.length > 4);
  const alpha = await byId('alpha-slider').inputValue();
  assert.ok(Math.abs(design.alpha_bar * 180 / Math.PI - Number(alpha)) < 0.06);
  assertSameBytes(bytes, await cliDesign(`example:${exampleName}`, Number(alpha), root), exampleName);
});

test('the example\'s suggested corners: a redesign from ᾱ min, design.json as the CLI\'s defaults', async () => {
  assert.ok(await byId('corners-example').isEnabled());
  const n = await designCount();
  await byId('corners-example').click();
  await until(async () => (await designCount()) === n + 1, 60000, 'the design on the suggested corners');
  assert.match(await text('corners-info'), /corners \(example\): /);
  const { bytes } = await downloadJson('download-design');
  const design = JSON.parse(bytes.toString('utf8'));
  assert.equal(design.options.corners, 'example');
  assert.ok(Math.abs(design.alpha_bar - design.alpha_bar_range[0]) < 1e-12, 'ᾱ from the minimum again');
  assertSameBytes(bytes, await cliDesign(`example:${exampleName}`, null, root, []), `${exampleName}-suggested`);
});

test('an option the patch depends on too (eta_max): the patch again with it, the design, the daemon\'s patch key', async () => {
  const seen = [];
  const onRequest = (r) => {
    const m = /\/v1\/(patch|design)$/.exec(r.url());
    if (m) seen.push({ method: m[1], key: r.headers()['x-gridshell-patch-key'], body: JSON.parse(r.postData()) });
  };
  const n = await designCount();
  page.on('request', onRequest);
  try {
    await byId('eta-max').fill('1.002');
    await until(async () => (await designCount()) === n + 1, 60000, 'the design on the new patch');
  } finally {
    page.off('request', onRequest);
  }
  const patch = seen.filter((x) => x.method === 'patch'), design = seen.filter((x) => x.method === 'design');
  assert.equal(patch.length, 1);
  assert.deepEqual(patch[0].body.options, { eta_max: 1.002 }); // the design options a patch takes too
  assert.equal(design.at(-1).body.options.eta_max, 1.002);
  assert.match(await text('patch-info'), /limit 1\.002\)/);
  // The page's key hashes the new eta_max (and the description's defaults): the daemon's.
  const reply = await (await fetch(base + 'v1/design', {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(design.at(-1).body),
  })).json();
  assert.match(design.at(-1).key ?? '', /^[0-9a-f]{32}$/);
  assert.equal(design.at(-1).key, reply.report.patch_key);
  assert.match(page.url(), /design\.eta_max=1\.002/);
  seen.length = 0;
  page.on('request', onRequest);
  try {
    await byId('eta-max').fill('1.0015'); // the default again: not sent
    await until(async () => (await designCount()) === n + 2, 60000, 'the design on the default patch');
  } finally {
    page.off('request', onRequest);
  }
  assert.deepEqual(seen.find((x) => x.method === 'patch').body.options, {});
  assert.equal(seen.filter((x) => x.method === 'design').at(-1).body.options.eta_max, undefined);
  assert.doesNotMatch(page.url(), /eta_max/);
});

test('member counts redesign live; a bad option shows its field next to the controls', async () => {
  const n = await designCount();
  await byId('members-u').fill('6');
  await until(async () => (await designCount()) === n + 1, 60000, 'the redesign with 6 g-members');
  assert.match(await text('summary'), /members: 6 g × \d+ h inner/);
  assert.match(await text('summary'), /distance maps cached: yes/);
  const slot = page.locator('.field-error[data-for="design.lamella_width"]');
  allowHttpErrors = true;
  try {
    await byId('lamella-width').fill('-1');
    // At once, from the description's range: the input is invalid and says why.
    assert.equal(await byId('lamella-width').evaluate((i) => i.validity.valid), false);
    assert.match(await slot.textContent(), /^options\.lamella_width: must be > 0 mesh units \(or 0: /);
    await until(() => byId('error').isVisible(), 10000, 'the error of the bad width');
  } finally {
    allowHttpErrors = false;
  }
  // Then the daemon's error, naming the field, next to that control.
  const shown = await text('error');
  assert.match(shown, /INVALID_ARGUMENT.*options\.lamella_width: .*got -1/);
  const next = await slot.textContent();
  assert.match(next, /^options\.lamella_width: .*got -1$/);
  assert.ok(shown.includes(next), `${shown}\n${next}`);
  assert.equal(await page.locator('.field-error[data-for=options]').textContent(), '');
  await byId('lamella-width').fill('0');
  await until(async () => (await designCount()) === n + 2, 60000, 'the redesign after the fix');
  assert.ok(await byId('error').isHidden());
  assert.equal(await slot.textContent(), '');
  assert.equal(await page.locator('.field-error[data-for=options]').textContent(), '');
});

test('an infeasible design lists the computed feasible changes under the error', async () => {
  const n = await designCount();
  allowHttpErrors = true;
  try {
    await byId('lamella-width').fill('12'); // 12 % of the longest side: too few members fit
    await until(() => byId('error').isVisible(), 120000, 'the infeasible design');
    await until(async () => (await page.locator('[data-testid=suggestions] li').count()) > 0, 1000,
      'the suggestions');
  } finally {
    allowHttpErrors = false;
  }
  assert.match(await text('error'), /FAILED_PRECONDITION/);
  assert.match(await text('error'), /Feasible changes \(computed\):/);
  const first = await page.locator('[data-testid=suggestions] li').first().textContent();
  assert.match(first, /(lamella width|members).*feasible planar angles/);
  await byId('lamella-width').fill('0');
  await until(async () => (await designCount()) === n + 1, 60000, 'the redesign after the fix');
  assert.ok(await byId('error').isHidden());
});

test('Simulate: deployment with RMS, deployment.json downloads', async () => {
  await byId('unit').selectOption('cm'); // a unit makes the stresses physical
  await byId('simulate').click();
  await until(async () => /RMS/.test(await text('summary')), 120000, 'the simulation');
  const summary = await text('summary');
  assert.match(summary, /with notches: RMS \d/);
  assert.match(summary, /without notches: RMS \d/);
  assert.match(summary, /max normal stress \d.* MPa = \d+% of 60 MPa.*unit cm/s);
  assert.ok(await byId('deviation-legend').isVisible());
  const { name, bytes } = await downloadJson('download-deployment');
  assert.equal(name, 'deployment.json');
  const dep = JSON.parse(bytes.toString('utf8'));
  assert.ok(dep.rods.length > 0 && Number.isFinite(dep.rms_with_notches));
  // One merged mesh of boxes: 8 vertices per rod vertex and 8 for the two end caps of each lamella.
  const drawn = dep.rods.filter((r) => r.centerline.length >= 2);
  assert.equal(await byId('viewer').getAttribute('data-lamellas'), String(drawn.length));
  assert.equal(await byId('viewer').getAttribute('data-lamella-vertices'),
               String(drawn.reduce((k, r) => k + 8 * r.centerline.length + 8, 0)));
  // The summary's percentage is the file's utilization: the largest corner stress over lime
  // wood's bending strength.
  const run = dep.with_notches;
  assert.equal(dep.options.bending_strength, 60e6);
  const largest = Math.max(...dep.rods.map((r) => r.max_normal_stress));
  assert.equal(run.max_normal_stress, largest);
  assert.ok(Math.abs(run.bending_utilization - largest / 60e6) < 1e-12);
  assert.ok(summary.includes(`= ${Math.round(100 * run.bending_utilization)}% of 60 MPa`));
  mkdirSync(outDir, { recursive: true });
  await page.screenshot({ path: path.join(outDir, 'deployment.png') });
  assert.ok((await canvasCoverage()) > 0.05, 'deployment drawn');
  await byId('colour-by').selectOption('bending');
  assert.match(await byId('deviation-legend').textContent(), /bending stress per lamella.*\d.* MPa/s);
  await byId('colour-by').selectOption('deviation');
  assert.match(await byId('deviation-legend').textContent(), /deviation from the target/);
});

test('Download kit: kit.zip holds the sheets, and kit.json is the CLI\'s for the same design', async () => {
  const { unzipSync } = createRequire(path.join(web, 'package.json'))('fflate');
  const { bytes: designBytes } = await downloadJson('download-design');
  const [download] = await Promise.all([page.waitForEvent('download', { timeout: 60000 }), byId('kit').click()]);
  assert.equal(download.suggestedFilename(), 'kit.zip');
  const zip = unzipSync(new Uint8Array(readFileSync(await download.path())));
  const names = Object.keys(zip).sort();
  for (const name of ['kit/kit.json', 'kit/assembly.svg', 'kit/supports.csv', 'kit/bom.csv',
                      'kit/sheets/sheet-01.dxf', 'kit/sheets/sheet-01.svg'])
    assert.ok(names.includes(name), `${name} in ${names.join(' ')}`);
  assert.match(await text('summary'), /kit: \d+ lamellas on \d+ sheet/);
  // The same design through the CLI in-process: the same kit.json and sheets, byte for byte.
  const dir = mkdtempSync(path.join(tmpdir(), 'gridshell-kit-'));
  try {
    writeFileSync(path.join(dir, 'design.json'), designBytes);
    const r = spawnSync(cliPath, ['fabricate', path.join(dir, 'design.json'), '--unit', 'cm', '--quiet',
                                  '--out', path.join(dir, 'kit')], { encoding: 'utf8' });
    assert.equal(r.status, 0, r.stderr);
    assert.equal(Buffer.from(zip['kit/kit.json']).toString('utf8'), readFileSync(path.join(dir, 'kit/kit.json'), 'utf8'));
    assert.deepEqual(Buffer.from(zip['kit/sheets/sheet-01.dxf']), readFileSync(path.join(dir, 'kit/sheets/sheet-01.dxf')));
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('Cancel stops a running simulation (the daemon cancels the job)', async () => {
  const before = (daemonLog().match(/CANCELLED/g) ?? []).length;
  await byId('simulate').click();
  await until(() => byId('cancel').isEnabled(), 5000, 'Cancel enabled');
  await byId('cancel').click();
  await until(async () => /simulate: cancelled/.test(await text('status')), 5000, 'the cancelled status');
  assert.ok(await byId('cancel').isDisabled());
  await until(() => (daemonLog().match(/CANCELLED/g) ?? []).length > before, 5000, 'the daemon to log the cancellation');
  assert.ok(await byId('simulate').isEnabled(), 'the page stays usable');
});

test('a 100 x 100-member deployment (synthetic, 204 lamellas, 41k rod vertices) draws; orbiting draws it light, then whole', async () => {
  // The daemon would take minutes to simulate it: the answer to this one Simulate is made here,
  // in the shape of the daemon's event stream (no files).
  const rods = [];
  for (const family of ['g', 'h'])
    for (let k = 0; k < 102; ++k) {
      const centerline = [], normals = [], deviation = [];
      for (let i = 0; i < 203; ++i) {
        const u = i / 202 * 100 - 50, v = k / 101 * 100 - 50;
        const [x, y] = family === 'g' ? [u, v] : [v, u];
        centerline.push([x, y, 30 - (x * x + y * y) / 400]);
        normals.push([x / 200, y / 200, 1]);
        deviation.push((i % 7) / 70);
      }
      rods.push({ member: { family, index: k }, boundary: k === 0 || k === 101, centerline, normals, deviation,
                  max_bending_stress: 1e6, max_torsion_stress: 0, max_normal_stress: 1e6 });
    }
  const run = { rms: 0.05, max_deviation: 0.0857, iterations: 10, converged: true, seconds: 300, max_bending_stress: 1e6,
                max_torsion_stress: 0, max_normal_stress: 1e6, bending_utilization: 1 / 60, shear_utilization: 0,
                overstressed_lamellas: 0 };
  const deployment = { rods, rods_without_notches: rods, with_notches: run, without_notches: run, rms_with_notches: 0.05,
                       rms_without_notches: 0.05, seconds_with_notches: 300, seconds_without_notches: 300, converged: true,
                       grid_vertices: 41412, options: { bending_strength: 60e6, shear_strength: 6.8e6 } };
  const body = `event: result\ndata: ${JSON.stringify({ deployment, views: [] })}\n\n`;
  await page.route('**/v1/simulate', (route) => route.fulfill({ status: 200, contentType: 'text/event-stream', body }));
  try {
    const t0 = Date.now();
    await byId('simulate').click();
    await until(async () => (await byId('viewer').getAttribute('data-lamellas')) === '204', 20000, 'the 204 lamellas drawn');
    console.log(`# synthetic 100 x 100 deployment: Simulate -> drawn in ${Date.now() - t0} ms (${body.length} bytes)`);
  } finally {
    await page.unroute('**/v1/simulate');
  }
  const viewer = byId('viewer');
  assert.equal(await viewer.getAttribute('data-lamella-vertices'), String(204 * (8 * 203 + 8)));
  assert.equal(await viewer.getAttribute('data-lamellas-light'), '0');
  // A drag: the frames while it lasts draw the light version, the frame after it the whole boxes.
  const box = await viewer.boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width / 2 + 60, box.y + box.height / 2, { steps: 3 });
  await until(async () => (await viewer.getAttribute('data-lamellas-light')) === '1', 10000, 'a light frame');
  await page.mouse.up();
  await until(async () => (await viewer.getAttribute('data-lamellas-light')) === '0', 10000, 'the whole boxes again');
  assert.ok((await canvasCoverage()) > 0.05, 'deployment drawn');
  assert.match(await text('summary'), /with notches: RMS 0\.05/);
});

test('a redesign after the simulation shows the design again, not the old deployment', async () => {
  const layers = () => byId('viewer').getAttribute('data-layers');
  assert.match(await layers(), /deployment/);
  assert.doesNotMatch(await layers(), /design/);
  const n = await designCount();
  await byId('members-v').fill('7');
  await until(async () => (await designCount()) === n + 1, 60000, 'the redesign');
  await until(async () => (await layers()) === 'mesh,markers,patch,design', 5000, 'the design layers');
  assert.ok(await byId('deviation-legend').isHidden());
  assert.doesNotMatch(await text('summary'), /RMS/);
});

test('inner anchors found by the simulation (waves-bump): listed, in design-anchored.json and in the kit\'s supports', async () => {
  const { unzipSync } = createRequire(path.join(web, 'package.json'))('fflate');
  await byId('example-select').selectOption('waves-bump');
  await until(async () => /waves-bump: \d+ vertices/.test(await text('mesh-info')), 15000, 'waves-bump');
  await byId('corners-example').click();
  await until(async () => /η = /.test(await text('patch-info')), 30000, 'the patch on the suggested corners');
  const n = await designCount();
  await byId('design').click();
  await until(async () => (await designCount()) === n + 1, 60000, 'its design');
  await byId('auto-anchors').check();
  assert.match(page.url(), /simulation\.interior_anchors=auto/); // kept in the URL with the other options
  await byId('simulate').click();
  await until(async () => /inner anchors:/.test(await text('summary')), 120000, 'the simulation with the anchor search');
  const { bytes } = await downloadJson('download-deployment');
  const dep = JSON.parse(bytes.toString('utf8'));
  assert.equal(dep.options.interior_anchors, 'auto');
  // Held at its boundary only, waves-bump snaps into a dome; the search keeps an inner anchor.
  assert.ok(dep.added_anchors.length >= 1, JSON.stringify(dep.anchor_trial_rms));
  assert.match(await text('summary'), new RegExp(`inner anchors: ${dep.added_anchors.length} added automatically`));
  assert.ok(dep.rms_with_notches < 0.5 * dep.anchor_trial_rms[0]);
  await page.screenshot({ path: path.join(outDir, 'inner-anchors.png') });
  const design = JSON.parse((await downloadJson('download-design')).bytes.toString('utf8'));
  const anchored = JSON.parse((await downloadJson('download-design-anchored-json')).bytes.toString('utf8'));
  assert.deepEqual(anchored.anchors, [...design.anchors, ...dep.added_anchors]);
  // The kit is cut for the anchored design: a support for each inner anchor.
  const [download] = await Promise.all([page.waitForEvent('download', { timeout: 60000 }), byId('kit').click()]);
  const zip = unzipSync(new Uint8Array(readFileSync(await download.path())));
  const supports = Buffer.from(zip['kit/supports.csv']).toString('utf8');
  const inner = anchored.anchors.filter((a) => !a.corner && a.side === -1).length;
  assert.equal(supports.split('\n').filter((l) => l.includes(',inner,')).length, inner, supports);
  assert.ok(inner >= dep.added_anchors.length);
  await byId('auto-anchors').uncheck();
});

/** A small curved height field as OBJ (n x n vertices), optionally far from the origin. */
function smallObj(n = 13, [ox, oy, oz] = [0, 0, 0]) {
  const lines = ['# bump'];
  for (let j = 0; j < n; ++j)
    for (let i = 0; i < n; ++i) {
      const x = i / (n - 1) * 10 - 5, y = j / (n - 1) * 10 - 5;
      lines.push(`v ${x + ox} ${y + oy} ${(1.5 * Math.exp(-(x * x + y * y) / 20) + oz).toFixed(6)}`);
    }
  for (let j = 0; j + 1 < n; ++j)
    for (let i = 0; i + 1 < n; ++i) {
      const a = j * n + i + 1, b = a + 1, c = a + n, d = c + 1;
      lines.push(`f ${a} ${b} ${d}`, `f ${a} ${d} ${c}`);
    }
  return Buffer.from(lines.join('\n') + '\n');
}

const testMeshes = path.join(root, 'tests/data/meshes'); // real meshes with their licence

test('a real mesh (knet1.obj, tests/data) uploaded: Auto corners, design, slider; design.json as the CLI\'s', async () => {
  const file = path.join(testMeshes, 'knet1.obj');
  assert.ok(existsSync(file), `no ${file} (tests/data/meshes of the repository)`);
  await byId('mesh-input').setInputFiles(file);
  await until(async () => /knet1\.obj: 441 vertices, 800 faces \(obj\)/.test(await text('mesh-info')), 15000, 'the real mesh');
  assert.match(await text('mesh-info'), /loader: 400 polygons triangulated/); // knet1 is a quad mesh
  await byId('corners-auto').click();
  await until(async () => /η = /.test(await text('patch-info')), 30000, 'its patch');
  const n = await designCount();
  await byId('design').click();
  await until(async () => (await designCount()) === n + 1, 60000, 'its design');
  const slider = byId('alpha-slider');
  const [min, max] = [Number(await slider.getAttribute('min')), Number(await slider.getAttribute('max'))];
  const alpha = Math.round((min + 0.3 * (max - min)) * 10) / 10;
  await slider.fill(String(alpha));
  await until(async () => (await designCount()) === n + 2, 60000, 'its redesign');
  assert.match(await text('summary'), /distance maps cached: yes/);
  const { bytes } = await downloadJson('download-design');
  assertSameBytes(bytes, await cliDesign('knet1.obj', alpha, testMeshes), 'knet1');
});

let clickedCorners;
async function clickFourCorners(order = [[-1, 1], [1, 1], [1, -1], [-1, -1]]) {
  const box = await byId('viewer').boundingBox();
  // Around the middle of the surface as the default camera shows it (seen from the front, above).
  const cx = box.x + box.width / 2, cy = box.y + box.height * 0.6, r = Math.min(box.width, box.height) * 0.1;
  for (const [dx, dy] of order) {
    await page.mouse.click(cx + dx * r, cy + dy * r);
  }
  assert.equal(await byId('corners-info').getAttribute('data-count'), '4');
}

test('upload a small OBJ, click four corners on the canvas: the patch', async () => {
  await byId('mesh-input').setInputFiles({ name: 'bump.obj', mimeType: 'text/plain', buffer: smallObj() });
  await until(async () => /bump\.obj: 169 vertices, 288 faces \(obj\)/.test(await text('mesh-info')), 15000, 'the uploaded mesh');
  await clickFourCorners();
  await until(async () => /η = /.test(await text('patch-info')), 30000, 'the patch of the clicked corners');
  clickedCorners = (await text('corners-info')).split('\n')[0];
  assert.match(clickedCorners, /1→v\d+, 2→v\d+, 3→v\d+, 4→v\d+/);
  assert.equal(new Set(clickedCorners.match(/v\d+/g)).size, 4);
});

test('click a marker, then the surface: the corner moves and the patch follows', async () => {
  const before = await text('corners-info');
  const patchBefore = await text('patch-info');
  const markers = await until(async () => {
    const m = await byId('viewer').getAttribute('data-markers');
    return m && m.split(';').length === 4 ? m.split(';').map((p) => p.split(',').map(Number)) : null;
  }, 5000, 'the four markers drawn');
  const box = await byId('viewer').boundingBox();
  await page.mouse.click(box.x + markers[0][0], box.y + markers[0][1]);
  assert.match(await text('corners-info'), /moving corner 1/);
  await page.mouse.click(box.x + box.width / 2, box.y + box.height * 0.6); // the middle of the surface
  const after = await text('corners-info');
  assert.notEqual(after.split('\n')[0], before.split('\n')[0]);
  assert.equal(after.split(', ').slice(1).join(), before.split('\n')[0].split(', ').slice(1).join()); // 2..4 stay
  await until(async () => (await text('patch-info')) !== patchBefore && /η = /.test(await text('patch-info')), 30000, 'the new patch');
});

test('an uploaded mesh in the URL: after a reload, opening the same file restores its corners', async () => {
  const corners = (await text('corners-info')).split('\n')[0];
  const hash = new URL(page.url()).hash;
  const digest = createHash('sha256').update(smallObj()).digest('hex').slice(0, 16);
  assert.match(hash, new RegExp(`file=bump\\.obj&sha256=${digest}&corners=`));
  await page.reload();
  await until(async () => /Open bump\.obj again/.test(await text('status')), 10000, 'the request to open the file again');
  await byId('mesh-input').setInputFiles({ name: 'bump.obj', mimeType: 'text/plain', buffer: smallObj() });
  await until(async () => /η = /.test(await text('patch-info')), 30000, 'the restored patch');
  assert.equal((await text('corners-info')).split('\n')[0], corners);
  assert.equal(new URL(page.url()).hash, hash);
});

test('far from the origin (UTM-like coordinates): the same view, the same picked vertices', async () => {
  const shifted = smallObj(13, [2500000, 5600000, 300]);
  await byId('mesh-input').setInputFiles({ name: 'utm.obj', mimeType: 'text/plain', buffer: shifted });
  await until(async () => /utm\.obj: 169 vertices/.test(await text('mesh-info')), 15000, 'the shifted mesh');
  await clickFourCorners();
  assert.equal((await text('corners-info')).split('\n')[0], clickedCorners);
  await until(async () => /η = /.test(await text('patch-info')), 30000, 'the patch far from the origin');
});

test('corners in a bow-tie order: the infeasible patch\'s reason next to the corners', async () => {
  await byId('corners-clear').click();
  allowHttpErrors = true; // the 422
  try {
    await clickFourCorners([[-1, 1], [1, -1], [1, 1], [-1, -1]]);
    await until(() => byId('error').isVisible(), 30000, 'the infeasible patch');
  } finally {
    allowHttpErrors = false;
  }
  assert.match(await text('error'), /FAILED_PRECONDITION.*corners: .*not a simple quadrilateral/s);
  assert.match(await page.locator('.field-error[data-for=corners]').textContent(), /^corners: .*cross/);
  assert.equal(await text('patch-info'), '');
  assert.ok(await byId('legend').isHidden());
  assert.ok(await byId('design').isDisabled());
});

/** A binary STL of an n x n height field: 2 (n-1)^2 triangles. */
function bigStl(n) {
  const tris = 2 * (n - 1) * (n - 1);
  const buf = Buffer.alloc(84 + 50 * tris);
  buf.writeUInt32LE(tris, 80);
  const z = (x, y) => 3 * Math.sin(x / 7) * Math.cos(y / 9);
  let o = 84;
  const put = (...p) => { for (const v of p) { buf.writeFloatLE(v, o); o += 4; } };
  for (let j = 0; j + 1 < n; ++j)
    for (let i = 0; i + 1 < n; ++i) {
      const a = [i, j, z(i, j)], b = [i + 1, j, z(i + 1, j)], c = [i, j + 1, z(i, j + 1)], d = [i + 1, j + 1, z(i + 1, j + 1)];
      for (const t of [[a, b, d], [a, d, c]]) { put(0, 0, 0); for (const p of t) put(...p); o += 2; }
    }
  return buf;
}

test('a 250k-triangle STL loads and picks (times printed)', async () => {
  const stl = bigStl(355); // 250,632 triangles, 12.5 MB
  const t0 = Date.now();
  await byId('mesh-input').setInputFiles({ name: 'big.stl', mimeType: 'application/octet-stream', buffer: stl });
  await until(async () => /big\.stl: 126025 vertices, 250632 faces \(stl\)/.test(await text('mesh-info')), 60000, 'the big mesh');
  console.log(`# 250k-triangle STL: upload + load + BVH + first frame ${Date.now() - t0} ms`);
  const box = await byId('viewer').boundingBox();
  const times = [];
  for (const [i, [dx, dy]] of [[0, 0], [-0.1, 0.05], [0.1, 0.05], [0.05, -0.05]].entries()) {
    await page.mouse.click(box.x + box.width * (0.5 + dx), box.y + box.height * (0.6 + dy));
    const ms = await byId('corners-info').getAttribute('data-pick-ms');
    assert.ok(ms !== null && Number.isFinite(Number(ms)), 'a surface pick');
    times.push(Number(ms));
    assert.equal(await byId('corners-info').getAttribute('data-count'), String(i + 1));
  }
  console.log(`# pick on 250k triangles (raycast + snap): ${times.map((t) => t.toFixed(1)).join(', ')} ms`);
  // Its patch takes long (geodesics on 126k vertices): Cancel stops it in the daemon.
  const cancelled = (daemonLog().match(/CANCELLED/g) ?? []).length;
  await until(() => byId('cancel').isEnabled(), 5000, 'Cancel enabled during the patch');
  // Progress from the kernel's SSE stream: stage name and percentage, the bar moving.
  await until(async () => /^patch: .+ \(\d+%\)$/.test(await text('status')), 10000, 'patch progress');
  await byId('cancel').click();
  await until(async () => /patch: cancelled/.test(await text('status')), 5000, 'the cancelled patch');
  await until(() => (daemonLog().match(/CANCELLED/g) ?? []).length > cancelled, 5000, 'the daemon to cancel the patch');
});

test('drag and drop of a mesh file loads it', async () => {
  const dataTransfer = await page.evaluateHandle((obj) => {
    const dt = new DataTransfer();
    dt.items.add(new File([obj], 'dropped.obj', { type: 'text/plain' }));
    return dt;
  }, smallObj(7).toString());
  await page.dispatchEvent('#drop', 'drop', { dataTransfer });
  await until(async () => /dropped\.obj: 49 vertices, 72 faces \(obj\)/.test(await text('mesh-info')), 15000, 'the dropped mesh');
  assert.equal(await byId('corners-info').getAttribute('data-count'), '0');
});

test('a mesh the loader repairs: its repairs and warnings, as the daemon reports them', async () => {
  const lines = [];
  for (let j = 0; j < 5; ++j) for (let i = 0; i < 5; ++i) lines.push(`v ${i} ${j} ${0.1 * i * j}`);
  lines.push('v 9 9 9', 'v 0 0 0'); // an isolated vertex, a duplicate of vertex 1
  for (let j = 0; j < 4; ++j) for (let i = 0; i < 4; ++i) { const a = j * 5 + i + 1; lines.push(`f ${a} ${a + 1} ${a + 6} ${a + 5}`); }
  lines.push('f 1 2 2'); // degenerate
  const bytes = Buffer.from(lines.join('\n') + '\n');
  const loaded = await (await fetch(base + 'v1/load', {
    method: 'POST', headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify({ mesh: { file: bytes.toString('base64'), format: 'obj' } }),
  })).json();
  assert.equal(loaded.report.warnings.length, 3, JSON.stringify(loaded.report));
  await byId('mesh-input').setInputFiles({ name: 'repairs.obj', mimeType: 'text/plain', buffer: bytes });
  await until(async () => /repairs\.obj: 25 vertices, 32 faces/.test(await text('mesh-info')), 15000, 'the repaired mesh');
  assert.match(await text('mesh-info'), /loader: 16 polygons triangulated, 1 duplicate vertices merged, 1 degenerate faces removed, 1 isolated vertices removed/);
  const shown = await text('warnings');
  for (const w of loaded.report.warnings) assert.ok(shown.includes(w), `warning shown: ${w}\n${shown}`);
});

test('a broken mesh file shows the daemon\'s error with its field', async () => {
  const broken = Buffer.from('v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n');
  const direct = await (await fetch(base + 'v1/load', {
    method: 'POST', headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify({ mesh: { name: 'broken.obj', file: broken.toString('base64'), format: 'obj' } }),
  })).json();
  assert.ok(direct.error?.message, JSON.stringify(direct));
  allowHttpErrors = true;
  try {
    await byId('mesh-input').setInputFiles({ name: 'broken.obj', mimeType: 'text/plain', buffer: broken });
    await until(() => byId('error').isVisible(), 10000, 'the error message');
  } finally {
    allowHttpErrors = false;
  }
  const shown = await text('error');
  assert.ok(shown.includes(direct.error.message), `page: ${shown}\ndaemon: ${direct.error.message}`);
  if (direct.error.field) assert.ok(shown.includes(direct.error.field), shown);
  const slot = await page.locator('.field-error[data-for=mesh]').textContent();
  assert.ok(slot.includes(direct.error.message), `next to the file input: ${slot}`);
  // The page stays usable: the previous mesh is still there.
  assert.match(await text('mesh-info'), /repairs\.obj/);
});

test('a daemon with a token: the page asks for it and keeps it in sessionStorage only', async () => {
  const dir = mkdtempSync(path.join(tmpdir(), 'gridshell-token-'));
  const token = 'web-e2e-' + Math.random().toString(36).slice(2);
  writeFileSync(path.join(dir, 'token'), token + '\n', { mode: 0o600 });
  const other = await startDaemon(['--token-file', path.join(dir, 'token')]);
  daemons.push(other.proc);
  const tab = await page.context().newPage();
  allowHttpErrors = true; // the 401 before the token is given
  try {
    await tab.goto(`http://${other.address}/`);
    await until(() => tab.locator('#token-box').isVisible(), 10000, 'the token field');
    assert.match(await tab.getByTestId('error').textContent(), /UNAUTHENTICATED/);
    await tab.locator('#token').fill(token);
    await tab.locator('#token-save').click();
    await until(() => tab.evaluate(() => Number(document.querySelector('[data-testid=example-select]').dataset.loaded ?? 0)),
                10000, 'the examples with the token');
    // The options' description too, asked for again with the token: the form is built.
    await until(() => tab.evaluate(() => Number(document.body.dataset.options ?? 0) > 0), 10000, 'the form with the token');
    assert.ok(await tab.getByTestId('material').locator('option').count() > 1);
    assert.equal(await tab.evaluate(() => sessionStorage.getItem('gridshell.token')), token);
    assert.equal(await tab.evaluate(() => localStorage.length), 0);
    assert.ok(!tab.url().includes(token));
  } finally {
    allowHttpErrors = false;
    await tab.close();
    await stopDaemon(other.proc);
    rmSync(dir, { recursive: true, force: true });
  }
});

test('a site\'s material library (GRIDSHELL_MATERIALS): its material is listed, simulated and reported', async () => {
  const dir = mkdtempSync(path.join(tmpdir(), 'gridshell-materials-'));
  const library = path.join(dir, 'lib.json');
  writeFileSync(library, JSON.stringify({ materials: [{ name: 'test-larch', label: 'test larch', young_modulus: 1.1e10,
    shear_modulus: 0.7e9, bending_strength: 7.0e7, shear_strength: 8e6, source: 'test' }] }));
  const other = await startDaemon([], '127.0.0.1:0', { GRIDSHELL_MATERIALS: library });
  daemons.push(other.proc);
  const url = `http://${other.address}/`;
  const tab = await page.context().newPage();
  tab.setDefaultTimeout(20000);
  tab.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(`materials tab: ${m.text()}`); });
  tab.on('pageerror', (e) => consoleErrors.push(`materials tab: pageerror: ${e.message}`));
  try {
    const d = await describedOptions(url);
    const builtIn = (await describedOptions()).materials.map((m) => m.name);
    assert.deepEqual(d.materials.map((m) => m.name), [...builtIn, 'test-larch']); // after the built-in ones
    await tab.goto(url);
    await until(() => tab.evaluate(() => document.body.dataset.ready === '1'), 15000, 'the page on the second daemon');
    const material = tab.getByTestId('material');
    const listed = await material.locator('option').evaluateAll((os) => os.map((o) => [o.value, o.textContent, o.title]));
    assert.deepEqual(listed.slice(0, d.materials.length).map(([v, l]) => [v, l]), d.materials.map((m) => [m.name, m.label]));
    assert.ok(listed.some(([v, l, t]) => v === 'test-larch' && l === 'test larch' && /^E = 11 GPa, G = 0\.7 GPa/.test(t)), JSON.stringify(listed));
    assert.equal(await material.inputValue(), builtIn[0]); // the default: the first
    // A small design on an example, simulated in test larch.
    const examples = await tab.getByTestId('example-select').locator('option').evaluateAll((os) => os.map((o) => o.value).filter(Boolean));
    await tab.getByTestId('example-select').selectOption(examples.includes('double-vault') ? 'double-vault' : examples[0]);
    await until(() => tab.evaluate(() => document.querySelector('[data-testid=mesh-info]').dataset.ready === '1'), 15000, 'the example');
    await tab.getByTestId('members-u').fill('4');
    await tab.getByTestId('members-v').fill('4');
    await tab.getByTestId('corners-auto').click();
    await until(async () => /η = /.test(await tab.getByTestId('patch-info').textContent()), 30000, 'the patch');
    await tab.getByTestId('design').click();
    await until(() => tab.getByTestId('simulate').isEnabled(), 60000, 'the design');
    await material.selectOption('test-larch');
    assert.match(tab.url(), /simulation\.material=test-larch/);
    const sent = [];
    const onRequest = (r) => { if (r.url().endsWith('/v1/simulate')) sent.push(JSON.parse(r.postData()).options); };
    tab.on('request', onRequest);
    await tab.getByTestId('simulate').click();
    await until(async () => /RMS/.test(await tab.getByTestId('summary').textContent()), 120000, 'the simulation in test larch');
    tab.off('request', onRequest);
    assert.deepEqual(sent, [{ material: 'test-larch' }]); // by field name, only what differs from the defaults
    assert.match(await tab.getByTestId('summary').textContent(), /material test-larch: E = 11 GPa, bending strength 70 MPa, shear strength 8 MPa/);
    const dep = JSON.parse((await downloadJson('download-deployment', tab)).bytes.toString('utf8'));
    assert.equal(dep.options.material, 'test-larch');
    assert.equal(dep.options.young_modulus, 1.1e10);
    assert.equal(dep.options.shear_modulus, 0.7e9);
    assert.equal(dep.options.bending_strength, 7.0e7);
  } finally {
    await tab.close();
    await stopDaemon(other.proc);
    rmSync(dir, { recursive: true, force: true });
  }
});

// ---- several patches (the layout section, issue 35) -----------------------------------------------
// In a tab of its own, so that the main page's state (the mesh the last tests expect) stays.

let lt;           // the layout tab
let knetLayout;   // the daemon's LayoutResult for the page's automatic-layout request
const ltId = (id) => lt.getByTestId(id);
const ltText = (id) => ltId(id).textContent();
/** The legend's number format (colormap.ts formatNumber): 3 significant digits, exponent when far from 1. */
const fmt = (v) => (v === 0 ? '0' : Math.abs(v) >= 1e4 || Math.abs(v) < 1e-2 ? v.toExponential(2) : String(Number(v.toPrecision(3))));

async function postJson(method, body) {
  const r = await fetch(base + 'v1/' + method, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body,
                                                 signal: AbortSignal.timeout(60000) });
  return { status: r.status, json: await r.json() };
}

/** The request bodies the tab sends to /v1/METHOD while `action` runs. */
async function requestsDuring(method, action) {
  const seen = [];
  const onRequest = (r) => { if (r.url().endsWith(`/v1/${method}`)) seen.push(r.postData()); };
  lt.on('request', onRequest);
  try {
    await action();
  } finally {
    lt.off('request', onRequest);
  }
  return seen;
}

async function ltDownload(testid) {
  const [download] = await Promise.all([lt.waitForEvent('download', { timeout: 10000 }), ltId(testid).click()]);
  return { name: download.suggestedFilename(), bytes: readFileSync(await download.path()) };
}

const tableRows = (testid) => ltId(testid).locator('tbody tr').evaluateAll((trs) => trs.map((tr) => [...tr.cells].map((td) => td.textContent)));
const canvasData = (key) => ltId('viewer').evaluate((c, k) => c.dataset[k], key);
/** Waits for the canvas's hook (published after the next frame) to be `value`. */
const canvasIs = (key, value) => until(async () => (await canvasData(key)) === value, 5000, `canvas data-${key} = ${value}`);
/** A result without its timings (a second computation takes other seconds). */
const untimed = (x) => JSON.parse(JSON.stringify(x, (k, v) => (k === 'seconds' ? undefined : v)));

test('layout: knet1.obj uploaded in a tab of its own; an out-of-range "patches at most" shows the daemon\'s error next to it', async () => {
  lt = await page.context().newPage();
  lt.setDefaultTimeout(20000);
  lt.on('console', (m) => {
    if (m.type() !== 'error') return;
    if (allowHttpErrors && /Failed to load resource: the server responded with a status of 4\d\d/.test(m.text())) return;
    consoleErrors.push(`layout tab: ${m.text()}`);
  });
  lt.on('pageerror', (e) => consoleErrors.push(`layout tab: pageerror: ${e.message}`));
  await lt.goto(base);
  await until(() => lt.evaluate(() => document.body.dataset.ready === '1'), 15000, 'the layout tab');
  // The two layout controls come from the description (group "layout"), with its range and default.
  const described = (await describedOptions()).options.filter((o) => o.group === 'layout' && !o.output);
  assert.deepEqual(described.map((o) => o.name).sort(), ['coverage_goal', 'max_patches']);
  const max = described.find((o) => o.name === 'max_patches');
  assert.ok(await ltId('layout-options').locator('[data-option="layout.max_patches"]').count() === 1, 'in the layout section');
  assert.equal(await ltId('max-patches').inputValue(), max.default_value);
  assert.equal(await ltId('max-patches').getAttribute('max'), String(max.maximum));
  await ltId('mesh-input').setInputFiles(path.join(testMeshes, 'knet1.obj'));
  await until(async () => /knet1\.obj: 441 vertices/.test(await ltText('mesh-info')), 15000, 'knet1 in the layout tab');
  assert.ok(await ltId('layout-auto').isEnabled());
  assert.ok(await ltId('layout-build').isDisabled(), 'nothing to build before a layout');
  const slot = lt.locator('.field-error[data-for="layout.max_patches"]');
  allowHttpErrors = true;
  try {
    await ltId('max-patches').fill(String(max.maximum + 36));
    // At once, from the description: the input is invalid and says why, naming the request's field.
    assert.equal(await ltId('max-patches').evaluate((i) => i.validity.valid), false);
    assert.match(await slot.textContent(), /^automatic\.max_patches: must be in \[1, 64\]/);
    await ltId('layout-auto').click();
    await until(() => ltId('error').isVisible(), 15000, 'the error of the bad max_patches');
  } finally {
    allowHttpErrors = false;
  }
  const shown = await ltText('error');
  assert.match(shown, /^layout failed \(INVALID_ARGUMENT\): automatic\.max_patches: .*got 100$/);
  assert.equal(await slot.textContent(), shown.replace(/^layout failed \(INVALID_ARGUMENT\): /, ''));
  assert.equal(await ltText('layout-info'), '');
  await canvasIs('layoutPatches', '0');
  assert.ok(await ltId('layout-build').isDisabled());
  assert.match(await lt.evaluate(() => location.hash), /layout\.max_patches=100/); // kept with the other options
  await ltId('max-patches').fill(max.default_value); // the default again: not sent, not in the URL
  assert.doesNotMatch(await lt.evaluate(() => location.hash), /max_patches/);
});

test('layout: Automatic layout (knet1.obj) draws the daemon\'s patches in colours, the seams, the table, coverage, uncovered regions and trials', async () => {
  const sent = await requestsDuring('layout', async () => {
    await ltId('layout-auto').click();
    await until(() => lt.evaluate(() => document.querySelector('[data-testid=layout-info]').dataset.ready === '1'), 30000, 'the layout');
  });
  assert.equal(sent.length, 1);
  const body = JSON.parse(sent[0]);
  assert.deepEqual(body.automatic, {}); // the defaults: nothing off them
  assert.equal(body.layout, undefined);
  assert.equal(body.mesh.name, 'knet1.obj');
  const direct = await postJson('layout', sent[0]); // the same request, answered without an event stream
  assert.equal(direct.status, 200);
  knetLayout = direct.json;
  const r = knetLayout.report;
  assert.equal(r.patches.length, 20); // docs/multi-patch.md: 5 × 4, 95.4 %
  // Drawn: one coloured surface per cut patch, the seams, over the faded mesh; the table one row per patch.
  await canvasIs('layoutPatches', String(knetLayout.patches.filter((p) => (p.indices ?? []).length).length));
  await canvasIs('layers', 'mesh,layout');
  const rows = await tableRows('layout-patches');
  assert.deepEqual(rows.map((row) => row[0]), r.patches.map((p) => p.name));
  assert.deepEqual(rows.map((row) => row[1]), r.patches.map((p) => (p.ok ? 'ok' : p.problem ? `${p.problem_field}: ${p.problem}`.replace(/^: /, '') : 'failed')));
  assert.deepEqual(rows.map((row) => row[2]), r.patches.map((p) => fmt(p.area)));
  assert.deepEqual(rows.map((row) => row[3]), r.patches.map((p) => p.eta.toFixed(5)));
  const info = await ltText('layout-info');
  assert.ok(info.startsWith(`coverage ${(100 * r.coverage).toFixed(1)} %: `), info);
  assert.match(info, /^coverage 95\.4 %/);
  assert.match(info, new RegExp(`20 patches \\(20 ok\\), ${r.seams.filter((x) => x.patches.length === 2).length} seams`));
  assert.match(info, new RegExp(`automatic: ${r.automatic.columns} × ${r.automatic.rows} grid, ${r.automatic.trials.length} trials`));
  const uncovered = await ltText('layout-uncovered');
  assert.ok(r.uncovered.length > 0);
  for (const u of r.uncovered) assert.ok(uncovered.includes(`${u.where}: ${fmt(u.area)} `) && uncovered.includes(u.reason), uncovered);
  const trials = await tableRows('layout-trials');
  // A trial checked in full shows its coverage, one only cut the bound that missed the goal.
  assert.deepEqual(trials.map((t) => [t[0], t[2]]), r.automatic.trials.map((t) => [`${t.columns} × ${t.rows}`,
    t.checked ? `${(100 * t.coverage).toFixed(1)} %` : `≤ ${(100 * t.cut_coverage).toFixed(1)} %`]));
  assert.ok(await ltId('layout-build').isEnabled());
  // layout.json is the report, and `gridshell layout` takes it back: the same patches, the same coverage.
  const { name, bytes } = await ltDownload('layout-download-layout-json');
  assert.equal(name, 'layout.json');
  const report = JSON.parse(bytes.toString('utf8'));
  assert.deepEqual(untimed(report), untimed(r));
  const dir = mkdtempSync(path.join(tmpdir(), 'gridshell-layout-'));
  try {
    writeFileSync(path.join(dir, 'layout.json'), bytes);
    const cli = spawnSync(cliPath, ['layout', path.join(testMeshes, 'knet1.obj'), '--layout', path.join(dir, 'layout.json'),
                                    '--out', path.join(dir, 'out'), '--quiet'], { encoding: 'utf8', timeout: 60000 });
    assert.equal(cli.status, 0, cli.stderr);
    const again = JSON.parse(readFileSync(path.join(dir, 'out/layout.json'), 'utf8'));
    assert.deepEqual(again.layout, report.layout);
    assert.ok(Math.abs(again.coverage - report.coverage) < 1e-12, `${again.coverage} vs ${report.coverage}`);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test('layout: Cancel stops "Build all patches": the daemon cancels, the page is idle, nothing is drawn', async () => {
  const before = (daemonLog().match(/CANCELLED/g) ?? []).length;
  await ltId('layout-build').click(); // the default member counts: seconds of work on 20 patches
  await until(() => ltId('cancel').isEnabled(), 5000, 'Cancel enabled');
  await until(async () => /^build: .+ \(\d+%\)$/.test(await ltText('status')), 15000, 'progress of the build');
  await ltId('cancel').click();
  await until(async () => /^build: cancelled$/.test(await ltText('status')), 5000, 'the cancelled status');
  assert.ok(await ltId('cancel').isDisabled());
  await until(() => (daemonLog().match(/CANCELLED/g) ?? []).length > before, 10000, 'the daemon to log the cancellation');
  assert.equal(await ltText('layout-summary'), '');
  assert.ok(await ltId('layout-run').isHidden());
  assert.ok(await ltId('error').isHidden());
  await canvasIs('layers', 'mesh,layout'); // the layout still drawn, no lamellas
  await canvasIs('layoutLamellas', '0');
  assert.equal(await ltId('layout-downloads').locator('[data-testid=layout-download-deployment-json]').count(), 0);
  assert.ok(await ltId('layout-build').isEnabled(), 'the page stays usable');
});

test('layout: "Build all patches" (knet1, 3 × 3 members): the deployed whole, one row per patch, its RMS and seams as deployment.json says, downloads', async () => {
  await ltId('members-u').fill('3');
  await ltId('members-v').fill('3');
  const sent = await requestsDuring('runlayout', async () => {
    await ltId('layout-build').click();
    await until(() => lt.evaluate(() => document.querySelector('[data-testid=layout-summary]').dataset.ready === '1'), 90000, 'the build');
  });
  assert.equal(sent.length, 1);
  const body = JSON.parse(sent[0]);
  assert.deepEqual(body.layout, knetLayout.report.layout); // the layout found, sent as it is
  assert.deepEqual(body.design, { members_u: 3, members_v: 3 });
  assert.deepEqual(body.simulation, {});
  const dep = JSON.parse((await ltDownload('layout-download-deployment-json')).bytes.toString('utf8'));
  const design = JSON.parse((await ltDownload('layout-download-design-json')).bytes.toString('utf8'));
  assert.equal(dep.patches.length, 20);
  const summary = await ltText('layout-summary');
  const pct = (x) => `${(100 * (x / dep.diagonal)).toFixed(3)} % of the diagonal`;
  assert.ok(summary.includes(`whole RMS with notches ${fmt(dep.rms_with_notches)} (${pct(dep.rms_with_notches)})`), summary);
  assert.ok(summary.includes(`whole RMS without notches ${fmt(dep.rms_without_notches)} (${pct(dep.rms_without_notches)})`), summary);
  assert.ok(summary.includes(`seam bolts ${design.seam_bolts} on ${design.seams.length} seams`), summary);
  assert.ok(design.seam_bolts > 0);
  assert.equal(dep.seams_joined, true);
  assert.ok(summary.includes(`largest seam gap ${fmt(dep.max_seam_gap)} (${pct(dep.max_seam_gap)}) after joining, ` +
                             `${fmt(dep.max_seam_gap_before_joining)} (${pct(dep.max_seam_gap_before_joining)}) before`), summary);
  assert.ok(summary.includes(`largest bolt force ${fmt(dep.max_bolt_force)} ${dep.force_unit}`), summary);
  assert.ok(summary.includes(`whole joined with notches: ${dep.joined_with_notches.iterations} iterations`), summary);
  assert.equal(await ltId('layout-nonconverged').isVisible(), dep.converged === false);
  assert.match(summary, dep.converged ? /every run of every patch and of the whole converged/ : /NOT converged/);
  const rows = await tableRows('layout-run');
  assert.deepEqual(rows, dep.patches.map((p) => [p.name, String(p.grid_vertices), fmt(p.rms_with_notches), fmt(p.rms_without_notches),
                                                 p.converged ? 'yes' : 'NO']));
  // Drawn: every patch's lamellas in the joined whole on one deviation scale, over the layout.
  await canvasIs('layers', 'mesh,layout,layout-deployment');
  assert.ok(Number(await canvasData('layoutLamellas')) >= 20 * 4, await canvasData('layoutLamellas'));
  assert.ok(await ltId('deviation-legend').isVisible());
  // The whole's files: deployed.obj and deviation.ply as the daemon wrote them, run.zip with every patch's folder.
  const obj = (await ltDownload('layout-download-deployed-obj')).bytes.toString('utf8');
  assert.match(obj, /^o P1-/m);
  assert.match(obj, /^o P20-/m);
  assert.match((await ltDownload('layout-download-deviation-ply')).bytes.toString('latin1'), /^ply\n/);
  const { unzipSync } = createRequire(path.join(web, 'package.json'))('fflate');
  const zip = unzipSync(new Uint8Array((await ltDownload('layout-download-run-zip')).bytes));
  assert.deepEqual(JSON.parse(Buffer.from(zip['run/deployment.json']).toString('utf8')), dep);
  const folders = new Set(Object.keys(zip).filter((k) => k.startsWith('run/patches/')).map((k) => k.split('/')[2]));
  assert.equal(folders.size, 20);
  assert.ok(zip['run/patches/P7/design.json'] && zip['run/patches/P7/deployment.json'], Object.keys(zip).join(' '));
  mkdirSync(outDir, { recursive: true });
  await lt.screenshot({ path: path.join(outDir, 'layout-deployment.png') }); // for a person to look at; nothing asserted on it
});

test('layout: a layout file (the sphere example in 2 × 2 patches) is cut as given; a bad one names its field', async () => {
  await ltId('example-select').selectOption('sphere');
  await until(async () => /^sphere: \d+ vertices/.test(await ltText('mesh-info')), 15000, 'the sphere');
  await canvasIs('layers', 'mesh'); // a new surface: the layout is gone
  assert.equal(await ltText('layout-summary'), '');
  const corners = [];
  for (const j of [0, 16, 32]) for (const i of [0, 16, 32]) corners.push({ vertex: j * 33 + i });
  const layout = { corners, patches: [{ corners: [0, 1, 4, 3] }, { corners: [1, 2, 5, 4] }, { name: 'north-west', corners: [3, 4, 7, 6] },
                                      { corners: [4, 5, 8, 7] }] };
  await ltId('layout-input').setInputFiles({ name: 'sphere-2x2.json', mimeType: 'application/json', buffer: Buffer.from(JSON.stringify(layout)) });
  await until(() => lt.evaluate(() => document.querySelector('[data-testid=layout-info]').dataset.ready === '1'), 30000, 'the layout from the file');
  await canvasIs('layoutPatches', '4');
  assert.deepEqual((await tableRows('layout-patches')).map((r) => [r[0], r[1]]), [['P1', 'ok'], ['P2', 'ok'], ['north-west', 'ok'], ['P4', 'ok']]);
  assert.match(await ltText('layout-info'), /^coverage 100\.0 %.*\n4 patches \(4 ok\), 4 seams \(largest mismatch 0\), 9 corners$/);
  assert.ok(await ltId('layout-trials-box').isHidden(), 'a layout file has no automatic trials');
  assert.equal(await ltText('layout-uncovered'), 'not covered: nothing');
  // Built (3 × 3 members, from the test before) in cm: the kit of the whole, one Fabricate, as kit.zip.
  await ltId('unit').selectOption('cm');
  await ltId('layout-build').click();
  await until(() => lt.evaluate(() => document.querySelector('[data-testid=layout-summary]').dataset.ready === '1'), 60000, 'the sphere built');
  assert.equal((await tableRows('layout-run')).length, 4);
  assert.match(await ltText('layout-summary'), /^4 of 4 patches built/);
  const { unzipSync } = createRequire(path.join(web, 'package.json'))('fflate');
  const [download] = await Promise.all([lt.waitForEvent('download', { timeout: 60000 }), ltId('layout-kit').click()]);
  assert.equal(download.suggestedFilename(), 'kit.zip');
  const kit = unzipSync(new Uint8Array(readFileSync(await download.path())));
  for (const name of ['kit/kit.json', 'kit/joining.svg', 'kit/bom.csv', 'kit/assembly-north-west.svg', 'kit/sheets/sheet-01.dxf'])
    assert.ok(kit[name], `${name} in ${Object.keys(kit).join(' ')}`);
  assert.match(await ltText('layout-summary'), /kit: \d+ lamellas on \d+ sheet/);
  // One patch's own ᾱ: P2 at the top of its feasible range, redesigned alone from the daemon's
  // cache (the build kept every patch's work), then the whole built again with that choice.
  assert.ok(await ltId('layout-patch-box').isVisible());
  await ltId('layout-patch').selectOption('P2');
  await ltId('layout-patch-alpha').evaluate((e) => { e.value = '1000'; e.dispatchEvent(new Event('input')); e.dispatchEvent(new Event('change')); });
  await until(() => lt.evaluate(() => document.querySelector('[data-testid=layout-patch-info]').dataset.ready === '1'), 30000, 'P2 redesigned');
  const info = await ltText('layout-patch-info');
  assert.match(info, /^P2: ᾱ [\d.]+°, \d+ × \d+ inner members, \d+ crossings — \d+ ms, patch work cached; Build all patches/);
  const shown = /–([\d.]+)°\)$/.exec(await ltText('layout-patch-alpha-value'));
  assert.ok(shown, await ltText('layout-patch-alpha-value'));
  const alphaBar = Number(await lt.evaluate(() => document.querySelector('[data-testid=layout-patch-info]').dataset.alphaBar));
  assert.ok(Math.abs(alphaBar * 180 / Math.PI - Number(shown[1])) < 0.01, `${alphaBar} rad against the range's top ${shown[1]}°`);
  await ltId('layout-build').click();
  await until(() => lt.evaluate(() => document.querySelector('[data-testid=layout-summary]').dataset.ready === '1'), 60000, 'built again');
  const runFiles = unzipSync(new Uint8Array((await ltDownload('layout-download-run-zip')).bytes));
  const p2 = JSON.parse(new TextDecoder().decode(runFiles['run/patches/P2/design.json']));
  assert.equal(p2.alpha_bar, alphaBar);
  assert.equal(JSON.parse(new TextDecoder().decode(runFiles['run/layout.json'])).layout.patches[1].alpha, String(alphaBar));
  // Drag a corner: the middle one (4, shared by all four patches) to a clicked vertex. The layout
  // is cut again and every patch at it follows; P2 keeps its own ᾱ.
  await ltId('layout-corner').selectOption('4');
  const view = await ltId('viewer').boundingBox();
  await lt.mouse.click(view.x + view.width * 0.54, view.y + view.height * 0.48);
  await until(() => lt.evaluate(() => document.querySelector('[data-testid=layout-info]').dataset.ready === '1'), 30000, 'the layout cut again');
  assert.match(await ltText('layout-info'), /\n4 patches \(4 ok\), 4 seams \(largest mismatch 0\), 9 corners$/);
  const moved = JSON.parse(new TextDecoder().decode((await ltDownload('layout-download-layout-json')).bytes)).layout;
  assert.equal(typeof moved.corners[4].vertex, 'number');
  assert.notEqual(moved.corners[4].vertex, 16 * 33 + 16, 'the corner moved');
  assert.deepEqual(moved.corners.map((c) => c.vertex).filter((_, k) => k !== 4), layout.corners.map((c) => c.vertex).filter((_, k) => k !== 4));
  assert.equal(moved.patches[1].alpha, String(alphaBar));
  assert.equal(await ltId('layout-corner').inputValue(), '');
  const bad = { ...layout, patches: layout.patches.map((p, i) => (i === 1 ? { corners: [1, 2, 5, 12] } : p)) };
  allowHttpErrors = true;
  try {
    await ltId('layout-input').setInputFiles({ name: 'bad.json', mimeType: 'application/json', buffer: Buffer.from(JSON.stringify(bad)) });
    await until(() => ltId('error').isVisible(), 15000, 'the error of the bad layout');
  } finally {
    allowHttpErrors = false;
  }
  assert.match(await ltText('error'), /INVALID_ARGUMENT.*layout\.patches\[1\]\.corners\[3\]: corner 12 is out of range/);
  assert.match(await lt.locator('.field-error[data-for=layout]').textContent(), /^layout\.patches\[1\]\.corners\[3\]: corner 12/);
  await canvasIs('layoutPatches', '0');
  await ltId('layout-input').setInputFiles({ name: 'notes.json', mimeType: 'application/json', buffer: Buffer.from('{"members": []}') });
  await until(async () => /notes\.json: no layout in it/.test(await lt.locator('.field-error[data-for=layout]').textContent()), 5000,
              'the file that holds no layout');
  await lt.close();
});

test('no console errors, no traffic off loopback', () => {
  assert.deepEqual(consoleErrors, []);
  assert.deepEqual(foreignRequests, []);
});

// After the check above: the refused connections are logged by Chromium.
// The new daemon binds the address the kernel gave the first one (port 0 at its start), once the
// page's first call was refused.
test('the daemon restarted during a call: the page retries and gets the answer (docs/api.md, Retries)', async () => {
  await stopDaemon(daemon);
  let attempts = 0;
  const count = (request) => { if (request.url().endsWith('/v1/patch')) ++attempts; };
  let refusedOnce;
  const refused = new Promise((r) => { refusedOnce = r; });
  const failed = (request) => { if (request.url().endsWith('/v1/patch')) refusedOnce(); };
  page.on('request', count);
  page.on('requestfailed', failed);
  try {
    await byId('corners-auto').click(); // refused at first; retried with back-off until the new daemon answers
    await refused;
    ({ proc: daemon, log: daemonLog } = await startDaemon([], address));
    daemons.push(daemon);
    await until(async () => /^patch: done/.test(await text('status')), 60000, 'the patch after the retries');
  } finally {
    page.off('request', count);
    page.off('requestfailed', failed);
  }
  assert.ok(attempts >= 2, `${attempts} patch calls`);
  assert.equal(await byId('error').isVisible(), false);
  assert.match(await text('patch-info'), /η = /);
});

// Last: stopping the daemon makes Chromium log the refused connection, after the check above.
test('the daemon gone: a message, and the page stays', async () => {
  await stopDaemon(daemon);
  await byId('corners-auto').click();
  // After the retries (docs/api.md: 5, 3.9-7.75 s of waiting in all).
  await until(() => byId('error').isVisible(), 30000, 'the error');
  assert.match(await text('error'), /UNAVAILABLE.*cannot be reached/);
  assert.match(await text('mesh-info'), /repairs\.obj/);
  assert.ok((await canvasCoverage()) > 0.05, 'the view is still drawn');
});
