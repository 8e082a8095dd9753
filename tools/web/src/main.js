// The workbench page: draws the design in 3D, lets the pattern maker draw style lines on the
// form, shows the pieces' strain live on the surface and flat side by side, the pattern, the nest
// and the device. Every change goes through the JSON API; every open page follows the design
// through /api/events.

import { api, listen } from './api.js';
import { heatScale, diverging } from './colours.js';
import { View3D } from './view3d.js';
import { View2D } from './view2d.js';
import { piecesPanel, seamsPanel, patternPanel, nestPanel } from './panels.js';
import { devicePanel } from './device.js';

const $ = (id) => document.getElementById(id);

const state = {
  health: null,
  tree: null,
  revision: 0,
  requested: 0,
  drawnRegions: 0,
  drawnFlat: 0,
  regions: null,
  flat: null,
  selected: null,
  tool: 'orbit',
  tab: 'pieces',
  draft: [],
  draftPart: null,
  draftEnds: [false, false],
  edit: null,
  pendingClose: null,
};

// What scripts (and the browser test) can read: the state, where a 3D point is on the page,
// and how long each closing click took to show its heat map.
const hooks = {
  state,
  timings: [],
  toScreen: (p) => v3.toScreen(p),
  pickAt: (x, y) => v3.pickSurface({ clientX: x, clientY: y }),
  pieceAt: (x, y) => v3.pickPiece({ clientX: x, clientY: y }),
  flatAt: (x, y) => v2.pick({ clientX: x, clientY: y }),
  flatToScreen: (xy) => v2.toScreen(xy),
  drawnRevision: () => state.drawnFlat,
};
window.__flatcut = hooks;

const v3 = new View3D($('c3d'));
const v2 = new View2D($('c2d'));

// ---- messages -------------------------------------------------------------------------------

function showError(msg) {
  const el = $('error');
  el.textContent = msg;
  el.hidden = false;
}
$('error').addEventListener('click', () => { $('error').hidden = true; });

function status(text) { $('status').textContent = text; }

function progress(done, total) {
  const p = $('progress');
  p.hidden = false;
  $('cancel').hidden = false;
  if (total > 0) { p.max = total; p.value = done; } else { p.removeAttribute('value'); }
}

function idle() {
  $('progress').hidden = true;
  $('cancel').hidden = true;
}

// ---- the design -----------------------------------------------------------------------------

function mmPerUnit(k) { return state.regions?.parts?.[k]?.mm_per_unit ?? 1; }

function toUnits(p, k) {
  const s = mmPerUnit(k);
  return p.map((x) => Math.round((x / s) * 1e4) / 1e4);
}

function bar(h) {
  $('saved').textContent = h.saved ? 'saved' : 'not saved';
  $('saved').className = `badge${h.saved ? '' : ' dirty'}`;
  $('undo').disabled = !h.can_undo;
  $('redo').disabled = !h.can_redo;
}

/** Brings the page to the design's revision `rev`: the tree, the regions, then the flattening. */
async function refresh(rev) {
  if (rev <= state.requested) return;
  state.requested = rev;
  // The flattening is asked for at once: the server started it with the edit.
  const flat = flatten();
  const [tree, regions] = await Promise.all([api('GET', '/api/design'), api('GET', '/api/regions')]);
  if (regions.revision >= state.drawnRegions) {
    state.tree = tree;
    state.regions = regions;
    state.drawnRegions = regions.revision;
    v3.setParts(regions.parts);
    const bad = regions.parts.find((p) => p.error);
    if (bad) showError(bad.error);
  }
  await flat;
}

