// bench/live_bench.sh's browser side: see there.
//   node live_bench.js --url URL --pidlab BIN --modules DIR --chromium BIN --tmp DIR --lcm-url URL --pairs N
'use strict';
const fs = require('fs');
const path = require('path');
const { execFile, spawn } = require('child_process');
const { parseArgs, launch, waitForPage } = require('../tests/browser/page_driver.js');

const args = parseArgs(process.argv.slice(2), ['url', 'pidlab', 'modules', 'chromium', 'tmp', 'lcm-url', 'pairs', 'server-pid']);
// The CPU seconds (user + system) process PID has used so far.
function cpuSeconds(pid) {
  const stat = fs.readFileSync('/proc/' + pid + '/stat', 'utf8');
  const f = stat.slice(stat.lastIndexOf(')') + 2).split(' ');
  return (Number(f[11]) + Number(f[12])) / 100;  // utime, stime in clock ticks (USER_HZ 100)
}
// The CPU seconds of process ROOT and all its descendants (Chromium's processes).
function treeCpuSeconds(root) {
  const parent = new Map();
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d)) continue;
    try {
      const stat = fs.readFileSync('/proc/' + d + '/stat', 'utf8');
      parent.set(Number(d), Number(stat.slice(stat.lastIndexOf(')') + 2).split(' ')[1]));
    } catch (e) { /* gone meanwhile */ }
  }
  let total = 0;
  for (const pid of parent.keys()) {
    let p = pid;
    while (p > 1 && p !== root) p = parent.get(p) || 0;
    if (p === root) { try { total += cpuSeconds(pid); } catch (e) { /* gone */ } }
  }
  return total;
}
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
  const cpu = { none: [], watched: [] };  // the server's CPU microseconds per lockstep step
  const browserCpu = { none: [], watched: [] };  // Chromium's, all its processes
  const chromium = browser.process().pid;
  await evaluate(0.001, 2);  // warm-up
  for (let i = 0; i < Number(args.pairs); ++i) {
    for (const mode of ['none', 'watched']) {
      await setWatched(mode === 'watched');
      const cpu0 = cpuSeconds(args['server-pid']), browser0 = treeCpuSeconds(chromium);
      const r = await evaluate(0.001, 10);
      const perStep = ((cpuSeconds(args['server-pid']) - cpu0) / 10000) * 1e6;
      browserCpu[mode].push(((treeCpuSeconds(chromium) - browser0) / 10000) * 1e6);
      rate[mode].push(r.steps_per_second);
      cpu[mode].push(perStep);
      console.log('run ' + (2 * i + (mode === 'watched' ? 2 : 1)) + ' ' + mode.padEnd(7) + ' ' + r.steps_per_second.toFixed(0) +
                  ' steps/s, server ' + perStep.toFixed(1) + ' us CPU per step, Chromium ' +
                  browserCpu[mode][browserCpu[mode].length - 1].toFixed(1) + ' us');
    }
  }
  const ratio = median(rate.watched) / median(rate.none);
  console.log('server CPU per step (10 ms resolution over 10000 steps: 1 us): none median ' + median(cpu.none).toFixed(1) +
              ' us, watched median ' + median(cpu.watched).toFixed(1) + ' us; Chromium none ' +
              median(browserCpu.none).toFixed(1) + ' us, watched ' + median(browserCpu.watched).toFixed(1) + ' us');
  const pairRatios = rate.watched.map((w, i) => w / rate.none[i]);
  console.log('lockstep steps/s: none median ' + median(rate.none).toFixed(0) + ', watched median ' +
              median(rate.watched).toFixed(0) + ', ratio ' + ratio.toFixed(3) + ' (target >= 0.9); pairs ' +
              pairRatios.map((r) => r.toFixed(2)).join(' ') + ' (median ' + median(pairRatios).toFixed(3) + ')');

  // The page's frame rate while a dt = 1e-4 s trio streams (unpaced: as fast as it goes), counted by
  // an animation-frame loop the benchmark adds to the page for this part only (the page itself asks
  // for an animation frame only when a frame waits to be drawn): at least 30 a second means the
  // frames and statuses arriving never hold the page's main thread.
  await setWatched(true);
  await page.evaluate(() => {
    const m = { ticks: 0, times: [], worst: Infinity, running: true };
    window.__fps = m;
    const tick = (now) => {
      m.ticks += 1;
      m.times.push(now);
      while (m.times.length && m.times[0] < now - 1000) m.times.shift();
      if (m.times.length > 1 && now - m.times[0] > 900)
        m.worst = Math.min(m.worst, ((m.times.length - 1) * 1000) / (m.times[m.times.length - 1] - m.times[0]));
      if (m.running) requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  });
  const before = await page.evaluate(() => ({ ticks: window.__fps.ticks, frames: window.pidlab.live.frames, drawn: window.pidlab.live.drawn, t: performance.now() }));
  const r = await evaluate(0.0001, 5);
  const after = await page.evaluate(() => {
    window.__fps.running = false;
    return { ticks: window.__fps.ticks, worst: window.__fps.worst, frames: window.pidlab.live.frames, drawn: window.pidlab.live.drawn, t: performance.now(), dropped: window.pidlab.live.dropped_frames };
  });
  const seconds = (after.t - before.t) / 1000;
  const fps = (after.ticks - before.ticks) / seconds;
  const worst = Number.isFinite(after.worst) ? after.worst : fps;
  console.log('10 kHz trio (dt 1e-4 s, 50000 steps in ' + seconds.toFixed(2) + ' s, ' + r.steps_per_second.toFixed(0) +
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
