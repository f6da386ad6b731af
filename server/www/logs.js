// The Logs tab: an LCM log opened on the server (a path under --log-dir, or
// uploaded to POST /api/upload), its episodes as `pidlab replay --json` lists
// them, and one episode's y, u, n with a cursor that scrubs every plot. Every
// number is the server's (the code of `pidlab replay`); the page only draws.
import { clippedAxis } from './plots.js';

const $ = (id) => document.getElementById(id);

function fmt(v) {
  if (v === null || v === undefined) return '-';
  if (typeof v !== 'number') return String(v);
  return Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-3 && v !== 0) ? v.toExponential(4) : String(Number(v.toPrecision(6)));
}

// Draws the gaps (red) and repairs (orange) as shaded stretches of time.
function marksPlugin(getMarks) {
  return {
    hooks: {
      drawClear: [(u) => {
        const m = getMarks();
        if (!m) return;
        const ctx = u.ctx;
        const { top, height } = u.bbox;
        for (const [ranges, colour] of [[m.gaps, 'rgba(214,39,40,0.18)'], [m.repairs, 'rgba(255,127,14,0.25)']]) {
          ctx.fillStyle = colour;
          for (const [a, b] of ranges) {
            const x0 = u.valToPos(a * m.dt, 'x', true), x1 = u.valToPos((b + 1) * m.dt, 'x', true);
            ctx.fillRect(x0, top, Math.max(1, x1 - x0), height);
          }
        }
      }],
    },
  };
}

let logs = null;  // window.pidlab.logs
let ask = null, token = null;
let charts = [];
const syncKey = 'pidlab-log';
const marks = () => (logs.episode ? { gaps: logs.episode.gaps, repairs: logs.episode.repairs, dt: logs.episode.replay.dt_s || 0 } : null);

function status(text) { $('log-status').textContent = text; }

function chart(el, title, label, colour, extra) {
  const series = [{ label: 't s' }, { label, stroke: colour, width: 1.5 }, ...(extra || [])];
  const axis = label === 'y' ? null : clippedAxis();  // u and n: the kick clipped and marked, a flat n readable
  return new uPlot({
    title, width: Math.max(400, el.clientWidth || 900), height: 200, series,
    scales: { x: { time: false }, ...(axis ? { y: { range: axis.range } } : {}) }, axes: [{ label: 't (s)' }, { label }],
    cursor: { sync: { key: syncKey }, drag: { x: true, y: false } },
    plugins: [marksPlugin(marks)], ...(axis ? { hooks: { draw: [axis.draw] } } : {}),
  }, series.map(() => []), el);
}

function showLog(reply) {
  logs.log = reply;
  logs.episode = null;
  $('log-view').classList.add('hidden');
  $('log-summary').textContent = reply.name + ': ' + reply.events + ' events, ' + reply.pidlab_messages +
    ' pidlab messages, ' + (reply.clean_end ? 'read to the end' : 'NOT read cleanly to the end') +
    (reply.notes && reply.notes.length ? '; ' + reply.notes.join('; ') : '');
  const body = $('log-episodes').querySelector('tbody');
  body.textContent = '';
  reply.episodes.forEach((e, i) => {
    const tr = document.createElement('tr');
    tr.dataset.index = String(i);
    tr.dataset.episodeId = String(e.episode_id);
    const g = e.gains ? [e.gains.kp, e.gains.ki, e.gains.kd].map(fmt).join(',') : '?';
    const iae = e.evaluation ? e.evaluation.iae : null;
    for (const text of [i, e.episode_id, e.prefix || '-', e.plant || '?', g, e.total_steps, fmt(iae), e.completeness]) {
      const td = document.createElement('td'); td.textContent = String(text); tr.append(td);
    }
    tr.addEventListener('click', () => openEpisode(i).catch((err) => status(err.message)));
    body.append(tr);
  });
}

function scrub(k) {
  const e = logs.episode;
  if (!e) return;
  const s = e.series;
  k = Math.max(0, Math.min(s.t.length - 1, k | 0));
  logs.cursor = k;
  $('log-scrub').value = String(k);
  const at = (a) => fmt(a[k]);
  $('log-cursor').textContent = 'k = ' + k * (s.stride || 1) + ', t = ' + at(s.t) + ' s: y ' + at(s.y) + ', u ' + at(s.u) + ', n ' + at(s.n) +
    ', e ' + fmt(s.y[k] === null || s.r === null ? null : s.r - s.y[k]);
  for (const c of charts) {
    const left = c.valToPos(s.t[k], 'x');
    if (Number.isFinite(left)) c.setCursor({ left, top: c.cursor.top > 0 ? c.cursor.top : 10 });
  }
}

