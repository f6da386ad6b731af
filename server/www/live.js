// The Live tab: the running trio seen through `pidlab serve --lcm-url`
// (docs/live.md has the protocol, docs/workbench.md the page). The server
// posts live_status (JSON) and binary frames of the selected episode: min/max
// per column, never averaged, drawn as bands. Frames are kept as they come and
// drawn at the next animation frame (the latest only, once); when an episode completes
// its whole data (live_data, Float64) lands in window.pidlab.live.final.
import { clippedAxis } from './plots.js';

const kMagic = 0x31564c50;  // "PLV1"
const $ = (id) => document.getElementById(id);

// A band chart: x, then [max, min] filled between, then extra lines.
function bandChart(el, title, label, colour, extra) {
  const series = [{ label: 't s' },
    { label: label + ' max', stroke: colour, width: 1 },
    { label: label + ' min', stroke: colour, width: 1 }];
  for (const e of extra || []) series.push(e);
  const fill = colour === '#1f77b4' ? 'rgba(31,119,180,0.25)' : colour === '#d62728' ? 'rgba(214,39,40,0.25)' : 'rgba(44,160,44,0.25)';
  // u and n: the docs' axis rules (plots.js clippedAxis): a derivative kick
  // clipped and marked, a flat signal (n = 0) on a readable range.
  const axis = label === 'y' ? null : clippedAxis();
  return new uPlot({
    title, width: Math.max(400, el.clientWidth || 800), height: 170, series,
    scales: { x: { time: false }, ...(axis ? { y: { range: axis.range } } : {}) }, axes: [{ label: 't (s)' }, { label }],
    bands: [{ series: [1, 2], fill }], ...(axis ? { hooks: { draw: [axis.draw] } } : {}),
  }, series.map(() => []), el);
}

// Parses a binary frame: the header's eight numbers and the arrays.
export function parseFrame(buffer) {
  const view = new DataView(buffer);
  if (buffer.byteLength < 72 || view.getUint32(0, true) !== kMagic) return null;
  const h = new Float64Array(buffer.slice(8, 72));
  const f = { kind: view.getUint32(4, true), episode_id: h[0], first_step: h[1], steps: h[2], columns: h[3],
    dt_s: h[4], total_steps: h[5], steps_done: h[6], dropped_frames: h[7] };
  if (f.kind === 1) {
    const c = f.columns;
    if (buffer.byteLength < 72 + 24 * c) return null;
    const a = (i) => new Float32Array(buffer, 72 + 4 * c * i, c);
    Object.assign(f, { y_min: a(0), y_max: a(1), u_min: a(2), u_max: a(3), n_min: a(4), n_max: a(5) });
  } else if (f.kind === 2) {
    const s = f.steps;
    if (buffer.byteLength < 72 + 24 * s) return null;
    const a = (i) => new Float64Array(buffer.slice(72 + 8 * s * i, 72 + 8 * s * (i + 1)));
    Object.assign(f, { y: a(0), u: a(1), n: a(2) });
  } else {
    return null;
  }
  return f;
}

// An episode's id as exact decimal text (live_status gives it: a double holds 53 bits).
const idText = (e) => e.episode_id_text || String(e.episode_id);
const nanToNull = (a) => Array.from(a, (v) => (Number.isNaN(v) ? null : v));

let live = null;  // window.pidlab.live
let rawSend = null;
let charts = null;
let latest = null;  // the newest frame not yet drawn
const asked = new Set();  // episodes whose live_data was asked for

function buildCharts() {
  if (charts) return;
  charts = {
    y: bandChart($('live-plot-y'), 'y (min/max per column) and r', 'y', '#1f77b4', [{ label: 'r', stroke: '#555', dash: [4, 4], width: 1 }]),
    u: bandChart($('live-plot-u'), 'u (min/max per column)', 'u', '#d62728'),
    n: bandChart($('live-plot-n'), 'n (min/max per column)', 'n', '#2ca02c'),
  };
}

