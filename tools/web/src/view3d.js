// The 3D view: the design's surfaces with their style lines, notches and grain, coloured by piece
// or by the strain heat map of the flattened pieces; orbit and zoom; picking of the surface (for
// drawing), of a piece (for the heat map's hover link) and of a line's points (for editing).

import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { heatColour, pieceColour } from './colours.js';

/** A colour given in sRGB (as the report's map is) in the renderer's linear working space. */
const linear = (c) => {
  const k = new THREE.Color().setRGB(c[0], c[1], c[2], THREE.SRGBColorSpace);
  return [k.r, k.g, k.b];
};

/** A non-indexed geometry of triangles with one colour per face (`colourOf(face) -> [r,g,b]`,
 * sRGB). */
function faceColoured(positions, triangles, colourOf) {
  const n = triangles.length / 3;
  const pos = new Float32Array(n * 9);
  const col = new Float32Array(n * 9);
  for (let f = 0; f < n; f++) {
    const c = linear(colourOf(f));
    for (let k = 0; k < 3; k++) {
      const v = triangles[3 * f + k];
      pos.set([positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]], 9 * f + 3 * k);
      col.set(c, 9 * f + 3 * k);
    }
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.setAttribute('color', new THREE.BufferAttribute(col, 3));
  g.computeVertexNormals();
  return g;
}

function indexed(positions, triangles) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(positions), 3));
  g.setIndex(new THREE.BufferAttribute(new Uint32Array(triangles), 1));
  g.computeBoundingBox();
  return g;
}

function polyline(points, colour, closed = false) {
  const pts = points.map((p) => new THREE.Vector3(p[0], p[1], p[2]));
  if (closed && pts.length) pts.push(pts[0].clone());
  const g = new THREE.BufferGeometry().setFromPoints(pts);
  return new THREE.Line(g, new THREE.LineBasicMaterial({ color: colour, depthTest: true }));
}

const surfaceMaterial = () => new THREE.MeshLambertMaterial({
  vertexColors: true, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
});

