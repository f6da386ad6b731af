// browser.tuning_path (run by tuning_path_test.sh inside its network
// namespace, under CPU load): the tuning app's whole path in headless
// Chromium at 1280x800, each step checked against the command line.
//   node tuning_path_test.js --url URL --pidlab BIN --modules DIR --chromium BIN --csv FILE --out DIR --tmp DIR
// 0. Every request of a burst of different kinds in flight at once is answered.
// 1. A step-test CSV is uploaded; 2. identified with auto (the JSON of pidlab
// identify --model auto --json); 3. the model accepted as the plant; 4. the
// response-time and robustness knobs moved: the gains equal pidlab tune
// --response-time T --robustness R --json's (1e-12); 4b. the knob's 51
// positions designed ahead: a move is drawn from what they kept, without a
// request, and equals pidlab tune's (1e-12); 5. exported at a dt;
// the downloaded pidlab_pid.c and .h, and the export's spec, are written to
// --tmp for the shell half (6. gcc, 7. the trio against evaluate --loop sampled).
'use strict';
const fs = require('fs');
const path = require('path');
const { execFileSync } = require('child_process');
const { parseArgs, launch, waitForPage, makeStep } = require('./page_driver.js');

const args = parseArgs(process.argv.slice(2), ['url', 'pidlab', 'modules', 'chromium', 'csv', 'out', 'tmp']);
function canonical(v) {
  if (Array.isArray(v)) return '[' + v.map(canonical).join(',') + ']';
  if (v && typeof v === 'object')
    return '{' + Object.keys(v).sort().map((k) => JSON.stringify(k) + ':' + canonical(v[k])).join(',') + '}';
  return JSON.stringify(v);
}
const waitMs = 60000;  // a fit or a design on a loaded machine

function pidlab(argv) {
  return execFileSync(args.pidlab, argv, { encoding: 'utf8', maxBuffer: 64 << 20, timeout: 120000 });
}
function relDiff(a, b) { return Math.abs(a - b) / Math.max(Math.abs(a), Math.abs(b), 1e-300); }
function expectClose(what, got, want, tol) {
  if (typeof got !== 'number' || typeof want !== 'number' || !(relDiff(got, want) <= tol))
    throw new Error(what + ': page ' + got + ', CLI ' + want);
}

// The burst: N requests of six kinds sent at once on a WebSocket of the
// page's origin, as the page sends them; resolves with the ids answered.
async function burst(page, count) {
  return page.evaluate(async (count) => {
    const url = 'ws://' + location.host + '/ws';
    const ws = new WebSocket(url);
    await new Promise((resolve, reject) => { ws.onopen = resolve; ws.onerror = reject; });
    const kinds = [
      { type: 'evaluate', spec: { plant: 'stepper_motor', gains: [1, 1, 0.001] } },
      { type: 'fields' },
      { type: 'paper_designs' },
      { type: 'export', spec: { plant: 'oscillator', gains: [2, 1, 1.5], loop: 'sampled', dt: 0.01 } },
      { type: 'evaluate', spec: { plant: 'custom', num: [1], den: [10, 1], delay: 2, gains: [1, 0.1, 0] }, series: false },
      { type: 'log_open', path: '../outside.lcmlog' },  // answered with an error: still a reply
    ];
    const answered = new Map();
    const done = new Promise((resolve) => {
      ws.onmessage = (e) => {
        const m = JSON.parse(e.data);
        if (m.id !== undefined) answered.set(m.id, m.type || (m.error ? 'error' : '?'));
        if (answered.size === count) resolve();
      };
    });
    for (let i = 1; i <= count; ++i) ws.send(JSON.stringify({ ...kinds[i % kinds.length], id: i }));
    await Promise.race([done, new Promise((resolve) => setTimeout(resolve, 60000))]);
    ws.close();
    const missing = [];
    for (let i = 1; i <= count; ++i) if (!answered.has(i)) missing.push(i + ' (' + kinds[i % kinds.length].type + ')');
    return { answered: answered.size, missing };
  }, count);
}

