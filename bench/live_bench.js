// bench/live_bench.sh's browser side: see there.
//   node live_bench.js --url URL --pidlab BIN --modules DIR --chromium BIN --tmp DIR --lcm-url URL --pairs N
'use strict';
const fs = require('fs');
const path = require('path');
const { execFile, spawn } = require('child_process');
const { parseArgs, launch, waitForPage } = require('../tests/browser/page_driver.js');

const args = parseArgs(process.argv.slice(2), ['url', 'pidlab', 'modules', 'chromium', 'tmp', 'lcm-url', 'pairs']);
const median = (a) => { const s = [...a].sort((x, y) => x - y); const m = s.length >> 1; return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2; };

function evaluate(dt, horizon) {
  return new Promise((resolve, reject) => {
    execFile(args.pidlab, ['evaluate', '--backend', 'lcm', '--lcm-url', args['lcm-url'], '--plant', 'oscillator',
      '--gains', '2,1,1.5', '--loop', 'sampled', '--dt', String(dt), '--horizon', String(horizon), '--json'],
    { encoding: 'utf8', maxBuffer: 64 << 20, timeout: 300000 }, (err, out, errText) => {
      if (err) reject(new Error('pidlab evaluate: ' + (errText || err.message).trim())); else resolve(JSON.parse(out));
    });
  });
}

async function main() {
  // The trio, held by launch until the fifo is written.
  const fifo = path.join(args.tmp, 'hold');
  require('child_process').execFileSync('mkfifo', [fifo]);
  const trio = spawn(args.pidlab, ['launch', '--quiet', '--lcm-url', args['lcm-url'], '--', 'bash', '-c', 'echo up; head -c 1 ' + fifo + ' >/dev/null'],
                     { stdio: ['ignore', 'pipe', 'inherit'] });
  await new Promise((resolve, reject) => {
    trio.stdout.on('data', (d) => { if (String(d).includes('up')) resolve(); });
    trio.on('exit', (c) => reject(new Error('pidlab launch exited ' + c)));
  });
  const session = await launch({ modules: args.modules, chromium: args.chromium, profileDir: path.join(args.tmp, 'profile') });
  const { browser, page, log } = session;
  await page.goto(args.url, { waitUntil: 'load', timeout: 30000 });
  await waitForPage(session, 'no server_info', 15000, () => window.pidlab.serverInfo !== undefined && window.pidlab.serverInfo.live);
  const setWatched = async (watched) => {
    await page.click(watched ? '#tab-live' : '#tab-design');
    await waitForPage(session, 'subscription state', 10000, (w) => window.pidlab.live.subscribed === w, watched);
  };
  const rate = { none: [], watched: [] };
  await evaluate(0.001, 2);  // warm-up
  for (let i = 0; i < Number(args.pairs); ++i) {
    for (const mode of ['none', 'watched']) {
      await setWatched(mode === 'watched');
      const r = await evaluate(0.001, 10);
      rate[mode].push(r.steps_per_second);
      console.log('run ' + (2 * i + (mode === 'watched' ? 2 : 1)) + ' ' + mode.padEnd(7) + ' ' + r.steps_per_second.toFixed(0) + ' steps/s');
    }
  }
  const ratio = median(rate.watched) / median(rate.none);
  const pairRatios = rate.watched.map((w, i) => w / rate.none[i]);
  console.log('lockstep steps/s: none median ' + median(rate.none).toFixed(0) + ', watched median ' +
              median(rate.watched).toFixed(0) + ', ratio ' + ratio.toFixed(3) + ' (target >= 0.9); pairs ' +
              pairRatios.map((r) => r.toFixed(2)).join(' ') + ' (median ' + median(pairRatios).toFixed(3) + ')');

  // The page's frame rate while a dt = 1e-4 s trio streams (unpaced: as fast as it goes).
  await setWatched(true);
  const before = await page.evaluate(() => ({ ticks: window.pidlab.live.ticks, frames: window.pidlab.live.frames, drawn: window.pidlab.live.drawn, t: performance.now() }));
  const samples = [];
  const sampler = setInterval(() => page.evaluate(() => window.pidlab.live.fps).then((f) => samples.push(f)).catch(() => {}), 500);
  const r = await evaluate(0.0001, 5);
  clearInterval(sampler);
  const after = await page.evaluate(() => ({ ticks: window.pidlab.live.ticks, frames: window.pidlab.live.frames, drawn: window.pidlab.live.drawn, t: performance.now(), dropped: window.pidlab.live.dropped_frames }));
  const seconds = (after.t - before.t) / 1000;
  const fps = (after.ticks - before.ticks) / seconds;
  const worst = samples.length > 2 ? Math.min(...samples.slice(1)) : fps;
  console.log('10 kHz trio (dt 1e-4 s, ' + (r.spec ? '' : '') + '50000 steps in ' + seconds.toFixed(2) + ' s, ' + r.steps_per_second.toFixed(0) +
              ' steps/s): page ' + fps.toFixed(1) + ' animation frames/s (worst 1 s window ' + worst.toFixed(1) + '), ' +
              (after.frames - before.frames) + ' live frames received, ' + (after.drawn - before.drawn) + ' drawn, ' +
              after.dropped + ' dropped by the server (target >= 30 fps)');
  if (log.errors.length) console.log('page errors: ' + log.errors.join(' | '));
  await browser.close();
  fs.writeFileSync(fifo, 'x');
  await new Promise((resolve) => trio.on('exit', resolve));
  const ok = ratio >= 0.9 && fps >= 30 && !log.errors.length;
  console.log(ok ? 'targets met' : 'TARGET MISSED');
  process.exit(ok ? 0 : 1);
}
main().catch((e) => { console.log('live_bench: ' + (e && e.stack ? e.stack : e)); process.exit(1); });