export class View3D {
  constructor(canvas) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, alpha: true, preserveDrawingBuffer: true });
    this.renderer.setClearColor(0x000000, 0);
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(35, 1, 1, 10000);
    this.camera.up.set(0, 0, 1);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.addEventListener('change', () => this.redraw());
    // Until the user moves the camera, a resized view is framed again.
    this.controls.addEventListener('start', () => { this.moved = true; });
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.4);
    sun.position.set(1, -2, 3);
    this.scene.add(sun);
    this.camera.add(new THREE.DirectionalLight(0xffffff, 0.6));
    this.scene.add(this.camera);
    this.groups = {};
    for (const k of ['regions', 'heat', 'lines', 'handles', 'draft', 'marker']) {
      this.groups[k] = new THREE.Group();
      this.scene.add(this.groups[k]);
    }
    this.pick = [];        // per part: its indexed surface mesh (invisible, for picking)
    this.heatMeshes = [];  // per flattened piece drawn
    this.handles = [];     // {mesh, part, line, point}
    this.mode = 'heat';
    this.diag = 100;
    this.raycaster = new THREE.Raycaster();
    this.raycaster.params.Line.threshold = 1;
    this.needs = true;
    new ResizeObserver(() => this.resize()).observe(canvas.parentElement);
    const loop = () => {
      if (this.needs) {
        this.needs = false;
        this.renderer.render(this.scene, this.camera);
      }
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
  }

  redraw() { this.needs = true; }

  resize() {
    const el = this.canvas.parentElement;
    const w = el.clientWidth, h = el.clientHeight;
    if (!w || !h) return;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    if (this.box && !this.moved) this.frame(this.box);
    this.redraw();
  }

  clear(group) {
    const g = this.groups[group];
    for (const o of [...g.children]) {
      g.remove(o);
      o.geometry?.dispose();
    }
  }

  /** The parts of the design (GET /api/regions): surfaces by region, lines, boundary, handles. */
  setParts(parts) {
    this.clear('regions');
    this.clear('lines');
    this.clear('handles');
    this.pick = [];
    this.handles = [];
    this.parts = parts;
    const box = new THREE.Box3();
    for (const part of parts) {
      const P = part.mesh?.positions || [];
      for (let i = 0; i < P.length; i += 3) box.expandByPoint(new THREE.Vector3(P[i], P[i + 1], P[i + 2]));
    }
    if (!box.isEmpty()) this.diag = box.getSize(new THREE.Vector3()).length();
    for (const part of parts) {
      if (!part.mesh) { this.pick.push(null); continue; }
      const { positions, triangles } = part.mesh;
      const g = indexed(positions, triangles);
      const pickMesh = new THREE.Mesh(g, new THREE.MeshBasicMaterial({ visible: false, side: THREE.DoubleSide }));
      pickMesh.userData.part = part.index;
      this.groups.regions.add(pickMesh);
      this.pick.push(pickMesh);
      const rof = part.region_of_face || [];
      const named = part.regions || [];
      const mesh = new THREE.Mesh(
        faceColoured(positions, triangles, (f) => {
          const r = rof[f] ?? 0;
          return named[r] && named[r].piece == null ? [0.85, 0.85, 0.85] : pieceColour(r);
        }),
        surfaceMaterial(),
      );
      mesh.userData.regionView = true;
      this.groups.regions.add(mesh);
      for (const loop of part.boundary || []) this.groups.lines.add(polyline(loop, 0x30363d, true));
      for (const g of part.grain || []) this.groups.lines.add(this.arrow(g.from, g.to));
      part.lines.forEach((l, li) => {
        if (l.path && l.path.length) this.groups.lines.add(polyline(l.path, 0x1d4ed8));
        l.points.forEach((p, pi) => this.addHandle(p, part.index, li, pi, 0x1d4ed8));
        for (const n of l.notches || []) this.addHandle(n, part.index, li, -1, 0xd97706, 0.8);
      });
    }
    if (!box.isEmpty()) {
      this.raycaster.params.Line.threshold = 0.005 * this.diag;
      for (const h of this.handles) h.mesh.scale.setScalar(this.handleSize());
      if (!this.box) this.frame(box);
      this.box = box;
    }
    this.applyMode();
  }

  handleSize() { return 0.006 * this.diag; }

  /** A piece's grain line as an arrow (the warp runs from its first point to its second). */
  arrow(from, to) {
    const a = new THREE.Vector3(...from), b = new THREE.Vector3(...to);
    const len = a.distanceTo(b);
    const dir = b.clone().sub(a).normalize();
    return new THREE.ArrowHelper(dir, a, len, 0x7c3aed, Math.min(0.25 * len, 0.03 * this.diag), Math.min(0.12 * len, 0.015 * this.diag));
  }

  addHandle(p, part, line, point, colour, scale = 1) {
    const m = new THREE.Mesh(new THREE.SphereGeometry(scale, 12, 8), new THREE.MeshLambertMaterial({ color: colour }));
    m.position.set(p[0], p[1], p[2]);
    m.scale.setScalar(this.handleSize());
    this.groups.handles.add(m);
    if (point >= 0) this.handles.push({ mesh: m, part, line, point });
  }

  /** The flattened pieces (POST /api/flatten) as heat maps on the surface; grain arrows. Of a
   * graded design's pieces only those of the selected piece's size are drawn (the sizes lie
   * over each other); picking still answers with the piece's index in `pieces`. */
  setPieces(pieces, scale, stops, selected) {
    this.clear('heat');
    this.heatMeshes = [];
    const size = pieces.find((p) => p.name === selected)?.size;
    pieces.forEach((p, k) => {
      if (p.size !== size) return;
      const { positions, triangles, strain } = p.mesh;
      const g = faceColoured(positions, triangles, (f) => heatColour(stops, scale, strain[f] ?? 0));
      const mesh = new THREE.Mesh(g, surfaceMaterial());
      mesh.userData.piece = k;
      this.groups.heat.add(mesh);
      this.heatMeshes.push(mesh);
      if (p.name === selected) this.groups.heat.add(this.outline(p));
    });
    this.pieces = pieces;
    this.applyMode();
  }

  /** A piece's 3D outline (its boundary edges), to show which piece is selected. */
  outline(p) {
    const { positions: P, triangles: T } = p.mesh;
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
      for (const v of key.split(',').map(Number)) pts.push(new THREE.Vector3(P[3 * v], P[3 * v + 1], P[3 * v + 2]));
    }
    const g = new THREE.BufferGeometry().setFromPoints(pts);
    return new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: 0x111111 }));
  }

  setMode(mode) { this.mode = mode; this.applyMode(); }

  applyMode() {
    const heat = this.mode === 'heat' && this.heatMeshes.length > 0;
    this.groups.heat.visible = heat;
    for (const o of this.groups.regions.children) if (o.userData.regionView) o.visible = !heat;
    this.redraw();
  }

  /** Looks at the box from the front-left and above, the whole of it in view. */
  frame(box) {
    const c = box.getCenter(new THREE.Vector3());
    const d = box.getSize(new THREE.Vector3()).length();
    const half = THREE.MathUtils.degToRad(this.camera.fov / 2);
    const fit = Math.min(half, Math.atan(Math.tan(half) * this.camera.aspect));
    const dist = (0.5 * d) / Math.sin(fit) * 0.8;
    this.camera.near = d / 100;
    this.camera.far = d * 20;
    this.camera.position.copy(c).add(new THREE.Vector3(0.35, -0.8, 0.5).normalize().multiplyScalar(dist));
    this.controls.target.copy(c);
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.redraw();
  }

  ndc(ev) {
    const r = this.canvas.getBoundingClientRect();
    return new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
  }

  /** The surface point under the pointer: {part, point: [x,y,z], face}. */
  pickSurface(ev) {
    this.raycaster.setFromCamera(this.ndc(ev), this.camera);
    const hits = this.raycaster.intersectObjects(this.pick.filter(Boolean), false);
    if (!hits.length) return null;
    const h = hits[0];
    return { part: h.object.userData.part, point: h.point.toArray(), face: h.faceIndex };
  }

  /** The flattened piece under the pointer: {piece, face, bary: [a,b,c]}. */
  pickPiece(ev) {
    if (!this.heatMeshes.length) return null;
    this.raycaster.setFromCamera(this.ndc(ev), this.camera);
    const hits = this.raycaster.intersectObjects(this.heatMeshes, false);
    if (!hits.length) return null;
    const h = hits[0];
    const pos = h.object.geometry.attributes.position;
    const f = h.faceIndex;
    const tri = [0, 1, 2].map((k) => new THREE.Vector3().fromBufferAttribute(pos, 3 * f + k));
    const bary = new THREE.Vector3();
    THREE.Triangle.getBarycoord(h.point, tri[0], tri[1], tri[2], bary);
    return { piece: h.object.userData.piece, face: f, bary: bary.toArray(), point: h.point.toArray() };
  }

  /** The line point handle under the pointer. */
  pickHandle(ev) {
    this.raycaster.setFromCamera(this.ndc(ev), this.camera);
    const hits = this.raycaster.intersectObjects(this.handles.map((h) => h.mesh), false);
    if (!hits.length) return null;
    return this.handles.find((h) => h.mesh === hits[0].object) || null;
  }

  /** The points of the line being drawn; ends that close on the boundary or a line are green. */
  setDraft(points, closedEnds) {
    this.clear('draft');
    if (!points.length) { this.redraw(); return; }
    this.groups.draft.add(polyline(points, 0xdc2626));
    points.forEach((p, i) => {
      const end = (i === 0 && closedEnds[0]) || (i === points.length - 1 && closedEnds[1]);
      const m = new THREE.Mesh(new THREE.SphereGeometry(1, 12, 8), new THREE.MeshLambertMaterial({ color: end ? 0x16a34a : 0xdc2626 }));
      m.position.set(...p);
      m.scale.setScalar(this.handleSize() * 1.2);
      this.groups.draft.add(m);
    });
    this.redraw();
  }

  /** A marker at a 3D point (the hover link), or none. */
  setMarker(p) {
    this.clear('marker');
    if (p) {
      const m = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 10), new THREE.MeshBasicMaterial({ color: 0x000000 }));
      m.position.set(...p);
      m.scale.setScalar(this.handleSize() * 1.1);
      this.groups.marker.add(m);
    }
    this.redraw();
  }

  /** Where a 3D point is drawn on the page (CSS pixels), for scripts that click on the form. */
  toScreen(p) {
    const v = new THREE.Vector3(...p).project(this.camera);
    const r = this.canvas.getBoundingClientRect();
    return { x: r.left + (v.x + 1) / 2 * r.width, y: r.top + (1 - v.y) / 2 * r.height, depth: v.z };
  }
}