async function main() {
  fs.mkdirSync(args.out, { recursive: true });
  const session = await launch({ modules: args.modules, chromium: args.chromium, profileDir: path.join(args.tmp, 'profile') });
  const { browser, page } = session;
  await page.setViewport({ width: 1280, height: 800 });
  const downloads = path.join(args.tmp, 'downloads');
  fs.mkdirSync(downloads, { recursive: true });
  const cdp = await page.target().createCDPSession();
  await cdp.send('Browser.setDownloadBehavior', { behavior: 'allow', downloadPath: downloads });
  const shot = (name, full) => page.screenshot({ path: path.join(args.out, 'tuning-' + name + '.png'), fullPage: !!full });
  const step = makeStep(session, () => shot('failure', true));

  await step('the page loads under load and every first request is answered (13 paper designs, fields, a drawn design)', async () => {
    await page.goto(args.url, { waitUntil: 'load' });
    await waitForPage(session, 'the page did not draw its first design', waitMs, () => window.pidlab.rendered > 0);
    await waitForPage(session, 'the paper designs did not arrive', waitMs,
      () => document.querySelectorAll('#paper-designs button.paper-design').length === 13);
    return 'rendered ' + (await page.evaluate(() => window.pidlab.rendered));
  });

  await step('0. 240 requests of six kinds in flight at once are each answered', async () => {
    const r = await burst(page, 240);
    if (r.missing.length) throw new Error(r.missing.length + ' unanswered: ' + r.missing.slice(0, 10).join(', '));
    return r.answered + ' replies';
  });

  let fit = null;
  await step('1-2. the CSV uploads and identify auto gives pidlab identify --model auto --json\'s model and parameters', async () => {
    const input = await page.$('#data-file');
    await input.uploadFile(args.csv);
    await waitForPage(session, 'the upload did not finish', waitMs, () => !!window.pidlab.design.upload);
    await page.evaluate(() => { document.getElementById('data-u0').value = '0'; document.getElementById('data-model').value = 'auto'; });
    await page.click('#data-identify');
    await waitForPage(session, 'no fit', waitMs * 2, () => !!window.pidlab.design.fit);
    fit = await page.evaluate(() => window.pidlab.design.fit);
    const cli = JSON.parse(pidlab(['identify', '--csv', args.csv, '--model', 'auto', '--u0', '0', '--json', '--quiet']));
    if (fit.result.model !== cli.model) throw new Error('model ' + fit.result.model + ', CLI ' + cli.model);
    for (const [name, p] of Object.entries(cli.parameters))
      if (fit.result.parameters[name].value !== p.value) throw new Error(name + ': page ' + fit.result.parameters[name].value + ', CLI ' + p.value);
    if (fit.result.aic !== cli.aic) throw new Error('AIC ' + fit.result.aic + ', CLI ' + cli.aic);
    const rows = await page.$$eval('#data-params tr[data-parameter]', (trs) => trs.length);
    if (rows !== Object.keys(cli.parameters).length) throw new Error('#data-params has ' + rows + ' rows');
    if (fit.fit.simulated.length !== fit.fit.y.length) throw new Error('the fit\'s curves differ in length');
    // The fit in view: open, in the viewport, at a readable size with axis labels; the model downloads.
    const view = await page.evaluate(async () => {
      const box = document.getElementById('data-box');
      const r = box.getBoundingClientRect();
      const a = document.getElementById('data-download');
      return {
        open: box.open,
        top: r.top,
        height: r.height,
        inner: window.innerHeight,
        widths: Array.from(document.querySelectorAll('#data-plots .uplot'))
                    .map((e) => e.getBoundingClientRect().width),
        labels:
            window.pidlab.design.fitCharts.flatMap((c) => c.axes.map((x) => x.label)),  // drawn on the canvas
        name: a.download,
        hidden: a.classList.contains('hidden')
      };
    });
    // The download as a user gets it: clicked, into the downloads folder.
    if (!view.hidden) await page.click('#data-download');
    const saved = path.join(downloads, view.name || 'none');
    for (const deadline = Date.now() + 20000; !fs.existsSync(saved) && Date.now() < deadline;)
      await new Promise((r) => setTimeout(r, 50));
    view.text = fs.existsSync(saved) ? fs.readFileSync(saved, 'utf8') : '';
    if (!view.open || view.top < -2 || view.top > view.inner - 200 || view.height < 300)
      throw new Error(
          'the fit is not in view: ' + JSON.stringify({open: view.open, top: view.top, height: view.height}));
    if (view.widths.length !== 3 || view.widths[0] < 480 || Math.min(...view.widths) < 240)
      throw new Error('the fit plots are ' + view.widths.join(', ') + ' px wide');
    if (!view.labels.includes('t (s)') || !view.labels.includes('y'))
      throw new Error('axis labels: ' + view.labels.join(', '));
    if (view.hidden || view.text !== fit.model_file ||
        canonical(JSON.parse(view.text)) !== canonical(fit.result))
      throw new Error('the download ' + view.name + ' is not the model file the server wrote');
    fit.download = view.name;
    fit.downloads = downloads;
    await shot('fit');
    return cli.model + ', AIC ' + cli.aic.toFixed(3) + ', ' + rows + ' parameters, bit for bit';
  });

  const knobGains = async (what) => {
    await waitForPage(session, what, waitMs, () => {
      const k = window.pidlab.design.knob;
      return k.last && !k.running && !k.pending;
    });
    return page.evaluate(() => ({ spec: window.pidlab.design.knob.last.spec, result: window.pidlab.design.knob.last.result,
      shown: window.pidlab.lastResult && window.pidlab.lastResult.gains }));
  };
  const compareWithTune = (got) => {
    const flags = ['tune', '--plant', got.spec.plant, '--json'];
    if (got.spec.method) flags.push('--method', got.spec.method);  // the page's knobs: optimal
    if (got.spec.plant === 'custom') flags.push('--num', got.spec.num.join(','), '--den', got.spec.den.join(','));
    if (got.spec.delay) flags.push('--delay', String(got.spec.delay));
    if (got.spec.response_time) flags.push('--response-time', String(got.spec.response_time));
    if (got.spec.robustness) flags.push('--robustness', String(got.spec.robustness));
    const cli = JSON.parse(pidlab(flags));
    for (const k of ['kp', 'ki', 'kd', 'tf']) expectClose(k, got.result.gains[k], cli.gains[k], 1e-12);
    for (const k of ['kp', 'ki', 'kd', 'tf']) expectClose('drawn ' + k, got.shown[k], cli.gains[k], 1e-12);
    return flags.slice(1).join(' ');
  };

  await step('3. the model is accepted as the plant and designed for (pidlab tune --plant model:FILE)', async () => {
    await page.click('#data-accept');
    const got = await knobGains('no design for the accepted model');
    if (got.spec.plant !== fit.plant) throw new Error('the design ran on ' + got.spec.plant + ', not ' + fit.plant);
    // The printed command names the downloaded file, and runs where it is, without the server's.
    const command = await page.evaluate(() => window.pidlab.command());
    if (!command.includes('--plant model:' + fit.download + ' '))
      throw new Error('the command does not name the download: ' + command);
    const env = Object.assign({}, process.env, {PATH: path.dirname(args.pidlab) + ':' + process.env.PATH});
    const out = JSON.parse(
        execFileSync('bash', ['-c', command], {encoding: 'utf8', env, cwd: fit.downloads, timeout: 60000}));
    const iae = await page.evaluate(() => window.pidlab.lastResult.iae);
    if (out.iae !== iae) throw new Error('the command gives IAE ' + out.iae + ', the page ' + iae);
    return compareWithTune(got) + '; ' + command;
  });

  await step('4. the response knob, then the robustness knob: the gains of pidlab tune at the front\'s Ms bound (1e-12)', async () => {
    const moved = [];
    const fastest = await page.evaluate(() => window.pidlab.design.knob.last.result);
    for (const [id, value] of [['knob-speed', '0.5'], ['knob-robustness', '1.3']]) {
      await page.evaluate((id, value) => {
        const r = document.getElementById(id);
        r.value = value;
        r.dispatchEvent(new Event('input', { bubbles: true }));
      }, id, value);
      const got = await knobGains('no design for ' + id + ' = ' + value);
      // Halfway along the front from Ms 1.1 to the bound: the default's, then 1.3.
      const bound = id === 'knob-speed' ? fastest.design.ms_bound : 1.3;
      const want = Number((1.1 + 0.5 * (bound - 1.1)).toFixed(3));
      if (got.spec.robustness !== want) throw new Error(id + ' = ' + value + ': robustness ' + got.spec.robustness + ', not ' + want);
      if (id === 'knob-speed' && !(got.result.response_time_s > fastest.response_time_s && got.result.design.load_iae > fastest.design.load_iae))
        throw new Error('the slower position is not slower: T ' + got.result.response_time_s + ' against ' + fastest.response_time_s);
      moved.push(compareWithTune(got));
    }
    await shot('knob');
    return moved.join('; ');
  });

  await step('4b. the knob\'s positions are designed ahead: a move is drawn from them, no request, and equals pidlab tune', async () => {
    const started = Date.now();
    await waitForPage(session, 'the knob positions not designed ahead', 240000, () => window.pidlab.design.knob.ready);
    const ahead = await page.$eval('#knob-ahead', (e) => e.textContent);
    if (ahead !== '(designed ahead: 51 of 51 positions)') throw new Error('#knob-ahead says: ' + ahead);
    const moved = [];
    for (const value of ['0.3', '0.92']) {
      await page.evaluate((value) => {
        window.pidlab.design.knob.last = null;
        const r = document.getElementById('knob-speed');
        r.value = value;
        r.dispatchEvent(new Event('input', { bubbles: true }));
      }, value);
      const got = await knobGains('no design for knob-speed = ' + value);
      await waitForPage(session, 'no redraw for knob-speed = ' + value, waitMs, () =>
        window.pidlab.lastResult && window.pidlab.lastResult.gains.kp === window.pidlab.design.knob.last.result.gains.kp);
      const t = await page.evaluate(() => window.pidlab.timings[window.pidlab.timings.length - 1]);
      if (!t.kept) throw new Error('the move to ' + value + ' sent a request: ' + JSON.stringify(t));
      const want = Number((1.1 + Number(value) * 0.2).toFixed(3));
      if (got.spec.robustness !== want) throw new Error('designed ahead at robustness ' + got.spec.robustness + ', not ' + want);
      moved.push(compareWithTune(got) + ' (drawn ' + (t.drawn_ms - t.sent_ms).toFixed(1) + ' ms after the input)');
    }
    return 'ready ' + ((Date.now() - started) / 1000).toFixed(1) + ' s after the robustness move; ' + moved.join('; ');
  });

  await step('5. export at a chosen dt: the loop check is stable, pidlab_pid.c and .h download', async () => {
    const dt = await page.evaluate(() => Number(document.getElementById('fw-dt').value));
    if (!(dt > 0)) throw new Error('#fw-dt offers no dt');
    await page.click('#fw-check');
    await waitForPage(session, 'no export', waitMs, () => !!window.pidlab.design.export);
    const ex = await page.evaluate(() => window.pidlab.design.export);
    if (!ex.loop_check.stable) throw new Error('the loop check: ' + ex.loop_check.verdict);
    await page.click('#fw-download-c');
    await page.click('#fw-download-h');
    const deadline = Date.now() + 20000;
    while (!['pidlab_pid.c', 'pidlab_pid.h'].every((f) => fs.existsSync(path.join(downloads, f))) && Date.now() < deadline)
      await new Promise((r) => setTimeout(r, 50));
    for (const f of ['pidlab_pid.c', 'pidlab_pid.h']) {
      const file = path.join(downloads, f);
      if (!fs.existsSync(file)) throw new Error(f + ' was not downloaded');
      if (fs.readFileSync(file, 'utf8') !== ex.files[f]) throw new Error(f + ' differs from the export reply');
    }
    const sampled = await page.evaluate(() => (window.pidlab.plots.step.series || []).some((s) => /sampled at dt/.test(s.label)));
    if (!sampled) throw new Error('the sampled loop is not drawn on the step plot');
    fs.writeFileSync(path.join(args.tmp, 'export_spec.json'), JSON.stringify(ex.spec));
    await page.evaluate(() => window.scrollTo(0, 0));
    await shot('fitted');
    await shot('fitted-full', true);
    return 'dt ' + dt + ' s: ' + ex.loop_check.verdict;
  });

  await step('5b. the exported design on the emulated Cortex-M3 and M4F in every scalar: cost per step, stack, size (docs/pil.md)', async () => {
    await page.click('#fw-pil');
    await waitForPage(session, 'no PIL costs', 180000, () => !!window.pidlab.design.pil ||
      /no PIL costs/.test(document.getElementById('fw-pil-status').textContent));
    const got = await page.evaluate(() => ({ pil: window.pidlab.design.pil, status: document.getElementById('fw-pil-status').textContent,
      rows: document.querySelectorAll('#fw-pil-table:not(.hidden) tbody tr').length }));
    if (!got.pil) throw new Error(got.status);
    const rows = got.pil.rows;
    const bad = rows.filter((r) => r.error || !(r.instructions_mean >= 40 && r.instructions_mean <= r.instructions_max && r.stack_bytes > 0 && r.text_bytes > 0));
    if (rows.length !== 8 || got.rows !== 8 || bad.length) throw new Error(got.rows + ' rows drawn; ' + JSON.stringify(bad.length ? bad : rows));
    const mean = (scalar, core) => rows.find((r) => r.scalar === scalar && r.core === core).instructions_mean;
    if (!(mean('float', 'm4f') < mean('float', 'm3'))) throw new Error('float on the M4F FPU is not cheaper than soft float on the M3');
    return rows.map((r) => r.scalar + '/' + r.core + ' ' + Math.round(r.instructions_mean)).join(', ') + ' instructions per step';
  });

  // Switching the plant resets what belongs to the plant; the knob's design
  // for the stepper motor and for a thermal plant equals pidlab tune's.
  const designFor = async (what, setPlant) => {
    await page.evaluate(setPlant);
    const state = await page.evaluate(() => ({ filter: window.pidlab.state.derivative_filter, pinned: window.pidlab.pinned.length,
      sampled: !!window.pidlab.design.sampled, speed: document.getElementById('knob-speed').value,
      links: document.querySelectorAll('#firmware a:not(.hidden)').length }));
    if (state.filter !== '' || state.pinned || state.sampled || state.speed !== '1' || state.links)
      throw new Error('switching to ' + what + ' kept ' + JSON.stringify(state));
    await page.evaluate(() => { window.pidlab.design.knob.last = null; });
    await page.click('#knob-design');
    const got = await knobGains('no design for ' + what);
    await waitForPage(session, 'no redraw for ' + what, waitMs, () => !window.pidlab.design.knob.running &&
      window.pidlab.lastResult && window.pidlab.lastResult.gains.kp === window.pidlab.design.knob.last.result.gains.kp);
    return compareWithTune(got);
  };
  await step('8. the stepper motor: the plant switch resets the filter, pins, firmware and knobs; its design equals pidlab tune --plant stepper_motor', async () => {
    const flags = await designFor('the stepper motor', () => {
      const p = document.getElementById('plant');
      p.value = 'stepper_motor';
      p.dispatchEvent(new Event('change', { bubbles: true }));
    });
    await shot('stepper');
    return flags;
  });
  await step('9. a thermal plant 2 e^-8s / (60 s + 1): its design equals pidlab tune --num 2 --den 60,1 --delay 8', async () => {
    const flags = await designFor('a thermal plant', () => {
      const set = (id, v) => { const e = document.getElementById(id); e.value = v; e.dispatchEvent(new Event('change', { bubbles: true })); };
      set('plant', 'custom');
      set('num', '2');
      set('den', '60,1');
      set('delay', '8');
    });
    await shot('thermal');
    return flags;
  });

  await browser.close();
}

main().catch((e) => { console.log('FAIL ' + (e && e.stack ? e.stack : e)); process.exit(1); });
