// SPDX-License-Identifier: GPL-3.0-or-later
// The 3D view: the input mesh, four numbered corner markers, the trimmed patch with its Gaussian
// curvature colours and boundary geodesics, the design on the surface (members, crossings,
// anchors) and the deployed lamellas as boxes coloured by deviation or bending stress; or a
// multi-patch layout (patches in their colours, seams) and its patches' deployed lamellas. Everything is drawn
// relative to the mesh's bounding-box centre (computed in double precision), so architectural
// coordinates far from the origin still render and pick precisely. Picking: three-mesh-bvh.
// Renders on demand only (one frame per change), which matters with a software GL.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { acceleratedRaycast, computeBoundsTree, disposeBoundsTree } from 'three-mesh-bvh';
import type { Deployment, Design, Lamella } from './api';
import { diverging, type Rgb } from './colormap';
import { lamellaMesh, type LamellaGroup } from './lamellas';

THREE.BufferGeometry.prototype.computeBoundsTree = computeBoundsTree;
THREE.BufferGeometry.prototype.disposeBoundsTree = disposeBoundsTree;
THREE.Mesh.prototype.raycast = acceleratedRaycast;

export type Pick = { kind: 'surface'; vertex: number } | { kind: 'marker'; index: number };

const MARKER_COLORS = [0xe6194b, 0x3cb44b, 0x4363d8, 0xf58231];

function disposeTree(object: THREE.Object3D): void {
  object.traverse((o) => {
    const m = o as THREE.Mesh;
    if (m.geometry) {
      m.geometry.disposeBoundsTree?.();
      m.geometry.dispose();
    }
    const mat = (m as { material?: THREE.Material | THREE.Material[] }).material;
    if (Array.isArray(mat)) mat.forEach((x) => x.dispose());
    else mat?.dispose();
  });
}

export class Viewer {
  readonly canvas: HTMLCanvasElement;
  onPick: (pick: Pick) => void = () => {};
  /** Milliseconds the last surface pick took (raycast + snap), for the page's status line. */
  lastPickMs = 0;

  private renderer: THREE.WebGLRenderer;
  private scene = new THREE.Scene();
  private camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
  private controls: OrbitControls;
  private offset: [number, number, number] = [0, 0, 0];
  private radius = 1;
  private positions: Float32Array<ArrayBuffer> = new Float32Array(0);
  private input: THREE.Mesh | null = null;
  private markers = new THREE.Group();
  private patch = new THREE.Group();
  private design = new THREE.Group();
  private deployment = new THREE.Group();
  private layout = new THREE.Group();           // a multi-patch layout: patches in colours, their sides
  private layoutDeployment = new THREE.Group(); // its patches' deployed lamellas
  private frameRequested = false;
  private moving = false; // the camera is being orbited, panned or zoomed
  private down: { x: number; y: number } | null = null;