async function flatten() {
  status('flattening…');
  progress(0, 0);
  try {
    const all = $('all-sizes').checked;
    const view = await api('POST', `/api/flatten${all ? '?sizes=all' : ''}`);
    if (view.revision < state.drawnFlat || all !== $('all-sizes').checked) return;
    state.flat = view;
    state.drawnFlat = view.revision;
    state.scale = heatScale(view.pieces);
    state.stops = view.colour_map;
    if (!view.pieces.some((p) => p.name === state.selected)) state.selected = view.pieces[0]?.name ?? null;
    drawPieces(false);
    $('sizes-box').hidden = view.sizes.length < 2;
    const base = view.sizes.length > 1 && !all ? view.pieces[0]?.size : null;
    status(`${view.pieces.length} pieces${base ? ` in size ${base} of ${view.sizes.join(', ')}` : ''} · ${view.elapsed_s.toFixed(2)} s`);
    if (state.pendingClose && view.revision >= state.pendingClose.revision) {
      // The heat map of the new pieces is drawn in the next frame (the render loop's turn comes
      // first); it is on the screen when the frame after it begins.
      const t0 = state.pendingClose.t0;
      state.pendingClose = null;
      requestAnimationFrame(() => requestAnimationFrame(() => hooks.timings.push({
        closeToHeatMs: performance.now() - t0, t0, revision: view.revision, serverFlattenMs: 1000 * view.elapsed_s,
      })));
    }
    $('legend').innerHTML = legend();
    panels();
  } catch (e) {
    if (e.status === 409) return; // superseded by a newer edit, or cancelled
    status('not flattened');
    showError(e.message);
  } finally {
    idle();
  }
}

function drawPieces(keepView) {
  const view = state.flat;
  if (!view) return;
  v3.setPieces(view.pieces, state.scale, state.stops, state.selected);
  const p = view.pieces.find((x) => x.name === state.selected);
  v2.setPiece(p, state.scale, state.stops, keepView);
  $('piece-title').textContent = p
    ? `${p.name}: stretch ${p.stretch_max_pct.toFixed(2)} %, compression ${p.compress_max_pct.toFixed(2)} % (flat, true mm)`
    : '';
}

function legend() {
  const s = state.scale;
  if (!s) return '';
  const grad = [-1, -0.5, 0, 0.5, 1].map((t) => `rgb(${diverging(state.stops, t).map((x) => Math.round(x * 255)).join(',')})`).join(',');
  const lo = s.compress != null ? `−${s.compress.toFixed(1)} %` : '';
  const hi = s.stretch != null ? `+${s.stretch.toFixed(1)} %` : '';
  return `<div>${s.limits ? 'strain against the material limits (darker: beyond)' : 'strain'}</div>
    <div class="bar" style="background:linear-gradient(90deg,${grad})"></div>
    <div class="ticks"><span>${lo} compression</span><span>0</span><span>stretch ${hi}</span></div>`;
}

function dartsAuto(name) {
  for (const part of state.tree?.part || []) {
    for (const p of part.piece || []) if (p.name === name) return p.darts === 'auto';
  }
  for (const p of state.tree?.piece || []) if (p.name === name) return p.darts === 'auto';
  return false;
}

function panels() {
  const view = state.flat;
  if (view) for (const p of view.pieces) p.darts_auto = dartsAuto(p.name);
  piecesPanel($('tab-pieces'), view, state.selected, (name) => {
    state.selected = name;
    drawPieces(false);
    panels();
  }, setDarts);
  seamsPanel($('tab-seams'), view, 0.1);
  if (state.tab === 'pattern') patternPanel($('tab-pattern'), state.drawnFlat);
  if (state.tab === 'nest') nestPanel($('tab-nest'), state.drawnFlat, api);
}

async function setDarts(name, on) {
  const tree = structuredClone(state.tree);
  const all = [...(tree.piece || []), ...(tree.part || []).flatMap((p) => p.piece || [])];
  const p = all.find((x) => x.name === name);
  if (!p) return;
  if (on) p.darts = 'auto'; else delete p.darts;
  await putTree(tree);
}

async function putTree(tree) {
  try {
    const r = await api('PUT', '/api/design?regions=name', tree);
    bar(r);
    await refresh(r.revision);
  } catch (e) {
    showError(e.message);
  }
}

// ---- tools ----------------------------------------------------------------------------------

function setTool(t) {
  state.tool = t;
  for (const b of document.querySelectorAll('[data-tool]')) b.classList.toggle('on', b.dataset.tool === t);
  dropDraft();
  const hints = {
    orbit: 'Drag to orbit, wheel to zoom; click a piece to see it flat.',
    line: 'Click on the surface to draw a style line; start and end it on the boundary or another line.',
    edit: 'Drag a line\'s point along the surface; Delete removes the selected point.',
    notch: 'Click on a line to put a notch there.',
    name: 'Click in a region to name its piece.',
  };
  $('hint').textContent = hints[t];
}