function showEpisode(reply) {
  logs.episode = reply;
  for (const c of charts) c.destroy();
  $('log-view').classList.remove('hidden');
  const s = reply.series;
  charts = [
    chart($('log-plot-y'), 'y and r', 'y', '#1f77b4', [{ label: 'r', stroke: '#555', width: 1, dash: [4, 4] }]),
    chart($('log-plot-u'), 'u', 'u', '#d62728'),
    chart($('log-plot-n'), 'n', 'n', '#2ca02c'),
  ];
  charts[0].setData([s.t, s.y, s.t.map(() => s.r)]);
  charts[1].setData([s.t, s.u]);
  charts[2].setData([s.t, s.n]);
  const ev = reply.replay.evaluation;
  const iae = ev ? ev.iae : null;
  $('log-iae').textContent = ev ? String(iae) : 'not evaluated: ' + reply.replay.evaluation_error;
  $('log-iae').dataset.value = String(iae);
  const r = reply.replay.redrive;
  $('log-redrive-result').textContent = r ? 're-drive: ' + (r.ok ? 'OK, ' : 'FAILED, ') + r.message : '';
  const count = (ranges) => ranges.reduce((n, [a, b]) => n + b - a + 1, 0);
  $('log-marks').textContent = 'gaps (red): ' + count(reply.gaps) + ' steps in ' + reply.gaps.length +
    ' stretches; commands repaired from trajectory chunks (orange): ' + count(reply.repairs) + ' steps';
  $('log-marks').dataset.gaps = JSON.stringify(reply.gaps);
  $('log-marks').dataset.repairs = JSON.stringify(reply.repairs);
  $('log-scrub').max = String(Math.max(0, s.t.length - 1));
  for (const tr of $('log-episodes').querySelectorAll('tr[data-index]'))
    tr.classList.toggle('selected', Number(tr.dataset.index) === reply.index);
  scrub(0);
}

async function openEpisode(index) {
  if (!logs.log) throw new Error('no log is open');
  const reply = await ask({ type: 'log_episode', log_id: logs.log.log_id, index, redrive: $('log-redrive').checked });
  showEpisode(reply);
  return reply;
}

async function openPath(path) {
  status('');
  const reply = await ask({ type: 'log_open', path });
  showLog(reply);
  return reply;
}

async function upload(file) {
  status('');
  const url = '/api/upload?name=' + encodeURIComponent(file.name) + (token ? '&token=' + encodeURIComponent(token) : '');
  const res = await fetch(url, { method: 'POST', body: file, headers: { 'Content-Type': 'application/octet-stream' } });
  const body = await res.json();
  if (!res.ok) throw new Error(body.error || 'upload: HTTP ' + res.status);
  const reply = await ask({ type: 'log_open', log_id: body.log_id });
  showLog(reply);
  return reply;
}

// Starts the Logs tab: `askServer` sends a request and resolves with its reply.
export function initLogs({ ask: askServer, token: urlToken }) {
  logs = { log: null, episode: null, cursor: 0 };
  window.pidlab.logs = logs;
  ask = askServer;
  token = urlToken;
  uPlot.sync(syncKey);
  $('log-open').addEventListener('click', () => openPath($('log-path').value).catch((e) => status(e.message)));
  $('log-upload').addEventListener('click', () => {
    const f = $('log-file').files[0];
    if (!f) { status('choose a log file first'); return; }
    upload(f).catch((e) => status(e.message));
  });
  $('log-scrub').addEventListener('input', () => scrub(Number($('log-scrub').value)));
  $('log-redrive').addEventListener('change', () => {
    if (logs.episode) openEpisode(logs.episode.index).catch((e) => status(e.message));
  });
  // The shown episode fitted on the Design tab (the identify request with
  // its log_id and index: pidlab identify --log's record), with the model chosen there.
  $('log-identify').addEventListener('click', () => {
    if (!logs.episode) return;
    window.pidlab.showView('design');
    const model = document.getElementById('data-model').value;
    window.pidlab.design.identify(model, { log_id: logs.episode.log_id, index: logs.episode.index })
      .catch((e) => { document.getElementById('data-status').textContent = e.message; });
  });
  Object.assign(logs, { openPath, openEpisode, upload, scrub });
}