function draw(f) {
  buildCharts();
  const x = new Array(f.columns);
  for (let j = 0; j < f.columns; j++) x[j] = (f.first_step + Math.floor((j * f.steps) / f.columns)) * f.dt_s;
  const ep = ((live.status && live.status.episodes) || []).find((e) => e.episode_id === f.episode_id);
  const r = ep ? new Array(f.columns).fill(ep.r) : [];
  charts.y.setData([x, nanToNull(f.y_max), nanToNull(f.y_min), r]);
  charts.u.setData([x, nanToNull(f.u_max), nanToNull(f.u_min)]);
  charts.n.setData([x, nanToNull(f.n_max), nanToNull(f.n_min)]);
  live.drawn += 1;
  $('live-frames').textContent = 'episode ' + (ep ? idText(ep) : f.episode_id) + ': ' + f.steps_done + ' of ' + (f.total_steps + 1) +
    ' steps, ' + live.frames + ' frames received, ' + live.drawn + ' drawn, ' + f.dropped_frames +
    ' dropped by the server';
}

// One draw per animation frame at most, and an animation frame only when a
// frame waits to be drawn: no loop runs while nothing arrives (an idle
// animation loop alone cost the trio on the same 2-core machine about 5 %).
let scheduled = false;
function drawLatest() {
  scheduled = false;
  if (latest && live.subscribed) { const f = latest; latest = null; draw(f); }
}
function scheduleDraw() {
  if (!scheduled) { scheduled = true; requestAnimationFrame(drawLatest); }
}
function cell(tr, text, cls) {
  const td = document.createElement('td');
  td.textContent = text;
  if (cls) td.className = cls;
  tr.append(td);
  return td;
}

// Sets a cell's text only when it changed: the status arrives ten times a
// second, and rewriting unchanged cells would make the browser lay the table
// out again each time (CPU the trio on the same machine would miss).
function setText(el, text) {
  if (el.textContent !== text) el.textContent = text;
}

// The rows of `body` keyed by `key` (kept in order, reused when their key
// stays): fill(tr, entry) writes the cells of a row made by make(entry).
function keyedRows(body, entries, key, make, fill) {
  const old = new Map([...body.children].map((tr) => [tr.dataset.key, tr]));
  let at = body.firstElementChild;
  for (const entry of entries) {
    const k = key(entry);
    let tr = old.get(k);
    if (!tr) { tr = make(entry); tr.dataset.key = k; }
    old.delete(k);
    fill(tr, entry);
    if (tr !== at) body.insertBefore(tr, at); else at = at.nextElementSibling;
  }
  for (const tr of old.values()) tr.remove();
}

function renderEpisodes(s) {
  const selected = s.selected_episode_id_text || String(s.selected_episode_id);
  keyedRows($('live-episodes').querySelector('tbody'), s.episodes, idText, (e) => {
    const tr = document.createElement('tr');
    const id = idText(e);
    tr.dataset.episodeId = id;
    for (const cls of ['', '', '', 'steps', 'status', 'realtime']) cell(tr, '', cls);
    tr.addEventListener('click', () => rawSend({ type: 'live_select', episode_id: id }));
    return tr;
  }, (tr, e) => {
    const id = idText(e);
    tr.classList.toggle('selected', id === selected);
    const [idCell, plant, gains, steps, st, rt] = tr.children;
    setText(idCell, id + (e.trio > 1 ? ' (trio ' + e.trio + ')' : ''));
    setText(plant, e.plant);
    setText(gains, (e.gains || []).map((g) => String(+Number(g).toPrecision(6))).join(','));
    setText(steps, e.steps_done + '/' + (e.total_steps + 1));
    setText(st, e.status + (e.message ? ': ' + e.message : ''));
    st.className = 'status status-' + e.status;
    st.dataset.status = e.status;
    setText(rt, e.realtime ? e.realtime.missed_deadlines + ' missed' : '-');
    if (e.realtime) rt.dataset.realtime = JSON.stringify(e.realtime);
  });
}

