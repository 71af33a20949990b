// SPDX-License-Identifier: GPL-3.0-or-later
// Pan (drag) and zoom (wheel, about the cursor) of an image in a pane: the 2D plan (planar.svg)
// and the distance maps (maps.svg), shown as the daemon's own SVG files.

export class Zoomable {
  private scale = 1;
  private x = 0;
  private y = 0;
  private drag: { x: number; y: number } | null = null;
  private url = '';

  constructor(private readonly pane: HTMLElement, private readonly img: HTMLImageElement) {
    img.draggable = false;
    img.addEventListener('load', () => this.fit());
    pane.addEventListener('wheel', (e) => {
      e.preventDefault();
      const r = pane.getBoundingClientRect();
      const cx = e.clientX - r.left, cy = e.clientY - r.top;
      const k = Math.exp(-e.deltaY * 0.0015);
      this.x = cx - (cx - this.x) * k;
      this.y = cy - (cy - this.y) * k;
      this.scale *= k;
      this.apply();
    }, { passive: false });
    pane.addEventListener('pointerdown', (e) => {
      this.drag = { x: e.clientX - this.x, y: e.clientY - this.y };
      pane.setPointerCapture(e.pointerId);
    });
    pane.addEventListener('pointermove', (e) => {
      if (!this.drag) return;
      this.x = e.clientX - this.drag.x;
      this.y = e.clientY - this.drag.y;
      this.apply();
    });
    pane.addEventListener('pointerup', () => { this.drag = null; });
    pane.addEventListener('dblclick', () => this.fit());
  }

  /** Shows the image at `url` (a blob URL this object now owns and revokes when replaced). */
  show(url: string): void {
    this.clear();
    this.url = url;
    this.img.src = url;
  }

  clear(): void {
    if (this.url) URL.revokeObjectURL(this.url);
    this.url = '';
    this.img.removeAttribute('src');
  }

  /** The whole image in the pane, centred. */
  fit(): void {
    const w = this.img.naturalWidth, h = this.img.naturalHeight;
    const pw = this.pane.clientWidth, ph = this.pane.clientHeight;
    if (!w || !h || !pw || !ph) return;
    this.scale = 0.95 * Math.min(pw / w, ph / h);
    this.x = (pw - w * this.scale) / 2;
    this.y = (ph - h * this.scale) / 2;
    this.apply();
  }

  private apply(): void {
    // CSSOM, not a style attribute: allowed by the daemon's CSP (style-src 'self').
    this.img.style.transform = `translate(${this.x}px, ${this.y}px) scale(${this.scale})`;
  }
}
