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

function timeChart(el, title, yLabel, label, pinned, band) {
  const series = [{ label: 't s' }, { label, stroke: colours[0], width: 2 }];
  pinned.forEach((p, i) => series.push({ label: p.label, stroke: pinColour(i), width: 1, dash: [6, 3] }));
  const opts = { title, ...size(el), series, scales: { x: { time: false } }, axes: [{ label: 't (s)' }, { label: yLabel }] };
  if (band) {  // eq. (3)'s linear motor (nonlinear stepper), then the Monte-Carlo band: the last two series, filled between
    series.push({ label: 'eq. (3) linear model', stroke: '#555', width: 1, dash: [2, 3] });
    const n = series.length;
    series.push({ label: 'Monte Carlo max', stroke: 'rgba(31,119,180,0.3)', width: 1 });
    series.push({ label: 'Monte Carlo min', stroke: 'rgba(31,119,180,0.3)', width: 1 });
    opts.bands = [{ series: [n, n + 1], fill: 'rgba(31,119,180,0.15)' }];
    // "Run on the trio": the trio's y at the same sample times, last.
    series.push({ label: 'trio y', stroke: '#ff7f0e', width: 2, dash: [3, 3] });
  }
  return new uPlot(opts, series.map((_, i) => (i === 0 ? [] : [])), el);
}

function freqChart(el, pinned) {
  const series = [{ label: 'w rad/s' },
    { label: '|S|', stroke: colours[0], width: 2 },
    { label: '|T|', stroke: colours[2], width: 2 },
    { label: '|CS|', stroke: colours[4], width: 1 },
    { label: 'Ms', stroke: '#888', width: 1, dash: [4, 4] }];
  pinned.forEach((p, i) => {
    series.push({ label: p.label + ' |S|', stroke: pinColour(i), width: 1, dash: [6, 3] });
    series.push({ label: p.label + ' |T|', stroke: pinColour(i), width: 1, dash: [2, 2] });
  });
  return new uPlot({
    title: '|S|, |T|, |CS| (Ms dashed)', ...size(el), series,
    scales: { x: { time: false, distr: 3 }, y: { distr: 3 } },
    axes: [{ label: 'w (rad/s)', values: logTicks }, { label: 'gain', values: logTicks }],
  }, [[], [], [], [], [], ...pinned.flatMap(() => [[], []])], el);
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
    mode: 2, title: 'Nyquist of L (1/Ms circle around -1)', ...size(el), series,
    legend: { show: false }, cursor: { show: false },
    scales: { x: { time: false, auto: false, range: [-4, 2] }, y: { auto: false, range: [-3, 3] } },
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

// Builds the five charts in `elements` ({step, effort, load, freq, nyquist})
// with a dashed series per pinned design.
export function createPlots(elements, pinned) {
  return {
    step: timeChart(elements.step, 'Setpoint step response y (Monte-Carlo band on request)', 'y', 'y', pinned, true),
    effort: timeChart(elements.effort, 'Control effort u (step response)', 'u', 'u', pinned),
    load: timeChart(elements.load, 'Load response y (unit step at the plant input)', 'y', 'y', pinned),
    freq: freqChart(elements.freq, pinned),
    nyquist: nyquistChart(elements.nyquist, pinned),
  };
}

export function destroyPlots(plots) {
  for (const k of Object.keys(plots || {})) plots[k].destroy();
}

// Sets every chart's data: the current design's `series` and the pinned ones'.
// `trio` ({t, y}, optional): the trio's run, drawn on the step plot where
// its sample times are the series' own.
export function drawPlots(plots, series, pinned, trio) {
  const n = series.t.length;
  const trioY = trio ? atSampleTimes(trio, series.t) : new Array(n).fill(null);
  const pin = (key) => pinned.map((p) => orEmpty(p.series && p.series[key], n));
  const mc = series.monte_carlo || {};
  plots.step.setData([series.t, series.y, ...pin('y'), orEmpty(series.linear_y, n), orEmpty(mc.y_max, n), orEmpty(mc.y_min, n), trioY]);
  plots.effort.setData([series.t, orEmpty(series.u, n), ...pin('u')]);
  plots.load.setData([series.t, orEmpty(series.load_y, n), ...pin('load_y')]);
  const m = series.w.length;
  // A pinned design has its own grid: its curve is drawn at this grid's
  // frequencies by interpolation on log w (drawing only; its numbers are its reply's).
  const onGrid = (p, key) => (p.series ? resample(p.series.w, p.series[key], series.w) : new Array(m).fill(null));
  plots.freq.setData([series.w, series.s, series.t_mag, series.cs, new Array(m).fill(series.ms),
    ...pinned.flatMap((p) => [onGrid(p, 's'), onGrid(p, 't_mag')])]);
  plots.nyquist.setData([null, ...nyquistSegments(series), circle(series.ms), [[-1], [0]],
    ...pinned.flatMap((p) => nyquistSegments(p.series))]);
}
