// The workbench in a real browser: headless Chromium (Debian's /usr/bin/chromium) driven by
// playwright-core against `flatcut serve` on the bundled shoe.
//
//   node tools/web/browser-test.mjs --flatcut target/debug/flatcut [--screenshots docs]
//   node tools/web/browser-test.mjs --flatcut target/release/flatcut --measure 9
//
// Steps: load the shoe; add a style line by clicking on the rendered surface at known screen
// points (the projections of surface points from the server's own mesh); see the piece count
// go from 4 to 5 (in the shoe's base size; every size in the pattern) and the heat map's colours
// on the new piece, in 3D and flat; download the pattern and compare it with `flatcut run`'s bytes
// for the saved design; stream sheet 1's job from the device panel to the embedded simulator,
// pause and resume it once, watch its progress events to the end, and check the simulator's
// executed motions against the G-code's moves (each once, in order, the same end point); open a
// second device (another embedded simulator) on a tab of its own beside the first, run sheet 2
// on it while sheet 1 runs again on the first, and check the second simulator executed sheet 2's
// moves, each once; plot sheet 1 on the embedded HP-GL plotter, paused (pen up) and resumed, and
// check its strokes against the job's HP-GL; then Ctrl-C the server during a job and check the job stopped with the tool off and its journal
// says so; then kill a server outright during sheet 3's job (a crash), resume from the journal
// on a new server, see the panel refuse and name the lines in doubt (drawn over the layout
// where the G-code moves), type a line among them, answer the origin question, and check the
// simulator ran the G-code's moves from that line on, each once. Prints one line per step and
// "N passed, N failed". Without Chromium it fails when FLATCUT_BROWSER_TEST=required (as CI
// sets it), and otherwise says it skipped.
//
// `--measure N` instead draws the closing line N times (undoing it between runs) and prints the
// time from the click that closes the region to the new pieces' heat map on the shoe, each run
// and the median, split into the request adding the line, the flattening (the server's own time
// within it), the response's transfer and the drawing.

import { spawn, execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const repo = path.resolve(here, '../..');
const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  return i >= 0 ? args[i + 1] : dflt;
};
const flatcut = path.resolve(opt('--flatcut', path.join(repo, 'target/debug/flatcut')));
const shots = opt('--screenshots', null);
const measure = Number(opt('--measure', 0));
const chromium = process.env.CHROMIUM || '/usr/bin/chromium';
const required = process.env.FLATCUT_BROWSER_TEST === 'required';

