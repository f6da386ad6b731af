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
  console.log('screenshots in ' + args.out);
  await browser.close();
}

main().catch((e) => { console.log('FAIL ' + (e && e.stack ? e.stack : e)); process.exit(1); });
