// SPDX-License-Identifier: GPL-3.0-or-later
// The page's design and simulation controls, built from the daemon's description of every request
// option (POST /v1/options, proto/gridshell/v1/options.proto): the kind of control, its range,
// default, label and help, the material presets and the length units all come from there, so an
// option or a material the daemon adds appears on the page with no change to it (issue 34). The
// page keeps no ranges or defaults of its own: the inputs' min/max give immediate feedback, the
// daemon's check (its error names the field) has the last word.
//
// Pure helpers first (no DOM; unit-tested by tests/web/unit.test.mjs), then OptionsForm, which
// builds the controls into the panel and reads them back as request options by field name.

import type { MaterialPreset, OptionDescription, OptionsResult } from './api';

/** The option groups the page offers controls for (DesignRequest.Options, SimulationOptions, AutoLayoutOptions). */
export const FORM_GROUPS: readonly string[] = ['design', 'simulation', 'layout'];

/**
 * The request field that holds a group's options, as the daemon's errors name it:
 * `options.lamella_width`, but `automatic.max_patches` (LayoutRequest.automatic).
 */
export const REQUEST_FIELD: Record<string, string> = { design: 'options', simulation: 'options', layout: 'automatic' };

/** "design.lamella_width": a control's key, as in its `data-option` attribute. */
export function optionKey(o: { group: string; name: string }): string {
  return `${o.group}.${o.name}`;
}

/** The request options of `groups` (output fields, which results only record, left out). */
export function formOptions(d: OptionsResult, groups: readonly string[] = FORM_GROUPS): OptionDescription[] {
  return (d.options ?? []).filter((o) => !o.output && groups.includes(o.group));
}

/**
 * How the page presents a few options; everything else about them (range, default, label, help,
 * choices) still comes from the description, and every other option gets the control its type
 * asks for.
 */
export interface Presentation {
  external?: boolean;                      // the page has its own control (main.ts binds it)
  control?: 'materials' | 'length-units';  // a select of the description's materials / length units
  testid?: string;                         // data-testid other than the name with hyphens
}

export const PRESENTATION: Record<string, Presentation> = {
  'design.alpha': { external: true },                    // the ᾱ slider, in degrees within the feasible range
  'simulation.material': { control: 'materials' },
  'simulation.unit': { control: 'length-units' },
  'simulation.interior_anchors': { testid: 'auto-anchors' },
};

/** A number as the daemon prints it: 1e+15, 1e-9, 1.0015, 100. */
export function formatValue(x: number): string {
  if (!Number.isFinite(x)) return String(x);
  const v = Number(x.toPrecision(6));
  if (v !== 0 && (Math.abs(v) >= 1e6 || Math.abs(v) < 1e-4)) return v.toExponential();
  return String(v);
}

/** The allowed range in the daemon's notation: "(0, 1e+15] mesh units (or 0: automatic)"; "" = none. */
export function rangeText(o: OptionDescription): string {
  const lo = o.minimum, hi = o.maximum;
  let r = '';
  if (lo !== undefined && hi !== undefined)
    r = `${o.exclusive_minimum ? '(' : '['}${formatValue(lo)}, ${formatValue(hi)}${o.exclusive_maximum ? ')' : ']'}`;
  else if (lo !== undefined) r = `${o.exclusive_minimum ? '>' : '≥'} ${formatValue(lo)}`;
  else if (hi !== undefined) r = `${o.exclusive_maximum ? '<' : '≤'} ${formatValue(hi)}`;
  if (!r) return '';
  return `${r}${o.unit ? ` ${o.unit}` : ''}${o.zero_allowed ? ` (or 0: ${o.zero_means || 'allowed'})` : ''}`;
}

function checkNumber(o: OptionDescription, v: number, integer: boolean): string {
  const range = rangeText(o);
  const within = range ? `${/^[[(]/.test(range) ? 'in ' : ''}${range}` : '';
  if (!Number.isFinite(v)) return 'not a number';
  if (integer && !Number.isInteger(v)) return `must be an integer${within ? ` ${within}` : ''}`;
  if (v === 0 && o.zero_allowed) return '';
  const below = o.minimum !== undefined && (v < o.minimum || (o.exclusive_minimum === true && v === o.minimum));
  const above = o.maximum !== undefined && (v > o.maximum || (o.exclusive_maximum === true && v === o.maximum));
  return below || above ? `must be ${within}` : '';
}

