// The workbench's charts, all drawn by uPlot (the global `uPlot` of
// uPlot.iife.min.js): step response, control effort, load response,
// |S| |T| |CS| with the Ms line, Nyquist with the 1/Ms circle. The data
// comes from the server's `series` (docs/workbench.md); the page only draws.

const colours = ['#1f77b4', '#d62728', '#2ca02c', '#9467bd', '#ff7f0e', '#8c564b', '#e377c2', '#17becf'];
const pinColour = (i) => colours[(i + 1) % colours.length];
// Nyquist points farther than this from the origin are left out of the
// drawing (a gap): L grows without bound near the loop's poles on the axis.
const kNyquistReach = 8;

// Tick labels of a log axis: 1e-4, 0.001, ..., 1000, 1e4 (uPlot's default
// rounds values below 0.001 to 0).
function logTicks(u, splits) {
  return splits.map((v) => (v == null ? "" : v >= 1e-3 && v < 1e4 ? String(+v.toPrecision(3)) : v.toExponential(0)));
}

function size(el) {
  return { width: Math.max(300, el.clientWidth || 560), height: 220 };
}

// The optional series of the step plot, in order, each drawn only when the
// reply has it (a legend lists only what is drawn).
const stepExtras = {
  linear: { label: 'eq. (3) linear model', stroke: '#555', width: 1, dash: [2, 3] },
  band: null,  // the Monte-Carlo max and min, filled between
  sampled: { label: 'sampled at dt (firmware)', stroke: '#8c564b', width: 1.5 },
  trio: { label: 'trio y', stroke: '#ff7f0e', width: 2, dash: [3, 3] },
};

function timeChart(el, title, yLabel, label, pinned, extras, clip) {
  const series = [{ label: 't s' }, { label, stroke: colours[0], width: 2 }];
  pinned.forEach((p, i) => series.push({ label: p.label, stroke: pinColour(i), width: 1, dash: [6, 3] }));
  const opts = { title, ...size(el), series, scales: { x: { time: false } }, axes: [{ label: 't (s)' }, { label: yLabel }] };
  for (const k of extras || []) {
    if (k === 'band') {
      const n = series.length;
      series.push({ label: 'Monte Carlo max', stroke: 'rgba(31,119,180,0.3)', width: 1 });
      series.push({ label: 'Monte Carlo min', stroke: 'rgba(31,119,180,0.3)', width: 1 });
      opts.bands = [{ series: [n, n + 1], fill: 'rgba(31,119,180,0.15)' }];
    } else {
      series.push({ ...stepExtras[k] });
    }
  }
  if (clip) {  // the effort: the axis fitted to u after the derivative kick, the kick marked
    const axis = clippedAxis();
    opts.scales.y = { range: axis.range };
    opts.hooks = { draw: [axis.draw] };
  }
  const chart = new uPlot(opts, series.map(() => []), el);
  chart.pidlabExtras = (extras || []).join(',');
  return chart;
}

// The derivative kick: u at the first samples, far outside the rest. The
// axis is fitted to the signal from the first sample where it is back within
// 3 times the rest's span; the clipped samples are named in the chart.
// `lo` and `hi` are the signal's least and largest value at each time (one
// curve: the same array twice; the live view's min/max columns: two).
function effortClip(t, lo, hi) {
  hi = hi || lo;
  const n = Math.min(lo.length, hi.length);
  const head = Math.ceil(n * 0.02);
  let a = Infinity, b = -Infinity;
  for (let i = head; i < n; i++) {
    if (lo[i] !== null && isFinite(lo[i])) a = Math.min(a, lo[i]);
    if (hi[i] !== null && isFinite(hi[i])) b = Math.max(b, hi[i]);
  }
  if (!(a <= b) || n < 10) return { range: null, kick: null };
  const span = Math.max(b - a, Math.abs(a), Math.abs(b), 1e-12);
  let start = 0, peak = 0;
  while (start < n && ((hi[start] !== null && hi[start] > b + 3 * span) || (lo[start] !== null && lo[start] < a - 3 * span))) {
    for (const v of [hi[start], lo[start]]) if (v !== null && Math.abs(v) > Math.abs(peak)) peak = v;
    start++;
  }
  if (start === 0) return { range: null, kick: null };
  // Padded by a tenth of the span, never less than 1e-6 of the values'
  // size: a flat tail must not make a range uPlot cannot split.
  const x = Math.min(a, 0), y = Math.max(b, 0);
  const pad = 0.1 * Math.max(y - x, 1e-6 * Math.max(Math.abs(x), Math.abs(y)), 1e-9);
  const range = [x - pad, y + pad];
  if (!range.every(isFinite)) return { range: null, kick: null };
  return { range, kick: { t: t[0], until: t[start], peak } };
}