function dropDraft() {
  state.draft = [];
  state.draftPart = null;
  state.draftEnds = [false, false];
  v3.setDraft([], [false, false]);
}

function dist(a, b) { return Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]); }

/** The nearest point of a polyline to p: [distance, point]. */
function nearestOn(line, p, closed) {
  let best = [Infinity, null];
  const n = line.length;
  for (let i = 0; i + 1 < n + (closed ? 1 : 0); i++) {
    const a = line[i], b = line[(i + 1) % n];
    const ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    const l2 = ab[0] ** 2 + ab[1] ** 2 + ab[2] ** 2;
    const t = l2 > 0 ? Math.min(1, Math.max(0, ((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1] + (p[2] - a[2]) * ab[2]) / l2)) : 0;
    const q = [a[0] + ab[0] * t, a[1] + ab[1] * t, a[2] + ab[2] * t];
    const d = dist(p, q);
    if (d < best[0]) best = [d, q];
  }
  return best;
}

/** Where a line's end closes (the design loader's rule: within end_tolerance_mm of the surface
 * boundary or another line), or null. */
function closingPoint(part, p) {
  let best = [Infinity, null];
  for (const loop of part.boundary) { const b = nearestOn(loop, p, true); if (b[0] < best[0]) best = b; }
  for (const l of part.lines) if (l.path.length) { const b = nearestOn(l.path, p, false); if (b[0] < best[0]) best = b; }
  return best[0] <= part.end_tolerance_mm ? best[1] : null;
}

async function lineClick(ev) {
  const hit = v3.pickSurface(ev);
  if (!hit) return;
  if (state.draftPart != null && hit.part !== state.draftPart) return;
  const part = state.regions.parts[hit.part];
  state.draftPart = hit.part;
  const d = state.draft;
  const tol = part.end_tolerance_mm;
  if (d.length >= 3 && dist(hit.point, d[0]) <= tol) {
    d.push([...d[0]]);
    return commitLine(ev.timeStamp);
  }
  const end = closingPoint(part, hit.point);
  d.push(end || hit.point);
  if (d.length === 1) state.draftEnds[0] = !!end;
  state.draftEnds[1] = d.length > 1 && !!end;
  v3.setDraft(d, state.draftEnds);
  if (d.length >= 2 && state.draftEnds[0] && state.draftEnds[1]) return commitLine(ev.timeStamp);
  $('hint').textContent = state.draftEnds[0]
    ? 'Go on clicking; the line closes when you click on the boundary or another line (Enter ends it here).'
    : 'This line does not start on the boundary or a line: it must close on itself (click its first point).';
}

/** Sends the drawn line; `t0`: when the click (or key) that ended it happened. */
async function commitLine(t0 = performance.now()) {
  const part = state.regions.parts[state.draftPart];
  const points = state.draft;
  dropDraft();
  try {
    const r = await api('POST', '/api/lines', { part: part.name, points });
    state.pendingClose = { t0, revision: r.revision };
    bar(r);
    status(`line '${r.line}' added${r.added.length ? `; new piece(s): ${r.added.join(', ')}` : ''}`);
    await refresh(r.revision);
  } catch (e) {
    showError(e.message);
  }
  $('hint').textContent = 'Line drawn. Click to start another.';
}

async function nameClick(ev) {
  const hit = v3.pickSurface(ev);
  if (!hit) return;
  const part = state.regions.parts[hit.part];
  const r = part.regions[part.region_of_face[hit.face]];
  const name = window.prompt('Name of the piece in this region', r?.piece ?? '');
  if (!name) return;
  try {
    const res = await api('POST', '/api/regions/name', { part: part.name, at: hit.point, name });
    bar(res);
    await refresh(res.revision);
  } catch (e) {
    showError(e.message);
  }
}