/**
 * The description's check of a control's text: "" when it is allowed (empty = the default), else
 * why not ("must be in [1, 1000] (or 0: automatic)"). Immediate feedback only: the daemon checks
 * every request again and its error is the one shown for a request.
 */
export function checkValue(o: OptionDescription, text: string): string {
  const t = text.trim();
  if (t === '') return '';
  switch (o.type) {
    case 'number':
    case 'integer':
      return checkNumber(o, Number(t), o.type === 'integer');
    case 'numbers': {
      const items = t.split(',').map((s) => s.trim());
      if (o.count && items.length !== o.count) return `needs ${o.count} numbers, got ${items.length}`;
      for (const item of items) {
        const m = item === '' ? 'not a number' : checkNumber(o, Number(item), false);
        if (m) return `${item || '(empty)'}: ${m}`;
      }
      return '';
    }
    case 'choice':
      return (o.choices ?? []).includes(t) ? '' : `expected one of ${(o.choices ?? []).join(', ')}`;
    case 'boolean':
      return t === 'true' || t === 'false' ? '' : 'expected true or false';
    default:
      return '';
  }
}

/** A control's text as the request's JSON value (proto field names, protobuf JSON). */
export function requestValue(o: OptionDescription, text: string): unknown {
  switch (o.type) {
    case 'number':
    case 'integer':
      return Number(text);
    case 'boolean':
      return text === 'true';
    case 'numbers':
      return text.split(',').map((s) => Number(s.trim()));
    default:
      return text;
  }
}

/** Whether a control's text means the option's default (empty text does): then it is not sent. */
export function isDefault(o: OptionDescription, text: string): boolean {
  const t = text.trim(), d = (o.default_value ?? '').trim();
  if (t === '') return true;
  switch (o.type) {
    case 'number':
    case 'integer':
      return d !== '' && Number(t) === Number(d);
    case 'numbers': {
      const a = t.split(',').map(Number), b = d.split(',').map(Number);
      return d !== '' && a.length === b.length && a.every((x, i) => x === b[i]);
    }
    case 'boolean':
      return (t === 'true') === (d === 'true');
    default:
      return t === d;
  }
}

/** A control's tooltip: help, range, default, note and the CLI flag. */
export function tooltip(o: OptionDescription): string {
  const lines = [o.help || o.label || o.name];
  const range = rangeText(o);
  if (range) lines.push(`allowed: ${o.type === 'integer' ? 'integer ' : ''}${range}`);
  else if (o.unit) lines.push(`unit: ${o.unit}`);
  if (o.type === 'choice' && o.choices?.length) lines.push(`one of: ${o.choices.map((c) => c || '""').join(' | ')}`);
  const d = o.default_value ?? '';
  if (d !== '') lines.push(`default: ${d}${o.zero_allowed && Number(d) === 0 && o.zero_means ? ` (${o.zero_means})` : ''}`);
  if (o.note) lines.push(o.note);
  if (o.flag) lines.push(`CLI: ${o.flag}`);
  return lines.join('\n');
}

function pascals(pa: number | undefined, unit: 'GPa' | 'MPa'): string {
  if (!pa) return 'unknown';
  return `${formatValue(pa / (unit === 'GPa' ? 1e9 : 1e6))} ${unit}`;
}

/** A material's tooltip: "E = 7.4 GPa, G = 0.46 GPa; bending strength 60 MPa, ...; source". */
export function materialTitle(m: MaterialPreset): string {
  return `E = ${pascals(m.young_modulus, 'GPa')}, G = ${pascals(m.shear_modulus, 'GPa')}; ` +
    `bending strength ${pascals(m.bending_strength, 'MPa')}, shear strength ${pascals(m.shear_strength, 'MPa')}` +
    `${m.source ? `\n${m.source}` : ''}${m.site ? '\n(this site\'s material library)' : ''}`;
}

export interface ChoiceItem {
  value: string;
  label: string;
  title: string;
}

