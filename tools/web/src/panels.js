// The side panels: the pieces' figures against the material's limits, the mating seams with
// their mismatch, the pattern in true millimetres, the nest with its utilisation, and the
// downloads (the files `flatcut run` writes, byte for byte).

import { pieceColour } from './colours.js';

const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
const pct = (v) => (v == null ? '–' : `${v.toFixed(2)} %`);

/** The pieces table; `onSelect(name)` when a row is clicked. */
export function piecesPanel(el, view, selected, onSelect, onDarts) {
  if (!view) { el.innerHTML = '<p class="muted">Not flattened yet.</p>'; return; }
  const rows = view.pieces.map((p, k) => {
    const sOver = p.limit_stretch_pct != null && p.stretch_max_pct > p.limit_stretch_pct;
    const cOver = p.limit_compress_pct != null && p.compress_max_pct > p.limit_compress_pct;
    const c = pieceColour(k).map((x) => Math.round(x * 255)).join(',');
    return `<tr class="piece${p.name === selected ? ' sel' : ''}" data-name="${esc(p.name)}">
      <td><span class="swatch" style="background:rgb(${c})"></span>${esc(p.name)}</td>
      <td class="${sOver ? 'over' : ''}">${pct(p.stretch_max_pct)}</td>
      <td class="${cOver ? 'over' : ''}">${pct(p.compress_max_pct)}</td>
      <td>${(p.area_3d_mm2 / 100).toFixed(1)}</td>
      <td>${p.darts.length || ''}</td>
      <td class="${p.within_limits ? 'ok' : 'over'}">${p.within_limits ? '✓' : '✗'}</td></tr>`;
  }).join('');
  const p0 = view.pieces[0] || {};
  const limits = p0.limit_stretch_pct != null || p0.limit_compress_pct != null
    ? `Material limits: stretch ${pct(p0.limit_stretch_pct)}, compression ${pct(p0.limit_compress_pct)}.`
    : 'No material limits in this project: the colours run to the largest strain.';
  const sel = view.pieces.find((p) => p.name === selected);
  const graded = view.sizes.length > 1 && view.pieces.every((p) => p.size === view.pieces[0]?.size)
    ? ` in size ${esc(view.pieces[0]?.size)}, the base of ${esc(view.sizes.join(', '))} (the others are graded for the pattern, nest and jobs; tick “all sizes” to see them)` : '';
  el.innerHTML = `<p id="piece-count">${view.pieces.length} pieces${graded}, flattened in ${view.elapsed_s.toFixed(2)} s (revision ${view.revision}).</p>
    <p class="muted">${limits}</p>
    <table><thead><tr><th>piece</th><th>stretch</th><th>compress</th><th>cm²</th><th>darts</th><th>limits</th></tr></thead>
    <tbody>${rows}</tbody></table>${sel ? detail(sel) : ''}`;
  for (const tr of el.querySelectorAll('tr.piece')) tr.addEventListener('click', () => onSelect(tr.dataset.name));
  const d = el.querySelector('#darts-auto');
  if (d) d.addEventListener('change', () => onDarts(sel.name, d.checked));
}

function detail(p) {
  const g = p.grain;
  const grain = g ? `<h3>Along the grain (${esc(g.material)})</h3><table>
    <tr><th></th><th>stretch</th><th>limit</th><th>compress</th><th>limit</th></tr>
    ${['along', 'across', 'bias'].map((d) => `<tr><td>${d}</td>
      <td>${pct(g[`stretch_max_pct_${d}`])}</td><td>${pct(g[`limit_stretch_pct_${d}`])}</td>
      <td>${pct(g[`compress_max_pct_${d}`])}</td><td>${pct(g[`limit_compress_pct_${d}`])}</td></tr>`).join('')}
    </table>` : '';
  const regions = p.regions.length
    ? `<h3>Beyond the limits</h3><table><tr><th>where (mm)</th><th>kind</th><th>worst</th><th>mm²</th></tr>${p.regions.slice(0, 8).map((r) =>
      `<tr><td>${r.centroid_3d.map((x) => x.toFixed(0)).join(', ')}</td><td>${r.kind}</td><td class="over">${pct(r.worst_pct)}</td><td>${r.area_mm2.toFixed(0)}</td></tr>`).join('')}</table>` : '';
  const darts = p.darts.length
    ? `<h3>Darts</h3><table><tr><th>#</th><th>length 3D</th><th>legs 2D</th><th>opening</th></tr>${p.darts.map((d, i) =>
      `<tr><td>${i + 1}</td><td>${d.length_3d_mm.toFixed(1)}</td><td>${d.leg_2d_mm.map((x) => x.toFixed(2)).join(' / ')}</td><td>${d.opening_mm.toFixed(1)}</td></tr>`).join('')}</table>` : '';
  const warn = p.warnings.length ? `<h3>Notes</h3>${p.warnings.map((w) => `<p class="muted">${esc(w)}</p>`).join('')}` : '';
  return `<h3>${esc(p.name)}</h3>
    <p>${p.faces} faces, area ${p.area_3d_mm2.toFixed(0)} mm² on the form, ${p.area_2d_mm2.toFixed(0)} mm² flat; δ2 mean ${p.delta2_mean.toFixed(4)}; cut ${p.quantity}${p.mirrored ? ` + ${p.mirrored} mirrored` : ''}.</p>
    <label class="check"><input type="checkbox" id="darts-auto" ${p.darts_auto ? 'checked' : ''}><span>cut darts where it exceeds the limits (<code>darts = "auto"</code>; not for a piece sewn to others)</span></label>
    ${grain}${regions}${darts}${warn}`;
}

