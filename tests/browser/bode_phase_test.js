// browser.bode_phase (run by bode_phase_test.sh inside its network namespace):
// the Bode plot of three dead-time loops as the page draws it, read back from
// the chart (uPlot's data and the phase axis's scale).
//   node bode_phase_test.js --url URL --modules DIR --chromium BIN --out DIR --tmp DIR
// Each step prints "ok   <step>" or "FAIL <step>: <what differed>".
'use strict';
const path = require('path');
const { parseArgs, launch, waitForPage, makeStep } = require('./page_driver.js');

const args = parseArgs(process.argv.slice(2), ['url', 'modules', 'chromium', 'out', 'tmp']);
const redrawMs = 20000;  // one evaluation and redraw; generous for a loaded machine
// The designs, as the page's form holds them (its address: #STATE); stable PI(D) loops.
const loops = [
  { name: 'tank', state: { plant: 'custom', num: '0.8', den: '1200,130,1', delay: '150', kp: 0.5, ki: 0.5 / 120, kd: 5, derivative_filter: '1' } },
  { name: 'motor', state: { plant: 'custom', num: '4', den: '0.0014,0.354,1', delay: '0.025', kp: 1.75, ki: 8.75, kd: 0.007, derivative_filter: '0.0004' } },
  { name: 'integrating', state: { plant: 'custom', num: '1', den: '1,0', delay: '1', kp: 0.5, ki: 0.0625, kd: 0 } },
  { name: 'tank sampled', state: { plant: 'custom', num: '0.8', den: '1200,130,1', delay: '150', kp: 0.5, ki: 0.5 / 120, kd: 5, derivative_filter: '1', loop: 'sampled', dt: '4' } },
];