/** What one control is, before the DOM: the pure part of the form builder. */
export interface ControlSpec {
  key: string;
  option: OptionDescription;
  kind: 'number' | 'select' | 'checkbox' | 'text' | 'numbers';
  label: string;
  unit: string;
  title: string;
  testid: string;
  advanced: boolean;
  value: string;       // the initial value (the default) as text
  min?: string;        // number inputs (numbers: each item)
  max?: string;
  step?: string;
  items?: ChoiceItem[]; // select
  checked?: string;     // checkbox: its value when checked ("true", or the non-empty choice)
  count?: number;       // numbers: how many inputs (any count: a text input, comma-separated)
}

function numberAttributes(o: OptionDescription): { min?: string; max?: string; step: string } {
  const integer = o.type === 'integer';
  let lo = o.minimum, hi = o.maximum;
  if (integer && lo !== undefined && o.exclusive_minimum) lo = Math.floor(lo) + 1;
  if (integer && hi !== undefined && o.exclusive_maximum) hi = Math.ceil(hi) - 1;
  if (o.zero_allowed) { // 0 is allowed besides the range: the input's range must reach it
    if (lo !== undefined && lo > 0) lo = 0;
    if (hi !== undefined && hi < 0) hi = 0;
  }
  const a: { min?: string; max?: string; step: string } = { step: integer ? '1' : 'any' };
  if (lo !== undefined) a.min = String(lo);
  if (hi !== undefined) a.max = String(hi);
  return a;
}

/** The controls the page builds for a description, in its order (externally presented ones left out). */
export function controlSpecs(d: OptionsResult, presentation: Record<string, Presentation> = PRESENTATION): ControlSpec[] {
  const options = formOptions(d).filter((o) => !presentation[optionKey(o)]?.external);
  const used = new Set<string>(Object.values(presentation).map((p) => p.testid).filter((t): t is string => !!t));
  const specs: ControlSpec[] = [];
  for (const o of options) {
    const key = optionKey(o);
    const p = presentation[key] ?? {};
    let testid = p.testid;
    if (!testid) {
      const plain = o.name.replace(/_/g, '-');
      testid = used.has(plain) ? `${o.group}-${plain}` : plain; // e.g. a simulation option named as a design one
      used.add(testid);
    }
    const base = {
      key, option: o, label: o.label || o.name, unit: o.unit ?? '', title: tooltip(o), testid,
      advanced: o.advanced === true, value: o.default_value ?? '',
    };
    const choices = o.choices ?? [];
    if (p.control === 'materials') {
      const items: ChoiceItem[] = (d.materials ?? []).map((m) => ({ value: m.name, label: m.label || m.name, title: materialTitle(m) }));
      for (const c of choices)
        if (!items.some((i) => i.value === c)) items.push({ value: c, label: c, title: o.help ?? '' });
      const value = items.some((i) => i.value === base.value) ? base.value : items[0]?.value ?? '';
      specs.push({ ...base, kind: 'select', items, value });
    } else if (p.control === 'length-units') {
      const units = d.length_units ?? [];
      const items: ChoiceItem[] = [{ value: '', label: 'unknown', title: o.help ?? '' },
        ...units.map((u) => ({ value: u, label: u, title: '' }))];
      if (!items.some((i) => i.value === base.value)) items.push({ value: base.value, label: base.value, title: '' });
      specs.push({ ...base, kind: 'select', items });
    } else if (o.type === 'boolean') {
      specs.push({ ...base, kind: 'checkbox', checked: 'true', value: base.value === 'true' ? 'true' : 'false' });
    } else if (o.type === 'choice' && choices.length === 2 && choices.includes('')) {
      specs.push({ ...base, kind: 'checkbox', checked: choices.find((c) => c !== '')! }); // "" or one value: on/off
    } else if (o.type === 'choice') {
      const items = choices.map((c) => ({ value: c, label: c === '' ? '(none)' : c, title: '' }));
      specs.push({ ...base, kind: 'select', items });
    } else if (o.type === 'number' || o.type === 'integer') {
      specs.push({ ...base, kind: 'number', ...numberAttributes(o) });
    } else if (o.type === 'numbers' && (o.count ?? 0) > 0) {
      specs.push({ ...base, kind: 'numbers', count: o.count!, ...numberAttributes({ ...o, type: 'number' }) });
    } else {
      specs.push({ ...base, kind: 'text' });
    }
  }
  return specs;
}