async function notchClick(ev) {
  const hit = v3.pickSurface(ev);
  if (!hit) return;
  const part = state.regions.parts[hit.part];
  let best = [Infinity, -1, null];
  part.lines.forEach((l, i) => {
    if (!l.path.length) return;
    const b = nearestOn(l.path, hit.point, false);
    if (b[0] < best[0]) best = [b[0], i, b[1]];
  });
  if (best[1] < 0 || best[0] > part.end_tolerance_mm) { showError('Click on a line to put a notch on it.'); return; }
  const tree = structuredClone(state.tree);
  const line = tree.part[hit.part].line[best[1]];
  line.notches = [...(line.notches || []), toUnits(best[2], hit.part)];
  await putTree(tree);
}

// Editing: drag a handle along the surface, Delete removes the selected one.
function editDown(ev) {
  const h = v3.pickHandle(ev);
  if (!h) return false;
  state.edit = { ...h, moved: false };
  v3.controls.enabled = false;
  return true;
}

function editMove(ev) {
  if (!state.edit) return;
  const hit = v3.pickSurface(ev);
  if (!hit || hit.part !== state.edit.part) return;
  state.edit.moved = true;
  state.edit.to = hit.point;
  state.edit.mesh.position.set(...hit.point);
  v3.redraw();
}

async function editUp() {
  const e = state.edit;
  v3.controls.enabled = true;
  if (!e || !e.moved) return;
  state.edit = { ...e, moved: false, to: null };
  const tree = structuredClone(state.tree);
  const line = tree.part[e.part].line[e.line];
  const end = e.point === 0 || e.point === line.points.length - 1;
  const part = state.regions.parts[e.part];
  const to = (end && closingPoint(part, e.to)) || e.to;
  line.points[e.point] = toUnits(to, e.part);
  await putTree(tree);
}

async function deleteSelected() {
  const e = state.edit;
  if (!e) return;
  state.edit = null;
  const tree = structuredClone(state.tree);
  const lines = tree.part[e.part].line;
  lines[e.line].points.splice(e.point, 1);
  if (lines[e.line].points.length < 2) lines.splice(e.line, 1);
  if (!lines.length) delete tree.part[e.part].line;
  await putTree(tree);
}

// ---- pointer and keys -----------------------------------------------------------------------

let down = null;
$('c3d').addEventListener('pointerdown', (ev) => {
  down = { x: ev.clientX, y: ev.clientY };
  if (state.tool === 'edit' && editDown(ev)) ev.stopPropagation();
}, true);
$('c3d').addEventListener('pointermove', (ev) => {
  if (state.tool === 'edit' && state.edit?.mesh && !v3.controls.enabled) { editMove(ev); return; }
  hover3d(ev);
});
window.addEventListener('pointerup', () => { if (state.tool === 'edit') editUp(); });
$('c3d').addEventListener('click', (ev) => {
  if (!down || Math.hypot(ev.clientX - down.x, ev.clientY - down.y) > 4) return;
  if (state.tool === 'line') lineClick(ev);
  else if (state.tool === 'name') nameClick(ev);
  else if (state.tool === 'notch') notchClick(ev);
  else if (state.tool === 'orbit') {
    const h = v3.pickPiece(ev);
    if (h) { state.selected = state.flat.pieces[h.piece].name; drawPieces(false); panels(); }
  }
});

function hover3d(ev) {
  const h = v3.pickPiece(ev);
  if (!h || !state.flat) { v2.setMarker(null); return; }
  const p = state.flat.pieces[h.piece];
  if (p.name !== state.selected) { v2.setMarker(null); $('hint').textContent = `${p.name} (click with Orbit to see it flat)`; return; }
  const T = p.mesh.triangles, F = p.mesh.flat;
  let x = 0, y = 0;
  for (let k = 0; k < 3; k++) { const v = T[3 * h.face + k]; x += h.bary[k] * F[2 * v]; y += h.bary[k] * F[2 * v + 1]; }
  v2.setMarker([x, y]);
  const s = p.mesh.strain[h.face];
  $('hint').textContent = `${p.name}: ${s >= 0 ? 'stretch' : 'compression'} ${Math.abs(s).toFixed(2)} % here`;
}

$('c2d').addEventListener('pointermove', (ev) => {
  const h = v2.pick(ev);
  const p = v2.piece;
  if (!h || !p) { v3.setMarker(null); return; }
  const T = p.mesh.triangles, P = p.mesh.positions;
  const q = [0, 0, 0];
  for (let k = 0; k < 3; k++) { const v = T[3 * h.face + k]; for (let i = 0; i < 3; i++) q[i] += h.bary[k] * P[3 * v + i]; }
  v3.setMarker(q);
});
$('c2d').addEventListener('pointerleave', () => v3.setMarker(null));

