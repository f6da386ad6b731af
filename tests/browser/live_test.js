// browser.live_trio (run by live_test.sh inside its network namespace): the
// Live and Logs tabs in headless Chromium against a trio run by `pidlab
// launch`, read back and compared with pidlab's own tools.
//   node live_test.js --url URL --pidlab BIN --modules DIR --chromium BIN --out DIR --tmp DIR --lcm-url URL
//                     [--parts all|logs]
// --parts logs runs only what needs no live server (a log recorded without
// the page watching, opened, uploaded and scrubbed). Each step prints "ok
// <step>" or "FAIL <step>: <what differed>" and the test stops at a failure.
'use strict';
const fs = require('fs');
const path = require('path');
const { execFileSync, spawn } = require('child_process');
const { parseArgs, launch, waitForPage, makeStep } = require('./page_driver.js');

const args = parseArgs(process.argv.slice(2), ['url', 'pidlab', 'modules', 'chromium', 'out', 'tmp', 'lcm-url']);
const live = (args.parts || 'all') === 'all';
const log25 = path.join(args.tmp, 'run.lcmlog');
const longArgs = ['evaluate', '--backend', 'lcm', '--lcm-url', args['lcm-url'], '--plant', 'oscillator',
  '--gains', '2,1,1.5', '--loop', 'sampled', '--dt', '0.001', '--horizon', '25', '--json'];

function pidlab(argv) {
  return execFileSync(args.pidlab, argv, { encoding: 'utf8', maxBuffer: 256 << 20, timeout: 120000, cwd: args.tmp });
}
// The steps of the log's episode with `steps` steps, as `pidlab replay --csv`
// writes them (17 digits: every double exactly), with its id as text (an
// int64 id is above 2^53: JSON.parse would round it).
function replayCsv(file, steps, pageId) {
  const csv = path.join(args.tmp, 'replay.csv');
  pidlab(['replay', file, '--csv', csv]);
  const byId = new Map();
  for (const line of fs.readFileSync(csv, 'utf8').trim().split('\n').slice(1)) {
    const c = line.split(',');
    if (!byId.has(c[0])) byId.set(c[0], { id: c[0], y: [], u: [], n: [] });
    const e = byId.get(c[0]);
    e.y.push(Number(c[4])); e.u.push(Number(c[5])); e.n.push(Number(c[6]));
  }
  const found = [...byId.values()].filter((e) => e.y.length === steps + 1 && e.id === pageId);
  if (found.length !== 1) throw new Error(found.length + ' episodes of ' + steps + ' steps and id ' + pageId + ' in the log');
  return found[0];
}
// Bit for bit: NaN equals NaN (u and n at total_steps), 0 is not -0.
function sameBits(what, got, want) {
  if (got.length !== want.length) throw new Error(what + ': the page has ' + got.length + ' values, the log ' + want.length);
  for (let i = 0; i < want.length; ++i)
    if (!Object.is(got[i], want[i])) throw new Error(what + '[' + i + ']: page ' + got[i] + ', log ' + want[i]);
}

// A byte offset in the middle of the payload of the lcm-logger event that
// holds byte `target` of `log` (events: sync word 0xEDA1DA01, event number,
// timestamp, channel and payload lengths, channel, payload; big-endian).
function midEvent(log, target) {
  for (let at = 0; at + 28 <= log.length;) {
    if (log.readUInt32BE(at) !== 0xEDA1DA01) throw new Error('no event starts at byte ' + at + ' of the log');
    const channel = log.readInt32BE(at + 20), payload = log.readInt32BE(at + 24);
    const end = at + 28 + channel + payload;
    if (end > target && payload >= 2) return at + 28 + channel + Math.floor(payload / 2);
    at = end;
  }
  throw new Error('no event holds byte ' + target + ' of the log');
}
// The steps an episode of `pidlab replay --json` misses on any stream, as
// inclusive [first, last] ranges over 0..total_steps.
function mergedGaps(episode) {
  const missing = new Uint8Array(episode.total_steps + 1);
  for (const stream of [episode.plant_outputs, episode.commands, episode.disturbance_samples])
    for (const [a, b] of stream.missing) for (let k = Math.max(0, a); k <= b && k < missing.length; ++k) missing[k] = 1;
  const ranges = [];
  for (let k = 0; k < missing.length; ++k) {
    if (!missing[k]) continue;
    const first = k;
    while (k + 1 < missing.length && missing[k + 1]) ++k;
    ranges.push([first, k]);
  }
  return ranges;
}