// The relay episodes (pidlab autotune, docs/autotune.md): the relay as the
// server follows it, its cycles and the estimates as they converge; the
// verdict is the autotune's row among the tunings.
function renderRelay(s) {
  const fmt = (v) => (v === null || v === undefined ? '-' : String(+Number(v).toPrecision(4)));
  const relays = (s.episodes || []).filter((e) => e.relay);
  $('live-relay-box').classList.toggle('hidden', relays.length === 0);
  keyedRows($('live-relay').querySelector('tbody'), relays, idText, (e) => {
    const tr = document.createElement('tr');
    tr.dataset.episodeId = idText(e);
    for (const cls of ['relay-phase', 'relay-cycles', '', 'relay-ku', 'relay-model', 'relay-why']) cell(tr, '', cls);
    return tr;
  }, (tr, e) => {
    const r = e.relay;
    const [phase, cycles, period, ku, model, why] = tr.children;
    tr.title = 'episode ' + idText(e);
    setText(phase, r.phase);
    phase.dataset.phase = r.phase;
    phase.title = 'operating point u0 ' + fmt(r.u0) + ', y0 ' + fmt(r.y0) + '; hysteresis ' + fmt(r.hysteresis) +
      ', relay +' + fmt(r.d_high) + ' / -' + fmt(r.d_low) + ', noise sigma ' + fmt(r.noise_sigma);
    setText(cycles, String(r.cycles) + (r.restarts ? ' (' + r.restarts + ' restart)' : ''));
    cycles.dataset.cycles = String(r.cycles);
    setText(period, r.last_period_s === null ? '-' : fmt(r.last_period_s) + ' s');
    const x = r.estimates;
    setText(ku, x ? fmt(x.ku) + ', ' + fmt(x.pu_s) + ' s' + (x.converged ? '' : ' (converging)') : '-');
    if (x) ku.dataset.ku = String(x.ku);
    setText(model, x ? 'K ' + fmt(x.model.gain) + (x.model.kind === 'fopdt' ? ', T ' + fmt(x.model.time_constant_s) : ' (ipdt)') +
      ', L ' + fmt(x.model.delay_s) : '-');
    setText(why, (r.why || '').split(':')[0]);  // the whole line in the title
    why.title = r.why || '';
  });
}

// The tunings over the trio (pidlab tune --backend lcm) with their best so far.
function renderTunings(s) {
  const fmt = (v) => String(+Number(v).toPrecision(6));
  keyedRows($('live-tunings').querySelector('tbody'), s.tunings || [], (t) => t.tuning_id_text, (t) => {
    const tr = document.createElement('tr');
    tr.dataset.tuningId = t.tuning_id_text;
    for (const cls of ['', '', '', 'evaluations', 'best-objective', 'best-gains', 'status']) cell(tr, '', cls);
    return tr;
  }, (tr, t) => {
    const [id, method, trios, evaluations, best, gains, st] = tr.children;
    setText(id, t.tuning_id_text);
    setText(method, t.method + ', ' + t.objective);
    setText(trios, String(t.trios));
    setText(evaluations, String(t.evaluations));
    setText(best, t.best_objective === null ? '-' : fmt(t.best_objective));
    best.dataset.value = String(t.best_objective);
    setText(gains, t.best_gains ? t.best_gains.map(fmt).join(',') : '-');
    gains.dataset.gains = JSON.stringify(t.best_gains);
    setText(st, t.status);
    st.dataset.status = t.status;
  });
}

