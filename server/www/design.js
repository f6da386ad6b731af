// The tuning app's path on the Design tab (docs/workbench.md, "From data to
// C"): a step-test CSV uploaded and fitted (the identify request: `pidlab
// identify`'s code and JSON), the model accepted as the plant, the design's
// two knobs (the design engine's front and its Ms bound: `pidlab tune
// --robustness`) and the firmware at a chosen dt (the
// sampled loop beside the continuous one, the export request's check, the
// .c and .h to download). Every number is the server's; the page only draws.

const $ = (id) => document.getElementById(id);
let app = null;  // {state, ask, spec, setDesign, setStatus, fmt, resetPlant, evaluate}
let design = null;  // window.pidlab.design

// ---- Data -> model.
async function uploadCsv(file) {
  const url = '/api/upload?name=' + encodeURIComponent(file.name) + (app.token ? '&token=' + encodeURIComponent(app.token) : '');
  const res = await fetch(url, { method: 'POST', body: file, headers: { 'Content-Type': 'application/octet-stream' } });
  const body = await res.json().catch(() => ({}));
  if (!res.ok) throw new Error(body.error || 'upload: HTTP ' + res.status);
  design.upload = { upload_id: body.log_id, name: body.name, bytes: body.bytes };
  $('data-name').textContent = body.name + ' (' + body.bytes + ' bytes)';
  $('data-identify').disabled = false;
  return design.upload;
}

function dataStatus(text) { $('data-status').textContent = text; }

function identifyProgress(m) {
  dataStatus('fitting ' + m.model + ': ' + m.done + ' of ' + m.total + ' starts, best cost ' + app.fmt(m.best_cost));
}

// Fits the uploaded CSV (or {log_id, index} of the Logs tab) with `model`.
async function identify(model, source) {
  const from = source || (design.upload ? { upload_id: design.upload.upload_id } : null);
  if (!from) throw new Error('upload a CSV first');
  dataStatus('fitting ' + model + ' ...');
  $('data-accept').disabled = true;
  const u0Text = $('data-u0').value.trim();
  const u0 = u0Text === '' ? {} : { u0: u0Text === 'estimate' ? u0Text : Number(u0Text) };
  const reply = await app.ask({ type: 'identify', model, ...from, ...u0 });
  design.fit = reply;
  showFit(reply);
  $('data-accept').disabled = false;
  return reply;
}

function showFit(reply) {
  const r = reply.result;
  const chosen = r.auto ? ' (auto: ' + r.auto.reason + ')' : '';
  dataStatus('model ' + r.model + chosen + '; fit ' + app.fmt(r.fit_percent) + ' %, residuals ' +
    (r.whiteness.white ? 'white' : 'NOT white') + ' (Ljung-Box p = ' + app.fmt(r.whiteness.p_value) + ')');
  const table = $('data-params');
  table.textContent = '';
  const head = document.createElement('tr');
  for (const h of ['parameter', 'value', '95 % interval']) { const th = document.createElement('th'); th.textContent = h; head.append(th); }
  table.append(head);
  for (const [name, p] of Object.entries(r.parameters)) {
    const tr = document.createElement('tr');
    tr.dataset.parameter = name;
    const se = p.standard_error;
    const interval = p.at_bound ? 'at its ' + p.at_bound + ' bound' : se === null ? '-' : '\u00b1 ' + app.fmt(1.96 * se);
    for (const [i, text] of [name, app.fmt(p.value), interval].entries()) {
      const td = document.createElement(i ? 'td' : 'th'); td.textContent = text; tr.append(td);
    }
    tr.children[1].dataset.value = String(p.value);
    table.append(tr);
  }
  $('data-warnings').textContent = (r.warnings || []).map((w) => 'warning: ' + w).join(' ');
  const box = $('data-box');
  box.classList.remove('hidden');
  box.open = true;
  drawFit(reply.fit, r.whiteness);
  offerModel(reply);
  box.scrollIntoView({block: 'start'});
}