// A y axis that clips a derivative kick (and marks it) and gives a flat
// signal a readable range: uPlot options' `range` and `draw` hook, the clip
// computed from the chart's own data at each redraw (every series but x).
export function clippedAxis() {
  const range = (u, lo, hi) => {
    const series = u.data.slice(1).filter((d) => d && d.length);
    const n = series.length ? Math.min(...series.map((d) => d.length)) : 0;
    const los = new Array(n), his = new Array(n);
    for (let i = 0; i < n; i++) {
      let a = null, b = null;
      for (const d of series) {
        const v = d[i];
        if (v === null || v === undefined || !isFinite(v)) continue;
        a = a === null ? v : Math.min(a, v);
        b = b === null ? v : Math.max(b, v);
      }
      los[i] = a; his[i] = b;
    }
    u.pidlabClip = effortClip(u.data[0] || [], los, his);
    return u.pidlabClip.range || autoRange(lo, hi);
  };
  return { range, draw: (u) => drawKick(u, u.pidlabClip) };
}

function drawKick(u, clip) {
  if (!clip || !clip.kick) return;
  const ctx = u.ctx;
  const x = u.valToPos(clip.kick.t, 'x', true);
  ctx.save();
  ctx.fillStyle = '#b00';
  ctx.textAlign = 'left';
  ctx.textBaseline = 'alphabetic';
  ctx.font = (12 * devicePixelRatio) + 'px system-ui, sans-serif';
  ctx.fillText('\u2191 derivative kick, u up to ' + Number(clip.kick.peak.toPrecision(4)) + ' (clipped)', x + 6 * devicePixelRatio, u.bbox.top + 14 * devicePixelRatio);
  ctx.restore();
}

// Bode: |L|, |S|, |T| and |CS| in dB (the Ms line dashed), the phase of L
// in degrees on the right axis: the server's l_phase_deg, its view clipped
// to the crossovers' range (phaseView).
function freqChart(el, pinned) {
  const series = [{ label: 'w rad/s' },
    { label: '|L| dB', stroke: '#000', width: 1.5 },
    { label: '|S| dB', stroke: colours[0], width: 2 },
    { label: '|T| dB', stroke: colours[2], width: 2 },
    { label: '|CS| dB', stroke: colours[4], width: 1 },
    { label: 'Ms dB', stroke: '#888', width: 1, dash: [4, 4] },
    { label: 'phase L deg', stroke: '#9467bd', width: 1.5, dash: [8, 3], scale: 'deg' }];
  pinned.forEach((p, i) => {
    series.push({ label: p.label + ' |S| dB', stroke: pinColour(i), width: 1, dash: [6, 3] });
    series.push({ label: p.label + ' |T| dB', stroke: pinColour(i), width: 1, dash: [2, 2] });
    series.push({ label: p.label + ' phase L deg', stroke: pinColour(i), width: 1, dash: [8, 3], scale: 'deg' });
  });
  const degRange = (u, lo, hi) => {
    u.pidlabPhase = phaseView(u.data[0] || [], u.data[6] || [], u.pidlabCrossovers || []);
    return u.pidlabPhase.range || autoRange(lo, hi);
  };
  return new uPlot({
    title: 'Bode: |L|, |S|, |T|, |CS| (dB) and the phase of L', ...size(el), series,
    scales: { x: { time: false, distr: 3 }, y: { auto: true }, deg: { auto: true, range: degRange } },
    axes: [{ label: 'w (rad/s)', values: logTicks }, { label: 'dB' },
      { label: 'phase (deg)', scale: 'deg', side: 1, grid: { show: false }, incrs: [15, 30, 45, 90, 180, 360, 720, 1440, 2880] }],
    hooks: { draw: [(u) => drawPhaseNotes(u, u.pidlabPhase)] },
  }, [[], [], [], [], [], [], [], ...pinned.flatMap(() => [[], [], []])], el);
}

const dB = (v) => (v === null || !(v > 0) ? null : 20 * Math.log10(v));