  constructor(canvas: HTMLCanvasElement) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
    this.renderer.setClearColor(0xf4f5f7, 1);
    this.camera.up.set(0, 0, 1);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.addEventListener('change', () => this.requestRender());
    // While the camera moves, large lamella meshes are drawn in their light version (lamellas.ts).
    this.controls.addEventListener('start', () => { this.moving = true; });
    this.controls.addEventListener('end', () => {
      this.moving = false;
      this.requestRender();
    });
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8f99, 1.6));
    const light = new THREE.DirectionalLight(0xffffff, 1.4);
    light.position.set(0.5, 0.3, 1);
    this.camera.add(light);
    this.scene.add(this.camera, this.markers, this.patch, this.design, this.deployment, this.layout, this.layoutDeployment);
    new ResizeObserver(() => this.resize()).observe(canvas);
    canvas.addEventListener('pointerdown', (e) => {
      if (e.button === 0) this.down = { x: e.clientX, y: e.clientY };
    });
    canvas.addEventListener('pointerup', (e) => {
      const d = this.down;
      this.down = null;
      if (!d || e.button !== 0 || Math.hypot(e.clientX - d.x, e.clientY - d.y) > 5) return;
      const pick = this.pick(e.clientX, e.clientY);
      if (pick) this.onPick(pick);
    });
    this.resize();
  }

  private resize(): void {
    const w = Math.max(1, this.canvas.clientWidth);
    const h = Math.max(1, this.canvas.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  requestRender(): void {
    if (this.frameRequested) return;
    this.frameRequested = true;
    requestAnimationFrame(() => {
      this.frameRequested = false;
      let light = false;
      for (const group of [this.deployment, this.layoutDeployment])
        for (const child of group.children)
          if (child.name === 'lamellas-light') {
            child.visible = this.moving;
            const full = group.getObjectByName('lamellas');
            if (full) full.visible = !this.moving;
            light ||= this.moving;
          }
      this.canvas.dataset['lamellasLight'] = light ? '1' : '0';
      this.renderer.render(this.scene, this.camera);
      this.publishHooks();
    });
  }

  /**
   * Test hooks, after every frame: the markers' pixel positions (CSS pixels from the canvas's
   * top left) as `data-markers` on the canvas, "x,y;x,y;...", corner 1 first; the layers drawn
   * as `data-layers` ("mesh,markers,patch,design"; a layout: "mesh,layout,layout-deployment"); the
   * layout's patches and deployed lamellas drawn as `data-layout-patches` and `data-layout-lamellas`;
   * the lamella boxes drawn (either) as `data-lamellas` and their mesh vertices as `data-lamella-vertices`
   * (`data-lamellas-light`: 1 when the frame drew their light version, while the camera moved).
   */
  private publishHooks(): void {
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    const spots: string[] = [];
    for (const m of this.markers.children) {
      if (!(m instanceof THREE.Mesh)) continue;
      const p = m.position.clone().project(this.camera);
      spots.push(`${((p.x + 1) / 2 * w).toFixed(1)},${((1 - p.y) / 2 * h).toFixed(1)}`);
    }
    this.canvas.dataset['markers'] = spots.join(';');
    const layers: [string, THREE.Object3D | null][] = [['mesh', this.input], ['markers', this.markers], ['patch', this.patch],
                                                       ['design', this.design], ['deployment', this.deployment],
                                                       ['layout', this.layout], ['layout-deployment', this.layoutDeployment]];
    this.canvas.dataset['layers'] = layers.filter(([, o]) => o && o.visible && (o === this.input || o.children.length > 0))
      .map(([name]) => name).join(',');
    this.canvas.dataset['layoutPatches'] = String(this.layout.children.filter((c) => c.name === 'layout-patch').length);
    this.canvas.dataset['layoutLamellas'] = String(this.layoutDeployment.userData['lamellas'] ?? 0);
    // The merged lamella meshes drawn (a single patch's deployment, a layout's): lamellas and vertices.
    let lamellas = 0, vertices = 0;
    for (const group of [this.deployment, this.layoutDeployment])
      for (const child of group.children)
        if (child.name === 'lamellas') {
          lamellas += child.userData['lamellas'] as number;
          vertices += child.userData['vertices'] as number;
        }
    this.canvas.dataset['lamellas'] = String(lamellas);
    this.canvas.dataset['lamellaVertices'] = String(vertices);
  }

  /** A Float32Array of `xyz` relative to the mesh's centre. */
  private local(xyz: ArrayLike<number>): Float32Array<ArrayBuffer> {
    const out = new Float32Array(xyz.length);
    for (let i = 0; i < xyz.length; ++i) out[i] = xyz[i]! - this.offset[i % 3]!;
    return out;
  }

  private localPoint(p: ArrayLike<number>): THREE.Vector3 {
    return new THREE.Vector3(p[0]! - this.offset[0], p[1]! - this.offset[1], p[2]! - this.offset[2]);
  }

  /** The input mesh; clears everything else and recentres the camera on it. */
  setMesh(positions: number[], indices: number[]): void {
    this.clear();
    const min = [Infinity, Infinity, Infinity];
    const max = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < positions.length; ++i) {
      const c = i % 3;
      min[c] = Math.min(min[c]!, positions[i]!);
      max[c] = Math.max(max[c]!, positions[i]!);
    }
    this.offset = [(min[0]! + max[0]!) / 2, (min[1]! + max[1]!) / 2, (min[2]! + max[2]!) / 2];
    this.radius = Math.max(1e-9, Math.hypot(max[0]! - min[0]!, max[1]! - min[1]!, max[2]! - min[2]!) / 2);
    this.positions = this.local(positions);
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(this.positions, 3));
    geometry.setIndex(new THREE.BufferAttribute(Uint32Array.from(indices), 1));
    geometry.computeVertexNormals();
    geometry.computeBoundsTree();
    const material = new THREE.MeshStandardMaterial({
      color: 0xc9ccd3, roughness: 0.85, metalness: 0, side: THREE.DoubleSide, transparent: false, opacity: 1,
      // Pushed back in depth: where the patch lies on it, the patch wins (no z-fighting).
      polygonOffset: true, polygonOffsetFactor: 4, polygonOffsetUnits: 8,
    });
    this.input = new THREE.Mesh(geometry, material);
    this.scene.add(this.input);
    this.fit();
  }

  private fit(): void {
    const r = this.radius;
    this.camera.near = r / 200;
    this.camera.far = r * 200;
    this.camera.position.set(0.55, -1.25, 0.95).normalize().multiplyScalar(r * 2.7);
    this.controls.target.set(0, 0, 0);
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.requestRender();
  }

  private clear(): void {
    for (const g of [this.markers, this.patch, this.design, this.deployment, this.layout, this.layoutDeployment]) this.clearGroup(g);
    if (this.input) {
      this.scene.remove(this.input);
      disposeTree(this.input);
      this.input = null;
    }
  }

  private clearGroup(group: THREE.Group): void {
    for (const child of [...group.children]) {
      group.remove(child);
      disposeTree(child);
    }
    group.userData = {};
    this.requestRender();
  }

  /** What is under the pixel: a marker first, else the nearest vertex of the hit face. */
  pick(clientX: number, clientY: number): Pick | null {
    const t0 = performance.now();
    const rect = this.canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((clientX - rect.left) / rect.width) * 2 - 1,
                                  -((clientY - rect.top) / rect.height) * 2 + 1);
    // Markers just placed have not been rendered yet: bring every world matrix up to date.
    this.scene.updateMatrixWorld();
    const raycaster = new THREE.Raycaster();
    raycaster.setFromCamera(ndc, this.camera);
    const markerHit = raycaster.intersectObjects(this.markers.children.filter((c) => c instanceof THREE.Mesh), false)[0];
    if (markerHit) return { kind: 'marker', index: markerHit.object.userData['index'] as number };
    if (!this.input) return null;
    raycaster.firstHitOnly = true;
    const hit = raycaster.intersectObject(this.input, false)[0];
    if (!hit || !hit.face) return null;
    const p = hit.point;
    let best = hit.face.a;
    let bestD = Infinity;
    for (const v of [hit.face.a, hit.face.b, hit.face.c]) {
      const d = Math.hypot(this.positions[3 * v]! - p.x, this.positions[3 * v + 1]! - p.y,
                           this.positions[3 * v + 2]! - p.z);
      if (d < bestD) {
        bestD = d;
        best = v;
      }
    }
    this.lastPickMs = performance.now() - t0;
    return { kind: 'surface', vertex: best };
  }

  /** Numbered markers at the corner vertices; `selected` is drawn larger. */
  setCorners(vertices: number[], selected: number | null): void {
    this.clearGroup(this.markers);
    const r = this.radius * 0.025;
    vertices.forEach((v, i) => {
      const at = new THREE.Vector3(this.positions[3 * v]!, this.positions[3 * v + 1]!, this.positions[3 * v + 2]!);
      const sphere = new THREE.Mesh(new THREE.SphereGeometry(i === selected ? r * 1.5 : r, 20, 12),
                                    new THREE.MeshStandardMaterial({ color: MARKER_COLORS[i % 4]!, emissive: i === selected ? 0x444444 : 0 }));
      sphere.position.copy(at);
      sphere.userData['index'] = i;
      this.markers.add(sphere);
      const label = new THREE.Sprite(new THREE.SpriteMaterial({ map: digitTexture(i + 1), depthTest: false }));
      label.position.copy(at).add(new THREE.Vector3(0, 0, r * 2.6));
      label.scale.setScalar(r * 3);
      label.renderOrder = 10;
      this.markers.add(label);
    });
    this.requestRender();
  }

  /** The trimmed patch coloured by Gaussian curvature in [-range, range], and its four sides. */
  setPatch(positions: number[], indices: number[], curvature: number[], range: number,
           sides: number[][]): void {
    this.clearPatch();
    const local = this.local(positions);
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(local, 3));
    const colors = new Float32Array(local.length);
    for (let v = 0; v < local.length / 3; ++v) colors.set(diverging(curvature[v] ?? 0, range), 3 * v);
    geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
    geometry.setIndex(indices);
    geometry.computeVertexNormals();
    const surface = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({
      vertexColors: true, roughness: 0.8, side: THREE.DoubleSide, transparent: false, opacity: 1,
    }));
    surface.name = 'patch-surface';
    this.patch.add(surface);
    const segments: number[] = [];
    for (const side of sides)
      for (let i = 0; i + 1 < side.length; ++i) {
        const a = side[i]!, b = side[i + 1]!;
        segments.push(local[3 * a]!, local[3 * a + 1]!, local[3 * a + 2]!, local[3 * b]!, local[3 * b + 1]!, local[3 * b + 2]!);
      }
    const lines = new THREE.BufferGeometry();
    lines.setAttribute('position', new THREE.BufferAttribute(new Float32Array(segments), 3));
    this.patch.add(new THREE.LineSegments(lines, new THREE.LineBasicMaterial({ color: 0x111111 })));
    this.setInputFaded(true);
    this.requestRender();
  }

  private setInputFaded(faded: boolean): void {
    if (!this.input) return;
    const m = this.input.material as THREE.MeshStandardMaterial;
    m.opacity = faded ? 0.35 : 1;
    m.transparent = faded;
    m.depthWrite = !faded;
    m.needsUpdate = true;
    this.requestRender();
  }

  /** Clears the single patch, its design and deployment, and a layout. */
  clearPatch(): void {
    for (const g of [this.patch, this.design, this.deployment, this.layout, this.layoutDeployment]) this.clearGroup(g);
    this.setInputFaded(false);
  }

  /** Members on the surface (g red, h blue, boundary black), crossings and anchors. */
  setDesign(design: Design): void {
    this.clearGroup(this.design);
    this.clearGroup(this.deployment);
    this.design.visible = true; // hidden while a deployment was shown
    this.setPatchOpacity(1);
    const families: Record<string, number[]> = { g: [], h: [], boundary: [] };
    for (const m of design.members) {
      const list = m.boundary ? families['boundary']! : families[m.family === 'g' ? 'g' : 'h']!;
      for (let i = 0; i + 1 < m.surface.length; ++i) {
        const a = this.localPoint(m.surface[i]!), b = this.localPoint(m.surface[i + 1]!);
        list.push(a.x, a.y, a.z, b.x, b.y, b.z);
      }
    }
    const colors: Record<string, number> = { g: 0xb2182b, h: 0x2166ac, boundary: 0x111111 };
    for (const [k, list] of Object.entries(families)) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(list), 3));
      this.design.add(new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: colors[k]!, depthTest: true })));
    }
    const crossing = new Float32Array(design.crossings.length * 3);
    design.crossings.forEach((c, i) => crossing.set(this.localPoint(c.surface_point).toArray(), 3 * i));
    const cg = new THREE.BufferGeometry();
    cg.setAttribute('position', new THREE.BufferAttribute(crossing, 3));
    this.design.add(new THREE.Points(cg, new THREE.PointsMaterial({ color: 0x222222, size: 4, sizeAttenuation: false })));
    const r = this.radius * 0.012;
    const anchors = new THREE.InstancedMesh(new THREE.BoxGeometry(r * 2, r * 2, r * 2),
                                            new THREE.MeshStandardMaterial({ color: 0x1b7837 }), Math.max(1, design.anchors.length));
    anchors.count = design.anchors.length;
    const m = new THREE.Matrix4();
    design.anchors.forEach((a, i) => anchors.setMatrixAt(i, m.makeTranslation(this.localPoint(a.position))));
    this.design.add(anchors);
    this.requestRender();
  }

  private setPatchOpacity(opacity: number): void {
    const surface = this.patch.getObjectByName('patch-surface') as THREE.Mesh | undefined;
    if (!surface) return;
    const m = surface.material as THREE.MeshStandardMaterial;
    m.opacity = opacity;
    m.transparent = opacity < 1; // opaque: drawn first, hides the faded input mesh under it
    m.depthWrite = opacity >= 1;
    m.needsUpdate = true;
  }

  /**
   * Deployed lamellas as boxes of the design's width and thickness (the cross-section spanned by
   * `normal × tangent` and the material normal), coloured by `value(rod, vertex)` in [0, max]:
   * the deviation of each vertex, or a per-lamella quantity (its largest bending stress).
   */
  setDeployment(deployment: Deployment, width: number, thickness: number, max: number,
                value: (rod: Lamella, vertex: number) => number): void {
    this.clearGroup(this.deployment);
    this.design.visible = false;
    this.setPatchOpacity(0.3);
    this.deployment.add(...this.lamellaBoxes([{ rods: deployment.rods, width, thickness }], max, value));
    // Inner anchors the simulation added (interior_anchors "auto"): orange cubes at their targets.
    const added = deployment.added_anchors ?? [];
    if (added.length) {
      const r = this.radius * 0.015;
      const cubes = new THREE.InstancedMesh(new THREE.BoxGeometry(r * 2, r * 2, r * 2),
                                            new THREE.MeshStandardMaterial({ color: 0xe66101 }), added.length);
      cubes.name = 'added-anchors';
      const m = new THREE.Matrix4();
      added.forEach((a, i) => cubes.setMatrixAt(i, m.makeTranslation(this.localPoint(a.position))));
      this.deployment.add(cubes);
    }
    this.requestRender();
  }

  /**
   * Lamellas as boxes, one geometry (lamellas.ts: typed arrays, outward normals, end caps):
   * each group's rods with its cross-section, coloured by `value(rod, vertex)` in [0, max] on
   * the sequential map. Its lamella and vertex counts go to the canvas hooks.
   */
  private lamellaBoxes(groups: LamellaGroup[], max: number,
                       value: (rod: Lamella, vertex: number) => number): THREE.Mesh[] {
    const boxes = lamellaMesh(groups, this.offset, max, value);
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(boxes.positions, 3));
    g.setAttribute('normal', new THREE.BufferAttribute(boxes.normals, 3));
    g.setAttribute('color', new THREE.BufferAttribute(boxes.colors, 3));
    g.setIndex(new THREE.BufferAttribute(boxes.indices, 1));
    // Closed boxes with outward faces: back faces culled, half the fragments of double-sided.
    const material = new THREE.MeshStandardMaterial({ vertexColors: true, side: THREE.FrontSide, roughness: 0.6 });
    const mesh = new THREE.Mesh(g, material);
    mesh.name = 'lamellas';
    mesh.userData['lamellas'] = boxes.lamellas;
    mesh.userData['vertices'] = boxes.vertices;
    mesh.userData['triangles'] = boxes.triangles;
    if (!boxes.light) return [mesh];
    // The light version, drawn instead while the camera moves: the same vertex buffers, fewer triangles.
    const lg = new THREE.BufferGeometry();
    for (const name of ['position', 'normal', 'color']) lg.setAttribute(name, g.getAttribute(name));
    lg.setIndex(new THREE.BufferAttribute(boxes.light, 1));
    const light = new THREE.Mesh(lg, material.clone());
    light.name = 'lamellas-light';
    light.visible = false;
    return [mesh, light];
  }

  /**
   * A multi-patch layout: each cut patch in its own colour over the faded input, the seams (sides
   * two patches share) as black lines and the outer sides grey. Clears the single patch.
   */
  setLayout(patches: { positions: number[]; indices: number[]; colour: Rgb }[], seams: number[], outer: number[]): void {
    this.clearPatch();
    for (const p of patches) {
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(this.local(p.positions), 3));
      geometry.setIndex(p.indices);
      geometry.computeVertexNormals();
      const surface = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({
        color: new THREE.Color(...p.colour), roughness: 0.8, side: THREE.DoubleSide,
        polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 2, // the lines on top win
      }));
      surface.name = 'layout-patch';
      this.layout.add(surface);
    }
    for (const [xyz, colour, name] of [[seams, 0x111111, 'layout-seams'], [outer, 0x6b7080, 'layout-outer']] as const) {
      const lines = new THREE.BufferGeometry();
      lines.setAttribute('position', new THREE.BufferAttribute(this.local(xyz), 3));
      const segments = new THREE.LineSegments(lines, new THREE.LineBasicMaterial({ color: colour }));
      segments.name = name;
      this.layout.add(segments);
    }
    this.setInputFaded(true);
    this.requestRender();
  }

  /**
   * The deployed lamellas of a layout's patches on one colour scale ([0, max]), over its patches
   * made translucent; `null` clears them (the patches opaque again).
   */
  setLayoutDeployment(groups: LamellaGroup[] | null, max = 0,
                      value: (rod: Lamella, vertex: number) => number = () => 0): void {
    this.clearGroup(this.layoutDeployment);
    for (const child of this.layout.children) {
      if (child.name !== 'layout-patch') continue;
      const m = (child as THREE.Mesh).material as THREE.MeshStandardMaterial;
      m.opacity = groups ? 0.3 : 1;
      m.transparent = groups !== null;
      m.depthWrite = groups === null;
      m.needsUpdate = true;
    }
    if (groups) {
      this.layoutDeployment.add(...this.lamellaBoxes(groups, max, value));
      this.layoutDeployment.userData['lamellas'] = groups.reduce((k, g) => k + g.rods.length, 0);
    }
    this.requestRender();
  }

}

const digitCache = new Map<number, THREE.Texture>();
function digitTexture(n: number): THREE.Texture {
  const cached = digitCache.get(n);
  if (cached) return cached;
  const canvas = document.createElement('canvas');
  canvas.width = canvas.height = 64;
  const ctx = canvas.getContext('2d')!;
  ctx.fillStyle = 'rgba(255,255,255,0.9)';
  ctx.beginPath();
  ctx.arc(32, 32, 28, 0, Math.PI * 2);
  ctx.fill();
  ctx.fillStyle = '#111';
  ctx.font = 'bold 40px sans-serif';
  ctx.textAlign = 'center';
  ctx.textBaseline = 'middle';
  ctx.fillText(String(n), 32, 34);
  const texture = new THREE.CanvasTexture(canvas);
  texture.colorSpace = THREE.SRGBColorSpace;
  digitCache.set(n, texture);
  return texture;
}