// The fit, its residuals and their autocorrelation, at the fit box's width
// (the fit across it, the other two side by side), with axis labels.
function drawFit(fit, whiteness) {
  for (const c of design.fitCharts) c.destroy();
  design.fitCharts = [];
  const full = Math.max(480, $('data-plots').clientWidth || 640);
  const half = Math.floor(full / 2) - 4;
  const t = fit.t;
  const chart = (title, width, height, series, axes, data) => design.fitCharts.push(new uPlot(
      {title, width, height, scales: {x: {time: false}}, series, legend: {show: false}, axes}, data,
      $('data-plots')));
  chart(
      'measured (grey) and model (blue) y', full, 220,
      [
        {label: 't s'}, {label: 'measured', stroke: '#555', width: 1},
        {label: 'model', stroke: '#1f77b4', width: 2}
      ],
      [{label: 't (s)'}, {label: 'y'}], [t, fit.y, fit.simulated]);
  chart(
      'residuals y - model', half, 170, [{label: 't s'}, {label: 'y - model', stroke: '#d62728', width: 1}],
      [{label: 't (s)'}, {label: 'y - model'}], [t, fit.residuals]);
  const lags = whiteness.autocorrelation.map((_, i) => i + 1);
  const band = whiteness.band;
  chart(
      'residual autocorrelation (\u00b1' + app.fmt(band) + ' band)', half, 170,
      [
        {label: 'lag'}, {label: 'r', stroke: '#1f77b4', width: 0, points: {show: true, size: 4}},
        {label: 'band', stroke: '#888', dash: [4, 4], width: 1},
        {label: '-band', stroke: '#888', dash: [4, 4], width: 1}
      ],
      [{label: 'lag (samples)'}, {label: 'r'}],
      [lags, whiteness.autocorrelation, lags.map(() => band), lags.map(() => -band)]);
}

// The model file the server wrote, as a download named after the record.
function offerModel(reply) {
  const a = $('data-download');
  if (a.href) URL.revokeObjectURL(a.href);
  const name = (design.upload ? design.upload.name.replace(/\.[^.]*$/, '') : 'record') + '.model.json';
  a.href = URL.createObjectURL(new Blob([reply.model_file], {type: 'application/json'}));
  a.download = name;
  a.textContent = 'download the model (' + name + ')';
  a.classList.remove('hidden');
  design.modelFile = {name, path: reply.plant.slice('model:'.length)};
}

// The spec as a user runs it: the fitted model named by its download, not
// by the server's file (gone when the server stops).
function portable(s) {
  const m = design && design.modelFile;
  if (!m || s.plant !== 'model:' + m.path) return s;
  return {...s, plant: 'model:' + m.name};
}

// The fitted model becomes the plant ("model:PATH", the file the server
// wrote), and the default design is made for it.
function acceptModel() {
  if (!design.fit) return null;
  app.resetPlant({ plant: 'model', model: design.fit.plant.slice('model:'.length), delay: '' });
  $('data-box').open = false;  // the fit stays one click away
  return knobDesign();
}

// ---- The two knobs, on the design engine (`pidlab tune`, docs/tuning.md):
// the robustness knob is the Ms bound R (until moved, the plant's default,
// which the first design reports); the response knob moves along the
// engine's optimal front, the design at each Ms bound from kFrontMinMs
// (slowest) to R (fastest), so slower always means a lower Ms and a larger
// load IAE. A position is one design: `pidlab tune --robustness MS`.
const kFrontMinMs = 1.1;
// The response knob's positions: 0, 1/kKnobSteps, ..., 1 (index.html's step).
const kKnobSteps = 50;
function knobValues(at) {
  const k = design.knob;
  const speed = at === undefined ? Number($('knob-speed').value) : at;  // 0 slowest .. 1 fastest
  const bound = k.robustnessMoved ? Number($('knob-robustness').value) : k.defaultMs;
  const values = {};
  if (speed < 1 && bound > kFrontMinMs) values.robustness = Number((kFrontMinMs + speed * (bound - kFrontMinMs)).toFixed(3));
  else if (k.robustnessMoved) values.robustness = Number(bound.toFixed(2));
  return values;
}