function renderHealth(s) {
  const h = s.health || {};
  const lines = Object.entries(h.roles || {}).map(([role, r]) => role + ': ' +
    (r.last_heard_s === null ? 'not heard' : 'heard ' + r.last_heard_s.toFixed(2) + ' s ago') +
    (r.pid === null || r.pid === undefined ? '' : ' (pid ' + r.pid + ')'));
  lines.push(['received', 'undecodable', 'unauthenticated', 'replayed', 'trajectory_requests']
    .map((k) => k + ' ' + h[k]).join(', '));
  lines.push('dropped frames (this page) ' + s.dropped_frames);
  const box = $('live-health');
  while (box.children.length > lines.length) box.lastElementChild.remove();
  while (box.children.length < lines.length) box.append(document.createElement('div'));
  lines.forEach((line, i) => setText(box.children[i], line));
  for (const k of ['received', 'undecodable', 'unauthenticated', 'replayed']) $('live-health').dataset[k] = String(h[k]);
}

function rows(tbody, entries) {
  keyedRows(tbody, entries, ([k]) => k, ([k]) => {
    const tr = document.createElement('tr');
    const th = document.createElement('th'); th.textContent = k;
    const td = document.createElement('td'); td.dataset.key = k;
    tr.append(th, td);
    return tr;
  }, (tr, [, v]) => {
    const td = tr.children[1];
    setText(td, v === null ? '-' : String(v));
    td.dataset.value = v === null ? 'null' : String(v);
  });
}

// The selected (else newest) episode's pacing progress and, when it has
// ended, its SUMMARY's realtime object.
function renderPacing(s) {
  const e = s.episodes.find((x) => x.episode_id === s.selected_episode_id) || s.episodes[s.episodes.length - 1];
  const box = $('live-pacing');
  box.dataset.episodeId = e ? String(e.episode_id) : '';
  const p = e && e.pacing;
  rows(box.querySelector('table.pacing tbody'), p ? Object.entries(p).filter(([k]) => k !== 'histogram') : []);
  const hist = box.querySelector('.histogram');
  const counts = (p && p.histogram) || [];
  while (hist.children.length > counts.length) hist.lastElementChild.remove();
  while (hist.children.length < counts.length) hist.append(document.createElement('div'));
  const top = Math.max(1, ...counts);
  counts.forEach((c, i) => {
    const bar = hist.children[i];
    const height = (100 * c) / top + '%';
    if (bar.style.height !== height) bar.style.height = height;
    bar.title = 'bin ' + i + ': ' + c;
  });
  rows(box.querySelector('table.realtime tbody'), e && e.realtime ? Object.entries(e.realtime) : []);
  box.querySelector('.note').textContent = !e ? 'no episode yet'
    : p || e.realtime ? (e.realtime ? 'the episode\'s deadline statistics (its SUMMARY):' : 'running, paced')
      : 'episode ' + idText(e) + ' is not paced (pidlab launch --realtime paces the plant)';
}

function onStatus(s) {
  live.status = s;
  live.dropped_frames = s.dropped_frames;
  $('live-source').textContent = s.lcm_url + ' prefix ' + s.channel_prefix;
  renderEpisodes(s);
  renderRelay(s);
  renderTunings(s);
  renderHealth(s);
  renderPacing(s);
  for (const e of s.episodes) {
    const id = idText(e);
    if (e.status === 'complete' && !asked.has(id)) {
      asked.add(id);
      // The reply is one kind-2 binary frame (onFrame), or an error line.
      if (!rawSend({ type: 'live_data', episode_id: id })) asked.delete(id);
    }
  }
}

function onFrame(buffer) {
  const f = parseFrame(buffer);
  if (!f) { console.warn('live: a binary frame that is not PLV1'); return; }
  if (f.kind === 2) {
    // Keyed by the header's id (a double) and, when the status names it, by its exact text.
    const data = { y: f.y, u: f.u, n: f.n };
    live.final[f.episode_id] = data;
    const e = ((live.status && live.status.episodes) || []).find((x) => x.episode_id === f.episode_id);
    if (e && e.episode_id_text) live.final[e.episode_id_text] = data;
    return;
  }
  live.frames += 1;
  latest = f;  // the server sends the selected episode's frames only
  scheduleDraw();
}