// The phase axis's view: the phase from a decade below the lowest of the
// `crossovers` (gain, and the gain margin's phase crossover) to twice the highest, -180 included, padded and widened to
// multiples of 45 degrees; where the curve leaves it, `exits` say where and
// how far it goes ({w, side: 'below' | 'above', extreme}). Without a
// crossover: no clip (range null).
export function phaseView(w, phase, crossovers) {
  const at = crossovers.filter((x) => typeof x === 'number' && x > 0 && isFinite(x));
  if (!at.length || !w.length) return { range: null, exits: [] };
  const from = Math.min(...at) / 10, to = Math.max(...at) * 2;
  let lo = -180, hi = -180;
  for (let i = 0; i < w.length; i++) {
    if (w[i] < from || w[i] > to || phase[i] === null || !isFinite(phase[i])) continue;
    lo = Math.min(lo, phase[i]);
    hi = Math.max(hi, phase[i]);
  }
  const pad = Math.max(0.05 * (hi - lo), 10);
  const range = [45 * Math.floor((lo - pad) / 45), 45 * Math.ceil((hi + pad) / 45)];
  // Each stretch outside the view: where it starts and its farthest value.
  const exits = [];
  let cur = null;
  for (let i = 0; i < w.length; i++) {
    const v = phase[i];
    const side = v === null || !isFinite(v) ? null : v < range[0] ? 'below' : v > range[1] ? 'above' : null;
    if (side && (!cur || cur.side !== side)) { cur = { w: w[i], side, extreme: v }; exits.push(cur); }
    else if (side) cur.extreme = side === 'below' ? Math.min(cur.extreme, v) : Math.max(cur.extreme, v);
    else cur = null;
  }
  return { range, exits };
}

// The -180 degree line and a note per stretch of the phase outside its view.
function drawPhaseNotes(u, view) {
  if (!view || !view.range) return;
  const ctx = u.ctx, px = devicePixelRatio;
  const y = u.valToPos(-180, 'deg', true);
  ctx.save();
  ctx.strokeStyle = 'rgba(148,103,189,0.5)';
  ctx.lineWidth = px;
  ctx.setLineDash([2 * px, 3 * px]);
  ctx.beginPath();
  ctx.moveTo(u.bbox.left, y);
  ctx.lineTo(u.bbox.left + u.bbox.width, y);
  ctx.stroke();
  ctx.fillStyle = '#6a3d9a';
  ctx.font = (11 * px) + 'px system-ui, sans-serif';
  ctx.textBaseline = 'alphabetic';
  ctx.textAlign = 'left';
  view.exits.slice(0, 2).forEach((e, i) => {
    const text = (e.side === 'below' ? '\u2193 phase below ' + view.range[0] : '\u2191 phase above ' + view.range[1]) +
      '\u00b0 from ' + Number(e.w.toPrecision(3)) + ' rad/s (to ' + Math.round(e.extreme) + '\u00b0, clipped)';
    // At the exit, kept inside the plotting area.
    const width = ctx.measureText(text).width;
    const x = Math.max(u.bbox.left + 4 * px, Math.min(u.valToPos(e.w, 'x', true) + 4 * px, u.bbox.left + u.bbox.width - width - 4 * px));
    const y = e.side === 'below' ? u.bbox.top + u.bbox.height - (6 + 14 * i) * px : u.bbox.top + (14 + 14 * i) * px;
    ctx.fillText(text, x, y);
  });
  ctx.restore();
}

const kNyquistX = [-3.5, 1.5];
const aspect = (u) => (u.bbox && u.bbox.width > 0 && u.bbox.height > 0 ? u.bbox.height / u.bbox.width : 1);
// uPlot's own padded range, and [0, 1] where there is no data (every value null).
function autoRange(lo, hi) {
  if (lo === null || hi === null || !isFinite(lo) || !isFinite(hi)) return [0, 1];
  if (lo === hi) { const d = Math.abs(lo) * 0.1 || 1; return [lo - d, hi + d]; }  // a flat signal (n = 0): not 0..100
  return uPlot.rangeNum(lo, hi, 0.1, true);
}
function square(el) {
  const w = Math.max(300, Math.min(el.clientWidth || 420, 420));
  return { width: w, height: w - 10 };
}

// Each design's Nyquist curve is drawn as up to kSegments series, one per
// stretch within kNyquistReach: uPlot's x-y mode would join the ends of a
// gap with a straight line.
const kSegments = 4;