function showKnob() {
  const k = design.knob;
  const v = knobValues();
  const last = k.last && k.last.spec.robustness === v.robustness ? k.last.result : null;
  const t = last && last.response_time_s > 0 ? ', T = ' + app.fmt(last.response_time_s) + ' s' : '';
  $('knob-speed-value').textContent = (v.robustness && Number($('knob-speed').value) < 1 ? 'Ms \u2264 ' + v.robustness : 'fastest') + t;
  $('knob-robustness-value').textContent = k.robustnessMoved ? 'Ms \u2264 ' + Number($('knob-robustness').value).toFixed(2)
    : 'default (SIMC\u2019s Ms' + (k.defaultMs > 0 ? ', ' + k.defaultMs.toFixed(3) : '') + ')';
}

// The tuning spec of the current plant with the knobs' values (the
// response-time knob at `at` when given).
function knobSpec(at) {
  const s = app.spec();
  for (const k
           of ['gains', 'monte_carlo', 'spread', 'derivative_filter', 'setpoint_weights', 'setpoint_filter',
               'max_ms', 'max_mt', 'max_noise_gain', 'min_phase_margin', 'loop', 'dt', 'response_time'])
    delete s[k];
  s.method = 'optimal';
  Object.assign(s, knobValues(at));
  return s;
}

// Runs the knob's design; while one runs, the latest knob position waits
// (latest wins).
// A position designed ahead (designAhead) is drawn from what it kept.
async function knobDesign() {
  const k = design.knob;
  if (k.running) { k.pending = true; return k.running; }
  const s = knobSpec();
  const key = JSON.stringify(s);
  const known = k.designs.get(key);
  $('knob-status').textContent = known ? '' : 'designing ...';
  k.error = null;
  const designed = known ? (known.error ? Promise.reject(new Error(known.error)) : app.tune(s, { quiet: true }, known.result))
    : app.tune(s, { quiet: true });
  k.running = designed.then((result) => {
    k.designs.set(key, { result });
    k.last = { spec: s, result };
    const d = result.design || {};
    if (!s.robustness && d.ms_bound > 0) {
      k.defaultMs = d.ms_bound;
      if (!k.robustnessMoved) $('knob-robustness').value = d.ms_bound;
    }
    const dt = suggestDt(result);  // the firmware's dt offered for this design
    if (dt) $('fw-dt').value = dt;
    showKnob();
    $('knob-status').textContent = 'pidlab tune ' + Object.entries(knobValues()).map(([a, b]) => '--' + a.replace('_', '-') + ' ' + b).join(' ');
    return result;
  }).catch((e) => {
    if (!known && /optimal/.test(e.message)) k.designs.set(key, { error: e.message });  // the engine's refusal of this position
    k.error = { spec: s, message: e.message };
    $('knob-status').textContent = 'design: ' + e.message;
    throw e;
  }).finally(() => {
    k.running = null;
    if (k.pending) { k.pending = false; knobDesign().catch(() => {}); } else designAhead();
  });
  return k.running;
}

// ---- The knob's positions designed ahead, on the background connection:
// after a design, every position of the response-time knob at the current
// robustness, nearest first, each tuned and its design evaluated, while no
// request of the user's waits. A move to a position designed ahead is drawn
// without a request (the same server answers, kept). A plant switch or a
// robustness move starts over (the generation).
async function designAhead() {
  const k = design.knob;
  if (!(k.defaultMs > 0) || k.ahead === k.generation) return;
  const generation = k.ahead = k.generation;
  const robustness = $('knob-robustness').value;
  const current = Number($('knob-speed').value);
  const positions = [];
  for (let i = 0; i <= kKnobSteps; ++i) positions.push(i / kKnobSteps);
  positions.sort((a, b) => Math.abs(a - current) - Math.abs(b - current));
  const stale = () => k.generation !== generation || $('knob-robustness').value !== robustness;
  let done = 0;
  const progress = () => { $('knob-ahead').textContent = '(designed ahead: ' + done + ' of ' + positions.length + ' positions)'; };
  progress();
  for (const at of positions) {
    await app.idle();
    if (stale()) break;
    const s = knobSpec(at);
    const key = JSON.stringify(s);
    let known = k.designs.get(key);
    try {
      if (!known) {
        try {
          known = { result: (await app.backgroundAsk({ type: 'tune', spec: s })).result };
        } catch (e) {
          if (!/optimal/.test(e.message)) throw e;
          known = { error: e.message };
        }
        if (stale()) break;
        k.designs.set(key, known);
      }
      if (known.result) await app.evaluateAhead(app.specAfterTune(known.result));
    } catch (e) {
      $('knob-ahead').textContent = 'designs ahead stopped: ' + e.message;
      if (k.ahead === generation) k.ahead = -1;
      return;
    }
    if (stale()) break;
    done += 1;
    progress();
  }
  if (stale()) {
    if (k.ahead === generation) k.ahead = -1;
    if (k.generation === generation && !k.running) designAhead();  // the robustness moved: its positions
    return;
  }
  k.ready = true;
}