function onMessage(m) {
  if (m.type === 'live_status') { onStatus(m); return true; }
  if (m.type === 'live_subscribed' || m.type === 'live_unsubscribed') return true;
  return false;
}

function show(active) {
  if (active && !live.subscribed) {
    const columns = Math.max(16, Math.min(4096, Math.round($('live-plots').clientWidth || 1000)));
    live.subscribed = rawSend({ type: 'live_subscribe', columns });
  } else if (!active && live.subscribed) {
    live.subscribed = !rawSend({ type: 'live_unsubscribe' });
  }
}

// Starts the Live tab: `send` sends one request without awaiting a reply.
export function initLive({ rawSend: send }) {
  live = { status: null, frames: 0, final: {}, drawn: 0, dropped_frames: 0, subscribed: false };
  window.pidlab.live = live;
  rawSend = send;
  return { onMessage, onFrame, show };
}

// "Run on the trio" (Design view): the design's spec runs on the running
// trio (always the sampled loop); its y is drawn over the exact prediction
// and their agreement shown in #trio-agreement.
export function initTrio({ ask, spec, setStatus, redraw }) {
  const trio = { last: null, running: false };
  window.pidlab.trio = trio;
  let chart = null;

  function show(m) {
    trio.last = m;
    trio.running = false;
    $('run-on-trio').disabled = false;
    $('trio-box').classList.remove('hidden');
    if (m.type === 'trio_error') {
      $('trio-agreement').textContent = 'the trio failed: ' + m.error;
      $('trio-agreement').dataset.bitIdentical = 'false';
      return;
    }
    if (!chart) {
      const el = $('plot-trio');
      chart = new uPlot({
        title: 'Step response on the trio (sampled loop) over the prediction', width: Math.max(300, el.clientWidth || 560), height: 220,
        series: [{ label: 't s' }, { label: 'prediction y', stroke: '#1f77b4', width: 3 }, { label: 'trio y', stroke: '#ff7f0e', width: 1.5, dash: [5, 3] }],
        scales: { x: { time: false } }, axes: [{ label: 't (s)' }, { label: 'y' }],
      }, [[], [], []], el);
    }
    window.pidlab.trioOverlay = m.series;  // on the step plot too
    redraw();
    const p = m.prediction_series, s = m.series;
    const n = Math.min(p.t.length, s.t.length);
    chart.setData([p.t.slice(0, n), p.y.slice(0, n), s.y.slice(0, n)]);
    const a = $('trio-agreement');
    a.dataset.bitIdentical = String(m.bit_identical);
    a.dataset.maxAbsDifference = String(m.max_abs_difference);
    a.textContent = (m.bit_identical ? 'bit for bit' : 'NOT bit for bit') + ' (max |difference| ' + m.max_abs_difference +
      ', IAE trio ' + m.result.iae + ', prediction ' + m.prediction.iae + ', loop ' + (m.loop || 'sampled') + ')';
  }

  async function run() {
    trio.running = true;
    $('run-on-trio').disabled = true;
    $('trio-agreement').textContent = 'running on the trio...';
    try {
      await ask({ type: 'run_on_trio', spec: spec() });
    } catch (e) {
      show({ type: 'trio_error', error: e.message });
    }
  }

  function onMessage(m) {
    if (m.type === 'trio_result' || m.type === 'trio_error') { show(m); return true; }
    return m.type === 'run_on_trio_started';
  }

  function enable(live) {
    $('run-on-trio').disabled = !live;
    $('run-on-trio').title = live ? 'run this design (sampled loop) on the trio the server watches'
      : 'pidlab serve was started without --lcm-url';
  }

  $('run-on-trio').addEventListener('click', () => run().catch((e) => setStatus('trio: ' + e.message)));
  trio.run = run;
  return { onMessage, enable };
}
