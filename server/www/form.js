// The form from the spec's field list: the server's `fields` reply
// (results::EvaluateSpecFields: key, flag, help, unit, default, example)
// gives one input per field the page has no control of its own for, so that
// a field added to the spec appears on the page without a page edit. Each
// value is read by its example's JSON type; an empty input is the spec's
// default and is not sent.

// The fields the page sets with its own controls (the plant, the gains, the
// knobs, the expert boxes): everything else is generated here.
export const kOwnFields = [
  'plant', 'num', 'den', 'model', 'delay', 'stepper', 'gains', 'derivative_filter', 'setpoint_weights',
  'setpoint_filter', 'output_limits', 'loop', 'dt', 'max_ms', 'max_mt', 'max_noise_gain', 'min_phase_margin',
  'monte_carlo', 'spread'
];

const kindOf = (example) => (Array.isArray(example) ? 'array' : example === null ? 'string' : typeof example);

// A number as the spec's JSON takes it: finite, or "inf" / "-inf" where the field allows it.
function numberOf(key, text) {
  const t = text.trim();
  if (/^[+-]?inf(inity)?$/i.test(t)) return t.startsWith('-') ? '-inf' : 'inf';
  const v = Number(t);
  if (t === '' || !Number.isFinite(v)) throw new Error(key + ' ' + JSON.stringify(text) + ' is not a number');
  return v;
}

// The JSON value of `text` for a field whose example is `example`.
export function valueOf(key, example, text) {
  switch (kindOf(example)) {
    case 'number':
      return numberOf(key, text);
    case 'boolean':
      return text === 'true';
    case 'array': {
      const items = text.split(',').map((x) => x.trim()).filter((x) => x !== '');
      return typeof example[0] === 'number' ? items.map((x) => numberOf(key, x)) : items;
    }
    case 'object':
      try {
        return JSON.parse(text);
      } catch (e) {
        throw new Error(key + ' is not a JSON object: ' + e.message);
      }
    default:
      return text;
  }
}

function inputFor(f, value, onChange) {
  let input;
  if (kindOf(f.example) === 'boolean') {
    input = document.createElement('select');
    for (const [v, label] of [['', 'default (' + f.default + ')'], ['true', 'true'], ['false', 'false']]) {
      const o = document.createElement('option');
      o.value = v;
      o.textContent = label;
      input.append(o);
    }
  } else {
    input = document.createElement('input');
    input.placeholder = f.default === '' ? 'default' : String(f.default);
    input.className = kindOf(f.example) === 'number' ? '' : 'wide';
  }
  input.id = 'field-' + f.key;
  input.dataset.key = f.key;
  input.value = value || '';
  input.title = f.flag + ': ' + f.help;
  input.addEventListener('change', () => onChange(f.key, input.value));
  return input;
}

// ctx: { state (its `fields` object: key -> text), $, ask, onChange, setStatus }.
export function initFields(ctx) {
  const {state, $} = ctx;
  let fields = [];

  function render() {
    const box = $('fields');
    if (!state.fields || typeof state.fields !== 'object') state.fields = {};
    for (const row of box.querySelectorAll('.row')) row.remove();
    for (const f of fields) {
      const row = document.createElement('div');
      row.className = 'row';
      const label = document.createElement('label');
      label.htmlFor = 'field-' + f.key;
      label.textContent = f.key + (f.unit ? ' ' + f.unit : '');
      label.title = f.help;
      row.append(label, inputFor(f, state.fields[f.key], (key, text) => {
                   if (text === '')
                     delete state.fields[key];
                   else
                     state.fields[key] = text;
                   ctx.onChange();
                 }));
      box.append(row);
    }
  }

  async function load() {
    try {
      const reply = await ctx.ask({type: 'fields'});
      fields = reply.fields.filter((f) => !kOwnFields.includes(f.key));
      render();
    } catch (e) {
      ctx.setStatus('fields: ' + e.message);
    }
  }

  // The generated fields' values into the spec `s` (throws naming a bad value).
  function apply(s) {
    if (!state.fields || typeof state.fields !== 'object' || Array.isArray(state.fields)) state.fields = {};
    for (const f of fields) {
      const text = state.fields[f.key];
      if (text !== undefined && text !== '') s[f.key] = valueOf(f.key, f.example, String(text));
    }
    return s;
  }

  return {load, render, apply, fields: () => fields};
}

// The gains' log sliders (with their number boxes) and the bounds' sliders
// (linear, or log10 for the noise gain: moving one sets its number box and
// the bound; an empty box is no bound). ctx: { state, $, send }.
const kBoundSliders = {
  max_ms: [1.05, 4, 0.01, false],
  max_mt: [1, 4, 0.01, false],
  max_noise_gain: [-1, 4, 0.01, true],
  min_phase_margin: [0, 90, 0.5, false]
};
export function initSliders(ctx) {
  const {state, $} = ctx;
  const setGain = (name, v, from) => {
    state[name] = v;
    if (from !== $(name)) $(name).value = v;
    if (from !== $(name + '-slider')) $(name + '-slider').value = v > 0 ? Math.log10(v) : -3;
    ctx.send();
  };
  for (const name of ['kp', 'ki', 'kd']) {
    const row = document.createElement('div');
    row.className = 'row';
    const label = document.createElement('label');
    label.textContent = name;
    label.htmlFor = name;
    const range = document.createElement('input');
    range.type = 'range';
    range.min = -3;
    range.max = 2.5;
    range.step = 0.001;
    range.id = name + '-slider';
    const box = document.createElement('input');
    box.type = 'number';
    box.step = 'any';
    box.min = 0;
    box.id = name;
    range.addEventListener(
        'input', () => setGain(name, Number(Math.pow(10, Number(range.value)).toPrecision(6)), range));
    box.addEventListener('change', () => setGain(name, Number(box.value), box));
    row.append(label, range, box);
    $('gains').append(row);
  }
  const syncBound = (k) => {
    const [lo, hi, , log] = kBoundSliders[k];
    const v = Number(state[k]);
    const r = $(k + '-slider');
    if (state[k] === '' || !isFinite(v)) {
      r.value = lo;
      return;
    }
    r.value = Math.min(hi, Math.max(lo, log ? Math.log10(v) : v));
  };
  for (const [k, [lo, hi, step, log]] of Object.entries(kBoundSliders)) {
    const r = document.createElement('input');
    r.type = 'range';
    r.id = k + '-slider';
    r.min = lo;
    r.max = hi;
    r.step = step;
    r.title = k + ' (slider)';
    $(k).after(r);
    r.addEventListener('input', () => {
      const x = Number(r.value);
      state[k] = String(log ? Number(Math.pow(10, x).toPrecision(4)) : x);
      $(k).value = state[k];
      ctx.send();
    });
    $(k).addEventListener(
        'change', () => setTimeout(() => syncBound(k)));  // after the box's own listener sets the state
    syncBound(k);
  }
  // The sliders and boxes to the state (showForm).
  function sync() {
    for (const g of ['kp', 'ki', 'kd']) {
      $(g).value = state[g];
      $(g + '-slider').value = state[g] > 0 ? Math.log10(state[g]) : -3;
    }
    for (const k of Object.keys(kBoundSliders)) syncBound(k);
  }
  return {sync};
}
