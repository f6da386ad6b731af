// The workbench page: the design form -> a spec -> the server (WebSocket /ws)
// -> the JSON of `pidlab evaluate --json` and the plot series, drawn by
// uPlot (plots.js). The page computes no result itself (docs/workbench.md).
import {initDesign, suggestDt} from './design.js';
import {initFields, initSliders} from './form.js';
import {initLive, initTrio} from './live.js';
import {initLogs} from './logs.js';
import {fmt, showKeyMetrics, showMetrics} from './metrics.js';
import {initPins} from './pins.js';
import {createPlots, destroyPlots, drawPlots} from './plots.js';
import {initTuning} from './tuning.js';

const token = new URLSearchParams(location.search).get('token');
const plants = ['double_integrator', 'oscillator', 'stepper_motor', 'custom', 'stepper_nonlinear', 'model'];
// The design: what the form shows. Empty strings are fields left to the spec's defaults.
const state = {
  plant: 'double_integrator',
  num: '1',
  den: '1,0,0',
  model: '',
  delay: '',
  stepper: '',
  kp: 3.9,
  ki: 0.06,
  kd: 4.9,
  derivative_filter: '',
  setpoint_weight_b: '',
  setpoint_weight_c: '',
  setpoint_filter: '',
  limit_lo: '',
  limit_hi: '',
  loop: 'continuous',
  dt: '',
  max_ms: '',
  max_mt: '',
  max_noise_gain: '',
  min_phase_margin: '',
  monte_carlo: '',
  spread: '',
  fields: {},  // the generated fields (form.js): key -> text
};
const textFields = [
  'num', 'den', 'model', 'delay', 'stepper', 'derivative_filter', 'setpoint_weight_b', 'setpoint_weight_c',
  'setpoint_filter', 'limit_lo', 'limit_hi', 'dt', 'max_ms', 'max_mt', 'max_noise_gain', 'min_phase_margin',
  'monte_carlo', 'spread'
];
const pidlab = window.pidlab = {
  state, lastResult: null, lastSeries: null, plots: {}, rendered: 0, timings: [], pinned: [],
  lastTune: null, paperDesigns: [],
};
let socket = null;
let seq = 0;
let inflight = null;  // the evaluate request awaiting its reply: at most one
let pending = false;  // the design changed meanwhile: send the latest when it returns
const waiting = new Map();  // id -> {resolve, reject} of other requests

const $ = (id) => document.getElementById(id);
const list = (text) => String(text).split(/[\s,]+/).filter((x) => x !== '').map(Number);
const given = (v) => v !== '' && v !== null && v !== undefined;
const pins = initPins({pidlab, state, $, setDesign, rebuildPlots, ask, setStatus});
pidlab.pin = () => pins.pin();
const form = initFields({state, $, ask, onChange: send, setStatus});
pidlab.form = form;
const sliders = initSliders({state, $, send: () => send()});
const tuning =
    initTuning({pidlab, state, $, spec, ask, rawSend, showForm, evaluated, pin: (label) => pins.pin(label)});

// The spec of the current design (docs/spec.md): only the fields the form sets.
function spec() {
  const s = {};
  if (state.plant === 'custom') Object.assign(s, { plant: 'custom', num: list(state.num), den: list(state.den) });
  else if (state.plant === 'model') s.plant = 'model:' + state.model;
  else s.plant = state.plant;
  s.gains = [state.kp, state.ki, state.kd];
  if (given(state.delay)) s.delay = Number(state.delay);
  if (given(state.stepper) && state.plant.startsWith('stepper')) s.stepper = JSON.parse(state.stepper);
  if (state.loop === 'sampled') s.loop = 'sampled';
  if (state.loop === 'sampled' && given(state.dt)) s.dt = Number(state.dt);
  if (given(state.derivative_filter)) s.derivative_filter = Number(state.derivative_filter);
  if (given(state.setpoint_weight_b) || given(state.setpoint_weight_c))
    s.setpoint_weights = [given(state.setpoint_weight_b) ? Number(state.setpoint_weight_b) : 1, given(state.setpoint_weight_c) ? Number(state.setpoint_weight_c) : 1];
  if (given(state.setpoint_filter)) s.setpoint_filter = Number(state.setpoint_filter);
  if (given(state.limit_lo) || given(state.limit_hi))
    s.output_limits = [given(state.limit_lo) ? Number(state.limit_lo) : '-inf', given(state.limit_hi) ? Number(state.limit_hi) : 'inf'];
  for (const k of ['max_ms', 'max_mt', 'max_noise_gain', 'min_phase_margin']) if (given(state[k])) s[k] = Number(state[k]);
  if (given(state.monte_carlo) && Number(state.monte_carlo) > 0) {
    s.monte_carlo = Number(state.monte_carlo);
    if (given(state.spread)) s.spread = Number(state.spread);
  }
  return form.apply(s);
}