let passed = 0;
let failed = 0;
const results = [];
function step(name, ok, detail = '') {
  results.push({ name, ok, detail });
  if (ok) passed++; else failed++;
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${name}${detail ? ` — ${detail}` : ''}`);
  if (!ok) throw new Error(`${name}: ${detail}`);
}

if (!fs.existsSync(chromium)) {
  const msg = `no Chromium at ${chromium} (apt-get install chromium)`;
  if (required) {
    console.log(`FAIL browser: ${msg}`);
    console.log('0 passed, 1 failed');
    process.exit(1);
  }
  console.log(`skipped: ${msg}`);
  process.exit(0);
}
if (!fs.existsSync(flatcut)) {
  console.log(`FAIL flatcut binary: ${flatcut} does not exist (cargo build first)`);
  console.log('0 passed, 1 failed');
  process.exit(1);
}

const { chromium: pw } = await import('playwright-core');

// The shoe, in a directory of its own (the workbench saves into it).
const work = fs.mkdtempSync(path.join(os.tmpdir(), 'flatcut-browser-'));
for (const f of ['project.toml', 'design.toml']) fs.copyFileSync(path.join(repo, 'patterns/shoe', f), path.join(work, f));

/** `flatcut serve` on the project in `dir`, on a free port: its process and address. */
async function startServer(dir) {
  const proc = spawn(flatcut, ['serve', path.join(dir, 'project.toml'), '--port', '0'], { stdio: ['ignore', 'pipe', 'pipe'] });
  let out = '';
  proc.stderr.on('data', (d) => { out += d; });
  const url = await new Promise((resolve, reject) => {
    const t = setTimeout(() => reject(new Error(`flatcut serve printed no address: ${out}`)), 60000);
    proc.stdout.on('data', (d) => {
      out += d;
      const m = /workbench: (http:\/\/\S+)/.exec(out);
      if (m) { clearTimeout(t); resolve(m[1]); }
    });
    proc.on('exit', (c) => reject(new Error(`flatcut serve exited (${c}): ${out}`)));
  });
  servers.push(proc);
  return { proc, url };
}
const servers = [];
const { proc: server, url } = await startServer(work);

const browser = await pw.launch({
  executablePath: chromium,
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
});
const context = await browser.newContext({ viewport: { width: 1600, height: 900 }, acceptDownloads: true });
const page = await context.newPage();
const pageErrors = [];
page.on('pageerror', (e) => pageErrors.push(String(e)));
const events = [];

async function shot(name) {
  if (!shots) return;
  fs.mkdirSync(shots, { recursive: true });
  await page.waitForTimeout(300);
  await page.screenshot({ path: path.join(shots, `workbench-${name}.png`) });
}

/** The rendered colour at a page point of a canvas (CSS px), 0..255. */
async function pixel(canvasId, x, y) {
  return page.evaluate(([id, x, y]) => {
    const c = document.getElementById(id);
    const r = c.getBoundingClientRect();
    const gl = c.getContext('webgl2') || c.getContext('webgl');
    const px = new Uint8Array(4);
    const sx = Math.round((x - r.left) * c.width / r.width);
    const sy = Math.round(c.height - (y - r.top) * c.height / r.height);
    gl.readPixels(sx, sy, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    return [px[0], px[1], px[2]];
  }, [canvasId, x, y]);
}

/** The G-code's moves (absolute coordinates): each with its file line (1-based), its text as the
 * simulator records it (comments and spaces gone, upper case), its end and its length; and where
 * the job ends. */
function gcodeMoves(gcode) {
  const moves = [];
  let pos = [0, 0, 0];
  let mode = null;
  for (const [n, raw] of gcode.split('\n').entries()) {
    const line = raw.replace(/\(.*?\)/g, '').replace(/;.*/, '').replace(/\s+/g, '').toUpperCase();
    if (!line) continue;
    if (/G91(?!\d)/.test(line)) throw new Error('the job uses relative moves; this check reads absolute ones');
    const g = /G0*([0-3])(?![\d.])/.exec(line);
    if (g) mode = Number(g[1]);
    const to = [...pos];
    let moved = false;
    for (const [k, ax] of ['X', 'Y', 'Z'].entries()) {
      const m = new RegExp(`${ax}(-?[\\d.]+)`).exec(line);
      if (m) { to[k] = Number(m[1]); moved = true; }
    }
    if (moved && mode != null && to.some((v, k) => Math.abs(v - pos[k]) > 1e-9)) {
      moves.push({ line: n + 1, text: line, to, length: Math.hypot(...to.map((v, k) => v - pos[k])) });
      pos = to;
    }
  }
  return { moves, end: pos };
}

/** The pen-down moves of an HP-GL job (mm), read from its text: `PU`/`PD`, absolute and relative
 * moves, `SP`/`IN` lifting the pen. */
function hpglStrokes(text) {
  const out = [];
  let pos = [0, 0]; let down = false; let rel = false;
  for (const raw of text.split(';')) {
    const instr = raw.trim();
    const op = instr.slice(0, 2);
    if (['PU', 'SP', 'IN'].includes(op)) down = false;
    if (op === 'PD') down = true;
    if (op === 'PA') rel = false;
    if (op === 'PR') rel = true;
    if (!['PU', 'PD', 'PA', 'PR'].includes(op)) continue;
    const n = instr.slice(2).split(/[ ,]+/).filter(Boolean).map(Number);
    for (let k = 0; k + 1 < n.length; k += 2) {
      const to = rel ? [pos[0] + n[k] / 40, pos[1] + n[k + 1] / 40] : [n[k] / 40, n[k + 1] / 40];
      if (down && (to[0] !== pos[0] || to[1] !== pos[1])) out.push({ from: pos, to });
      pos = to;
    }
  }
  return out;
}

/** What the simulator executed (`GET /api/devices/sim`), the motions that moved; a line a hold
 * stopped part-way is one motion resumed, so its two pieces are joined. */
function ranMotions(sim) {
  const ran = [];
  for (const m of sim.motions.filter((m) => m.from.some((v, k) => Math.abs(v - m.to[k]) > 1e-9))) {
    const last = ran[ran.length - 1];
    if (last && last.line === m.line && last.to.every((v, k) => Math.abs(v - m.from[k]) < 1e-6)) last.to = m.to; else ran.push({ ...m });
  }
  return ran;
}

const near = (a, b) => a.every((v, k) => Math.abs(v - b[k]) <= 0.01);

/** Walks the G-code's `moves` and the executed motions `ran` (from `ran[head]`) in order: each
 * executed motion is the G-code's next move, at its end point within 0.01 mm (the machine's
 * step); a move the simulator did not make must be shorter than a step of the machine (its target
 * rounds to where the machine stands). `k`: motions matched; `bad`: the first difference. */
function walk(moves, ran, head = 0) {
  let i = 0, k = head, tiny = 0, bad = null;
  while (i < moves.length && !bad) {
    if (ran[k] && ran[k].text === moves[i].text && near(ran[k].to, moves[i].to)) { i++; k++; }
    else if (moves[i].length < 0.01) { tiny++; i++; }
    else bad = { at: i, ran: ran[k], want: moves[i] };
  }
  if (!bad && k < ran.length) bad = { at: i, ran: ran[k], want: 'nothing more' };
  return { k: k - head, tiny, bad };
}

/** Thrown to end the run after `--measure`: its figures are printed, no step follows. */
class Measured extends Error {}

const median = (xs) => {
  const v = [...xs].sort((a, b) => a - b);
  return v.length % 2 ? v[(v.length - 1) / 2] : (v[v.length / 2 - 1] + v[v.length / 2]) / 2;
};

/** `--measure N`: the time from the click that closes the vamp's region to the new pieces' heat
 * map on the shoe, N times (each line undone before the next), and where it goes: the request
 * adding the line, the flattening's request (the server's own flattening time within it, then
 * the response's transfer), and the page drawing it (parse, meshes, the frame on screen). */
async function measureClose(screen) {
  await page.click('[data-tool=line]');
  const runs = [];
  for (let r = 0; r < measure; r++) {
    const n = await page.evaluate(() => { performance.clearResourceTimings(); return window.__flatcut.timings.length; });
    for (const s of screen) await page.mouse.click(s.x, s.y);
    await page.waitForFunction((n) => window.__flatcut.timings.length > n, n, { timeout: 120000 });
    const t = await page.evaluate((n) => {
      const t = window.__flatcut.timings[n];
      const req = (p) => performance.getEntriesByType('resource')
        .find((e) => new URL(e.name).pathname === p && e.startTime >= t.t0);
      const line = req('/api/lines');
      const flat = performance.getEntriesByType('resource')
        .filter((e) => new URL(e.name).pathname === '/api/flatten' && e.startTime >= line.responseEnd)[0];
      return {
        total: t.closeToHeatMs,
        line: line.responseEnd - t.t0,
        flattenWait: flat.responseStart - line.responseEnd,
        server: t.serverFlattenMs,
        transfer: flat.responseEnd - flat.responseStart,
        bytes: flat.encodedBodySize,
        draw: t.closeToHeatMs - (flat.responseEnd - t.t0),
      };
    }, n);
    runs.push(t);
    console.log(`run ${r + 1}: ${t.total.toFixed(0)} ms (line ${t.line.toFixed(0)}, flatten wait ${t.flattenWait.toFixed(0)} (the server's flattening, begun with the line: ${t.server.toFixed(0)}), transfer ${t.transfer.toFixed(0)} ms of ${(t.bytes / 1e6).toFixed(2)} MB, draw ${t.draw.toFixed(0)})`);
    await page.click('#undo');
    await page.waitForFunction(() => /^4 pieces/.test(document.querySelector('#piece-count')?.textContent || ''), null, { timeout: 120000 });
    await page.waitForTimeout(300);
  }
  const m = (k) => median(runs.map((x) => x[k])).toFixed(0);
  console.log(`click to heat map, median of ${runs.length}: ${m('total')} ms (line ${m('line')}, flatten wait ${m('flattenWait')} (the server's flattening ${m('server')}), transfer ${m('transfer')}, draw ${m('draw')} ms)`);
}

let code = 0;
try {
  // 1. Load the shoe.
  await page.goto(url);
  await page.waitForFunction(() => window.__flatcut && window.__flatcut.state.flat && window.__flatcut.state.regions, null, { timeout: 120000 });
  await page.exposeFunction('__event', (e) => events.push(e));
  await page.evaluate(() => {
    const es = new EventSource('/api/events');
    for (const t of ['job', 'device']) es.addEventListener(t, (ev) => window.__event({ type: t, ...JSON.parse(ev.data) }));
  });
  const count0 = await page.textContent('#piece-count');
  // The shoe is graded in three sizes (40, 42, 44): live, its 4 pieces are flattened in the base
  // size (42); the pattern, nest and jobs have every size.
  step('loads the shoe: 4 pieces flattened in its base size', /^4 pieces in size 42/.test(count0), count0);
  await shot('pieces');

  // 2. A style line by clicking on the rendered surface: from the medial featherline at x = 190 mm,
  // up over the vamp, to the toe cap's line near the top.
  const target = await page.evaluate(() => {
    const part = window.__flatcut.state.regions.parts[0];
    const P = part.mesh.positions;
    const nearest = (t) => {
      let best = null, bd = Infinity;
      for (let i = 0; i < P.length; i += 3) {
        const d = (P[i] - t[0]) ** 2 + (P[i + 1] - t[1]) ** 2 + (P[i + 2] - t[2]) ** 2;
        if (d < bd) { bd = d; best = [P[i], P[i + 1], P[i + 2]]; }
      }
      return best;
    };
    const toe = part.lines.find((l) => l.name === 'toe-cap').path;
    let onToe = toe[0], bd = Infinity;
    for (const q of toe) { const d = (q[0] - 231) ** 2 + (q[1] + 8) ** 2 + (q[2] - 35) ** 2; if (d < bd) { bd = d; onToe = q; } }
    return [nearest([190, -60, 0]), nearest([205, -35, 45]), onToe];
  });
  const screen = [];
  for (const p of target) {
    const s = await page.evaluate((p) => window.__flatcut.toScreen(p), p);
    const hit = await page.evaluate(([x, y]) => window.__flatcut.pickAt(x, y), [s.x, s.y]);
    const off = hit ? Math.hypot(hit.point[0] - p[0], hit.point[1] - p[1], hit.point[2] - p[2]) : Infinity;
    step(`surface point (${p.map((x) => x.toFixed(1)).join(', ')}) is under screen point (${s.x.toFixed(0)}, ${s.y.toFixed(0)})`, off < 1.5, `${off.toFixed(2)} mm off`);
    screen.push(s);
  }
  if (measure) {
    await measureClose(screen);
    throw new Measured();
  }
  await page.click('[data-tool=line]');
  for (const s of screen) await page.mouse.click(s.x, s.y);
  await page.waitForFunction(() => /^5 pieces/.test(document.querySelector('#piece-count')?.textContent || ''), null, { timeout: 120000 });
  await page.waitForFunction(() => window.__flatcut.timings.length > 0, null, { timeout: 10000 });
  const timing = await page.evaluate(() => window.__flatcut.timings[0].closeToHeatMs);
  const count1 = await page.textContent('#piece-count');
  step('the third click closes a region: 5 pieces', /^5 pieces/.test(count1), `${count1}; click to heat map ${timing.toFixed(0)} ms`);

  // 3. The heat map's colours on the new piece: flat (unlit, exact) and on the surface (lit: same
  // hue).
  await page.click('#tabs [data-tab=pieces]');
  await page.click('tr.piece[data-name="upper 1 42"]');
  await page.waitForTimeout(300);
  // The centre of the piece's largest face on screen (away from its edges, which are blended).
  const flat = await page.evaluate(() => {
    const h = window.__flatcut;
    const s = h.state;
    const p = s.flat.pieces.find((x) => x.name === 'upper 1 42');
    const T = p.mesh.triangles, F = p.mesh.flat;
    let best = null, area = 0;
    for (let f = 0; f < T.length / 3; f++) {
      const q = [0, 1, 2].map((k) => h.flatToScreen([F[2 * T[3 * f + k]], F[2 * T[3 * f + k] + 1]]));
      const a = Math.abs((q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (q[1].y - q[0].y)) / 2;
      if (a > area) { area = a; best = { f, x: (q[0].x + q[1].x + q[2].x) / 3, y: (q[0].y + q[1].y + q[2].y) / 3 }; }
    }
    const hit = best && h.flatAt(best.x, best.y);
    if (!hit || hit.face !== best.f) return null;
    return { x: best.x, y: best.y, strain: p.mesh.strain[best.f], scale: s.scale, stops: s.stops };
  });
  step('the new piece is drawn flat', !!flat);
  const want = await page.evaluate(({ strain, scale, stops }) => {
    const t = strain >= 0 ? strain / scale.stretch : strain / scale.compress;
    const u = Math.min(1, Math.max(0, 0.5 * (t + 1))) * (stops.length - 1);
    const i = Math.min(stops.length - 2, Math.floor(u)), f = u - i;
    const c = [0, 1, 2].map((k) => stops[i][k] * (1 - f) + stops[i + 1][k] * f);
    return Math.abs(t) > 1 ? c.map((x) => x * 0.55) : c;
  }, flat);
  const got = await pixel('c2d', flat.x, flat.y);
  const diff = Math.max(...got.map((v, k) => Math.abs(v - want[k])));
  step('its flat heat map has the report\'s colour for its strain', diff <= 3, `strain ${flat.strain.toFixed(2)} %: rgb(${got}) against rgb(${want.map(Math.round)})`);
  // On the surface: at the new piece's most strained face in view, the pixel leans the way its
  // strain does (red for stretch, blue for compression), and differs from the piece colours.
  const spot = await page.evaluate(() => {
    const h = window.__flatcut;
    const k = h.state.flat.pieces.findIndex((x) => x.name === 'upper 1 42');
    const p = h.state.flat.pieces[k];
    const T = p.mesh.triangles, P = p.mesh.positions;
    const faces = [...p.mesh.strain.keys()].sort((a, b) => Math.abs(p.mesh.strain[b]) - Math.abs(p.mesh.strain[a]));
    for (const f of faces) {
      const c = [0, 1, 2].map((i) => (P[3 * T[3 * f] + i] + P[3 * T[3 * f + 1] + i] + P[3 * T[3 * f + 2] + i]) / 3);
      const s = h.toScreen(c);
      const under = h.pieceAt(s.x, s.y);
      if (under && under.piece === k && under.face === f) return { x: s.x, y: s.y, strain: p.mesh.strain[f] };
    }
    return null;
  });
  step('a face of the new piece is in view', !!spot);
  const heat = await pixel('c3d', spot.x, spot.y);
  await page.selectOption('#colour', 'pieces');
  await page.waitForTimeout(200);
  const plain = await pixel('c3d', spot.x, spot.y);
  await page.selectOption('#colour', 'heat');
  await page.waitForTimeout(200);
  const lean = spot.strain >= 0 ? heat[0] - heat[2] : heat[2] - heat[0];
  const changed = Math.max(...heat.map((v, k) => Math.abs(v - plain[k])));
  step('on the surface the new piece shows its heat map', lean > 5 && changed > 10,
    `strain ${spot.strain.toFixed(2)} %: rgb(${heat}) (piece colour rgb(${plain}))`);
  await shot('heatmap');

  // Every size on demand: the base size's 5 pieces in each of the 3 sizes.
  await page.check('#all-sizes');
  await page.waitForFunction(() => /^15 pieces/.test(document.querySelector('#piece-count')?.textContent || ''), null, { timeout: 300000 });
  const allSizes = await page.textContent('#piece-count');
  await page.uncheck('#all-sizes');
  await page.waitForFunction(() => /^5 pieces/.test(document.querySelector('#piece-count')?.textContent || ''), null, { timeout: 60000 });
  step('every size flattened on demand: 5 pieces in 3 sizes', /^15 pieces/.test(allSizes), allSizes);

  // 4. The pattern: saved, downloaded, compared with `flatcut run`'s bytes for the saved design.
  await page.click('#save');
  await page.waitForFunction(() => document.querySelector('#saved').textContent === 'saved', null, { timeout: 30000 });
  await page.click('#tabs [data-tab=seams]');
  await shot('seams');
  await page.click('#tabs [data-tab=pattern]');
  const [download] = await Promise.all([
    page.waitForEvent('download', { timeout: 120000 }),
    page.click('a[download="pattern.svg"]'),
  ]);
  const got1 = fs.readFileSync(await download.path());
  const out = path.join(work, 'out');
  execFileSync(flatcut, ['run', path.join(work, 'project.toml'), '--no-send', '--quiet', '-o', out], { stdio: 'ignore' });
  const cli = fs.readFileSync(path.join(out, 'pattern.svg'));
  step('the downloaded pattern.svg is flatcut run\'s, byte for byte', Buffer.compare(got1, cli) === 0, `${got1.length} bytes; 5 pieces in 3 sizes`);
  await page.waitForFunction(() => document.getElementById('pattern-img')?.complete, null, { timeout: 60000 });
  await shot('pattern');
  await page.click('#tabs [data-tab=nest]');
  await page.waitForSelector('#utilization', { timeout: 120000 });
  await page.waitForFunction(() => document.getElementById('layout-img')?.complete, null, { timeout: 60000 });
  const util = await page.textContent('#utilization');
  step('the nest shows its utilisation', /Utilization [\d.]+ %/.test(util), util.trim().split('\n')[0]);
  await shot('nest');

  // 5. The device: sheet 1's job streamed from the panel to the embedded simulator (the default
  // device, set up as the project's machine), paused and resumed once, watched to its end; then
  // what the simulator executed is checked against the G-code itself.
  await page.click('#tabs [data-tab=device]');
  await page.waitForSelector('#job-start:not([disabled])', { timeout: 60000 });
  await page.waitForSelector('#job-svg', { timeout: 120000 });
  const jobState = () => page.evaluate(() => window.__flatcut.lastJob);
  await page.click('#job-start');
  await page.waitForFunction(() => { const j = window.__flatcut.lastJob; return j && j.state === 'running' && j.progress && j.progress.lines_done > 50; }, null, { timeout: 120000 });
  await page.click('#job-hold');
  await page.waitForFunction(() => { const j = window.__flatcut.lastJob; return j.state === 'held' && j.progress.machine_state === 'Hold:0'; }, null, { timeout: 30000 });
  const held = await jobState();
  await page.waitForTimeout(1000);
  const still = await jobState();
  await shot('device');
  const same = still.progress.lines_done === held.progress.lines_done
    && still.progress.position.every((v, k) => Math.abs(v - held.progress.position[k]) < 1e-9);
  step('pause holds the machine where it is', still.state === 'held' && same,
    `held at line ${held.progress.lines_done} of ${held.progress.lines_total}, ${held.progress.position.map((v) => v.toFixed(2)).join(', ')} mm; 1 s later line ${still.progress.lines_done}`);
  await page.click('#job-resume');
  await page.waitForFunction(() => ['done', 'failed', 'stopped'].includes(window.__flatcut.lastJob.state), null, { timeout: 600000 });
  const job = await jobState();
  const progress = events.filter((e) => e.type === 'job' && e.id === job.id && e.progress);
  const monotone = progress.every((e, i) => i === 0 || e.progress.lines_done >= progress[i - 1].progress.lines_done);
  const resumedAfter = progress.some((e) => e.progress.lines_done > held.progress.lines_done && e.state === 'running');
  step('a job streams to the embedded simulator, progress to the end', job.state === 'done' && progress.length > 1 && monotone && resumedAfter
    && job.progress.lines_done === job.progress.lines_total,
  `${progress.length} progress events, ${job.progress.lines_done} of ${job.progress.lines_total} lines, state ${job.state}: ${job.message}`);
  const shown = await page.textContent('#job-state');
  step('the panel says the job is done', shown === 'done', shown);
  // What the simulator executed, motion by motion, against the G-code's own moves.
  const [gcode, sim] = await page.evaluate(async () => [
    await (await fetch('/api/job.gcode?sheet=1')).text(),
    await (await fetch('/api/devices/sim')).json(),
  ]);
  const { moves, end: pos } = gcodeMoves(gcode);
  const ran = ranMotions(sim);
  const { k, tiny, bad } = walk(moves, ran);
  const end = ran[ran.length - 1]?.to || [NaN, NaN, NaN];
  step('the simulator executed the G-code\'s moves, each once, in order', !bad && near(end, pos),
    `${k} motions executed of the G-code's ${moves.length} moves (${tiny} shorter than 0.01 mm, below a step)${bad ? `; first difference at move ${bad.at}: ran ${JSON.stringify(bad.ran)}, the G-code ${JSON.stringify(bad.want)}` : ''}; ended at ${end.map((v) => v.toFixed(3)).join(', ')} mm (the G-code: ${pos.map((v) => v.toFixed(3)).join(', ')})`);

  // 5b. A second device beside the first: another embedded simulator on a tab of its own, sheet
  // 2 streamed to it while sheet 1 runs again on the first; each tab shows its own job, and the
  // second simulator executed sheet 2's moves, each once, in order.
  await page.selectOption('#dev-select', 'simulator:new');
  await page.click('#dev-connect');
  await page.waitForSelector('#dev-tabs [data-device="simulator:2"].on', { timeout: 60000 });
  await page.selectOption('#job-sheet', '2');
  await page.click('#job-start');
  await page.waitForFunction(() => { const j = window.__flatcut.lastJob; return j && j.device_id === 'simulator:2' && j.progress && j.progress.lines_done > 20; }, null, { timeout: 120000 });
  // Held there while the first device starts, so that both run at once whatever their speed.
  await page.click('#job-hold');
  await page.waitForFunction(() => window.__flatcut.lastJob.state === 'held', null, { timeout: 30000 });
  await page.click('#dev-tabs [data-device="simulator"]');
  await page.selectOption('#job-sheet', '1');
  await page.click('#job-start');
  await page.waitForFunction(() => { const j = window.__flatcut.lastJob; return j && j.device_id === 'simulator' && j.state === 'running' && j.progress; }, null, { timeout: 120000 });
  const tabs = await page.$$eval('#dev-tabs [data-device]', (bs) => bs.map((b) => ({ id: b.dataset.device, text: [...b.children].map((c) => c.textContent.trim()).join(': '), busy: b.classList.contains('busy') })));
  await shot('device-two');
  const twoRunning = await page.evaluate(async () => (await (await fetch('/api/devices')).json()).running.map((j) => `${j.device_id}: ${j.name} ${j.state}`));
  await page.click('#dev-tabs [data-device="simulator:2"]');
  await page.waitForFunction(() => window.__flatcut.lastJob?.device_id === 'simulator:2', null, { timeout: 30000 });
  await page.click('#job-resume');
  // Both jobs to their ends (each device's latest job, as the server lists them).
  for (const t0 = Date.now(); ; await page.waitForTimeout(500)) {
    const ended = await page.evaluate(async () => {
      const r = await (await fetch('/api/jobs')).json();
      const last = (d) => r.jobs.filter((j) => j.device_id === d).pop();
      return ['simulator', 'simulator:2'].every((d) => ['done', 'failed', 'stopped'].includes(last(d)?.state));
    });
    if (ended) break;
    if (Date.now() - t0 > 600000) throw new Error('the two jobs did not end within 10 min');
  }
  const [gcode2, sim2, jobs2] = await page.evaluate(async () => [
    await (await fetch('/api/job.gcode?sheet=2')).text(),
    await (await fetch('/api/devices/sim?device=simulator:2')).json(),
    (await (await fetch('/api/jobs')).json()).jobs,
  ]);
  const second = jobs2.filter((j) => j.device_id === 'simulator:2').pop();
  const again = jobs2.filter((j) => j.device_id === 'simulator').pop();
  const w2 = walk(gcodeMoves(gcode2).moves, ranMotions(sim2));
  step('a second device runs a job beside the first, each on its own tab', twoRunning.length === 2 && tabs.length === 2
    && tabs.every((t) => t.busy) && second.state === 'done' && second.sheet === 2 && again.state === 'done' && again.sheet === 1 && !w2.bad,
  `running at once: ${twoRunning.join(', ')}; tabs: ${tabs.map((t) => t.text).join(' | ')}; simulator 2 executed ${w2.k} motions of sheet 2's ${gcodeMoves(gcode2).moves.length} moves${w2.bad ? `; first difference at move ${w2.bad.at}` : ''}`);
  // 5c. An HP-GL plotter: the embedded HP-GL plotter (opened at 115200 baud, so the sheet plots
  // in seconds), sheet 1 plotted from the panel, paused with the pen up and resumed, watched to
  // its end; the GRBL controls are hidden, the panel says the progress is bytes sent, and the
  // plotter drew the job's pen-down moves (`GET /api/job.plt`'s), each once, in order.
  await page.evaluate(() => fetch('/api/devices/connect', { method: 'POST', headers: { 'content-type': 'application/json' }, body: '{"device":"plotter-sim","speed":200,"baud":115200}' }));
  await page.waitForSelector('#dev-tabs [data-device="plotter-sim"]', { timeout: 60000 });
  await page.click('#dev-tabs [data-device="plotter-sim"]');
  await page.waitForSelector('#dev-tabs [data-device="plotter-sim"].on', { timeout: 30000 });
  await page.selectOption('#job-sheet', '1');
  const grblHidden = await page.isHidden('#dev-grbl-row') && await page.isVisible('#dev-grbl-note');
  await page.click('#job-start');
  await page.waitForFunction(() => { const j = window.__flatcut.lastJob; return j && j.device_id === 'plotter-sim' && j.progress && j.progress.bytes_sent > j.progress.bytes_total / 4; }, null, { timeout: 120000 });
  await page.click('#job-hold');
  await page.waitForFunction(() => { const j = window.__flatcut.lastJob; return j.state === 'held' && j.progress.paused; }, null, { timeout: 30000 });
  const basis = await page.textContent('#job-basis');
  const penUp = await page.evaluate(async () => {
    for (;;) {
      const s = await (await fetch('/api/devices/sim?device=plotter-sim')).json();
      if (s.idle) return !s.pen_down;
      await new Promise((r) => setTimeout(r, 50));
    }
  });
  await shot('device-plotter');
  await page.click('#job-resume');
  await page.waitForFunction(() => ['done', 'failed', 'stopped'].includes(window.__flatcut.lastJob.state), null, { timeout: 600000 });
  const plot = await jobState();
  const [plt, plotted] = await page.evaluate(async () => [
    await (await fetch('/api/job.plt?sheet=1')).text(),
    await (await fetch('/api/devices/sim?device=plotter-sim')).json(),
  ]);
  const pd = hpglStrokes(plt);
  const sameStrokes = plotted.strokes.length === pd.length && pd.every((s, i) => [0, 1].every((k) => Math.abs(s.from[k] - plotted.strokes[i].from[k]) < 1e-9 && Math.abs(s.to[k] - plotted.strokes[i].to[k]) < 1e-9));
  step('an HP-GL job plots on the embedded plotter: pause lifts the pen, the strokes are the job\'s', plot.state === 'done' && plot.protocol === 'hpgl'
    && plot.progress.progress_basis === 'bytes_sent' && grblHidden && penUp && /bytes the plotter.s link accepted/.test(basis) && sameStrokes,
  `${plot.progress.bytes_sent} of ${plot.progress.bytes_total} bytes, state ${plot.state}: ${plot.message}; GRBL controls hidden: ${grblHidden}; pen up while paused: ${penUp}; ${plotted.strokes.length} strokes drawn, the job has ${pd.length}`);
  await page.click('#dev-tabs [data-device="simulator"]');
  await page.waitForFunction(() => window.__flatcut.lastJob?.device_id === 'simulator', null, { timeout: 30000 });
  step('no script error on the page', pageErrors.length === 0, pageErrors.join('; '));

  // 6. Ctrl-C to the server while a job runs: the job stops with the tool off, its journal says
  // so, and the server ends cleanly.
  await page.evaluate(() => fetch('/api/jobs', { method: 'POST', headers: { 'content-type': 'application/json' }, body: '{"sheet":2,"device":"simulator"}' }));
  await page.waitForFunction(() => { const j = window.__flatcut.lastJob; return j && j.sheet === 2 && j.progress && j.progress.lines_done > 50; }, null, { timeout: 120000 });
  const exited = new Promise((r) => server.on('exit', (c, sig) => r({ c, sig })));
  server.kill('SIGINT');
  const ended = await Promise.race([exited, new Promise((r) => setTimeout(() => r(null), 30000))]);
  const journal = fs.readFileSync(path.join(work, 'job-2.gcode.journal'), 'utf8').trim().split('\n');
  const stopRecord = journal.filter((l) => l.startsWith('S ')).pop() || '';
  const done = journal.some((l) => l === 'D');
  step('Ctrl-C stops the running job with the tool off and ends the server', !!ended && ended.c === 0 && !done
    && / M5( |$)/.test(stopRecord) && journal.some((l) => l.startsWith('N tool off')),
  `exit ${ended ? ended.c ?? ended.sig : 'none within 30 s'}; journal ends: ${journal.slice(-3).join(' | ')}`);

  // 7. A crash during a job (the server killed outright: nothing stopped, the simulator gone
  // with it; here while the job is paused with lines queued) leaves lines the journal cannot
  // tell ran or not. On the next server the panel's
  // resume from the journal is refused and names them; the operator types the line to continue
  // from, answers the origin question in the page, and the simulator runs the G-code's moves
  // from that line on, each once.
  const openDevice = async (at) => {
    await page.goto(at);
    await page.waitForFunction(() => window.__flatcut && window.__flatcut.state.flat, null, { timeout: 120000 });
    await page.click('#tabs [data-tab=device]');
    await page.waitForSelector('#job-start:not([disabled])', { timeout: 60000 });
    // The sheets are listed once the new server has nested the design.
    await page.waitForFunction(() => document.querySelectorAll('#job-sheet option').length >= 3, null, { timeout: 300000 });
    await page.selectOption('#job-sheet', '3');
  };
  const crashed = await startServer(work);
  await openDevice(crashed.url);
  await page.click('#job-start');
  await page.waitForFunction(() => { const j = window.__flatcut.lastJob; return j && j.sheet === 3 && j.progress && j.progress.lines_done > 300; }, null, { timeout: 120000 });
  // The power fails while the job is paused with lines queued (acknowledged, not yet run); a
  // pause that found the planner drained (at a dwell) is resumed and tried again further on.
  for (let tries = 0; ; tries++) {
    await page.click('#job-hold');
    await page.waitForFunction(() => { const j = window.__flatcut.lastJob; return j.state === 'held' && j.progress.machine_state === 'Hold:0'; }, null, { timeout: 30000 });
    const p = (await jobState()).progress;
    if (p.lines_acked > p.lines_done) break;
    if (tries === 20) throw new Error('every pause found the planner drained');
    await page.click('#job-resume');
    await page.waitForFunction((n) => window.__flatcut.lastJob.progress.lines_done > n, p.lines_done + 30, { timeout: 30000 });
  }
  const gone = new Promise((r) => crashed.proc.on('exit', r));
  crashed.proc.kill('SIGKILL');
  await gone;
  const next = await startServer(work);
  await openDevice(next.url);
  await page.check('#job-resume-journal');
  await page.click('#job-start');
  await page.waitForSelector('#job-doubt:not([hidden])', { timeout: 120000 });
  const refused = await jobState();
  const doubt = refused.in_doubt;
  const said = (await page.textContent('#job-doubt p')).replace(/\s+/g, ' ').trim();
  step('after a crash, the resume is refused and the panel names the lines in doubt', refused.state === 'failed' && !!doubt
    && doubt.from <= doubt.to && said.startsWith(`Lines ${doubt.from} to ${doubt.to} of job-3.gcode may or may not have run`)
    && (await page.textContent('#job-state')) === 'resume refused: lines in doubt', said);
  // The operator looks at the work: the cut ended about half-way through those lines.
  const typed = Math.round((doubt.from + doubt.to) / 2);
  await page.fill('#job-from', String(typed));
  // The lines in doubt over the layout, each where the G-code moves (read here from the file):
  // grey before the line typed, orange from it on, and a mark where the tool continues.
  const drawn = await page.evaluate(() => {
    const svg = document.getElementById('job-svg');
    const h = svg.viewBox.baseVal.height;
    return {
      lines: [...svg.querySelectorAll('#job-doubt-path polyline')].map((p) => ({
        line: Number(p.dataset.line), colour: p.getAttribute('stroke'),
        end: (() => { const q = p.points[p.points.length - 1]; return [q.x, h - q.y]; })(),
      })),
      mark: !!svg.querySelector('#job-from-mark'),
      text: document.getElementById('job-from-text').textContent,
    };
  });
  const gcode3 = await page.evaluate(async () => (await fetch('/api/job.gcode?sheet=3')).text());
  const job3 = gcodeMoves(gcode3);
  const inDoubt = job3.moves.filter((m) => m.line >= doubt.from && m.line <= doubt.to);
  const placed = inDoubt.every((m) => drawn.lines.some((l) => l.line === m.line && Math.hypot(l.end[0] - m.to[0], l.end[1] - m.to[1]) < 0.01
    && l.colour === (m.line >= typed ? '#e8590c' : '#868e96')));
  const firstSent = gcode3.split('\n').findIndex((t, i) => i + 1 >= typed && t.trim() && !t.trim().startsWith('(')) + 1;
  await shot('device-doubt');
  step('the lines in doubt are drawn over the layout where the G-code moves, the line typed named', placed && drawn.lines.length === inDoubt.length
    && drawn.mark && drawn.text.startsWith(`line ${firstSent}: `),
  `${drawn.lines.length} lines drawn of the ${inDoubt.length} moves in lines ${doubt.from} to ${doubt.to}; ${drawn.text}`);
  await page.click('#job-resume-from');
  await page.waitForSelector('#answer-yes', { timeout: 60000 });
  const asked = (await page.textContent('#job-question p')).trim();
  await page.click('#answer-yes');
  await page.waitForFunction(() => { const j = window.__flatcut.lastJob; return j.resume_from != null && ['done', 'failed', 'stopped'].includes(j.state); }, null, { timeout: 600000 });
  const resumed = await jobState();
  const sim3 = await page.evaluate(async () => (await fetch('/api/devices/sim')).json());
  const rest = job3.moves.filter((m) => m.line >= typed);
  const ran3 = ranMotions(sim3);
  // First the travel to the line's start (at most a lift, a traverse and a plunge).
  let w = walk(rest, ran3, 0);
  for (let h = 1; h <= 3 && w.bad; h++) w = walk(rest, ran3, h);
  const end3 = ran3[ran3.length - 1]?.to || [NaN, NaN, NaN];
  step(`resumed from line ${typed} typed in the panel: the simulator ran the G-code's moves from it, each once`,
    resumed.state === 'done' && resumed.resume_from === typed && /continues with line/.test(asked) && !w.bad && near(end3, job3.end),
    `${resumed.state}: ${resumed.message}; asked "${asked.split('\n')[0].slice(0, 80)}…"; ${w.k} motions of the ${rest.length} moves from line ${typed} after ${ran3.length - w.k} of travel${w.bad ? `; first difference at move ${w.bad.at}: ran ${JSON.stringify(w.bad.ran)}, the G-code ${JSON.stringify(w.bad.want)}` : ''}`);
  step('no script error on the page after the crash', pageErrors.length === 0, pageErrors.join('; '));
} catch (e) {
  if (!(e instanceof Measured)) {
    if (!results.length || results[results.length - 1].ok) {
      failed++;
      console.log(`FAIL ${e.message.split('\n')[0]}`);
    }
    code = 1;
  }
} finally {
  await browser.close().catch(() => {});
  for (const p of servers) {
    if (p.exitCode === null && p.signalCode === null) {
      p.kill('SIGTERM');
      await new Promise((r) => { p.on('exit', r); setTimeout(r, 5000); });
    }
  }
  fs.rmSync(work, { recursive: true, force: true });
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(code || (failed ? 1 : 0));
