// The workbench's tables of numbers: the metrics of the design drawn, the
// few beside the knobs, and the difference to the pinned designs. Every
// number is the server's (docs/workbench.md); this module only lays them out.

// The paper's plants, where eq. (4)'s sum is the paper's IAE and heads the table.
const kPaperPlants = ['double_integrator', 'oscillator', 'stepper_motor', 'stepper_nonlinear'];

export function fmt(v) {
  if (v === null || v === undefined) return '-';
  if (typeof v === 'boolean') return v ? 'yes' : 'no';
  if (typeof v !== 'number') return String(v);
  return Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-3 && v !== 0) ? v.toExponential(4) :
                                                                 String(Number(v.toPrecision(5)));
}

// [key, label, value, the bound's name in the violations] of a result. The
// headline is the integral of |e| in the plant's units, for the setpoint
// step and for a unit load step at the plant input; eq. (4)'s sum of
// samples keeps its name, first only for the paper's plants.
export function metricRows(r) {
  const rb = r.robustness || {};
  const paper = kPaperPlants.includes(r.plant);
  const eq4 = ['iae', paper ? 'IAE (eq. 4)' : 'sum |e(t_k)| (eq. 4\'s form)', r.iae];
  const headline = [
    ['iae_continuous', 'setpoint \u222b|e|dt', r.iae_continuous],
    ['load_iae_continuous', 'load \u222b|e|dt', r.load_iae_continuous]
  ];
  return [
    ...(paper ? [eq4, ...headline] : [...headline, eq4]),
    ['ise', 'ISE', r.ise],
    ['itae', 'ITAE', r.itae],
    ['load_iae', 'load sum |e(t_k)|', r.load_iae],
    ['stable', 'stable', r.stable],
    ['rise_time', 'rise time s', r.rise_time_s],
    ['overshoot', 'overshoot %', r.overshoot_pct],
    ['settling_time', 'settling time s', r.settling_time_s],
    ['ms', 'Ms', rb.ms, 'Ms'],
    ['mt', 'Mt', rb.mt, 'Mt'],
    ['noise_gain', 'noise gain', rb.noise_gain, 'noise gain'],
    ['phase_margin', 'phase margin deg', rb.phase_margin_deg, 'phase margin'],
    ['gain_margin', 'gain margin', rb.gain_margin, 'gain margin'],
    ['delay_margin', 'delay margin s', rb.delay_margin_s],
    ['time_constant', 'slowest time constant s', rb.slowest_time_constant_s, 'time constant'],
  ];
}

function fillRows(body, rows) {
  body.textContent = '';
  for (const [name, text, decorate] of rows) {
    const tr = document.createElement('tr');
    const th = document.createElement('th');
    th.textContent = name;
    const td = document.createElement('td');
    td.textContent = text;
    if (decorate) decorate(td);
    tr.append(th, td);
    body.append(tr);
  }
}

export function showMetrics(r) {
  const violations = (r.robustness && r.robustness.violations) || [];
  fillRows(
      document.querySelector('#metrics tbody'),
      metricRows(r).map(([key, name, value, bound]) => [name, fmt(value), (td) => {
                          td.id = 'metric-' + key;
                          td.dataset.value = value === undefined ? 'null' : String(value);
                          const broken = violations.filter(
                              (v) => (bound && v.toLowerCase().startsWith(bound.toLowerCase())) ||
                                  v === 'unstable loop');
                          if (broken.length && (bound || key === 'stable')) {
                            td.classList.add('violated');
                            td.title = broken.join('; ');
                          }
                        }]));
}

// The few numbers an engineer reads first, beside the knobs.
export function showKeyMetrics(r) {
  const rb = r.robustness || {};
  const g = r.gains || {};
  fillRows(document.querySelector('#key-metrics tbody'), [
    ['kp, ki, kd', [g.kp, g.ki, g.kd].map(fmt).join(', ')], ['tf s', fmt(g.tf)],
    ['load \u222b|e|dt', fmt(r.load_iae_continuous)], ['setpoint \u222b|e|dt', fmt(r.iae_continuous)],
    ['overshoot %', fmt(r.overshoot_pct)], ['settling s', fmt(r.settling_time_s)], ['Ms', fmt(rb.ms)],
    ['phase margin', fmt(rb.phase_margin_deg) + ' deg'], ['stable', fmt(r.stable)]
  ]);
}

// Metrics of the current design and every pinned one, and the difference.
export function renderDiff(table, current, pinned) {
  table.textContent = '';
  if (!pinned.length || !current) return;
  const head = document.createElement('tr');
  for (const h
           of ['metric', 'current', ...pinned.map((p) => p.label),
               ...pinned.map((p) => 'current - ' + p.label.split(' ')[0])]) {
    const th = document.createElement('th');
    th.textContent = h;
    head.append(th);
  }
  table.append(head);
  // By key: a pinned design of another plant orders its rows otherwise.
  const pinnedRows = pinned.map((p) => new Map(metricRows(p.result).map((row) => [row[0], row[2]])));
  for (const [key, name, value] of metricRows(current)) {
    const tr = document.createElement('tr');
    const cells = [
      name, fmt(value), ...pinnedRows.map((r) => fmt(r.get(key))),
      ...pinnedRows.map(
          (r) =>
              (typeof value === 'number' && typeof r.get(key) === 'number' ? fmt(value - r.get(key)) : '-'))
    ];
    cells.forEach((c, j) => {
      const td = document.createElement(j ? 'td' : 'th');
      td.textContent = c;
      tr.append(td);
    });
    tr.dataset.key = key;
    table.append(tr);
  }
}