window.addEventListener('keydown', (ev) => {
  if (ev.target.tagName === 'INPUT' || ev.target.tagName === 'SELECT') return;
  const k = ev.key.toLowerCase();
  if ((ev.ctrlKey || ev.metaKey) && k === 'z') { ev.preventDefault(); (ev.shiftKey ? redo : undo)(); return; }
  if ((ev.ctrlKey || ev.metaKey) && k === 'y') { ev.preventDefault(); redo(); return; }
  if ((ev.ctrlKey || ev.metaKey) && k === 's') { ev.preventDefault(); save(); return; }
  if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
  if (k === 'escape') dropDraft();
  else if (k === 'backspace' && state.draft.length) { state.draft.pop(); v3.setDraft(state.draft, state.draftEnds); }
  else if (k === 'enter' && state.draft.length >= 2) commitLine(ev.timeStamp);
  else if ((k === 'delete' || k === 'backspace') && state.tool === 'edit') deleteSelected();
  else if ({ o: 1, l: 1, e: 1, n: 1, r: 1 }[k]) setTool({ o: 'orbit', l: 'line', e: 'edit', n: 'notch', r: 'name' }[k]);
});

async function undo() { try { bar(await api('POST', '/api/design/undo')); } catch (e) { showError(e.message); } }
async function redo() { try { bar(await api('POST', '/api/design/redo')); } catch (e) { showError(e.message); } }
async function save() {
  try { const r = await api('POST', '/api/design/save'); bar(r); status(`saved to ${r.path}`); } catch (e) { showError(e.message); }
}

$('undo').addEventListener('click', undo);
$('redo').addEventListener('click', redo);
$('save').addEventListener('click', save);
$('cancel').addEventListener('click', () => api('POST', '/api/flatten/cancel'));
$('colour').addEventListener('change', (e) => v3.setMode(e.target.value));
$('all-sizes').addEventListener('change', () => { state.drawnFlat = 0; flatten(); });
for (const b of document.querySelectorAll('[data-tool]')) b.addEventListener('click', () => setTool(b.dataset.tool));

function setTab(t) {
  state.tab = t;
  for (const b of document.querySelectorAll('[data-tab]')) b.classList.toggle('on', b.dataset.tab === t);
  for (const el of document.querySelectorAll('.tab')) el.classList.toggle('on', el.id === `tab-${t}`);
  // The pattern, nest and device want room: the flat view gives way to them.
  document.querySelector('main').classList.toggle('wide-side', ['pattern', 'nest', 'device'].includes(t));
  if (t === 'pattern') patternPanel($('tab-pattern'), state.drawnFlat);
  if (t === 'nest') nestPanel($('tab-nest'), state.drawnFlat, api);
  if (t === 'device') devicePanel($('tab-device'), api, hooks);
}
for (const b of document.querySelectorAll('[data-tab]')) b.addEventListener('click', () => setTab(b.dataset.tab));
hooks.setTab = setTab;
hooks.setTool = setTool;

// ---- start ----------------------------------------------------------------------------------

async function start() {
  setTool('orbit');
  setTab('pieces');
  const h = await api('GET', '/api/health');
  state.health = h;
  $('file').textContent = h.design_path;
  bar(h);
  listen({
    hello: (s) => bar(s),
    design: (s) => { bar(s); refresh(s.revision); },
    stage: (s) => {
      if (s.state === 'started') { status(`${s.stage}…`); progress(0, 0); } else { idle(); status(`${s.stage}: done`); }
    },
    progress: (s) => { status(`${s.stage}: ${s.what || ''} ${s.done}/${s.total}`); progress(s.done, s.total); },
    solver: (s) => { status(`solving (${s.stage}) step ${s.iteration}`); progress(s.iteration, s.max_iterations); },
    warning: (s) => status(s.message),
    device: (s) => hooks.onDevice?.(s),
    job: (s) => hooks.onJob?.(s),
  });
  await refresh(h.revision);
}

hooks.ready = start().catch((e) => showError(e.message));
