// browser.workbench (run by workbench_test.sh inside its network namespace):
// the real page in headless Chromium, read back and compared with the CLI.
//   node workbench_test.js --url URL --pidlab BIN --modules DIR --chromium BIN --out DIR --tmp DIR
// Each step prints "ok   <step>" or "FAIL <step>: <what differed>"; on a
// failure the page's console follows and the test stops (exit 1).
'use strict';
const fs = require('fs');
const path = require('path');
const { execFileSync } = require('child_process');
const { parseArgs, launch, waitForPage, moveSlider, selectPlant, makeStep } = require('./page_driver.js');

const args = parseArgs(process.argv.slice(2), ['url', 'pidlab', 'modules', 'chromium', 'out', 'tmp']);
const plants = ['double_integrator', 'oscillator', 'stepper_motor'];  // the paper's three
const redrawMs = 15000;  // one evaluation and redraw; generous for a loaded machine
const tuneMs = 90000;    // a --robust tuning on the server
let files = 0;

// The CLI, as a user runs it; the page's spec is written to a file for --spec.
function pidlab(argv) {
  return execFileSync(args.pidlab, argv, { encoding: 'utf8', maxBuffer: 64 << 20, timeout: 120000 });
}
function specFile(spec) {
  const file = path.join(args.tmp, 'spec' + (++files) + '.json');
  fs.writeFileSync(file, JSON.stringify(spec));
  return file;
}
function readCsv(file) {
  const lines = fs.readFileSync(file, 'utf8').trim().split('\n');
  const head = lines[0].split(',');
  const cols = Object.fromEntries(head.map((h) => [h, []]));
  for (const line of lines.slice(1)) line.split(',').forEach((v, i) => cols[head[i]].push(Number(v)));
  return cols;
}
function relDiff(a, b) { return Math.abs(a - b) / Math.max(Math.abs(a), Math.abs(b), 1e-300); }
function expectClose(what, got, want, tol) {
  if (typeof got !== 'number' || typeof want !== 'number' || !(relDiff(got, want) <= tol))
    throw new Error(what + ': page ' + got + ', CLI ' + want + (typeof got === 'number' && typeof want === 'number'
                                                                  ? ' (relative ' + relDiff(got, want).toExponential(2) + ' > ' + tol + ')' : ''));
}
function expectSeries(what, got, want, tol) {
  got = Array.from(got || []);
  if (got.length !== want.length) throw new Error(what + ': page has ' + got.length + ' points, CLI ' + want.length);
  for (let i = 0; i < want.length; ++i)
    if (!(Math.abs(got[i] - want[i]) <= tol * Math.max(1, Math.abs(want[i]))))
      throw new Error(what + '[' + i + ']: page ' + got[i] + ', CLI ' + want[i]);
}
function canonical(v) {
  if (Array.isArray(v)) return '[' + v.map(canonical).join(',') + ']';
  if (v && typeof v === 'object') return '{' + Object.keys(v).sort().map((k) => JSON.stringify(k) + ':' + canonical(v[k])).join(',') + '}';
  return JSON.stringify(v);
}