/** The mating seams: both sides' flat lengths, their mismatch, and the notches' offsets. */
export function seamsPanel(el, view, tolerance) {
  if (!view) { el.innerHTML = '<p class="muted">Not flattened yet.</p>'; return; }
  if (!view.mating_seams.length) { el.innerHTML = '<p class="muted">No mating seams.</p>'; return; }
  const rows = view.mating_seams.map((s) => {
    const notch = s.notches.reduce((m, n) => Math.max(m, Math.abs(n.offset_mm[0] - n.offset_mm[1])), 0);
    const bad = s.mismatch_mm > tolerance || notch > tolerance;
    return `<tr><td>${esc(s.name)}</td><td class="names">${esc(s.pieces.join(' / '))}</td><td>${s.length_3d_mm.toFixed(2)}</td>
      <td>${s.length_2d_mm.map((x) => x.toFixed(2)).join(' / ')}</td>
      <td class="${bad ? 'over' : 'ok'}">${s.mismatch_mm.toFixed(3)}</td><td>${s.notches.length ? notch.toFixed(3) : ''}</td></tr>`;
  }).join('');
  el.innerHTML = `<p>Each seam's two sides flat, and their difference (tolerance ${tolerance} mm).</p>
    <table><thead><tr><th>seam</th><th>pieces</th><th>3D mm</th><th>flat mm (both sides)</th><th>mismatch</th><th>notches</th></tr></thead><tbody>${rows}</tbody></table>`;
}

/** The pattern pieces in true millimetres (the run's pattern.svg) and its downloads. */
export function patternPanel(el, revision) {
  const q = `?rev=${revision}`;
  el.innerHTML = `<div class="row">Zoom <button data-zoom="fit">fit</button><button data-zoom="true">true size (1 mm = 1 mm)</button>
    <span class="downloads">Download: <a href="/api/pattern.svg" download="pattern.svg">pattern.svg</a>
    <a href="/api/pattern.dxf" download="pattern.dxf">pattern.dxf</a>
    <a href="/api/report.html" target="_blank">report.html</a></span></div>
    <p class="muted">With seam allowance, notches, grain lines and labels, as <code>flatcut run</code> writes them.</p>
    <div class="drawing"><img class="fit-height" id="pattern-img" alt="pattern pieces" src="/api/pattern.svg${q}"></div>`;
  const img = el.querySelector('#pattern-img');
  for (const b of el.querySelectorAll('[data-zoom]')) {
    b.addEventListener('click', () => { img.className = b.dataset.zoom === 'true' ? 'true-size' : 'fit-height'; });
  }
}

/** The nest on the sheet or roll with its utilisation, and the job downloads. */
export async function nestPanel(el, revision, api) {
  el.innerHTML = '<p class="muted">Nesting…</p>';
  let s;
  try {
    s = await api('GET', '/api/summary.json');
  } catch (e) {
    el.innerHTML = `<p class="over">${esc(e.message)}</p>`;
    return;
  }
  const sheets = Array.from({ length: Math.max(1, s.sheets) }, (_, i) => i + 1);
  el.innerHTML = `<p id="utilization">Utilization <strong>${s.utilization_pct.toFixed(1)} %</strong> on ${s.sheets} sheet(s)${s.unplaced ? `, <span class="over">${s.unplaced} unplaced</span>` : ''};
    cut ${(s.cut_length_mm / 1000).toFixed(2)} m, travel ${(s.travel_length_mm / 1000).toFixed(2)} m, about ${Math.round(s.est_time_s)} s.</p>
    <div class="row">Sheet <select id="sheet">${sheets.map((n) => `<option>${n}</option>`).join('')}</select></div>
    <div class="downloads" id="job-links"></div>
    <img class="pattern-img" id="layout-img" alt="nest">`;
  const show = () => {
    const n = el.querySelector('#sheet').value;
    el.querySelector('#layout-img').src = `/api/layout.svg?sheet=${n}&rev=${revision}`;
    el.querySelector('#job-links').innerHTML = `Download: <a href="/api/layout.svg?sheet=${n}" download="layout-${n}.svg">layout-${n}.svg</a>
      <a href="/api/layout.dxf?sheet=${n}" download="layout-${n}.dxf">layout-${n}.dxf</a>
      <a href="/api/job.gcode?sheet=${n}" download="job-${n}.gcode" id="dl-gcode">job-${n}.gcode</a>
      <a href="/api/job.plt?sheet=${n}" download="job-${n}.plt">job-${n}.plt (HP-GL)</a>`;
  };
  el.querySelector('#sheet').addEventListener('change', show);
  show();
}