/** The request options of one group: every control whose text is not the default, by field name. */
export function requestOptions(values: ReadonlyMap<string, string>, options: OptionDescription[],
                               group: string, names?: ReadonlySet<string>): Record<string, unknown> {
  const out: Record<string, unknown> = {};
  for (const o of options) {
    if (o.group !== group || (names && !names.has(o.name))) continue;
    const text = values.get(optionKey(o));
    if (text === undefined || isDefault(o, text)) continue;
    out[o.name] = requestValue(o, text.trim());
  }
  return out;
}

// ---- the DOM --------------------------------------------------------------------------------------

type Input = HTMLInputElement | HTMLSelectElement;

interface Control {
  spec: ControlSpec;
  root: HTMLElement;
  inputs: Input[];
  slot: HTMLElement; // its .field-error
  get(): string;
  set(text: string): void;
}

/** Where a group's controls go: the panel's grid, and the grid inside its collapsed "Advanced". */
export interface FormHost {
  main: HTMLElement;
  advanced: HTMLElement;
}

function element<K extends keyof HTMLElementTagNameMap>(tag: K, className = '', text = ''): HTMLElementTagNameMap[K] {
  const e = document.createElement(tag);
  if (className) e.className = className;
  if (text) e.textContent = text;
  return e;
}

function numberInput(spec: ControlSpec, value: string, testid: string): HTMLInputElement {
  const input = element('input');
  input.type = 'number';
  if (spec.min !== undefined) input.min = spec.min;
  if (spec.max !== undefined) input.max = spec.max;
  input.step = spec.step ?? 'any';
  input.value = value;
  input.dataset['testid'] = testid;
  return input;
}

function buildControl(spec: ControlSpec): Control {
  const root = element('div', 'option');
  root.dataset['option'] = spec.key;
  root.title = spec.title;
  const label = element('label');
  const caption = element('span', 'caption', spec.label);
  if (spec.unit && spec.kind !== 'checkbox') caption.append(' ', element('span', 'unit', `(${spec.unit})`));
  const slot = element('div', 'field-error');
  slot.dataset['for'] = spec.key;
  let inputs: Input[];
  let get: () => string;
  let set: (text: string) => void;
  switch (spec.kind) {
    case 'checkbox': {
      root.classList.add('wide');
      label.className = 'check';
      const box = element('input');
      box.type = 'checkbox';
      box.dataset['testid'] = spec.testid;
      const on = spec.checked ?? 'true', off = spec.option.type === 'boolean' ? 'false' : '';
      set = (text) => { box.checked = text === on; };
      get = () => (box.checked ? on : off);
      set(spec.value);
      label.append(box, caption);
      inputs = [box];
      break;
    }
    case 'select': {
      const select = element('select');
      select.dataset['testid'] = spec.testid;
      for (const item of spec.items ?? []) {
        const option = element('option', '', item.label);
        option.value = item.value;
        if (item.title) option.title = item.title;
        select.append(option);
      }
      set = (text) => { if ((spec.items ?? []).some((i) => i.value === text)) select.value = text; };
      get = () => select.value;
      set(spec.value);
      label.append(caption, select);
      inputs = [select];
      break;
    }
    case 'number': {
      const input = numberInput(spec, spec.value, spec.testid);
      set = (text) => { input.value = text; };
      get = () => input.value;
      label.append(caption, input);
      inputs = [input];
      break;
    }
    case 'numbers': { // a fixed count: one number input each
      root.classList.add('wide');
      const row = element('span', 'numbers');
      const defaults = spec.value.split(',');
      const items = Array.from({ length: spec.count ?? 0 }, (_, i) =>
        numberInput(spec, defaults[i]?.trim() ?? '', `${spec.testid}-${i + 1}`));
      row.append(...items);
      set = (text) => { const v = text.split(','); items.forEach((x, i) => { x.value = v[i]?.trim() ?? ''; }); };
      get = () => (items.every((x) => x.value === '') ? '' : items.map((x) => x.value).join(','));
      label.append(caption, row);
      inputs = items;
      break;
    }
    default: { // text, and numbers of any count (comma-separated)
      const input = element('input');
      input.type = 'text';
      input.value = spec.value;
      if (spec.value) input.placeholder = spec.value;
      input.dataset['testid'] = spec.testid;
      set = (text) => { input.value = text; };
      get = () => input.value;
      label.append(caption, input);
      inputs = [input];
    }
  }
  root.append(label, slot);
  return { spec, root, inputs, slot, get, set };
}

