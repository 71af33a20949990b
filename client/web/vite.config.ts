// SPDX-License-Identifier: GPL-3.0-or-later
// Vite build of the gridshell page into dist/, served by gridshelld at /. Everything the page needs
// is in the bundle: no CDN, no web fonts, no inline script or style (the daemon's CSP forbids
// them), relative asset URLs so the folder can be served under any path.
import { defineConfig } from 'vite';

export default defineConfig({
  base: './',
  build: {
    outDir: 'dist',
    emptyOutDir: true,
    target: 'es2022',
    assetsInlineLimit: 0,
    modulePreload: { polyfill: false },
    chunkSizeWarningLimit: 1200,
    reportCompressedSize: true,
  },
  server: { proxy: { '/v1': 'http://127.0.0.1:8080', '/healthz': 'http://127.0.0.1:8080' } },
});