function shellWord(v) {
  const text = String(v);
  return /^[\w.,:/+=-]+$/.test(text) ? text : "'" + text.replace(/'/g, "'\\''") + "'";
}

// The `pidlab` command line of a spec (`verb` evaluate or tune).
function commandOf(s, verb, extra) {
  const words = ['pidlab', verb];
  for (const [key, value] of Object.entries(s)) {
    const flag = '--' + key.replace(/_/g, '-');
    if (key === 'stepper') {
      for (const [k, v] of Object.entries(value)) words.push(flag, shellWord(k + '=' + v));
    } else if (typeof value === 'boolean') {
      if (value) words.push(flag);
    } else {
      const text = Array.isArray(value) ? value.join(',') : String(value);
      words.push(text.startsWith('-') ? flag + '=' + shellWord(text) : flag + ' ' + shellWord(text));
    }
  }
  return words.concat(extra || ['--json']).join(' ');
}
pidlab.spec = spec;
// The command names the fitted model by its download (design.js), not the server's file.
pidlab.command = () => commandOf(views.design ? views.design.portable(spec()) : spec(), 'evaluate');

function setStatus(text) { $('status').textContent = text; }

function rawSend(message) {
  if (!socket || socket.readyState !== WebSocket.OPEN) return false;
  socket.send(JSON.stringify(message));
  return true;
}

// Asks the server; resolves with the reply (rejects with its error).
function ask(message) {
  const id = ++seq;
  return new Promise((resolve, reject) => {
    waiting.set(id, { resolve, reject });
    if (!rawSend({ ...message, id })) { waiting.delete(id); reject(new Error('not connected')); }
  });
}

// The evaluations answered, by their spec: the reply is a pure function of
// it, so a design drawn before (or evaluated ahead: the knob's positions,
// design.js) is drawn again without a request. The newest kept last.
const kKeptEvaluations = 200;
const evaluations = new Map();
function keepEvaluation(key, reply) {
  evaluations.delete(key);
  evaluations.set(key, reply);
  if (evaluations.size > kKeptEvaluations) evaluations.delete(evaluations.keys().next().value);
}

// Evaluates the current design: latest wins, no queue.
function send() {
  writeHash();
  pidlab.trioOverlay = null;  // a trio run belongs to the design it ran
  if (inflight) { pending = true; return; }
  let s;
  try { s = spec(); } catch (e) { setStatus('bad design: ' + e.message); return; }
  const key = JSON.stringify(s);
  const kept = evaluations.get(key);
  if (kept) {
    keepEvaluation(key, kept);
    const now = performance.now();
    show(kept, { seq: ++seq, sent_ms: now, kept: true }, now);
    return;
  }
  inflight = { seq: ++seq, sent_ms: performance.now(), key };
  if (!rawSend({ id: inflight.seq, type: 'evaluate', spec: s })) inflight = null;
}

// The spec of the current design with `fields` of the state changed (the
// state itself unchanged).
function specWith(fields) {
  const saved = {};
  for (const k of Object.keys(fields)) saved[k] = state[k];
  Object.assign(state, fields);
  try { return spec(); } finally { Object.assign(state, saved); }
}

// What a tuning's result sets in the design: gains, filter, setpoint weights.
function tunedFields(r) {
  const g = r.gains;
  const w = r.two_dof && r.two_dof.ran ? r.two_dof.setpoint_weights : null;
  return {
    kp: g.kp,
    ki: g.ki,
    kd: g.kd,
    derivative_filter: g.tf > 0 ? g.tf : '',
    setpoint_weight_b: w ? w[0] : '',
    setpoint_weight_c: w ? w[1] : '',
    setpoint_filter: w && r.two_dof.setpoint_filter_s > 0 ? r.two_dof.setpoint_filter_s : ''
  };
}

// A second connection for work done ahead of the user (design.js's knob
// positions): its own tune slot on the server, so that the user's requests
// never queue behind it. Its requests run one at a time.
let background = null;
function backgroundAsk(message) {
  if (!background) {
    const ws = new WebSocket(wsUrl());
    const b = { ws, waits: new Map(), seq: 0, chain: null };
    b.chain = new Promise((resolve, reject) => {
      ws.addEventListener('open', resolve);
      ws.addEventListener('error', () => reject(new Error('the background connection failed')));
    });
    ws.addEventListener('message', (e) => {
      if (typeof e.data !== 'string') return;
      const reply = JSON.parse(e.data);
      const w = b.waits.get(reply.id);
      if (!w || reply.type === 'tune_progress' || reply.type === 'identify_progress') return;
      b.waits.delete(reply.id);
      if (reply.error) w.reject(new Error(reply.error)); else w.resolve(reply);
    });
    ws.addEventListener('close', () => {
      for (const w of b.waits.values()) w.reject(new Error('the background connection closed'));
      b.waits.clear();
      if (background === b) background = null;
    });
    background = b;
  }
  const b = background;
  const asked = b.chain.then(() => new Promise((resolve, reject) => {
    const id = ++b.seq;
    b.waits.set(id, { resolve, reject });
    b.ws.send(JSON.stringify({ ...message, id }));
  }));
  b.chain = asked.catch(() => {});
  return asked;
}

// Evaluates `s` ahead on the background connection, unless it is kept.
async function evaluateAhead(s) {
  const key = JSON.stringify(s);
  if (evaluations.has(key)) return;
  const reply = await backgroundAsk({ type: 'evaluate', spec: s });
  keepEvaluation(key, reply);
}

// Resolves when no request of the user's is waiting for its reply.
function idle() {
  return new Promise((resolve) => {
    const poll = () => (!inflight && !pending && waiting.size === 0 ? resolve() : setTimeout(poll, 20));
    poll();
  });
}

function show(reply, sent, reply_ms) {
  pidlab.lastResult = reply.result;
  pidlab.lastSeries = reply.series;
  setStatus('');
  showMetrics(reply.result);
  showKeyMetrics(reply.result);
  if (!$('fw-dt').value) { const dt = suggestDt(reply.result); if (dt) $('fw-dt').value = dt; }
  $('notes').textContent = (reply.series.notes || []).join('; ') + ((reply.result.robustness || {}).violations || []).map((v) => '; breaks ' + v).join('');
  drawPlots(pidlab.plots, reply.series, pidlab.pinned, pidlab.trioOverlay, sampledOverlay());
  $('spec').textContent = JSON.stringify(reply.result.spec);
  $('command').textContent = pidlab.command();
  pins.diff();
  queueMicrotask(() => {  // after uPlot's own commit (a microtask queued by setData)
    pidlab.timings.push({ seq: sent.seq, sent_ms: sent.sent_ms, reply_ms, drawn_ms: performance.now(),
      server_ms: sent.kept ? 0 : reply.compute_ms, kept: !!sent.kept });
    pidlab.rendered += 1;
  });
}

function onMessage(reply, arrived_ms) {
  if (inflight && reply.id === inflight.seq) {
    const sent = inflight;
    inflight = null;
    if (reply.error) setStatus(reply.error); else keepEvaluation(sent.key, reply), show(reply, sent, arrived_ms);
    if (pending) { pending = false; send(); }
    return;
  }
  if (reply.type === 'tune_progress') {
    tuning.progress(reply);
    return;
  }
  if (reply.type === 'identify_progress') { views.design.onIdentifyProgress(reply); return; }
  if (views.live.onMessage(reply) || views.trio.onMessage(reply)) {
    if (reply.id === undefined || !waiting.has(reply.id)) return;
  }
  const w = waiting.get(reply.id);
  if (!w) return;
  waiting.delete(reply.id);
  if (reply.error) w.reject(new Error(reply.error)); else w.resolve(reply);
}

// ---- The form.
function showForm() {
  $('plant').value = state.plant;
  $('loop').value = state.loop;
  for (const k of textFields) $(k).value = state[k];
  sliders.sync();
  for (const el of document.querySelectorAll('.plant-custom')) el.classList.toggle('hidden', state.plant !== 'custom');
  for (const el of document.querySelectorAll('.plant-model')) el.classList.toggle('hidden', state.plant !== 'model');
  for (const el of document.querySelectorAll('.plant-stepper')) el.classList.toggle('hidden', !state.plant.startsWith('stepper'));
}

// The firmware's sampled loop, while it belongs to the design drawn.
function sampledOverlay() {
  const d = views.design && views.design.sampled;
  return d && d.spec === JSON.stringify(withoutLoop(spec())) ? d.series : null;
}
function withoutLoop(s) { const c = { ...s }; delete c.loop; delete c.dt; return c; }

// What belongs to a plant goes when the plant changes: the filter, the
// weights, the limits, the bounds, the pinned designs, the trio's and the
// firmware's runs, the knobs. `fields`: the new plant's state fields.
function resetPlant(fields) {
  for (const k
           of ['derivative_filter', 'setpoint_weight_b', 'setpoint_weight_c', 'setpoint_filter', 'limit_lo',
               'limit_hi', 'max_ms', 'max_mt', 'max_noise_gain', 'min_phase_margin', 'monte_carlo', 'spread',
               'dt'])
    state[k] = '';
  state.loop = 'continuous';
  state.fields = {};
  Object.assign(state, fields);
  pidlab.pinned = [];
  pidlab.trioOverlay = null;
  pidlab.lastTune = null;
  if (views.design) { views.design.sampled = null; views.design.export = null; views.design.pil = null; views.design.resetKnob(); }
  $('fw-dt').value = '';
  $('fw-verdict').textContent = '';
  $('fw-pil-status').textContent = '';
  $('fw-pil-table').classList.add('hidden');
  for (const id of ['fw-download-c', 'fw-download-h']) $(id).classList.add('hidden');
  pins.render();
  form.render();
  rebuildPlots();
  showForm();
}
pidlab.resetPlant = resetPlant;

// Sets the design from a spec-like object (a paper design, a tuning, a pin).
function setDesign(d) {
  if (d.plant !== undefined && d.plant !== state.plant) resetPlant({ plant: d.plant });
  if (d.gains) [state.kp, state.ki, state.kd] = d.gains;
  showForm();
  send();
}
pidlab.setDesign = setDesign;

// The design in the address (a link reopens it), written once the design
// has stopped moving for 300 ms: replaceState is an IPC to the browser
// process, and a slider moves many times a second.
let hashTimer = null;
function writeHash() {
  clearTimeout(hashTimer);
  hashTimer = setTimeout(() => {
    history.replaceState(null, '', location.pathname + location.search + '#' + encodeURIComponent(JSON.stringify(state)));
  }, 300);
}

function readHash() {
  if (location.hash.length < 2) return;
  try {
    const saved = JSON.parse(decodeURIComponent(location.hash.slice(1)));
    for (const k of Object.keys(state)) if (k in saved) state[k] = saved[k];
  } catch (e) { setStatus('the URL does not hold a design: ' + e.message); }
}

// ---- The plots, the pins and the paper's designs.
function rebuildPlots() {
  destroyPlots(pidlab.plots);
  const el = (k) => $('plot-' + k);
  pidlab.plots = createPlots({ step: el('step'), effort: el('effort'), load: el('load'), freq: el('freq'), nyquist: el('nyquist') }, pidlab.pinned);
  if (pidlab.lastSeries) drawPlots(pidlab.plots, pidlab.lastSeries, pidlab.pinned, pidlab.trioOverlay, sampledOverlay());
}

// A tuning spec run on the server, its gains, filter and setpoint weights
// made the design, and the design evaluated (the knobs' designs).
// `known`: the result of this spec's tuning when it was run before.
async function tuneSpec(s, options, known) {
  const r = known || (await ask({ type: 'tune', spec: s })).result;
  pidlab.lastTune = r;
  Object.assign(state, tunedFields(r));
  showForm();
  await evaluated();
  return r;
}
pidlab.tuneSpec = tuneSpec;

// Resolves once the current design's reply is drawn.
function evaluated() {
  send();
  const target = seq;
  return new Promise((resolve) => {
    const poll = () => (!inflight && !pending && pidlab.timings.length && pidlab.timings[pidlab.timings.length - 1].seq >= target ? resolve() : setTimeout(poll, 10));
    poll();
  });
}

// ---- The design as C (the export request: pidlab export's module, as text).
async function exportC() {
  const reply = await ask({ type: 'export', spec: spec() });
  pidlab.lastExport = reply.files;
  for (const [id, name] of [['export-h', 'pidlab_pid.h'], ['export-c', 'pidlab_pid.c']]) {
    $(id).textContent = '// ' + name + '\n' + reply.files[name];
    $(id).classList.remove('hidden');
  }
  return reply.files;
}
pidlab.exportC = exportC;

// ---- Start.
function wsUrl() {
  return (location.protocol === 'https:' ? 'wss://' : 'ws://') + location.host + '/ws' +
      (token ? '?token=' + encodeURIComponent(token) : '');
}

function connect() {
  socket = new WebSocket(wsUrl());
  socket.binaryType = 'arraybuffer';  // the live view's frames (live.js)
  socket.addEventListener('open', () => {
    send();
    pins.loadPaperDesigns();
    serverInfo();
    form.load().then(() => {
      if (Object.keys(state.fields).length) send();
    });
  });
  socket.addEventListener('message', (e) => {
    const arrived = performance.now();
    if (e.data instanceof ArrayBuffer) views.live.onFrame(e.data); else onMessage(JSON.parse(e.data), arrived);
  });
  socket.addEventListener('close', () => setStatus('disconnected from the server'));
}

for (const p of plants) {
  const o = document.createElement('option');
  o.value = p; o.textContent = p;
  $('plant').append(o);
}
$('plant').addEventListener('change', () => {
  resetPlant({ plant: $('plant').value });
  send();
});
$('loop').addEventListener('change', () => { state.loop = $('loop').value; send(); });
// A plant field is another plant: what belonged to the old one goes (resetPlant).
const plantFields = ['num', 'den', 'model', 'delay', 'stepper'];
for (const k of textFields) {
  $(k).addEventListener('change', () => {
    if (plantFields.includes(k)) resetPlant({ [k]: $(k).value }); else state[k] = $(k).value;
    send();
  });
}
$('pin-button').addEventListener('click', () => pins.pin());
$('copy-command').addEventListener('click', () => navigator.clipboard.writeText(pidlab.command()).catch((e) => setStatus('copy: ' + e.message)));
$('copy-spec').addEventListener('click', () => navigator.clipboard.writeText(JSON.stringify(spec())).catch((e) => setStatus('copy: ' + e.message)));
$('export-button').addEventListener('click', () => exportC().catch((e) => setStatus('export: ' + e.message)));
// ---- The Live and Logs tabs (live.js, logs.js) and "Run on the trio".
const views = {};
views.live = initLive({ rawSend });
views.trio = initTrio({ ask, spec, setStatus, redraw: rebuildPlots });
initLogs({ ask, token });
views.design = initDesign({ state, ask, rawSend, token, spec, setStatus, fmt, resetPlant, tune: tuneSpec,
  backgroundAsk, evaluateAhead, idle, specAfterTune: (r) => specWith(tunedFields(r)),
  redraw: rebuildPlots, lastResult: () => pidlab.lastResult });
// server_info: live when pidlab serve has --lcm-url (an older server does not know the request).
async function serverInfo() {
  try {
    pidlab.serverInfo = await ask({ type: 'server_info' });
  } catch (e) {
    pidlab.serverInfo = { live: false };
  }
  views.trio.enable(!!pidlab.serverInfo.live);
  if (pidlab.view === 'live') views.live.show(true);
}
function showView(name) {
  pidlab.view = name;
  for (const v of ['design', 'live', 'logs']) {
    $('view-' + v).classList.toggle('hidden', v !== name);
    $('tab-' + v).classList.toggle('active', v === name);
  }
  views.live.show(name === 'live');
}
pidlab.showView = showView;
for (const b of document.querySelectorAll('#tabs .tab')) b.addEventListener('click', () => showView(b.dataset.view));
pidlab.view = 'design';
readHash();
showForm();
rebuildPlots();
connect();
