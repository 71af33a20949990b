// SPDX-License-Identifier: GPL-3.0-or-later
// The ranked feasible suggestions of an infeasible design (issue 18), listed under the error.
import type { Suggestion } from './api';

/** One line per suggestion: its description (which names the feasible planar angles). */
export function suggestionLines(suggestions: Suggestion[]): string[] {
  return suggestions.map((s) => `${s.rank}. ${s.description}`);
}

/** Appends the suggestions to `area` as a list (text only: no HTML from the daemon). */
export function appendSuggestions(area: HTMLElement, suggestions: Suggestion[]): void {
  if (suggestions.length === 0) return;
  const title = document.createElement('div');
  title.className = 'suggestions-title';
  title.textContent = 'Feasible changes (computed):';
  const list = document.createElement('ol');
  list.className = 'suggestions';
  list.dataset.testid = 'suggestions';
  for (const s of suggestions) {
    const item = document.createElement('li');
    item.textContent = s.description;
    list.appendChild(item);
  }
  area.appendChild(title);
  area.appendChild(list);
}