function nyquistChart(el, pinned) {
  const segments = (label, stroke, width, dash) =>
    Array.from({ length: kSegments }, () => ({ label, stroke, width, dash }));
  const series = [null, ...segments('L(jw)', colours[0], 2),
    { label: '1/Ms circle', stroke: '#888', width: 1, dash: [4, 4] },
    { label: '-1', stroke: '#000', width: 1, points: { show: true, size: 6 } }];
  pinned.forEach((p, i) => series.push(...segments(p.label, pinColour(i), 1, [6, 3])));
  const empty = () => [[], []];
  return new uPlot({
    mode: 2, title: 'Nyquist of L (1/Ms circle around -1, equal axes)', ...square(el), series,
    legend: { show: false }, cursor: { show: false },
    // Equal aspect: the y span is the x span times the plotting area's
    // height over its width, so the circle is round.
    scales: { x: { time: false, auto: false, range: kNyquistX },
      y: { auto: false, range: (u) => { const h = (kNyquistX[1] - kNyquistX[0]) * aspect(u) / 2; return [-h, h]; } } },
    axes: [{ label: 'Re L' }, { label: 'Im L' }],
  }, [null, ...Array.from({ length: kSegments }, empty), empty(), [[-1], [0]],
    ...pinned.flatMap(() => Array.from({ length: kSegments }, empty))], el);
}

// The stretches of L(jw) within kNyquistReach of the origin, as kSegments
// [xs, ys] pairs (the shortest left out when there are more).
function nyquistSegments(s) {
  const out = [];
  let cur = null;
  if (s) {
    s.l_re.forEach((re, i) => {
      const im = s.l_im[i];
      if (re !== null && im !== null && Math.hypot(re, im) <= kNyquistReach) {
        if (!cur) { cur = [[], []]; out.push(cur); }
        cur[0].push(re); cur[1].push(im);
      } else {
        cur = null;
      }
    });
  }
  out.sort((a, b) => b[0].length - a[0].length);
  while (out.length < kSegments) out.push([[], []]);
  return out.slice(0, kSegments);
}

function circle(ms) {
  if (!(ms > 0) || !isFinite(ms)) return [[], []];
  const xs = [], ys = [];
  for (let i = 0; i <= 120; i++) {
    const a = (2 * Math.PI * i) / 120;
    xs.push(-1 + Math.cos(a) / ms);
    ys.push(Math.sin(a) / ms);
  }
  return [xs, ys];
}

// v (given at the increasing frequencies w) at the frequencies `at`, linear
// in log w; null outside w.
function resample(w, v, at) {
  const out = [];
  let j = 0;
  for (const x of at) {
    while (j + 1 < w.length && w[j + 1] < x) j++;
    if (x < w[0] || x > w[w.length - 1] || j + 1 >= w.length) { out.push(x === w[j] ? v[j] : null); continue; }
    const f = (Math.log(x) - Math.log(w[j])) / (Math.log(w[j + 1]) - Math.log(w[j]));
    out.push(v[j] === null || v[j + 1] === null ? null : v[j] + f * (v[j + 1] - v[j]));
  }
  return out;
}

const orEmpty = (v, n) => (Array.isArray(v) ? v : new Array(n).fill(null));

// The trio's y at the times `t` that are its own sample times (within 1e-9
// relative: the plots' frame has its own grid, docs/workbench.md); null elsewhere.
function atSampleTimes(trio, t) {
  return t.map((x) => {
    let lo = 0, hi = trio.t.length - 1;
    if (hi < 0) return null;
    while (lo < hi) {  // the first trio time >= x
      const mid = (lo + hi) >> 1;
      if (trio.t[mid] < x) lo = mid + 1; else hi = mid;
    }
    for (const k of [lo - 1, lo])
      if (k >= 0 && Math.abs(trio.t[k] - x) <= 1e-9 * Math.max(1, Math.abs(x))) return trio.y[k];
    return null;
  });
}

// The step plot's optional series present in a reply (and the overlays).
function stepExtrasOf(series, trio, sampled) {
  const mc = series.monte_carlo || {};
  const out = [];
  if (Array.isArray(series.linear_y)) out.push('linear');
  if (Array.isArray(mc.y_max)) out.push('band');
  if (sampled) out.push('sampled');
  if (trio) out.push('trio');
  return out;
}

// Builds the five charts in `elements` ({step, effort, load, freq, nyquist})
// with a dashed series per pinned design.
export function createPlots(elements, pinned) {
  return {
    elements, pinnedCount: pinned.length,
    step: timeChart(elements.step, 'Setpoint step response y', 'y', 'y', pinned, []),
    effort: timeChart(elements.effort, 'Control effort u (step response)', 'u', 'u', pinned, [], {}),
    load: timeChart(elements.load, 'Load response y (unit step at the plant input)', 'y', 'y', pinned),
    freq: freqChart(elements.freq, pinned),
    nyquist: nyquistChart(elements.nyquist, pinned),
  };
}