// Runs `pidlab launch LAUNCH_ARGS -- bash -c SCRIPT`; resolves with its
// stdout when it exits 0; `onLine` sees each line of stdout as it comes.
function launchTrio(launchArgs, script, onLine) {
  return new Promise((resolve, reject) => {
    const child = spawn(args.pidlab, ['launch', '--quiet', ...launchArgs, '--', 'bash', '-c', script],
                        { cwd: args.tmp, env: { ...process.env, PIDLAB: args.pidlab } });
    let out = '', err = '', partial = '';
    child.stdout.on('data', (d) => {
      out += d; partial += d;
      let i;
      while ((i = partial.indexOf('\n')) >= 0) { if (onLine) onLine(partial.slice(0, i)); partial = partial.slice(i + 1); }
    });
    child.stderr.on('data', (d) => { err += d; });
    child.on('exit', (code) => (code === 0 ? resolve(out) : reject(new Error('pidlab launch exited ' + code + ': ' + err.trim().split('\n').slice(-3).join(' | ')))));
  });
}

async function main() {
  fs.mkdirSync(args.out, { recursive: true });
  const session = await launch({ modules: args.modules, chromium: args.chromium, profileDir: path.join(args.tmp, 'profile') });
  const { browser, page, log } = session;
  const step = makeStep(session,
    () => page.screenshot({ path: path.join(args.out, 'live-failure.png'), fullPage: true }));

  await step('the page loads; the Live tab subscribes', async () => {
    await page.goto(args.url, { waitUntil: 'load', timeout: 30000 });
    await waitForPage(session, 'no server_info', 15000, () => window.pidlab.serverInfo !== undefined);
    const info = await page.evaluate(() => window.pidlab.serverInfo);
    if (live && !info.live) throw new Error('server_info says live: ' + JSON.stringify(info));
    await page.click('#tab-live');
    if (live) await waitForPage(session, 'the Live tab did not subscribe', 15000, () => window.pidlab.live.subscribed);
    return 'server_info ' + JSON.stringify(info);
  });

  let episodeId = null, liveFinal = null;
  if (live) {
    await step('a 25 s episode at dt = 1 ms by pidlab launch, watched: final y, u, n bit for bit, listed complete', async () => {
      const fifo = path.join(args.tmp, 'hold');
      execFileSync('mkfifo', [fifo]);
      let held = null;
      const running = launchTrio(['--lcm-url', args['lcm-url'], '--log', log25],
        '"$PIDLAB" ' + longArgs.map((a) => "'" + a + "'").join(' ') + ' > long.json && echo LONG_DONE && head -c 1 hold > /dev/null',
        (line) => { if (line === 'LONG_DONE' && held) held(); });
      await new Promise((resolve, reject) => { held = resolve; running.catch(reject); });
      const long = JSON.parse(fs.readFileSync(path.join(args.tmp, 'long.json'), 'utf8'));
      // The newest complete episode on the page is this one.
      await waitForPage(session, 'the episode is not listed complete with its final data', 30000, () => {
        const s = window.pidlab.live.status;
        if (!s || !s.episodes.length) return false;
        const e = s.episodes[s.episodes.length - 1];
        const row = document.querySelector('#live-episodes tr[data-episode-id="' + (e.episode_id_text || e.episode_id) + '"] .status');
        return e.status === 'complete' && row && row.dataset.status === 'complete' && window.pidlab.live.final[e.episode_id];
      });
      liveFinal = await page.evaluate(() => {
        const s = window.pidlab.live.status;
        const e = s.episodes[s.episodes.length - 1];
        const f = window.pidlab.live.final[e.episode_id];
        // The doubles' bytes, base64 (JSON would turn NaN into null).
        const b64 = (a) => { let t = ''; const b = new Uint8Array(a.buffer, a.byteOffset, a.byteLength); for (let i = 0; i < b.length; i += 8192) t += String.fromCharCode(...b.subarray(i, i + 8192)); return btoa(t); };
        return { id: e.episode_id, idText: e.episode_id_text || String(e.episode_id), y: b64(f.y), u: b64(f.u), n: b64(f.n), frames: window.pidlab.live.frames };
      });
      const doubles = (t) => { const b = Buffer.from(t, 'base64'); return Array.from(new Float64Array(b.buffer, b.byteOffset, b.length / 8)); };
      for (const k of ['y', 'u', 'n']) liveFinal[k] = doubles(liveFinal[k]);
      await page.screenshot({ path: path.join(args.out, 'live.png') });
      // Run on the trio while it still runs (launch's COMMAND waits on the fifo).
      await page.click('#tab-design');
      await waitForPage(session, '#run-on-trio is not enabled', 15000, () => !document.getElementById('run-on-trio').disabled);
      await page.click('#run-on-trio');
      await waitForPage(session, 'no trio result', 60000, () => window.pidlab.trio.last !== null);
      const agreement = await page.$eval('#trio-agreement', (a) => ({ bit: a.dataset.bitIdentical, text: a.textContent }));
      const overlaid = await page.evaluate(() => {
        const d = window.pidlab.plots.step.data;
        return d[d.length - 1].filter((v) => v !== null).length;
      });
      await page.screenshot({ path: path.join(args.out, 'live-trio.png'), fullPage: true });
      if (!(overlaid > 0)) throw new Error('the trio\'s y is not on the step plot');
      fs.writeFileSync(fifo, 'x');
      await running;
      if (agreement.bit !== 'true') throw new Error('#trio-agreement: ' + agreement.text);
      episodeId = liveFinal.id;
      return 'IAE ' + long.iae + ', ' + liveFinal.frames + ' frames; #trio-agreement ' + agreement.text + '; ' + overlaid + ' trio points on the step plot';
    });

    await step('the final y, u, n equal the log\'s (pidlab replay --csv) bit for bit', async () => {
      const replay = JSON.parse(pidlab(['replay', '--json', log25]));
      const e = replay.episodes.find((x) => x.episode_id === liveFinal.id);
      if (!e || !e.complete) throw new Error('the log has no complete episode ' + liveFinal.id);
      const want = replayCsv(log25, 25000, liveFinal.idText);
      sameBits('y', liveFinal.y, want.y);
      sameBits('u', liveFinal.u, want.u);
      sameBits('n', liveFinal.n, want.n);
      return want.y.length + ' steps of y, u and n';
    });

    await step('a --realtime episode: the deadline statistics on the page equal evaluate --json\'s realtime', async () => {
      await page.click('#tab-live');
      await launchTrio(['--lcm-url', args['lcm-url'], '--realtime'],
        '"$PIDLAB" evaluate --backend lcm --lcm-url \'' + args['lcm-url'] + '\' --plant oscillator --gains 2,1,1.5 --loop sampled --horizon 1 --json > rt.json');
      const rt = JSON.parse(fs.readFileSync(path.join(args.tmp, 'rt.json'), 'utf8')).realtime;
      if (!rt) throw new Error('evaluate --json printed no realtime object');
      await waitForPage(session, 'no realtime object on the page', 30000, () => {
        const cells = document.querySelectorAll('#live-pacing table.realtime td');
        const s = window.pidlab.live.status;
        return s && s.episodes.length && s.episodes[s.episodes.length - 1].status === 'complete' && cells.length > 0 &&
          document.querySelector('#live-episodes tr:last-child .realtime').dataset.realtime;
      });
      const shown = await page.evaluate(() => {
        const out = {};
        for (const td of document.querySelectorAll('#live-pacing table.realtime td')) out[td.dataset.key] = td.dataset.value;
        return { cells: out, row: JSON.parse(document.querySelector('#live-episodes tr:last-child .realtime').dataset.realtime) };
      });
      for (const [k, v] of Object.entries(rt)) {
        const cell = shown.cells[k] === 'null' ? null : Number(shown.cells[k]);
        if (!Object.is(cell, v) || !Object.is(shown.row[k], v))
          throw new Error(k + ': page ' + shown.cells[k] + ' (row ' + shown.row[k] + '), evaluate --json ' + v);
      }
      if (Object.keys(shown.cells).length !== Object.keys(rt).length) throw new Error('keys differ: ' + Object.keys(shown.cells));
      return JSON.stringify(rt);
    });

    await step('a tuning over the trio: listed with its best so far, done with the gains and objective of tune --json', async () => {
      await launchTrio(['--lcm-url', args['lcm-url']],
        '"$PIDLAB" tune --backend lcm --lcm-url \'' + args['lcm-url'] + '\' --plant oscillator --loop sampled --dt 0.01 ' +
        '--horizon 2 --max-evals 12 --starts 2 --json > tune.json');
      const tuned = JSON.parse(fs.readFileSync(path.join(args.tmp, 'tune.json'), 'utf8'));
      await waitForPage(session, 'no finished tuning in #live-tunings', 30000,
        () => document.querySelector('#live-tunings tbody tr:last-child .status[data-status="done"]'));
      const shown = await page.evaluate(() => {
        const tr = document.querySelector('#live-tunings tbody tr:last-child');
        return { gains: JSON.parse(tr.querySelector('.best-gains').dataset.gains),
          objective: Number(tr.querySelector('.best-objective').dataset.value),
          evaluations: Number(tr.querySelector('.evaluations').textContent) };
      });
      const want = [tuned.gains.kp, tuned.gains.ki, tuned.gains.kd];
      if (!want.every((g, i) => Object.is(shown.gains[i], g)) || !Object.is(shown.objective, tuned.objective))
        throw new Error('page ' + JSON.stringify(shown) + ', tune --json ' + JSON.stringify(want) + ' ' + tuned.objective);
      if (shown.evaluations !== tuned.evaluations)
        throw new Error('#live-tunings says ' + shown.evaluations + ' evaluations, tune --json ' + tuned.evaluations);
      // Every table and the page fit a 1280-pixel window.
      await page.setViewport({ width: 1280, height: 800 });
      const wide = await page.evaluate(() => [...document.querySelectorAll('#view-live table:not(.u-legend)')]
        .map((e) => ({ id: e.id || e.className, right: e.getBoundingClientRect().right }))
        .filter((e) => e.right > 1280));
      await page.screenshot({ path: path.join(args.out, 'live-1280.png') });
      await page.setViewport({ width: 1400, height: 1000 });
      if (wide.length) throw new Error('wider than 1280 px: ' + JSON.stringify(wide));
      return shown.evaluations + ' evaluations (tune --json\'s), best ' + JSON.stringify(shown.gains) + '; every table within 1280 px';
    });

    await step('a relay autotune over the trio: its cycles and Ku on the page equal autotune --json\'s, its verdict among the tunings', async () => {
      await launchTrio(['--lcm-url', args['lcm-url']],
        '"$PIDLAB" autotune --backend lcm --lcm-url \'' + args['lcm-url'] + '\' --num 1 --den 1,1 --delay 0.5 --dt 0.001 ' +
        '--gains 1,1,0 --json > autotune.json');
      const at = JSON.parse(fs.readFileSync(path.join(args.tmp, 'autotune.json'), 'utf8'));
      await waitForPage(session, 'no finished relay in #live-relay', 30000,
        () => document.querySelector('#live-relay tbody tr .relay-phase[data-phase="done"]'));
      const shown = await page.evaluate(() => {
        const tr = [...document.querySelectorAll('#live-relay tbody tr')]
          .find((r) => r.querySelector('.relay-phase').dataset.phase === 'done');
        return { ku: Number(tr.querySelector('.relay-ku').dataset.ku), cycles: Number(tr.querySelector('.relay-cycles').dataset.cycles),
          model: tr.querySelector('.relay-model').textContent, why: tr.querySelector('.relay-why').title };
      });
      if (!Object.is(shown.ku, at.estimates.ku) || shown.cycles !== at.experiment.cycles.length || shown.why !== at.experiment.why)
        throw new Error('page ' + JSON.stringify(shown) + ', autotune --json Ku ' + at.estimates.ku + ', ' +
          at.experiment.cycles.length + ' cycles, ' + at.experiment.why);
      await waitForPage(session, 'no autotune verdict in #live-tunings', 30000,
        () => [...document.querySelectorAll('#live-tunings tbody tr')]
          .some((tr) => tr.textContent.includes('autotune optimal') && tr.querySelector('.status[data-status="done"]')));
      const verdict = await page.evaluate(() => {
        const tr = [...document.querySelectorAll('#live-tunings tbody tr')].find((r) => r.textContent.includes('autotune optimal'));
        return { gains: JSON.parse(tr.querySelector('.best-gains').dataset.gains), ms: Number(tr.querySelector('.best-objective').dataset.value) };
      });
      const want = [at.gains.kp, at.gains.ki, at.gains.kd];
      if (!at.adopted || !want.every((g, i) => Object.is(verdict.gains[i], g)) || !Object.is(verdict.ms, at.design.ms))
        throw new Error('verdict ' + JSON.stringify(verdict) + ', autotune --json ' + JSON.stringify(want) + ' Ms ' + at.design.ms);
      await page.setViewport({ width: 1280, height: 800 });
      const wide = await page.evaluate(() => [...document.querySelectorAll('#view-live table:not(.u-legend)')]
        .map((e) => ({ id: e.id || e.className, right: e.getBoundingClientRect().right }))
        .filter((e) => e.right > 1280));
      await page.screenshot({ path: path.join(args.out, 'live-relay.png') });
      await page.setViewport({ width: 1400, height: 1000 });
      if (wide.length) throw new Error('wider than 1280 px: ' + JSON.stringify(wide));
      return 'Ku ' + shown.ku + ', ' + shown.cycles + ' cycles, ' + shown.model + '; adopted ' + JSON.stringify(verdict.gains) + ', Ms ' + verdict.ms;
    });
  } else {
    await step('(logs only) a 25 s episode at dt = 1 ms recorded by pidlab launch --log', async () => {
      await launchTrio(['--lcm-url', args['lcm-url'], '--log', log25], '"$PIDLAB" ' + longArgs.map((a) => "'" + a + "'").join(' ') + ' > long.json');
      return fs.statSync(log25).size + ' bytes';
    });
  }

  await step('the log opened by path (log_open) and scrubbed: #log-iae equals pidlab replay --json', async () => {
    const replay = JSON.parse(pidlab(['replay', '--json', log25]));
    const index = replay.episodes.findIndex((x) => (episodeId === null ? x.total_steps === 25000 : x.episode_id === episodeId));
    const want = replay.episodes[index].evaluation.iae;
    await page.click('#tab-logs');
    await page.$eval('#log-path', (el) => { el.value = 'run.lcmlog'; });
    await page.click('#log-open');
    await waitForPage(session, 'the log\'s episodes are not listed', 30000, (n) => document.querySelectorAll('#log-episodes tbody tr').length === n, replay.episodes.length);
    await page.click('#log-episodes tbody tr[data-index="' + index + '"]');
    await waitForPage(session, 'the episode is not shown', 30000, () => document.getElementById('log-iae').dataset.value);
    const iae = await page.$eval('#log-iae', (e) => e.dataset.value);
    if (!Object.is(Number(iae), want)) throw new Error('#log-iae ' + iae + ', pidlab replay --json ' + want);
    const listed = await page.evaluate(() => window.pidlab.logs.log.episodes);
    if (JSON.stringify(listed) !== JSON.stringify(replay.episodes)) throw new Error('the log_open episodes differ from pidlab replay --json\'s');
    // Scrub: the range input moves the cursor of every plot to step k.
    const scrub = await page.evaluate(() => {
      const r = document.getElementById('log-scrub');
      r.value = '12345';
      r.dispatchEvent(new Event('input', { bubbles: true }));
      const s = window.pidlab.logs.episode.series;
      return { cursor: window.pidlab.logs.cursor, text: document.getElementById('log-cursor').textContent, y: s.y[12345],
               lefts: Array.from(document.querySelectorAll('#log-plots .u-cursor-x')).map((e) => e.style.transform || e.style.left) };
    });
    if (scrub.cursor !== 12345 || !scrub.text.startsWith('k = 12345, t = 12.345 s')) throw new Error('scrub: ' + JSON.stringify(scrub));
    if (scrub.lefts.length !== 3 || new Set(scrub.lefts).size !== 1) throw new Error('the three plots\' cursors differ: ' + scrub.lefts);
    await page.screenshot({ path: path.join(args.out, 'logs.png') });
    return 'IAE ' + iae + '; ' + scrub.text;
  });

  await step('"Identify this episode": the Design tab fits it as pidlab identify --log --episode --model p1d --json does', async () => {
    await page.evaluate(() => { document.getElementById('data-model').value = 'p1d'; document.getElementById('data-u0').value = ''; });
    await page.click('#log-identify');
    await waitForPage(session, 'no fit of the episode', 90000, () => window.pidlab.design && window.pidlab.design.fit);
    const fit = await page.evaluate(() => window.pidlab.design.fit);
    // The episode's id, an int64 past a double's 2^53, read exactly from pidlab replay --json by Python.
    const index = await page.evaluate(() => window.pidlab.logs.episode.index);
    const exactId = execFileSync('/usr/bin/python3', ['-c', 'import json, subprocess, sys; ' +
      'print(json.loads(subprocess.run([sys.argv[1], "replay", "--json", sys.argv[2]], capture_output=True).stdout)["episodes"][int(sys.argv[3])]["episode_id"])',
      args.pidlab, log25, String(index)], { encoding: 'utf8' }).trim();
    const cli = JSON.parse(pidlab(['identify', '--log', log25, '--episode', exactId, '--model', 'p1d', '--json', '--quiet']));
    for (const [name, p] of Object.entries(cli.parameters))
      if (!Object.is(fit.result.parameters[name].value, p.value)) throw new Error(name + ': page ' + fit.result.parameters[name].value + ', CLI ' + p.value);
    if (fit.result.source.episode !== cli.source.episode) throw new Error('episode ' + fit.result.source.episode + ', CLI ' + cli.source.episode);
    const view = await page.evaluate(() => window.pidlab.view);
    await page.click('#tab-logs');
    if (view !== 'design') throw new Error('the fit is not shown on the Design tab');
    return 'episode ' + exactId + ', ' + Object.entries(cli.parameters).map(([k, p]) => k + ' ' + p.value).join(', ');
  });

  await step('the same log uploaded (POST /api/upload): the same IAE; a path outside --log-dir is refused', async () => {
    const bytes = fs.readFileSync(log25).toString('base64');
    const got = await page.evaluate(async (b64) => {
      const raw = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
      const reply = await window.pidlab.logs.upload(new File([raw], 'uploaded.lcmlog'));
      const ep = await window.pidlab.logs.openEpisode(0);
      let refused = '';
      try { await window.pidlab.logs.openPath('../../etc/passwd'); } catch (e) { refused = e.message; }
      return { name: reply.name, iae: ep.replay.evaluation.iae, shown: document.getElementById('log-iae').dataset.value, refused };
    }, bytes);
    const replay = JSON.parse(pidlab(['replay', '--json', log25]));
    const want = replay.episodes[0].evaluation.iae;
    if (!Object.is(got.iae, want) || !Object.is(Number(got.shown), want)) throw new Error('uploaded: ' + JSON.stringify(got) + ', replay ' + want);
    if (!/outside the log directory/.test(got.refused)) throw new Error('../../etc/passwd: ' + (got.refused || 'opened'));
    await page.evaluate(() => { document.getElementById('log-status').textContent = ''; });
    return got.name + ', refused: ' + got.refused;
  });

  await step('the log cut mid-event, uploaded: the page shows what pidlab replay --json reads of the same cut file', async () => {
    const whole = fs.readFileSync(log25);
    // A third in: inside the 25 s episode's steps, the log's first third and more.
    const at = midEvent(whole, Math.floor(whole.length / 3));
    const cutFile = path.join(args.tmp, 'cut.lcmlog');
    fs.writeFileSync(cutFile, whole.subarray(0, at));
    const replay = JSON.parse(pidlab(['replay', '--json', cutFile]));
    // The cut is inside an event, wherever the run's timing put the events.
    if (replay.clean_end !== false || replay.file_bytes !== at) throw new Error('pidlab replay --json of the cut file: clean_end ' + replay.clean_end + ', file_bytes ' + replay.file_bytes + ' (cut at ' + at + ')');
    if (!replay.episodes.length) throw new Error('pidlab replay --json lists no episode before byte ' + at);
    const b64 = whole.subarray(0, at).toString('base64');
    const shown = await page.evaluate(async (b) => {
      const raw = Uint8Array.from(atob(b), (c) => c.charCodeAt(0));
      await window.pidlab.logs.upload(new File([raw], 'cut.lcmlog'));
      const gaps = [];
      for (let i = 0; i < window.pidlab.logs.log.episodes.length; ++i) {
        await window.pidlab.logs.openEpisode(i);
        gaps.push(JSON.parse(document.getElementById('log-marks').dataset.gaps));
      }
      return { log: window.pidlab.logs.log, summary: document.getElementById('log-summary').textContent, gaps };
    }, b64);
    for (const key of Object.keys(replay)) {
      if (key === 'log') continue;  // the path: the page has the upload's name
      if (JSON.stringify(shown.log[key]) !== JSON.stringify(replay[key]))
        throw new Error('log_open ' + key + ' ' + JSON.stringify(shown.log[key]).slice(0, 200) + ', pidlab replay --json ' + JSON.stringify(replay[key]).slice(0, 200));
    }
    if (!shown.summary.includes('NOT read cleanly to the end')) throw new Error('#log-summary: ' + shown.summary);
    const want = replay.episodes.map(mergedGaps);
    shown.gaps.forEach((g, i) => {
      if (JSON.stringify(g) !== JSON.stringify(want[i]))
        throw new Error('episode ' + i + '\'s gaps on the page ' + JSON.stringify(g).slice(0, 200) + ', pidlab replay --json ' + JSON.stringify(want[i]).slice(0, 200));
    });
    return 'cut at byte ' + at + ' of ' + whole.length + ': ' + replay.events + ' events, ' +
      replay.episodes.map((e, i) => 'episode ' + i + ' ' + (e.complete ? 'complete' : 'gaps ' + JSON.stringify(want[i]).slice(0, 80))).join(', ');
  });

  await step('no console error, page error or failed request during the whole run', async () => {
    if (log.errors.length) throw new Error(log.errors.length + ' of them, the first: ' + log.errors[0]);
  });
  await browser.close();
}

main().catch((e) => {
  console.log('FAIL the browser test itself: ' + (e && e.stack ? e.stack : String(e)));
  process.exit(1);
});