async function main() {
  fs.mkdirSync(args.out, { recursive: true });
  const session = await launch({ modules: args.modules, chromium: args.chromium,
                                 profileDir: path.join(args.tmp, 'profile') });
  const { browser, page, log } = session;
  const shot = (name) => page.screenshot({ path: path.join(args.out, 'workbench-' + name + '.png'), fullPage: true });
  const step = makeStep(session, () => shot('failure'));
  // For docs/workbench.png: the top of the page in the 1400x1000 viewport.
  const docsShot = async () => {
    await page.evaluate(() => window.scrollTo(0, 0));
    await page.screenshot({ path: path.join(args.out, 'workbench-docs-1400x1000.png') });
  };
  const iaeCell = () => page.$eval('#metric-iae', (e) => e.dataset.value);

  await step('(a) the page loads with no console error, page error or failed request', async () => {
    const response = await page.goto(args.url, { waitUntil: 'load', timeout: 30000 });
    if (!response || response.status() !== 200) throw new Error('GET ' + args.url + ' answered ' + (response && response.status()));
    await waitForPage(session, 'no first redraw (window.pidlab.rendered >= 1)', redrawMs,
                      () => window.pidlab && window.pidlab.rendered >= 1 && window.pidlab.lastResult);
    if (log.errors.length) throw new Error(log.errors[0]);
    await shot('loaded');
  });

  for (const plant of plants) {
    await step('(b) ' + plant + ': the kp slider moves the IAE cell and the step plot to evaluate --json and --samples-csv (1e-12)', async () => {
      await selectPlant(session, plant, redrawMs);
      const before = await iaeCell();
      const at = await page.$eval('#kp-slider', (e) => Number(e.value));
      const { gain } = await moveSlider(session, 'kp', at + 0.137, redrawMs);
      const shown = await page.evaluate(() => ({
        spec: window.pidlab.spec(), result: window.pidlab.lastResult,
        iae: document.getElementById('metric-iae').dataset.value,
        t: Array.from(window.pidlab.plots.step.data[0]), y: Array.from(window.pidlab.plots.step.data[1]),
        frame: window.pidlab.lastSeries.time_scale,
      }));
      if (shown.spec.gains[0] !== gain) throw new Error('pidlab.spec() has kp ' + shown.spec.gains[0] + ', the slider set ' + gain);
      if (shown.iae === before) throw new Error('the IAE cell did not change (' + before + ')');
      const csv = path.join(args.tmp, plant + '.csv');
      const cli = JSON.parse(pidlab(['evaluate', '--spec', specFile(shown.spec), '--json']));
      // The plots' frame is `pidlab plot`'s (the transient fills it): the samples of evaluate on it.
      if (!shown.frame || !(shown.frame.horizon_s > 0)) throw new Error('the series has no time_scale: ' + JSON.stringify(shown.frame));
      pidlab(['evaluate', '--spec', specFile(shown.spec), '--horizon', String(shown.frame.horizon_s),
              '--sample-time', String(shown.frame.sample_time_s), '--json', '--samples-csv', csv]);
      if (canonical(cli.spec) !== canonical(shown.result.spec))
        throw new Error('pidlab.lastResult.spec differs from the spec evaluate --spec echoes: ' +
                        JSON.stringify(shown.result.spec) + ' vs ' + JSON.stringify(cli.spec));
      expectClose('#metric-iae data-value', Number(shown.iae), cli.iae, 1e-12);
      if (shown.iae !== String(cli.iae)) throw new Error('#metric-iae data-value ' + shown.iae + ' is not String(' + cli.iae + ')');
      const samples = readCsv(csv);
      expectSeries('plots.step.data[0] (t)', shown.t, samples.t, 1e-12);
      expectSeries('plots.step.data[1] (y)', shown.y, samples.y, 1e-12);
      await shot(plant);
      return 'kp ' + gain + ', IAE ' + before + ' -> ' + shown.iae + ', ' + shown.y.length + ' samples on ' +
             shown.frame.horizon_s + ' s (' + shown.frame.source + ')';
    });
  }

  await step('(e) #copy-command copies pidlab.command(), #command shows it; run by a shell it gives the page\'s IAE', async () => {
    const command = await page.evaluate(() => window.pidlab.command());
    const shown = await page.$eval('#command', (e) => e.textContent.trim());
    if (shown !== command) throw new Error('#command shows "' + shown + '", pidlab.command() is "' + command + '"');
    await browser.defaultBrowserContext().overridePermissions(new URL(args.url).origin, ['clipboard-read', 'clipboard-write', 'clipboard-sanitized-write']);
    await page.evaluate(() => navigator.clipboard.writeText('(nothing copied yet)'));
    await page.click('#copy-command');
    await waitForPage(session, 'the clipboard did not receive the command', redrawMs,
                      (command) => navigator.clipboard.readText().then((t) => t === command), command);
    const copied = await page.evaluate(() => navigator.clipboard.readText());
    if (!/^pidlab evaluate /.test(copied)) throw new Error('the command is not a pidlab evaluate command: ' + copied);
    // What a user pastes into a shell: the copied text, with this build's pidlab first on the PATH.
    const env = Object.assign({}, process.env, { PATH: path.dirname(args.pidlab) + ':' + process.env.PATH });
    const out = execFileSync('bash', ['-c', copied], { encoding: 'utf8', env, cwd: args.tmp, timeout: 60000 });
    expectClose('the command\'s IAE against #metric-iae', JSON.parse(out).iae, Number(await iaeCell()), 1e-12);
    return copied;
  });

  await step('(e2) the URL\'s hash holds the design once it stops moving, and a new page opened on that URL shows it', async () => {
    await waitForPage(session, 'the hash does not hold the design', redrawMs, () => {
      try {
        const saved = JSON.parse(decodeURIComponent(location.hash.slice(1)));
        return saved.kp === window.pidlab.state.kp && saved.plant === window.pidlab.state.plant;
      } catch (e) { return false; }
    });
    const { url: link, kp, plant } = await page.evaluate(() => ({ url: location.href, kp: window.pidlab.state.kp, plant: window.pidlab.state.plant }));
    const other = await browser.newPage();
    try {
      await other.goto(link, { waitUntil: 'load', timeout: 30000 });
      await other.waitForFunction(() => window.pidlab && window.pidlab.rendered >= 1, { timeout: redrawMs, polling: 50 });
      const shown = await other.evaluate(() => ({ kp: window.pidlab.state.kp, plant: window.pidlab.state.plant,
        drawn: window.pidlab.lastResult.spec.gains[0] }));
      if (shown.kp !== kp || shown.plant !== plant || shown.drawn !== kp)
        throw new Error('the link opened ' + JSON.stringify(shown) + ', not kp ' + kp + ' on ' + plant);
    } finally {
      await other.close();
    }
    return 'kp ' + kp + ' on ' + plant;
  });

  await step('(b2) the Ms bound slider sets max_ms in the spec the page runs; an Ms above it is marked; clearing the box removes it', async () => {
    const moveMs = async (value) => {
      const before = await page.evaluate(() => window.pidlab.rendered);
      await page.evaluate((v) => {
        const r = document.getElementById('max_ms-slider');
        r.value = String(v);
        r.dispatchEvent(new Event('input', { bubbles: true }));
      }, value);
      await waitForPage(session, 'no redraw with max_ms ' + value, redrawMs,
                        (before, v) => window.pidlab.rendered > before && window.pidlab.lastResult.spec.max_ms === v, before, value);
    };
    await moveMs(1.05);
    const box = await page.$eval('#max_ms', (e) => e.value);
    if (box !== '1.05') throw new Error('#max_ms shows "' + box + '" after the slider moved to 1.05');
    const ms = await page.evaluate(() => window.pidlab.lastResult.robustness.ms);
    const marked = await page.$eval('#metric-ms', (e) => e.classList.contains('violated'));
    if (!(ms > 1.05) || !marked) throw new Error('Ms ' + ms + ' against the bound 1.05: marked ' + marked);
    const before = await page.evaluate(() => window.pidlab.rendered);
    await page.evaluate(() => { const b = document.getElementById('max_ms'); b.value = ''; b.dispatchEvent(new Event('change')); });
    await waitForPage(session, 'no redraw after the bound was cleared', redrawMs,
                      (before) => window.pidlab.rendered > before && !('max_ms' in window.pidlab.lastResult.spec && window.pidlab.lastResult.spec.max_ms !== null && isFinite(window.pidlab.lastResult.spec.max_ms)), before);
    return 'Ms ' + ms + ' marked against 1.05, then cleared';
  });

  await step('(c) two pinned designs: two .pinned-design, the diff table, each pin\'s IAE that of its spec', async () => {
    const base = await page.evaluate(() => window.pidlab.pinned.length);
    await page.evaluate(() => window.pidlab.pin());
    const at = await page.$eval('#kp-slider', (e) => Number(e.value));
    await moveSlider(session, 'kp', at - 0.2, redrawMs);
    await page.evaluate(() => window.pidlab.pin());
    const pins = await page.evaluate(() => ({
      pinned: window.pidlab.pinned.map((p) => ({ label: p.label, spec: p.spec, iae: p.result && p.result.iae })),
      designs: document.querySelectorAll('#pinned .pinned-design').length,
      diffRows: document.querySelectorAll('#diff-table tr').length,
      diffText: (document.getElementById('diff-table') || { textContent: '' }).textContent,
    }));
    if (pins.pinned.length !== base + 2) throw new Error('pidlab.pinned has ' + pins.pinned.length + ' designs, want ' + (base + 2));
    if (pins.designs !== base + 2) throw new Error('#pinned has ' + pins.designs + ' .pinned-design children, want ' + (base + 2));
    if (pins.diffRows < 2 || !pins.diffText.trim()) throw new Error('#diff-table is missing or empty (' + pins.diffRows + ' rows)');
    const [a, b] = pins.pinned.slice(-2);
    for (const p of [a, b])
      if (!pins.diffText.includes(p.label)) throw new Error('#diff-table does not name the pin "' + p.label + '"');
    if (canonical(a.spec) === canonical(b.spec)) throw new Error('the two pins have the same spec');
    for (const p of [a, b]) {
      const cli = JSON.parse(pidlab(['evaluate', '--spec', specFile(p.spec), '--json']));
      expectClose('pin "' + p.label + '" IAE', p.iae, cli.iae, 1e-12);
    }
    await shot('pinned');
    await docsShot();  // taken again after the tuning, if it passes
  });

  await step('(d) pidlab.tune({robust: true}) on the stepper motor (kp, kd, tf inside the box) gives the gains of pidlab tune --robust --json', async () => {
    await selectPlant(session, 'stepper_motor', redrawMs);
    const before = await page.evaluate(() => {
      const before = window.pidlab.lastTune;
      window.pidlab.tune({ robust: true });
      return before === undefined ? null : before;
    });
    await waitForPage(session, 'no new pidlab.lastTune', tuneMs,
                      (before) => window.pidlab.lastTune && window.pidlab.lastTune !== before, before);
    const tune = await page.evaluate(() => ({
      reply: window.pidlab.lastTune, status: (document.getElementById('tune-status') || {}).textContent,
      cancel: !!document.getElementById('tune-cancel'), button: !!document.getElementById('tune-button'),
    }));
    if (!tune.button || !tune.cancel) throw new Error('#tune-button or #tune-cancel is missing');
    if (tune.reply.plant !== 'stepper_motor') throw new Error('pidlab.lastTune is for plant ' + tune.reply.plant);
    if (!tune.reply.gains) throw new Error('pidlab.lastTune has no gains: ' + JSON.stringify(tune.reply).slice(0, 300));
    // The same tuning twice: the CLI's flags, and the spec the page's reply echoes.
    const runs = [['tune', '--plant', 'stepper_motor', '--robust', '--json']];
    if (tune.reply.spec) runs.push(['tune', '--spec', specFile(tune.reply.spec), '--json']);
    for (const argv of runs) {
      const cli = JSON.parse(pidlab(argv));
      for (const g of ['kp', 'ki', 'kd', 'tf'])
        if (tune.reply.gains[g] !== cli.gains[g])
          throw new Error('lastTune.gains.' + g + ' ' + tune.reply.gains[g] + ', pidlab ' + argv.join(' ') + ': ' + cli.gains[g]);
    }
    await shot('tuned');
    const g = tune.reply.gains;
    return 'kp ' + g.kp + ', ki ' + g.ki + ', kd ' + g.kd + ', tf ' + g.tf + '; ' + runs.length + ' CLI runs';
  });

  await step(
      '(f) a FOPDT and an integrating plant with dead time: the step, u and load plots hold finite points over the horizon, evaluate --samples-csv\'s y, u and y_load (1e-9)',
      async () => {
        const details = [];
        for (const [num, den, delay] of [['1', '1,1', '0.5'], ['0.2', '1,0', '1']]) {
          const before = await page.evaluate(() => window.pidlab.rendered);
          await page.evaluate((num, den, delay) => {
            window.pidlab.resetPlant({plant: 'custom', num, den, delay});
            Object.assign(window.pidlab.state, {kp: 0.6, ki: 0.15, kd: 0.05, derivative_filter: '0.01'});
            window.pidlab.setDesign({});
          }, num, den, delay);
          await waitForPage(
              session, 'no redraw of the dead-time plant ' + num + '/' + den, redrawMs,
              (before) => window.pidlab.rendered > before && window.pidlab.lastResult.spec.delay > 0, before);
          const shown = await page.evaluate(
              () => ({
                spec: window.pidlab.spec(),
                frame: window.pidlab.lastSeries.time_scale,
                t: Array.from(window.pidlab.plots.step.data[0]),
                y: Array.from(window.pidlab.plots.step.data[1]),
                u: Array.from(window.pidlab.plots.effort.data[1]),
                load: Array.from(window.pidlab.plots.load.data[1]),
                titles: Array.from(document.querySelectorAll('.u-title')).map((e) => e.textContent)
              }));
          for (const key of ['y', 'u', 'load'])
            if (!shown[key].length || !shown[key].every(Number.isFinite))
              throw new Error(key + ' has points that are not finite: ' + shown[key].slice(0, 5));
          const csv = path.join(args.tmp, 'deadtime' + delay + '.csv');
          pidlab([
            'evaluate', '--spec', specFile(shown.spec), '--horizon', String(shown.frame.horizon_s),
            '--sample-time', String(shown.frame.sample_time_s), '--json', '--samples-csv', csv
          ]);
          const samples = readCsv(csv);
          expectSeries('plots.step.data[1] (y)', shown.y, samples.y, 1e-9);
          expectSeries('plots.effort.data[1] (u)', shown.u, samples.u, 1e-9);
          expectSeries('plots.load.data[1] (y_load)', shown.load, samples.y_load, 1e-9);
          if (shown.titles.some((t) => /not computed/.test(t)))
            throw new Error('a plot says: ' + shown.titles.join(' | '));
          details.push(
              num + '/(' + den + ') e^-' + delay + 's: ' + shown.t.length + ' samples to ' +
              shown.frame.horizon_s + ' s');
        }
        await shot('deadtime');
        // docs/workbench-thermal.png: the knob's default design on a thermal plant with dead time, 1280x800.
        await page.setViewport({ width: 1280, height: 800 });
        await page.evaluate(() => window.pidlab.resetPlant({ plant: 'custom', num: '2', den: '60,1', delay: '8' }));
        await page.click('#knob-design');
        await waitForPage(session, 'no default design for the thermal plant', tuneMs, () => {
          const k = window.pidlab.design.knob, r = window.pidlab.lastResult;
          return k.last && !k.running && !k.pending && r && r.spec.delay === 8 && r.gains.kp === k.last.result.gains.kp;
        });
        const thermal = await page.evaluate(() => ({ u: window.pidlab.lastSeries.u, load: window.pidlab.lastSeries.load_y }));
        if (!Array.isArray(thermal.u) || !Array.isArray(thermal.load))
          throw new Error('the thermal design has no u or load response');
        await page.evaluate(() => window.scrollTo(0, 0));
        await page.screenshot({ path: path.join(args.out, 'workbench-thermal.png') });
        await page.setViewport({ width: 1400, height: 1000 });
        details.push('the thermal plant\'s default design drawn (workbench-thermal.png)');
        return details.join('; ');
      });

  await step(
      '(g) "Every other field" holds one input per field of the fields request the page has no control for; a value set there runs, a bad one is refused naming it',
      async () => {
        const got = await page.evaluate(async () => {
          const reply = await new Promise((resolve) => {
            const u = new URL(location.href);
            const ws =
                new WebSocket((u.protocol === 'https:' ? 'wss:' : 'ws:') + '//' + u.host + '/ws' + u.search);
            ws.onopen = () => ws.send(JSON.stringify({id: 1, type: 'fields'}));
            ws.onmessage = (e) => {
              resolve(JSON.parse(e.data));
              ws.close();
            };
          });
          const inputs =
              Array.from(document.querySelectorAll('#fields [data-key]')).map((e) => e.dataset.key);
          return {all: reply.fields.map((f) => f.key), inputs};
        });
        const own = [
          'plant', 'num', 'den', 'model', 'delay', 'stepper', 'gains', 'derivative_filter',
          'setpoint_weights', 'setpoint_filter', 'output_limits', 'loop', 'dt', 'max_ms', 'max_mt',
          'max_noise_gain', 'min_phase_margin', 'monte_carlo', 'spread'
        ];
        const want = got.all.filter((k) => !own.includes(k));
        if (canonical(want) !== canonical(got.inputs))
          throw new Error('inputs ' + got.inputs.join(',') + ', fields ' + want.join(','));
        if (!got.inputs.includes('horizon') || !got.inputs.includes('anti_windup'))
          throw new Error('no horizon or anti_windup input');
        const set = async (key, value) => {
          const before = await page.evaluate(() => window.pidlab.rendered);
          await page.evaluate((key, value) => {
            const e = document.getElementById('field-' + key);
            e.value = value;
            e.dispatchEvent(new Event('change', {bubbles: true}));
          }, key, value);
          return before;
        };
        const before = await set('horizon', '7');
        await waitForPage(
            session, 'no redraw after horizon 7', redrawMs,
            (before) => window.pidlab.rendered > before && window.pidlab.lastResult.spec.horizon === 7,
            before);
        await set('horizon', 'seven');
        await waitForPage(
            session, 'no refusal of horizon "seven"', redrawMs,
            () => /horizon "seven" is not a number/.test(document.getElementById('status').textContent));
        const back = await set('horizon', '');
        await waitForPage(
            session, 'no redraw after the horizon was cleared', redrawMs,
            (back) => window.pidlab.rendered > back && !('horizon' in window.pidlab.lastResult.spec) ||
                (window.pidlab.rendered > back && window.pidlab.lastResult.spec.horizon !== 7),
            back);
        return want.length + ' generated inputs; horizon 7 ran, "seven" refused, cleared';
      });

  await step('pidlab.timings: one entry per redraw, sent <= reply <= drawn, the server\'s time inside the round trip', async () => {
    const { timings, rendered } = await page.evaluate(() => ({ timings: window.pidlab.timings, rendered: window.pidlab.rendered }));
    if (timings.length !== rendered) throw new Error(timings.length + ' timings for ' + rendered + ' redraws');
    for (const t of timings) {
      const ok = ['seq', 'sent_ms', 'reply_ms', 'drawn_ms', 'server_ms'].every((k) => typeof t[k] === 'number') &&
                 t.sent_ms <= t.reply_ms && t.reply_ms <= t.drawn_ms && t.server_ms >= 0 &&
                 t.server_ms <= t.reply_ms - t.sent_ms;
      if (!ok) throw new Error('the entry ' + JSON.stringify(t));
    }
    return rendered + ' redraws';
  });

  await step('no console error, page error or failed request during the whole run', async () => {
    if (log.errors.length) throw new Error(log.errors.length + ' of them, the first: ' + log.errors[0]);
  });
  await docsShot();
  console.log('screenshots in ' + args.out);
  await browser.close();
}

main().catch((e) => {
  console.log('FAIL the browser test itself: ' + (e && e.stack ? e.stack : String(e)));
  process.exit(1);
});