/**
 * The built controls of the design, simulation and layout options. `onChange(key, option, settled)` is
 * called on every edit: settled = a select or checkbox changed (act now), else typing (debounce).
 */
export class OptionsForm {
  readonly description: OptionsResult;
  readonly controls = new Map<string, Control>();
  onChange: (key: string, option: OptionDescription, settled: boolean) => void = () => {};

  constructor(description: OptionsResult, hosts: Record<string, FormHost>) {
    this.description = description;
    for (const spec of controlSpecs(description)) {
      const host = hosts[spec.option.group];
      if (!host) continue;
      const control = buildControl(spec);
      this.controls.set(spec.key, control);
      (spec.advanced ? host.advanced : host.main).append(control.root);
      for (const input of control.inputs) {
        const settled = input instanceof HTMLSelectElement || input.type === 'checkbox';
        input.addEventListener(settled ? 'change' : 'input', () => {
          this.validate(control);
          this.onChange(spec.key, spec.option, settled);
        });
      }
    }
    for (const host of Object.values(hosts)) {
      const details = host.advanced.closest('details');
      if (details) details.hidden = host.advanced.childElementCount === 0;
    }
  }

  /** An option of any group, as described. */
  option(key: string): OptionDescription | undefined {
    return (this.description.options ?? []).find((o) => !o.output && optionKey(o) === key);
  }

  /** A control's text ("" where the page has no such control). */
  value(key: string): string {
    return this.controls.get(key)?.get() ?? '';
  }

  /** Sets a control (a restored URL); false when there is no such control (an option gone). */
  set(key: string, text: string): boolean {
    const c = this.controls.get(key);
    if (!c) return false;
    c.set(text);
    this.validate(c);
    return true;
  }

  /** The request options of `group` (only those `names`, when given): values other than the default. */
  requestOptions(group: string, names?: ReadonlySet<string>): Record<string, unknown> {
    const values = new Map<string, string>();
    for (const [key, c] of this.controls) values.set(key, c.get());
    return requestOptions(values, formOptions(this.description), group, names);
  }

  /** The value an option takes in a request: its control's, else its default; undefined without either. */
  effective(key: string): unknown {
    const o = this.option(key);
    if (!o) return undefined;
    const text = this.value(key).trim();
    if (text !== '') return requestValue(o, text);
    return (o.default_value ?? '') === '' ? undefined : requestValue(o, o.default_value!);
  }

  /** key -> text of every control not at its default (the URL keeps these). */
  changed(): Record<string, string> {
    const out: Record<string, string> = {};
    for (const [key, c] of this.controls) {
      const text = c.get();
      if (!isDefault(c.spec.option, text)) out[key] = text;
    }
    return out;
  }

  /** Names of `group`'s controls. */
  names(group: string): Set<string> {
    return new Set([...this.controls.values()].filter((c) => c.spec.option.group === group).map((c) => c.spec.option.name));
  }

  /** Clears the daemon's errors next to `group`'s controls (the description's own check stays). */
  clearErrors(group: string): void {
    for (const c of this.controls.values()) if (c.spec.option.group === group) this.validate(c);
  }

  /** Shows `message` next to the control of `key`; false when there is none. */
  showError(key: string, message: string): boolean {
    const c = this.controls.get(key);
    if (!c) return false;
    c.slot.textContent = message;
    return true;
  }

  private validate(c: Control): void {
    const message = checkValue(c.spec.option, c.get());
    for (const input of c.inputs) input.setCustomValidity(message);
    c.slot.textContent = message ? `${REQUEST_FIELD[c.spec.option.group] ?? 'options'}.${c.spec.option.name}: ${message}` : '';
  }
}
