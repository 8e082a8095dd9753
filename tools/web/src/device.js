// The device panel: the devices (serial ports and the embedded simulator, the project's own
// first, and more embedded simulators), several open at once, each on a tab of its own with its
// state and its job's progress; connect, unlock, home, jog and frame the device of the tab shown;
// a sheet's job started on it, paused, resumed and stopped, with its progress, ETA and the live
// position drawn over the sheet's layout; the sender's questions (a resume whose machine position
// is unknown, an edited job) asked here, and the line to continue from when a resume cannot tell
// which lines ran (those lines drawn over the layout).
// Every page follows the same devices and jobs through the `device` and `job` events (each names
// its device).
// An HP-GL plotter or vinyl cutter (the embedded HP-GL plotter, or a port opened as one) shows
// what makes sense for it: start, pause (pen up), resume, stop, its progress in bytes sent (HP-GL
// has no acknowledgements: the panel says so), the ETA, and the job's strokes sent so far over
// the layout; GRBL's unlock, home, jog and frame are hidden with the reason.

const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
const mm = (p) => (p ? `X ${p[0].toFixed(2)}  Y ${p[1].toFixed(2)}  Z ${p[2].toFixed(2)}` : '–');
const SVG = 'http://www.w3.org/2000/svg';
const ENDED = ['done', 'failed', 'stopped'];
/** How the panel names a device: the embedded simulator, another one, or the port's path. */
const PLOTTER_SIM = 'plotter-sim';
const label = (id) => (id === 'simulator' ? 'embedded simulator' : id === PLOTTER_SIM ? 'embedded HP-GL plotter'
  : id.startsWith('simulator:') ? `simulator ${id.slice(10)}` : id);
const isSim = (id) => id.startsWith('simulator') || id === PLOTTER_SIM;

function secs(s) {
  if (s == null) return '–';
  const m = Math.floor(s / 60);
  return m ? `${m} min ${Math.round(s - 60 * m)} s` : `${s.toFixed(1)} s`;
}

/** The panel in `el`; `hooks` (the page's script hooks) get `onDevice`, `onJob`, `lastJob` (the
 * job of the device shown) and `shownDevice`. */