function resetKnob() {
  const k = design.knob;
  k.generation += 1;
  k.designs.clear();
  k.ready = false;
  $('knob-ahead').textContent = '';
  Object.assign(k, { defaultMs: 0, robustnessMoved: false, last: null });
  $('knob-speed').value = 1;
  $('knob-robustness').value = 1.4;
  showKnob();
}

// ---- Firmware at a chosen dt.
function fwDt() {
  const dt = Number($('fw-dt').value);
  if (!(dt > 0) || !isFinite(dt)) throw new Error('dt ' + $('fw-dt').value + ' must be a positive number of seconds');
  return dt;
}

// The sampled loop at dt (drawn beside the continuous one) and the export
// request's check and files.
async function firmware() {
  const dt = fwDt();
  const s = app.spec();
  delete s.loop; delete s.dt;
  const key = JSON.stringify(s);  // the design it belongs to (app.js draws it while it is current)
  s.loop = 'sampled';
  s.dt = dt;
  delete s.monte_carlo; delete s.spread;
  const sampled = await app.ask({ type: 'evaluate', spec: s });
  design.sampled = { dt, spec: key, result: sampled.result, series: sampled.series };
  app.redraw();
  let reply;
  try {
    reply = await app.ask({ type: 'export', spec: s });
  } catch (e) {
    $('fw-verdict').textContent = 'not exported: ' + e.message;
    $('fw-verdict').dataset.stable = 'false';
    throw e;
  }
  design.export = { dt, spec: s, files: reply.files, loop_check: reply.loop_check };
  // Overshoot and settling compare across the two loops (each IAE is a sum on its own grid).
  const c = app.lastResult() || {};
  $('fw-verdict').textContent = 'sampled loop at dt = ' + dt + ' s: ' + reply.loop_check.verdict +
    '; overshoot ' + app.fmt(sampled.result.overshoot_pct) + ' % (continuous ' + app.fmt(c.overshoot_pct) + ' %), settling ' +
    app.fmt(sampled.result.settling_time_s) + ' s (continuous ' + app.fmt(c.settling_time_s) + ' s)';
  $('fw-verdict').dataset.stable = String(reply.loop_check.stable);
  for (const [id, name] of [['fw-download-c', 'pidlab_pid.c'], ['fw-download-h', 'pidlab_pid.h']]) {
    const a = $(id);
    if (a.href.startsWith('blob:')) URL.revokeObjectURL(a.href);
    a.href = URL.createObjectURL(new Blob([reply.files[name]], { type: 'text/x-c' }));
    a.download = name;
    a.classList.remove('hidden');
  }
  return design.export;
}

