// SPDX-License-Identifier: GPL-3.0-or-later
// How the page copes with a large deployment (issue 36): the time from Simulate to the first
// frame with the lamellas drawn, the JS heap, and the frame time while orbiting, in headless
// Chromium with SwiftShader (a software renderer: every triangle is rasterised on the CPU).
//
//   node client/web/bench/frame-time.mjs RUN_DIR [--dist DIR]... [--members N] [--frames N] [--repeats N]
//
// RUN_DIR is the output of `gridshell run` (deployment.json, deployed.obj, deviation.ply and their
// *_without_notches twins), e.g. of
//   gridshell run example:double-vault --members-u 100 --members-v 100 --lamella-width 0.1 --out RUN_DIR
// The page (each --dist, default client/web/dist; several are measured alternately, in the same
// run) is served by a real gridshelld (GRIDSHELLD, default build/gridshelld) behind a small
// proxy that answers POST /v1/simulate with that run's deployment and files, as the daemon's
// event stream would, so the 10-minute simulation is not repeated. The page designs
// example:double-vault with the example's corners and N x N members on the real daemon, then
// Simulate is clicked. Frame time: a pointer drag rotates the camera by a few pixels every
// animation frame (the events OrbitControls listens to), and the rAF timestamps of that many
// frames give the intervals; median and 95th percentile. Prints a Markdown table.
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';
import { existsSync, readFileSync, readdirSync } from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import os from 'node:os';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../..');
const web = path.join(root, 'client/web');
const { chromium } = createRequire(path.join(web, 'package.json'))('playwright-core');

const args = process.argv.slice(2);
const runDir = args.find((a, i) => !a.startsWith('--') && !(i > 0 && args[i - 1].startsWith('--')));
const opt = (name, fallback) => {
  const i = args.indexOf(`--${name}`);
  return i >= 0 ? args[i + 1] : fallback;
};
const dists = args.flatMap((a, i) => (a === '--dist' ? [path.resolve(args[i + 1])] : []));
if (dists.length === 0) dists.push(path.join(web, 'dist'));
const members = Number(opt('members', 100));
const frames = Number(opt('frames', 120));
const repeats = Number(opt('repeats', 1));
const daemonPath = process.env.GRIDSHELLD ?? path.join(root, 'build/gridshelld');
if (!runDir || !existsSync(path.join(runDir, 'deployment.json'))) {
  console.error('usage: node client/web/bench/frame-time.mjs RUN_DIR [--dist DIR]... [--members N] [--frames N] [--repeats N]');
  process.exit(2);
}

// ---- the simulate answer: the run's deployment and files, as the daemon sends them --------------
const deploymentText = readFileSync(path.join(runDir, 'deployment.json'), 'utf8');
const deployment = JSON.parse(deploymentText);
const VIEWS = ['deployment.json', 'deployed.obj', 'deviation.ply', 'deployed_without_notches.obj',
               'deviation_without_notches.ply'];
const views = VIEWS.filter((n) => existsSync(path.join(runDir, n)))
  .map((name) => ({ name, content: readFileSync(path.join(runDir, name)).toString('base64') }));
const simulateBody = Buffer.from(`event: progress\ndata: ${JSON.stringify({ stage: 'simulation', fraction: 0.5 })}\n\n` +
                                 `event: result\ndata: ${JSON.stringify({ deployment, views })}\n\n`);
const rods = deployment.rods.length;
const rodVertices = deployment.rods.reduce((k, r) => k + r.centerline.length, 0);

async function until(predicate, ms, what) {
  const end = Date.now() + ms;
  for (;;) {
    const v = await predicate();
    if (v) return v;
    if (Date.now() > end) throw new Error(`timed out after ${ms} ms waiting for ${what}`);
    await new Promise((r) => setTimeout(r, 50));
  }
}