export async function devicePanel(el, api, hooks) {
  el.innerHTML = `<h3>Devices</h3>
    <div id="dev-tabs" class="dev-tabs" role="tablist" aria-label="devices open"></div>
    <div class="row"><select id="dev-select" aria-label="device to open"></select>
      <label title="Time scale of the embedded simulator (1: real time)">speed <input id="dev-speed" type="number" min="0.1" max="1000" step="any" value="50" style="width:5em"></label>
      <button id="dev-connect">Connect</button><button id="dev-close">Disconnect</button></div>
    <div class="row" id="dev-hpgl-row"><label title="Open the port as an HP-GL plotter or vinyl cutter, with the profile's flow control"><input type="checkbox" id="dev-hpgl"> HP-GL plotter</label>
      <label>profile <select id="dev-profile" aria-label="plotter profile"><option value="">the project's, else vinyl</option><option>vinyl</option><option>pen-hpgl</option></select></label></div>
    <p id="dev-state" class="dev-pos">not connected</p>
    <p id="dev-grbl-note" class="muted" hidden>An HP-GL plotter takes no GRBL commands: unlock, home, jog and frame are for GRBL controllers. Pause stops the feed at the end of an instruction and lifts the pen.</p>
    <div class="row" id="dev-grbl-row"><button id="dev-unlock" title="Clear an alarm lock ($X): only when the position is known to be right">Unlock</button>
      <button id="dev-home" title="Home the machine ($H)">Home</button>
      <span>Jog <select id="jog-step" aria-label="jog step">${[0.1, 1, 10, 50].map((s) => `<option ${s === 10 ? 'selected' : ''}>${s}</option>`).join('')}</select> mm</span>
      ${['X-', 'X+', 'Y-', 'Y+', 'Z-', 'Z+'].map((a) => `<button data-jog="${a}">${a.replace('-', '−')}</button>`).join('')}
      <button id="dev-frame" title="Trace the rectangle the sheet's job cuts in, tool off">Frame</button></div>
    <h3>Job</h3>
    <div class="row">Sheet <select id="job-sheet"></select>
      <label title="Continue the sheet's job from its journal after a stop"><input type="checkbox" id="job-resume-journal"> resume from the journal</label></div>
    <div class="row"><button id="job-start">Start</button><button id="job-hold">Pause</button>
      <button id="job-resume">Resume</button><button id="job-stop" title="Feed hold, soft reset, tool off">Stop</button></div>
    <div class="row"><progress id="job-progress" max="1" value="0"></progress><span id="job-text" class="muted">no job</span></div>
    <div id="job-question" hidden></div>
    <div id="job-doubt" hidden></div>
    <div id="job-notices"></div>
    <div id="job-view" class="drawing job-view"></div>`;
  const $ = (id) => el.querySelector(`#${id}`);
  let info, all;
  try {
    [info, all] = await Promise.all([api('GET', '/api/devices'), api('GET', '/api/jobs')]);
  } catch (e) {
    $('dev-state').textContent = e.message;
    return;
  }
  const sel = $('dev-select');
  const ids = info.devices.map((d) => d.id);
  const order = [info.project_device, ...ids.filter((i) => i !== info.project_device)];
  sel.innerHTML = order.filter((id) => ids.includes(id)).map((id) => {
    const d = info.devices.find((x) => x.id === id);
    const text = d.kind === 'simulator' ? `${label(d.id)} (GRBL 1.1h)` : d.kind === 'plotter-simulator' ? `${label(d.id)} (HP-GL)` : `${d.id} (${d.description})`;
    return `<option value="${esc(d.id)}">${esc(text)}${id === info.project_device ? ' · the project\'s' : ''}</option>`;
  }).join('') + '<option value="simulator:new">another embedded simulator</option>';

  let sheets = 1;
  try { sheets = Math.max(1, (await api('GET', '/api/summary.json')).sheets); } catch { /* the run's error shows on start */ }
  $('job-sheet').innerHTML = Array.from({ length: sheets }, (_, i) => `<option>${i + 1}</option>`).join('');

  const view = { sheet: null, height: 0, dot: null, doubt: null, from: null, plot: null };
  async function showSheet(n) {
    if (view.sheet === n) return;
    view.sheet = n;
    const box = $('job-view');
    box.textContent = 'loading the layout…';
    try {
      const text = await api('GET', `/api/layout.svg?sheet=${n}`);
      const svg = new DOMParser().parseFromString(text, 'image/svg+xml').documentElement;
      const vb = (svg.getAttribute('viewBox') || '0 0 0 0').split(/\s+/).map(Number);
      view.height = vb[3];
      svg.removeAttribute('width');
      svg.removeAttribute('height');
      svg.setAttribute('id', 'job-svg');
      // Where the tool is, over the layout (machine y is up, the drawing's down).
      const g = document.createElementNS(SVG, 'g');
      g.setAttribute('id', 'job-overlay');
      g.setAttribute('visibility', 'hidden');
      g.innerHTML = '<circle r="6" fill="none" stroke="#3b82c4" stroke-width="1.5"/><path d="M-10 0H10M0-10V10" stroke="#3b82c4" stroke-width="1"/><circle r="2" fill="#3b82c4"/>';
      const doubt = document.createElementNS(SVG, 'g');
      doubt.setAttribute('id', 'job-doubt-path');
      const sent = document.createElementNS(SVG, 'path');
      sent.setAttribute('id', 'job-sent-path');
      sent.setAttribute('fill', 'none');
      sent.setAttribute('stroke', '#3b82c4');
      sent.setAttribute('stroke-width', '2');
      sent.setAttribute('vector-effect', 'non-scaling-stroke');
      svg.append(doubt, sent, g);
      box.replaceChildren(document.importNode(svg, true));
      view.dot = box.querySelector('#job-overlay');
      drawDoubtPath();
    } catch (e) {
      box.textContent = e.message;
    }
  }
  function mark(p) {
    if (!p || !view.dot) return;
    view.dot.setAttribute('transform', `translate(${p[0]} ${view.height - p[1]})`);
    view.dot.setAttribute('visibility', 'visible');
    inView(view.dot);
  }

  /** Scrolls the layout so that `node` (drawn over it) is in view, when it is not. */
  function inView(node) {
    const box = $('job-view');
    const [r, b] = [node.getBoundingClientRect(), box.getBoundingClientRect()];
    if (r.height && (r.top < b.top || r.bottom > b.bottom)) box.scrollTop += (r.top + r.bottom) / 2 - (b.top + b.bottom) / 2;
    if (r.width && (r.left < b.left || r.right > b.right)) box.scrollLeft += (r.left + r.right) / 2 - (b.left + b.right) / 2;
  }

  /** A plot's HP-GL (`GET /api/job.plt`, the bytes it streams) read into its pen-down strokes,
   * each with the byte offset where it ends, so the strokes sent so far can be drawn. */
  async function loadPlot(j, d) {
    const spec = d && d.plotter ? d.plotter.profile_spec : '';
    const key = `${j.id}`;
    if (view.plot && view.plot.key === key) return;
    view.plot = { key, strokes: [] };
    try {
      const text = await api('GET', `/api/job.plt?sheet=${j.sheet}${spec ? `&profile=${encodeURIComponent(spec)}` : ''}`);
      const strokes = [];
      let pos = [0, 0]; let down = false; let rel = false; let at = 0;
      const bytes = new TextEncoder();
      for (const instr of text.split(';')) {
        at += bytes.encode(instr).length + 1;
        const op = instr.trim().slice(0, 2).toUpperCase();
        const nums = instr.trim().slice(2).split(/[ ,]+/).filter(Boolean).map(Number);
        if (op === 'PU' || op === 'SP' || op === 'IN') down = false;
        if (op === 'PD') down = true;
        if (op === 'PA') rel = false;
        if (op === 'PR') rel = true;
        if (!['PU', 'PD', 'PA', 'PR'].includes(op)) continue;
        for (let k = 0; k + 1 < nums.length; k += 2) {
          const to = rel ? [pos[0] + nums[k] / 40, pos[1] + nums[k + 1] / 40] : [nums[k] / 40, nums[k + 1] / 40];
          if (down) strokes.push({ from: pos, to, end: at });
          pos = to;
        }
      }
      view.plot.strokes = strokes;
    } catch { /* the layout stays without the strokes sent */ }
  }

  /** The strokes of the plot sent so far (their instruction accepted by the link), over the
   * layout: sent, not necessarily drawn yet (the plotter's buffer holds some). */
  function drawSent(j) {
    const path = $('job-view').querySelector('#job-sent-path');
    if (!path) return;
    const sent = j && j.protocol === 'hpgl' && j.progress ? j.progress.bytes_sent : 0;
    if (!sent || !view.plot) { path.setAttribute('d', ''); return; }
    const h = view.height;
    const d = view.plot.strokes.filter((s) => s.end <= sent)
      .map((s) => `M${s.from[0]} ${h - s.from[1]}L${s.to[0]} ${h - s.to[1]}`).join('');
    path.setAttribute('d', d);
  }

  // Every device open (by id), the latest job of each device, and the device shown.
  const devices = new Map(info.opened.map((d) => [d.id, d]));
  const jobs = new Map();
  for (const j of all.jobs) jobs.set(j.device_id, j);
  let shown = info.default || (info.opened[0] && info.opened[0].id) || null;
  let closedNote = '';
  let job = shown ? jobs.get(shown) || null : null;
  let device = shown ? devices.get(shown) : null;
  const busy = () => job && !ENDED.includes(job.state);

  /** One tab per device open: its name, and its job's state and progress. */
  function drawTabs() {
    const tabs = $('dev-tabs');
    if (!devices.size) { tabs.innerHTML = '<span class="muted">no device open</span>'; return; }
    tabs.innerHTML = [...devices.keys()].map((id) => {
      const j = jobs.get(id);
      const run = j && !ENDED.includes(j.state);
      const what = j ? `${j.state}${run && j.progress ? ` ${(100 * j.progress.fraction).toFixed(0)} %` : ''} · ${esc(j.name)}` : 'idle';
      return `<button role="tab" data-device="${esc(id)}" class="${id === shown ? 'on' : ''}${run ? ' busy' : ''}" aria-selected="${id === shown}">
        <strong>${esc(label(id))}</strong><span class="muted">${what}</span></button>`;
    }).join('');
    for (const b of tabs.querySelectorAll('[data-device]')) b.addEventListener('click', () => show(b.dataset.device));
  }

  /** Shows device `id`'s tab: its state, its job, its position over its job's layout. */
  async function show(id) {
    shown = id;
    hooks.shownDevice = id;
    device = devices.get(id) || null;
    job = jobs.get(id) || null;
    drawTabs();
    drawDevice();
    if (job) { await showSheet(job.sheet); drawJob(); } else { hooks.lastJob = null; noJob(); }
  }

  function noJob() {
    $('job-start').disabled = false;
    $('job-hold').disabled = $('job-resume').disabled = $('job-stop').disabled = true;
    $('job-progress').value = 0;
    $('job-text').innerHTML = '<span class="muted">no job on this device</span>';
    $('job-question').hidden = true;
    $('job-notices').innerHTML = '';
    drawDoubt({ id: null });
    drawSent(null);
    if (view.dot) view.dot.setAttribute('visibility', 'hidden');
  }

  // A GRBL job's machine state before the controller has reported one since the job began: the
  // status from before the job (Idle) would say the machine stands while the job starts.
  const ran = new Set();
  function machineState(p) {
    const st = p && p.machine_state;
    if (st && st !== 'Idle') ran.add(job.id);
    return !st || (st === 'Idle' && !ran.has(job.id)) ? 'Starting' : st;
  }

  function drawDevice() {
    const d = device;
    const open = d && d.open;
    const plotter = open && d.protocol === 'hpgl';
    // While a job runs its progress says where the machine is; between jobs, the status reports.
    const p = busy() && !plotter && (job.progress || {});
    const st = open && (p ? { state: machineState(p), work: p.position } : d.status);
    const pl = plotter && d.plotter;
    $('dev-state').textContent = !open ? closedNote || 'not connected'
      : plotter ? `${label(d.id)}: ${d.description} · HP-GL, profile ${pl.profile}, ${pl.flow_control}${pl.buffer_query ? ' with buffer query' : ''}, ${pl.baud} baud · ${!busy() ? 'ready' : ['held', 'paused'].includes(job.state) ? 'paused, pen up' : 'plotting'}`
        : `${label(d.id)}: ${d.description}${d.controller ? `, GRBL ${d.controller.version}` : ''} · ${st && st.state ? `${st.state} · ${mm(st.work)}` : 'connected'}`;
    $('dev-close').disabled = !open;
    $('dev-grbl-row').hidden = !!plotter;
    $('dev-grbl-note').hidden = !plotter;
    for (const id of ['dev-unlock', 'dev-home', 'dev-frame']) $(id).disabled = !open || busy() || !!plotter;
    for (const b of el.querySelectorAll('[data-jog]')) b.disabled = !open || busy() || !!plotter;
    $('dev-speed').disabled = !isSim(sel.value);
    $('dev-hpgl-row').hidden = isSim(sel.value) && sel.value !== PLOTTER_SIM;
    $('dev-hpgl').disabled = sel.value === PLOTTER_SIM;
    $('dev-hpgl').checked = sel.value === PLOTTER_SIM || (!isSim(sel.value) && $('dev-hpgl').checked);
    $('job-hold').textContent = plotter ? 'Pause (pen up)' : 'Pause';
    $('job-stop').title = plotter ? 'The plotter drops its buffer (ESC.K), pen up' : 'Feed hold, soft reset, tool off';
    if (st && !p && st.work) mark(st.work);
  }

  function drawJob() {
    const j = job;
    hooks.lastJob = j;
    const running = busy();
    $('job-start').disabled = running;
    $('job-hold').disabled = !running || j.state !== 'running';
    $('job-resume').disabled = !running || !['held', 'paused'].includes(j.state);
    $('job-stop').disabled = !running;
    if (!j) return;
    if (String(j.sheet) !== $('job-sheet').value && running) $('job-sheet').value = String(j.sheet);
    const p = j.progress;
    const frac = p ? p.fraction : 0;
    $('job-progress').value = frac;
    // A resume refused before anything was sent: the box below says why and asks.
    const refused = j.in_doubt && j.state === 'failed' && !(p && p.lines_done);
    const plot = j.protocol === 'hpgl';
    const what = refused ? 'resume refused: lines in doubt' : {
      running: 'running', held: plot ? 'paused (pen up)' : 'paused (feed hold)', paused: 'paused by the job', asking: 'waiting for your answer',
      done: 'done', failed: 'failed', stopped: plot ? 'stopped (buffer dropped, pen up)' : 'stopped (tool off)',
    }[j.state] || j.state;
    // HP-GL has no acknowledgements: a plot's progress is the bytes its link accepted.
    const where = !p || refused ? '' : plot
      ? ` · ${p.bytes_sent} of ${p.bytes_total} bytes sent (${(100 * frac).toFixed(1)} %) · ETA ${secs(p.eta_s)}${p.device_holding ? ' · the plotter holds the feed (XOFF)' : ''}
        <br><span class="muted" id="job-basis">progress counts the bytes the plotter's link accepted, not what it has drawn: its buffer may still hold some</span>`
      : ` · line ${p.lines_done} of ${p.lines_total} · ${(100 * frac).toFixed(1)} % of the path · ETA ${secs(p.eta_s)} · <span class="dev-pos">${mm(p.position)}</span>`;
    $('job-text').innerHTML = `<strong id="job-state">${esc(what)}</strong> · ${esc(j.name)}
      ${where}
      ${j.message && j.state !== 'done' && !refused ? `<br><span class="${j.state === 'failed' ? 'over' : 'muted'}">${esc(j.message)}</span>` : ''}`;
    const q = $('job-question');
    if (j.question) {
      q.hidden = false;
      q.innerHTML = `<p class="question">${esc(j.question.text).replace(/\n/g, '<br>')}</p>
        <div class="row"><strong>${esc(j.question.prompt.replace(/\s*\[y\/N\]\s*$/, ''))}</strong>
        <button id="answer-yes">Yes</button><button id="answer-no">No (stop)</button></div>`;
      const answer = (yes) => act('POST', `/api/jobs/${j.id}/answer`, { question: j.question.id, yes });
      q.querySelector('#answer-yes').addEventListener('click', () => answer(true));
      q.querySelector('#answer-no').addEventListener('click', () => answer(false));
    } else {
      q.hidden = true;
      q.innerHTML = '';
    }
    drawDoubt(j);
    $('job-notices').innerHTML = j.notices.map((n) => `<p class="muted">${esc(n)}</p>`).join('');
    if (p && p.position) mark(p.position);
    if (plot) {
      if (view.dot) view.dot.setAttribute('visibility', 'hidden');
      loadPlot(j, devices.get(j.device_id)).then(() => drawSent(job));
    } else drawSent(null);
    drawDevice();
  }

  // A resume that cannot tell which lines ran names them, and shows them over the layout: the
  // operator looks at the work and says where to continue (as `flatcut send --resume-from
  // LINE`). The lines before the one typed count as run (grey); from it on they run (orange).
  function drawDoubt(j) {
    const box = $('job-doubt');
    const d = j.in_doubt;
    if (!d || busy() || !j.id) {
      box.hidden = true;
      box.innerHTML = '';
      delete box.dataset.job;
      if (view.doubt) { view.doubt = null; drawDoubtPath(); }
      return;
    }
    if (box.dataset.job === String(j.id)) return;
    box.dataset.job = String(j.id);
    box.hidden = false;
    view.doubt = d;
    view.from = d.from;
    box.innerHTML = `<p class="question">Lines ${d.from} to ${d.to} of ${esc(j.name)} may or may not have run: ${esc(d.reason)}.
      They are drawn over the sheet below, orange from the line to continue from on.</p>
      <div class="row">Look at the work, then continue from line
        <input id="job-from" type="number" min="1" step="1" value="${d.from}" style="width:6em" aria-label="line to continue from">
        <button id="job-resume-from">Resume from this line</button></div>
      <p id="job-from-text" class="dev-pos muted"></p>`;
    const input = box.querySelector('#job-from');
    input.addEventListener('input', () => { view.from = Number(input.value); drawDoubtPath(); });
    drawDoubtPath();
    box.querySelector('#job-resume-from').addEventListener('click', async () => {
      const line = Number(input.value);
      if (!Number.isInteger(line) || line < 1) {
        $('job-text').innerHTML = '<span class="over">the line to continue from is a line number of the file (1 or more)</span>';
        return;
      }
      $('job-text').textContent = `resuming from line ${line}…`;
      const r = await act('POST', '/api/jobs', { sheet: j.sheet, resume_from: line, device: j.device_id });
      if (r) took(r);
    });
  }

  /** The lines in doubt over the layout, and what the line typed is. */
  function drawDoubtPath() {
    const g = $('job-view').querySelector('#job-doubt-path');
    const d = view.doubt;
    const said = $('job-doubt').querySelector('#job-from-text');
    if (g) g.replaceChildren();
    if (!d) return;
    const from = view.from;
    // Where a resume from `from` continues: the first line sent from there on (a comment or a
    // blank line names the next), as the sender counts it.
    const first = d.lines.find((l) => l.line >= from);
    if (said) {
      said.textContent = first && Number.isInteger(from) && from >= d.from
        ? `line ${first.line}: ${first.text}`
        : (Number.isInteger(from) && from > 0 ? `line ${from} is outside the lines in doubt` : '');
    }
    if (!g) return;
    const xy = (p) => `${p[0]},${view.height - p[1]}`;
    for (const l of d.lines) {
      if (l.path.length < 2) continue;
      const runs = Number.isInteger(from) && l.line >= from;
      const pl = document.createElementNS(SVG, 'polyline');
      pl.setAttribute('points', l.path.map(xy).join(' '));
      pl.setAttribute('fill', 'none');
      pl.setAttribute('stroke', runs ? '#e8590c' : '#868e96');
      pl.setAttribute('stroke-width', l.cuts ? '3' : '1.5');
      if (!l.cuts) pl.setAttribute('stroke-dasharray', '4 3');
      pl.setAttribute('vector-effect', 'non-scaling-stroke');
      pl.dataset.line = String(l.line);
      g.append(pl);
    }
    const start = first && d.lines.slice(d.lines.indexOf(first)).find((l) => l.path.length);
    if (start && from >= d.from) {
      const c = document.createElementNS(SVG, 'circle');
      c.setAttribute('cx', start.path[0][0]);
      c.setAttribute('cy', view.height - start.path[0][1]);
      c.setAttribute('r', '5');
      c.setAttribute('fill', '#e8590c');
      c.setAttribute('id', 'job-from-mark');
      g.append(c);
    }
    inView(g);
  }

  async function act(method, path, body) {
    try {
      return await api(method, path, body);
    } catch (e) {
      $('job-text').innerHTML = `<span class="over">${esc(e.message)}</span>`;
      return null;
    }
  }

  /** A device's state: its tab, and the panel when it is the one shown. */
  function tookDevice(d) {
    if (d.open) {
      const first = !devices.has(d.id);
      devices.set(d.id, d);
      if (first && (!shown || !devices.has(shown))) { show(d.id); return; }
    } else if (d.id != null) {
      devices.delete(d.id);
      if (d.id === shown) {
        closedNote = d.message ? `${label(d.id)} closed: ${d.message}` : `${label(d.id)} closed`;
        device = null;
        const next = [...devices.keys()].pop();
        if (next) { show(next); return; }
      }
    }
    drawTabs();
    if (d.id === shown) { device = d.open ? d : null; drawDevice(); }
  }

  /** A job's state: the latest of its device's, drawn when its device is shown. */
  function took(j) {
    const had = jobs.get(j.device_id);
    if (had && j.id < had.id) return;
    jobs.set(j.device_id, j);
    drawTabs();
    if (j.device_id !== shown) return;
    if (!job || j.id !== job.id) showSheet(j.sheet);
    job = j;
    drawJob();
  }

  hooks.onDevice = (d) => {
    if (d.event === 'restarted') {
      if (d.id === shown) $('job-notices').insertAdjacentHTML('beforeend', `<p class="over">${esc(d.message)}</p>`);
      return;
    }
    tookDevice(d);
  };
  hooks.onJob = took;

  /** What to open: the device chosen, or another embedded simulator under the next free name. */
  function chosen() {
    if (sel.value !== 'simulator:new') return sel.value;
    let n = 2;
    while (devices.has(`simulator:${n}`)) n++;
    return `simulator:${n}`;
  }
  const connectBody = (id) => ({
    device: id,
    ...(isSim(id) ? { speed: Number($('dev-speed').value) || 50 } : {}),
    ...((id === PLOTTER_SIM || (!isSim(id) && $('dev-hpgl').checked)) ? { protocol: 'hpgl', ...($('dev-profile').value ? { profile: $('dev-profile').value } : {}) } : {}),
  });
  $('dev-connect').addEventListener('click', async () => {
    $('dev-state').textContent = 'connecting…';
    const id = chosen();
    const d = await act('POST', '/api/devices/connect', connectBody(id));
    if (d) { devices.set(d.id, d); await show(d.id); }
  });
  const on = (extra = {}) => ({ device: shown, ...extra });
  $('dev-close').addEventListener('click', () => shown && act('POST', '/api/devices/close', on()));
  $('dev-unlock').addEventListener('click', () => act('POST', '/api/devices/unlock', on()));
  $('dev-home').addEventListener('click', () => act('POST', '/api/devices/home', on()));
  $('dev-frame').addEventListener('click', () => act('POST', '/api/devices/frame', on({ sheet: Number($('job-sheet').value) })));
  for (const b of el.querySelectorAll('[data-jog]')) {
    b.addEventListener('click', () => {
      const step = Number($('jog-step').value);
      const by = [0, 0, 0];
      by['XYZ'.indexOf(b.dataset.jog[0])] = b.dataset.jog[1] === '+' ? step : -step;
      act('POST', '/api/devices/jog', on({ by, feed: b.dataset.jog[0] === 'Z' ? 300 : 2000 }));
    });
  }
  $('job-sheet').addEventListener('change', () => showSheet(Number($('job-sheet').value)));
  $('job-start').addEventListener('click', async () => {
    const sheet = Number($('job-sheet').value);
    await showSheet(sheet);
    // Opening the device chosen (the simulator at the speed asked for), unless one is shown.
    if (!(device && device.open)) {
      $('job-text').textContent = 'connecting…';
      const d = await act('POST', '/api/devices/connect', connectBody(chosen()));
      if (!d) return;
      devices.set(d.id, d);
      await show(d.id);
    }
    $('job-text').textContent = 'preparing the job…';
    const j = await act('POST', '/api/jobs', on({ sheet, resume: $('job-resume-journal').checked }));
    if (j) took(j);
  });
  $('job-hold').addEventListener('click', () => job && act('POST', `/api/jobs/${job.id}/hold`));
  $('job-resume').addEventListener('click', () => job && act('POST', `/api/jobs/${job.id}/resume`));
  $('job-stop').addEventListener('click', () => job && act('POST', `/api/jobs/${job.id}/stop`));
  sel.addEventListener('change', drawDevice);

  await showSheet(job ? job.sheet : 1);
  if (shown) await show(shown); else { drawTabs(); drawDevice(); hooks.lastJob = null; noJob(); }
}