export function destroyPlots(plots) {
  for (const k of ['step', 'effort', 'load', 'freq', 'nyquist']) if (plots && plots[k]) plots[k].destroy();
}

// y of a series on its own grid `ts`, held from each sample to the next, at the times `t`.
function heldAt(ts, ys, t) {
  let j = 0;
  return t.map((x) => {
    if (x < ts[0] || x > ts[ts.length - 1]) return null;
    while (j + 1 < ts.length && ts[j + 1] <= x) j++;
    return ys[j];
  });
}

// Sets every chart's data: the current design's `series` and the pinned ones'.
// `trio` ({t, y}, optional): the trio's run, drawn on the step plot where
// its sample times are the series' own. `sampled` (optional): the series of
// the sampled loop at the firmware's dt, held between its samples.
export function drawPlots(plots, series, pinned, trio, sampled) {
  const n = series.t.length;
  const extras = stepExtrasOf(series, trio, sampled);
  if (plots.step.pidlabExtras !== extras.join(',')) {
    plots.step.destroy();
    plots.step = timeChart(plots.elements.step, 'Setpoint step response y', 'y', 'y', pinned, extras);
  }
  const pin = (key) => pinned.map((p) => orEmpty(p.series && p.series[key], n));
  const mc = series.monte_carlo || {};
  const extraData = { linear: () => [series.linear_y], band: () => [mc.y_max, mc.y_min],
    sampled: () => [heldAt(sampled.t, sampled.y, series.t)], trio: () => [atSampleTimes(trio, series.t)] };
  plots.step.setData([series.t, series.y, ...pin('y'), ...extras.flatMap((k) => extraData[k]())]);
  // u is in every series but the stepper's failed ones; the firmware's
  // sampled loop, when it is drawn, fills a gap (held between its samples).
  const u = Array.isArray(series.u) ? series.u
    : sampled && Array.isArray(sampled.u) ? heldAt(sampled.t, sampled.u, series.t) : orEmpty(series.u, n);
  const title = (chart, text) => { const el = chart.root.querySelector('.u-title'); if (el) el.textContent = text; };
  title(
      plots.effort,
      Array.isArray(series.u) ? 'Control effort u (step response)' :
          sampled && Array.isArray(sampled.u) ?
                                'Control effort u of the sampled loop at the firmware\'s dt' :
                                'Control effort u: not computed (' + (series.notes || []).join('; ') + ')');
  title(
      plots.load,
      Array.isArray(series.load_y) ? 'Load response y (unit step at the plant input)' :
                                     'Load response: not computed (' + (series.notes || []).join('; ') + ')');
  plots.effort.setData([series.t, u, ...pin('u')]);
  plots.load.setData([series.t, orEmpty(series.load_y, n), ...pin('load_y')]);
  const m = series.w.length;
  // A pinned design has its own grid: its curve is drawn at this grid's
  // frequencies by interpolation on log w (drawing only; its numbers are its reply's).
  const onGrid = (p, key) => (p.series ? resample(p.series.w, p.series[key], series.w).map(dB) : new Array(m).fill(null));
  // Its phase likewise, in degrees (continuous on its own grid, so linear in log w between its points).
  const phaseOnGrid = (p) => (p.series && Array.isArray(p.series.l_phase_deg)
    ? resample(p.series.w, p.series.l_phase_deg, series.w) : new Array(m).fill(null));
  const lMag = series.l_re.map((re, i) => (re === null || series.l_im[i] === null ? null : Math.hypot(re, series.l_im[i])));
  // The crossovers that matter: every gain crossover and the gain margin's
  // phase crossover (a dead time has phase crossovers without end).
  plots.freq.pidlabCrossovers = [...(series.gain_crossovers_rad_s || []), series.phase_crossover_rad_s];
  plots.freq.setData([series.w, lMag.map(dB), series.s.map(dB), series.t_mag.map(dB), series.cs.map(dB), new Array(m).fill(dB(series.ms)),
    orEmpty(series.l_phase_deg, m), ...pinned.flatMap((p) => [onGrid(p, 's'), onGrid(p, 't_mag'), phaseOnGrid(p)])]);
  plots.nyquist.setData([null, ...nyquistSegments(series), circle(series.ms), [[-1], [0]],
    ...pinned.flatMap((p) => nyquistSegments(p.series))]);
}