async function startDaemon(dist) {
  const proc = spawn(daemonPath, ['--listen', '127.0.0.1:0', '--http', '127.0.0.1:0', '--static', dist, '--workers', '2'],
                     { stdio: ['ignore', 'ignore', 'pipe'] });
  let log = '';
  proc.stderr.setEncoding('utf8');
  proc.stderr.on('data', (d) => { log += d; });
  const address = await until(() => {
    if (proc.exitCode !== null) throw new Error(`gridshelld exited: ${log}`);
    return (log.match(/"event":\s*"listening"[^\n]*?"http":\s*"([^"]+)"/) ??
            log.match(/"http":\s*"([^"]+)"[^\n]*"event":\s*"listening"/))?.[1];
  }, 20000, 'gridshelld to listen');
  return { proc, address };
}

/** A loopback proxy to the daemon that answers /v1/simulate itself. */
function startProxy(target) {
  const [host, port] = target.split(':');
  const server = http.createServer((req, res) => {
    if (req.method === 'POST' && req.url.endsWith('/v1/simulate')) {
      req.resume();
      req.on('end', () => {
        res.writeHead(200, { 'Content-Type': 'text/event-stream', 'Cache-Control': 'no-store' });
        // In 1 MiB writes, as a stream arrives.
        for (let i = 0; i < simulateBody.length; i += 1 << 20) res.write(simulateBody.subarray(i, i + (1 << 20)));
        res.end();
      });
      return;
    }
    const up = http.request({ host, port, path: req.url, method: req.method, headers: req.headers }, (r) => {
      res.writeHead(r.statusCode, r.headers);
      r.pipe(res);
    });
    req.pipe(up);
  });
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve(server)));
}

const percentile = (xs, p) => {
  const s = [...xs].sort((a, b) => a - b);
  return s[Math.min(s.length - 1, Math.max(0, Math.ceil(p * s.length) - 1))];
};

/** Orbits by a few pixels per frame for `n` frames; the intervals between their rAF timestamps. */
function orbit(page, n) {
  return page.evaluate(async (n) => {
    const canvas = document.querySelector('[data-testid=viewer]');
    const r = canvas.getBoundingClientRect();
    let x = r.left + r.width / 2;
    const y = r.top + r.height / 2;
    const ev = (type) => new PointerEvent(type, { pointerId: 1, pointerType: 'mouse', isPrimary: true, button: 0,
                                                  buttons: type === 'pointerup' ? 0 : 1, clientX: x, clientY: y,
                                                  bubbles: true });
    canvas.dispatchEvent(ev('pointerdown'));
    const stamps = [];
    await new Promise((resolve) => {
      const step = (t) => {
        stamps.push(t);
        if (stamps.length > n + 1) return resolve();
        x += 4;
        canvas.dispatchEvent(ev('pointermove'));
        requestAnimationFrame(step);
      };
      requestAnimationFrame(step);
    });
    canvas.dispatchEvent(ev('pointerup'));
    // The first interval only starts the drag.
    return stamps.slice(2).map((t, i) => t - stamps[i + 1]);
  }, n);
}

async function heapMiB(cdp) {
  await cdp.send('HeapProfiler.collectGarbage');
  // The JS heap and the ArrayBuffers' backing stores (typed arrays live outside the heap).
  const { usedSize, backingStorageSize } = await cdp.send('Runtime.getHeapUsage');
  return (usedSize + (backingStorageSize ?? 0)) / 2 ** 20;
}

