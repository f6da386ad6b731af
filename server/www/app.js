// The workbench page: controls -> a spec -> the server (WebSocket /ws) ->
// the same JSON as `pidlab evaluate --json`. No computation happens here.
'use strict';
const token = new URLSearchParams(location.search).get('token');
const plants = ['double_integrator', 'oscillator', 'stepper_motor'];
const state = { plant: 'double_integrator', kp: 3.9, ki: 0.06, kd: 4.9, seq: 0, lastShown: 0 };
let socket = null;

function spec() {
  return { plant: state.plant, gains: [state.kp, state.ki, state.kd] };
}

function command(s) {
  return 'pidlab evaluate --plant ' + s.plant + ' --gains ' + s.gains.join(',') + ' --json';
}

function slider(name) {
  const row = document.createElement('div');
  const label = document.createElement('label');
  label.textContent = name;
  const range = document.createElement('input');
  range.type = 'range'; range.min = -3; range.max = 2; range.step = 0.001; range.id = name + '-slider';
  const box = document.createElement('input');
  box.type = 'number'; box.step = 'any'; box.min = 0; box.id = name;
  const set = (v, from) => {
    state[name] = v;
    if (from !== box) box.value = v;
    if (from !== range) range.value = v > 0 ? Math.log10(v) : -3;
    send();
  };
  range.addEventListener('input', () => set(Number(Math.pow(10, Number(range.value)).toPrecision(6)), range));
  box.addEventListener('change', () => set(Number(box.value), box));
  row.append(label, range, box);
  document.getElementById('gains').append(row);
  box.value = state[name];
  range.value = Math.log10(state[name]);
}

function show(reply) {
  const status = document.getElementById('status');
  if (reply.error) { status.textContent = reply.error; return; }
  if (reply.id < state.lastShown) return;
  state.lastShown = reply.id;
  status.textContent = '';
  const r = reply.result;
  const rows = [
    ['IAE (eq. 4)', r.iae], ['ISE', r.ise], ['ITAE', r.itae], ['stable', r.stable],
    ['overshoot %', r.overshoot_pct], ['settling time s', r.settling_time_s],
    ['Ms', r.robustness && r.robustness.ms], ['Mt', r.robustness && r.robustness.mt],
    ['phase margin deg', r.robustness && r.robustness.phase_margin_deg],
  ];
  const body = document.querySelector('#metrics tbody');
  body.textContent = '';
  for (const [name, value] of rows) {
    const tr = document.createElement('tr');
    const a = document.createElement('th'); a.textContent = name;
    const b = document.createElement('td'); b.textContent = value === null || value === undefined ? '-' : String(value);
    b.dataset.key = name;
    tr.append(a, b);
    body.append(tr);
  }
  document.getElementById('spec').textContent = JSON.stringify(r.spec);
  document.getElementById('command').textContent = command(spec());
}

function send() {
  if (!socket || socket.readyState !== WebSocket.OPEN) return;
  state.seq += 1;
  socket.send(JSON.stringify({ id: state.seq, type: 'evaluate', spec: spec() }));
}

function connect() {
  const url = (location.protocol === 'https:' ? 'wss://' : 'ws://') + location.host + '/ws' +
      (token ? '?token=' + encodeURIComponent(token) : '');
  socket = new WebSocket(url);
  socket.addEventListener('open', send);
  socket.addEventListener('message', (e) => show(JSON.parse(e.data)));
  socket.addEventListener('close', () => {
    document.getElementById('status').textContent = 'disconnected from the server';
  });
}

const select = document.getElementById('plant');
for (const p of plants) {
  const o = document.createElement('option');
  o.value = p; o.textContent = p;
  select.append(o);
}
select.addEventListener('change', () => { state.plant = select.value; send(); });
for (const name of ['kp', 'ki', 'kd']) slider(name);
connect();