// The exported design on the emulated Cortex-M3 and M4F in every scalar
// (the pil_cost request, docs/pil.md): instructions per step, stack, size.
async function pilCost() {
  if (!design.export) await firmware();
  const s = design.export.spec;
  $('fw-pil-status').textContent = 'building and running the firmware for 4 scalars on 2 cores under QEMU ...';
  let reply;
  try {
    reply = await app.ask({ type: 'pil_cost', spec: s });
    if (reply.error) throw new Error(reply.error);
  } catch (e) {
    $('fw-pil-status').textContent = 'no PIL costs: ' + e.message;
    throw e;
  }
  design.pil = { spec: s, rows: reply.rows };
  const body = $('fw-pil-table').querySelector('tbody');
  body.textContent = '';
  for (const r of reply.rows) {
    const tr = document.createElement('tr');
    const cells = r.error ? [r.scalar, r.core, 'not built: ' + r.error, '', '', '']
      : [r.scalar, r.core === 'm3' ? 'M3' : 'M4F', Math.round(r.instructions_mean) + ' (' + r.instructions_max + ')',
        r.stack_bytes, r.text_bytes, r.data_bss_bytes];
    for (const c of cells) { const td = document.createElement('td'); td.textContent = String(c); tr.appendChild(td); }
    body.appendChild(tr);
  }
  $('fw-pil-table').classList.remove('hidden');
  $('fw-pil-status').textContent = 'emulated, not silicon timing: ' + reply.emulated + '; the first ' +
    (reply.rows.find((r) => r.steps) || {}).steps + ' steps of the loop at dt = ' + design.export.dt + ' s; fixed point over r, y in [' +
    reply.input_range.map(app.fmt).join(', ') + ']' + (reply.fixed_point_output_limits
    ? ' and, the design having no output limits, u in [' + reply.fixed_point_output_limits.map(app.fmt).join(', ') + ']' : '');
  return design.pil;
}

// A dt a tenth of the design's fastest time (1/crossover), rounded down to
// 1, 2 or 5 times a power of ten: the default the box offers.
export function suggestDt(result) {
  const wc = result && result.robustness && result.robustness.gain_crossover_rad_s;
  if (!(wc > 0)) return null;
  const x = 0.1 / wc;
  const p = Math.pow(10, Math.floor(Math.log10(x)));
  return [5, 2, 1].map((m) => m * p).find((v) => v <= x);
}

export function initDesign(context) {
  app = context;
  design = window.pidlab.design = {
    upload: null,
    fit: null,
    fitCharts: [],
    sampled: null,
    export: null,
    pil: null,
    knob: {
      defaultMs: 0,
      robustnessMoved: false,
      running: null,
      pending: false,
      last: null,
      error: null,
      designs: new Map(),
      generation: 0,
      ahead: -1,
      ready: false
    },
    uploadCsv,
    identify,
    acceptModel,
    knobDesign,
    firmware,
    pilCost,
    resetKnob,
    onIdentifyProgress: identifyProgress,
    portable,
    modelFile: null,
  };
  $('data-file').addEventListener('change', () => {
    const f = $('data-file').files[0];
    if (f) uploadCsv(f).catch((e) => dataStatus(e.message));
  });
  const drop = $('data-drop');
  drop.addEventListener('dragover', (e) => { e.preventDefault(); drop.classList.add('over'); });
  drop.addEventListener('dragleave', () => drop.classList.remove('over'));
  drop.addEventListener('drop', (e) => {
    e.preventDefault();
    drop.classList.remove('over');
    const f = e.dataTransfer.files[0];
    if (f) uploadCsv(f).catch((err) => dataStatus(err.message));
  });
  $('data-identify').addEventListener('click', () => identify($('data-model').value).catch((e) => dataStatus(e.message)));
  $('data-cancel').addEventListener('click', () => app.rawSend({ type: 'identify_cancel' }));
  $('data-accept').addEventListener('click', () => { acceptModel(); });
  $('knob-speed').addEventListener('input', () => { showKnob(); knobDesign().catch(() => {}); });
  $('knob-robustness').addEventListener('input', () => {
    design.knob.robustnessMoved = true;
    design.knob.ready = false;
    showKnob();
    knobDesign().catch(() => {});
  });
  $('knob-design').addEventListener('click', () => knobDesign().catch(() => {}));
  $('fw-check').addEventListener('click', () => firmware().catch((e) => app.setStatus('firmware: ' + e.message)));
  $('fw-pil').addEventListener('click', () => pilCost().catch((e) => app.setStatus('PIL: ' + e.message)));
  showKnob();
  return design;
}