async function measure(browser, base) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  const page = await context.newPage();
  page.setDefaultTimeout(60000);
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  const cdp = await context.newCDPSession(page);
  await page.goto(base, { waitUntil: 'load' });
  await until(() => page.evaluate(() => Number(document.querySelector('[data-testid=example-select]')?.dataset.loaded ?? 0)),
              20000, 'the example list');
  await page.getByTestId('example-select').selectOption('double-vault');
  await page.waitForFunction(() => document.querySelector('[data-testid=mesh-info]')?.dataset.ready === '1');
  const meshOnly = await orbit(page, 30);
  await page.getByTestId('corners-example').click();
  await page.waitForFunction(() => document.querySelector('[data-testid=viewer]')?.dataset.layers?.includes('patch'));
  await page.getByTestId('members-u').fill(String(members));
  await page.getByTestId('members-v').fill(String(members));
  await page.getByTestId('lamella-width').fill(String(deployment.options?.lamella_width ?? 0));
  await page.getByTestId('design').click();
  await until(() => page.getByTestId('simulate').isEnabled(), 120000, 'the design');
  await until(async () => !(await page.getByTestId('design').isDisabled()), 120000, 'the design to settle');
  await new Promise((r) => setTimeout(r, 1000)); // the debounced redesigns after the fills
  await until(() => page.getByTestId('simulate').isEnabled(), 120000, 'the last design');
  const designs = await page.evaluate(() => document.querySelector('[data-testid=viewer]').dataset.layers);
  const heapDesign = await heapMiB(cdp);
  // Transfer alone: the same answer fetched and read as text in the page.
  const transferMs = await page.evaluate(async () => {
    const t0 = performance.now();
    const r = await fetch('v1/simulate', { method: 'POST', body: '{}', headers: { Accept: 'text/event-stream' } });
    await r.text();
    return performance.now() - t0;
  });
  // Simulate → the first frame with the deployment (the viewer publishes data-layers after each frame).
  const drawMs = await page.evaluate(() => new Promise((resolve) => {
    const canvas = document.querySelector('[data-testid=viewer]');
    const t0 = performance.now();
    const observer = new MutationObserver(() => {
      if (!canvas.dataset.layers.split(',').includes('deployment')) return;
      observer.disconnect();
      resolve(performance.now() - t0);
    });
    observer.observe(canvas, { attributes: true, attributeFilter: ['data-layers'] });
    document.querySelector('[data-testid=simulate]').click();
  }));
  const summaryOk = /RMS/.test(await page.getByTestId('summary').textContent());
  const heapDeployment = await heapMiB(cdp);
  const intervals = await orbit(page, frames);
  await context.close();
  if (errors.length) throw new Error(`page errors: ${errors.join('; ')}`);
  if (!summaryOk) throw new Error('no RMS in the summary after Simulate');
  return { designs, heapDesign, heapDeployment, transferMs, drawMs, intervals, meshOnly };
}

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--no-sandbox', '--headless',
         '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
});
const servers = [];
const rows = [];
try {
  const targets = [];
  for (const dist of dists) {
    const d = await startDaemon(dist);
    servers.push(d);
    const proxy = await startProxy(d.address);
    servers.push({ proxy });
    targets.push({ dist, base: `http://127.0.0.1:${proxy.address().port}/` });
  }
  for (let round = 0; round < repeats; ++round)
    for (const t of targets) {
      const m = await measure(browser, t.base);
      const row = {
        dist: path.relative(process.cwd(), t.dist) || '.', round: round + 1,
        draw: m.drawMs, transfer: m.transferMs, heapDesign: m.heapDesign, heap: m.heapDeployment,
        median: percentile(m.intervals, 0.5), p95: percentile(m.intervals, 0.95),
        meshMedian: percentile(m.meshOnly, 0.5),
      };
      rows.push(row);
      console.error(`# ${JSON.stringify(row)}`);
    }
} finally {
  await browser.close().catch(() => {});
  for (const s of servers) {
    if (s.proxy) s.proxy.close();
    else s.proc.kill('SIGTERM');
  }
}

const f = (x, d = 0) => x.toFixed(d);
console.log(`${rods} lamellas, ${rodVertices} rod vertices (${runDir}); ${members} x ${members} members; ` +
            `${frames} frames orbited; viewport 1280 x 800; ${os.cpus()[0]?.model ?? '?'}, ${os.cpus().length} hardware threads; ` +
            `load average ${os.loadavg()[0].toFixed(2)}`);
console.log('');
console.log('| page | round | Simulate → first frame ms | transfer + read alone ms | JS heap + ArrayBuffers MiB (design → deployment) | frame ms median | frame ms p95 | mesh alone frame ms median |');
console.log('|---|---:|---:|---:|---:|---:|---:|---:|');
for (const r of rows)
  console.log(`| ${r.dist} | ${r.round} | ${f(r.draw)} | ${f(r.transfer)} | ${f(r.heapDesign, 1)} → ${f(r.heap, 1)} | ` +
              `${f(r.median, 1)} | ${f(r.p95, 1)} | ${f(r.meshMedian, 1)} |`);
