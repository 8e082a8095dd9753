// The flat view: one flattened piece at true scale (mm) with the same heat map as on the surface,
// its outline and a millimetre grid; wheel zooms, drag pans; hovering a face tells where it is
// on the 3D piece, and a point hovered in 3D is marked here.

import * as THREE from 'three';
import { heatColour } from './colours.js';

export class View2D {
  constructor(canvas) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.setClearColor(0xfafbfc);
    this.scene = new THREE.Scene();
    this.camera = new THREE.OrthographicCamera(-1, 1, 1, -1, -10, 10);
    this.group = new THREE.Group();
    this.marker = new THREE.Group();
    this.scene.add(this.group, this.marker);
    this.raycaster = new THREE.Raycaster();
    this.view = { cx: 0, cy: 0, half: 100 };
    this.needs = true;
    new ResizeObserver(() => this.resize()).observe(canvas.parentElement);
    let drag = null;
    canvas.addEventListener('pointerdown', (e) => { drag = { x: e.clientX, y: e.clientY, cx: this.view.cx, cy: this.view.cy }; });
    window.addEventListener('pointerup', () => { drag = null; });
    canvas.addEventListener('pointermove', (e) => {
      if (!drag) return;
      const s = (2 * this.view.half) / this.canvas.clientHeight;
      this.view.cx = drag.cx - (e.clientX - drag.x) * s;
      this.view.cy = drag.cy + (e.clientY - drag.y) * s;
      this.applyView();
    });
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      this.view.half *= Math.exp(e.deltaY * 0.001);
      this.applyView();
    }, { passive: false });
    const loop = () => {
      if (this.needs) { this.needs = false; this.renderer.render(this.scene, this.camera); }
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
  }

  resize() {
    const el = this.canvas.parentElement;
    if (!el.clientWidth || !el.clientHeight) return;
    this.renderer.setSize(el.clientWidth, el.clientHeight, false);
    this.applyView();
  }

  applyView() {
    const a = this.canvas.clientWidth / Math.max(1, this.canvas.clientHeight);
    const { cx, cy, half } = this.view;
    Object.assign(this.camera, { left: cx - half * a, right: cx + half * a, top: cy + half, bottom: cy - half });
    this.camera.updateProjectionMatrix();
    this.needs = true;
  }

  /** Shows piece `p` (from POST /api/flatten) flat, coloured on `scale`. */
  setPiece(p, scale, stops, keepView) {
    for (const o of [...this.group.children]) { this.group.remove(o); o.geometry?.dispose(); }
    this.piece = p;
    this.setMarker(null);
    if (!p) { this.needs = true; return; }
    const { flat, triangles, strain } = p.mesh;
    const n = triangles.length / 3;
    const pos = new Float32Array(n * 9);
    const col = new Float32Array(n * 9);
    let minx = Infinity, miny = Infinity, maxx = -Infinity, maxy = -Infinity;
    for (let f = 0; f < n; f++) {
      const k = new THREE.Color().setRGB(...heatColour(stops, scale, strain[f] ?? 0), THREE.SRGBColorSpace);
      const c = [k.r, k.g, k.b];
      for (let k = 0; k < 3; k++) {
        const v = triangles[3 * f + k];
        const x = flat[2 * v], y = flat[2 * v + 1];
        pos.set([x, y, 0], 9 * f + 3 * k);
        col.set(c, 9 * f + 3 * k);
        minx = Math.min(minx, x); maxx = Math.max(maxx, x); miny = Math.min(miny, y); maxy = Math.max(maxy, y);
      }
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    g.setAttribute('color', new THREE.BufferAttribute(col, 3));
    this.mesh = new THREE.Mesh(g, new THREE.MeshBasicMaterial({ vertexColors: true, side: THREE.DoubleSide }));
    this.group.add(this.mesh);
    this.group.add(this.grid(minx, miny, maxx, maxy));
    this.group.add(this.outline(p));
    if (!keepView) {
      this.view = { cx: (minx + maxx) / 2, cy: (miny + maxy) / 2, half: 0.6 * Math.max(maxy - miny, (maxx - minx) / Math.max(0.5, this.canvas.clientWidth / Math.max(1, this.canvas.clientHeight))) };
    }
    this.applyView();
  }

  /** A 10 mm grid under the piece (its scale at a glance). */
  grid(minx, miny, maxx, maxy) {
    const pts = [];
    const s = 10;
    const x0 = Math.floor(minx / s) * s, x1 = Math.ceil(maxx / s) * s;
    const y0 = Math.floor(miny / s) * s, y1 = Math.ceil(maxy / s) * s;
    for (let x = x0; x <= x1; x += s) pts.push(new THREE.Vector3(x, y0, -1), new THREE.Vector3(x, y1, -1));
    for (let y = y0; y <= y1; y += s) pts.push(new THREE.Vector3(x0, y, -1), new THREE.Vector3(x1, y, -1));
    return new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color: 0xdde3ea }));
  }

  outline(p) {
    const { flat: F, triangles: T } = p.mesh;
    const count = new Map();
    for (let f = 0; f < T.length / 3; f++) {
      for (let k = 0; k < 3; k++) {
        const a = T[3 * f + k], b = T[3 * f + (k + 1) % 3];
        const key = a < b ? `${a},${b}` : `${b},${a}`;
        count.set(key, (count.get(key) || 0) + 1);
      }
    }
    const pts = [];
    for (const [key, c] of count) {
      if (c !== 1) continue;
      for (const v of key.split(',').map(Number)) pts.push(new THREE.Vector3(F[2 * v], F[2 * v + 1], 1));
    }
    return new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color: 0x111111 }));
  }

  /** The face under the pointer and the barycentric coordinates of the point in it. */
  pick(ev) {
    if (!this.mesh) return null;
    const r = this.canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.camera);
    const hits = this.raycaster.intersectObject(this.mesh, false);
    if (!hits.length) return null;
    const h = hits[0];
    const pos = this.mesh.geometry.attributes.position;
    const tri = [0, 1, 2].map((k) => new THREE.Vector3().fromBufferAttribute(pos, 3 * h.faceIndex + k));
    const bary = new THREE.Vector3();
    THREE.Triangle.getBarycoord(new THREE.Vector3(h.point.x, h.point.y, 0), tri[0], tri[1], tri[2], bary);
    return { face: h.faceIndex, bary: bary.toArray() };
  }

  /** Where a flat point [x, y] (mm) is drawn on the page (CSS pixels). */
  toScreen(xy) {
    const v = new THREE.Vector3(xy[0], xy[1], 0).project(this.camera);
    const r = this.canvas.getBoundingClientRect();
    return { x: r.left + (v.x + 1) / 2 * r.width, y: r.top + (1 - v.y) / 2 * r.height };
  }

  /** Marks a flat point [x, y], or nothing. */
  setMarker(xy) {
    for (const o of [...this.marker.children]) { this.marker.remove(o); o.geometry?.dispose(); }
    if (xy) {
      const r = this.view.half * 0.02;
      const m = new THREE.Mesh(new THREE.CircleGeometry(r, 20), new THREE.MeshBasicMaterial({ color: 0x000000 }));
      m.position.set(xy[0], xy[1], 2);
      this.marker.add(m);
    }
    this.needs = true;
  }
}
