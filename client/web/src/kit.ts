// SPDX-License-Identifier: GPL-3.0-or-later
// The fabrication kit on the page: a Fabricate call for the design on screen, its files packed
// into one kit.zip (fflate) with the folder layout `gridshell fabricate` writes.
import { zipSync } from 'fflate';
import { base64ToBytes, type Design, type FileJson } from './api';

export interface KitJson {
  parts: { name: string }[];
  sheets: { index: number; dxf: string; svg: string }[];
  utilisation: number;
  baseline_utilisation: number;
  holes: number;
  slots: number;
  top_family: string;
}

export interface FabricateResult {
  kit: KitJson;
  files: FileJson[];
}

/** The Fabricate request for a design (unit: the design's length unit, required by the daemon). */
export function fabricateRequest(design: Design, unit: string): unknown {
  return { design, options: { unit }, design_name: 'design.json' };
}

/** kit.zip: every file of the result under `kit/`, sheets in `kit/sheets/`. */
export function kitZip(files: FileJson[]): Uint8Array<ArrayBuffer> {
  const entries: Record<string, Uint8Array> = {};
  for (const f of files) entries[`kit/${f.name}`] = base64ToBytes(f.content);
  return zipSync(entries, { level: 6, mtime: new Date(2026, 0, 1) }) as Uint8Array<ArrayBuffer>;
}

/** One line for the summary. */
export function kitSummary(kit: KitJson): string {
  return `kit: ${kit.parts.length} lamellas on ${kit.sheets.length} sheet(s), ` +
    `${(100 * kit.utilisation).toFixed(1)} % used (one per row: ${(100 * kit.baseline_utilisation).toFixed(1)} %), ` +
    `${kit.holes} holes, ${kit.slots} slots; ${kit.top_family} lamellas on top`;
}
