// SPDX-License-Identifier: GPL-3.0-or-later
// Colour maps of the page: a diverging map for Gaussian curvature (blue < 0 < red, white at 0)
// and a sequential one for deviations (0 = dark blue ... max = yellow), with their legends.
// Pure functions, no DOM beyond the legend canvas.

export type Rgb = [number, number, number];

function lerp(a: Rgb, b: Rgb, t: number): Rgb {
  return [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t];
}

function ramp(stops: Rgb[], t: number): Rgb {
  const x = Math.min(1, Math.max(0, Number.isFinite(t) ? t : 0)) * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(x));
  return lerp(stops[i]!, stops[i + 1]!, x - i);
}

const DIVERGING: Rgb[] = [[0.13, 0.4, 0.67], [0.57, 0.77, 0.87], [0.97, 0.97, 0.97], [0.96, 0.65, 0.51], [0.7, 0.09, 0.17]];
const SEQUENTIAL: Rgb[] = [[0.27, 0.0, 0.33], [0.23, 0.32, 0.55], [0.13, 0.57, 0.55], [0.37, 0.79, 0.38], [0.99, 0.91, 0.14]];

/** Symmetric range for a diverging map: the 98th percentile of |v| (robust to one spike), > 0. */
export function symmetricRange(values: ArrayLike<number>): number {
  const abs: number[] = [];
  for (let i = 0; i < values.length; ++i) {
    const v = values[i]!;
    if (Number.isFinite(v)) abs.push(Math.abs(v));
  }
  if (abs.length === 0) return 1;
  abs.sort((a, b) => a - b);
  const r = abs[Math.min(abs.length - 1, Math.floor(0.98 * (abs.length - 1)))]!;
  return r > 0 ? r : Math.max(abs[abs.length - 1]!, 1e-12);
}

/** Colour of v in [-range, range] on the diverging map. */
export function diverging(v: number, range: number): Rgb {
  return ramp(DIVERGING, 0.5 + 0.5 * v / range);
}

/** Colour of v in [0, max] on the sequential map. */
export function sequential(v: number, max: number): Rgb {
  return ramp(SEQUENTIAL, max > 0 ? v / max : 0);
}

/** A number short enough for a legend: 3 significant digits, exponent when far from 1. */
export function formatNumber(v: number): string {
  if (!Number.isFinite(v)) return String(v);
  if (v === 0) return '0';
  const a = Math.abs(v);
  if (a >= 1e4 || a < 1e-2) return v.toExponential(2);
  return String(Number(v.toPrecision(3))); // 1.50 -> 1.5, 2000 stays 2000
}

/** Fills `canvas` with a horizontal colour bar of `map` over t in [0, 1]. */
export function drawBar(canvas: HTMLCanvasElement, map: (t: number) => Rgb): void {
  const ctx = canvas.getContext('2d');
  if (!ctx) return;
  const w = canvas.width;
  for (let x = 0; x < w; ++x) {
    const [r, g, b] = map(x / Math.max(1, w - 1));
    ctx.fillStyle = `rgb(${Math.round(r * 255)},${Math.round(g * 255)},${Math.round(b * 255)})`;
    ctx.fillRect(x, 0, 1, canvas.height);
  }
}