async function main() {
  const session = await launch({ modules: args.modules, chromium: args.chromium, profileDir: path.join(args.tmp, 'profile') });
  const { browser, page } = session;
  await page.setViewport({ width: 1280, height: 800 });
  const step = makeStep(session, () => page.screenshot({ path: path.join(args.out, 'bode-failure.png'), fullPage: true }));

  for (const loop of loops) {
    await step(loop.name + ': the drawn phase is l_phase_deg, no neighbours more than 180 deg apart, its axis clipped around the crossovers', async () => {
      await page.goto('about:blank');
      await page.goto(args.url + '#' + encodeURIComponent(JSON.stringify(loop.state)), { waitUntil: 'load', timeout: 30000 });
      await waitForPage(session, 'no redraw of the ' + loop.name, redrawMs, (delay) => {
        const p = window.pidlab;
        return p && p.rendered >= 1 && p.lastResult && p.lastResult.spec && p.lastResult.spec.delay === delay && p.lastSeries;
      }, Number(loop.state.delay));
      const shown = await page.evaluate(() => {
        const f = window.pidlab.plots.freq;
        return { w: Array.from(f.data[0]), phase: Array.from(f.data[6]), served: window.pidlab.lastSeries.l_phase_deg,
          stable: window.pidlab.lastResult.stable, scale: [f.scales.deg.min, f.scales.deg.max],
          view: f.pidlabPhase, crossovers: f.pidlabCrossovers, loop: window.pidlab.lastSeries.frequency_loop };
      });
      if (!shown.stable) throw new Error('the design is not a stable loop');
      if (shown.loop !== (loop.state.loop || 'continuous')) throw new Error('the frequency plots are of the ' + shown.loop + ' loop');
      if (!Array.isArray(shown.served) || shown.served.length !== shown.w.length) throw new Error('the series has no l_phase_deg on its grid');
      let largest = 0, at = 0;
      for (let i = 0; i < shown.phase.length; i++) {
        if (shown.phase[i] !== shown.served[i]) throw new Error('drawn phase[' + i + '] ' + shown.phase[i] + ' is not the served ' + shown.served[i]);
        if (i > 0 && Math.abs(shown.phase[i] - shown.phase[i - 1]) > largest) { largest = Math.abs(shown.phase[i] - shown.phase[i - 1]); at = shown.w[i]; }
      }
      if (!(largest <= 180)) throw new Error('the drawn phase jumps by ' + largest + ' deg at ' + at + ' rad/s');
      const [lo, hi] = shown.scale;
      if (!(isFinite(lo) && isFinite(hi) && lo < -180 && hi > -180)) throw new Error('the phase axis ' + lo + '..' + hi + ' does not hold -180');
      if (!shown.crossovers.length) throw new Error('no crossover reached the chart');
      const least = Math.min(...shown.phase);
      // The delay's phase runs far below the view at the top of the grid: the view is clipped and says so.
      if (!(least < lo) || !shown.view.exits.some((e) => e.side === 'below'))
        throw new Error('the phase (down to ' + least + ') is not clipped below ' + lo + ' with a note: ' + JSON.stringify(shown.view.exits));
      if (!(hi - lo <= 1080)) throw new Error('the phase view ' + lo + '..' + hi + ' spans more than three turns');
      if (loop.name === 'tank') {
        await page.$eval('#plot-freq', (e) => e.scrollIntoView());
        const el = await page.$('#plot-freq');
        await el.screenshot({ path: path.join(args.out, 'bode-tank.png') });
      }
      return shown.w.length + ' points, phase ' + least.toFixed(0) + '..' + Math.max(...shown.phase).toFixed(0) +
        ' deg, largest step ' + largest.toFixed(1) + ' deg, view ' + lo + '..' + hi + ', ' + shown.view.exits.length + ' clipped stretch(es)';
    });
  }
  // A pinned design draws its phase of L too (issue 58): pin the tank, move
  // its kp, and read the pin's phase series back, on the current grid.
  await step(
      'tank pinned: its phase of L is drawn beside the current one, its own served phase on this grid',
      async () => {
        const tank = loops[0];
        await page.goto('about:blank');
        await page.goto(
            args.url + '#' + encodeURIComponent(JSON.stringify(tank.state)),
            {waitUntil: 'load', timeout: 30000});
        await waitForPage(session, 'no redraw of the tank', redrawMs, () => {
          const p = window.pidlab;
          return p && p.rendered >= 1 && p.lastSeries && p.lastResult && p.lastResult.spec.delay === 150;
        });
        await page.evaluate(() => window.pidlab.pin('tank kp 0.5'));
        await waitForPage(
            session, 'the pin did not arrive', redrawMs,
            () => window.pidlab.pinned.length === 1 && window.pidlab.pinned[0].series);
        const before = await page.evaluate(() => window.pidlab.rendered);
        await page.evaluate(() => {
          const e = document.getElementById('kp');
          e.value = '0.3';
          e.dispatchEvent(new Event('input', {bubbles: true}));
          e.dispatchEvent(new Event('change', {bubbles: true}));
        });
        await waitForPage(
            session, 'no redraw after kp 0.3', redrawMs,
            (n) => window.pidlab.rendered > n && window.pidlab.lastResult.spec.gains[0] === 0.3, before);
        const shown = await page.evaluate(() => {
          const f = window.pidlab.plots.freq, pin = window.pidlab.pinned[0];
          const k = f.series.findIndex((s) => s.label === pin.label + ' phase L deg');
          return {
            k,
            labels: f.series.map((s) => s.label),
            w: Array.from(f.data[0]),
            drawn: k > 0 ? Array.from(f.data[k]) : [],
            current: Array.from(f.data[6]),
            pinW: pin.series.w,
            pinPhase: pin.series.l_phase_deg
          };
        });
        if (shown.k < 0) throw new Error('no pinned phase series among ' + JSON.stringify(shown.labels));
        // The pin's grid is its own: at each of this grid's frequencies inside
        // it, the drawn pin phase is its served phase between its two nearest
        // frequencies, linear in log w (the served phase is continuous).
        let checked = 0, differs = 0;
        for (let i = 0; i < shown.w.length; i++) {
          const x = shown.w[i];
          const j =
              shown.pinW.findIndex((v, k) => k + 1 < shown.pinW.length && v <= x && x <= shown.pinW[k + 1]);
          if (j >= 0 && shown.pinPhase[j] !== null && shown.pinPhase[j + 1] !== null) {
            const f = (Math.log(x) - Math.log(shown.pinW[j])) /
                (Math.log(shown.pinW[j + 1]) - Math.log(shown.pinW[j]));
            const want = shown.pinPhase[j] + f * (shown.pinPhase[j + 1] - shown.pinPhase[j]);
            if (!(Math.abs(shown.drawn[i] - want) <= 1e-9 * Math.max(1, Math.abs(want))))
              throw new Error(
                  'pin phase at ' + x + ' rad/s: drawn ' + shown.drawn[i] + ', its served phase there ' +
                  want);
            checked++;
          }
          if (shown.drawn[i] !== null && shown.current[i] !== null &&
              Math.abs(shown.drawn[i] - shown.current[i]) > 1e-6)
            differs++;
        }
        if (checked < shown.w.length / 2)
          throw new Error('only ' + checked + ' of ' + shown.w.length + ' points inside the pin\'s grid');
        const finite = shown.drawn.filter((v) => v !== null && isFinite(v)).length;
        if (finite < shown.w.length / 2)
          throw new Error('only ' + finite + ' of ' + shown.w.length + ' pinned phase points drawn');
        if (!differs)
          throw new Error('the pinned phase is the current one: the pin draws nothing of its own');
        return finite + ' of ' + shown.w.length + ' points drawn, ' + checked +
            ' checked against the pin\'s served phase, ' + differs + ' apart from the current design';
      });
  console.log('screenshots in ' + args.out);
  await browser.close();
}

main().catch((e) => { console.log('FAIL ' + (e && e.stack ? e.stack : e)); process.exit(1); });
