// What the browser test and the interactivity benchmark share: launching
// Debian's Chromium through puppeteer-core (nothing is downloaded), recording
// what the page logs, and moving a gain slider the way a hand does (set the
// value, dispatch `input`) until the page has redrawn for that gain. The page's
// side of the contract is docs/workbench.md: `#kp-slider`, `window.pidlab`.
'use strict';
const path = require('path');

// --key value pairs; every key in `required` must be given.
function parseArgs(argv, required) {
  const args = {};
  for (let i = 0; i < argv.length; i += 2) {
    if (!argv[i].startsWith('--') || i + 1 >= argv.length) throw new Error('bad argument ' + argv[i]);
    args[argv[i].slice(2)] = argv[i + 1];
  }
  for (const key of required) if (!(key in args)) throw new Error('missing --' + key);
  return args;
}

// Starts headless Chromium at 1400x1000 and opens a tab whose console, page
// errors and failed or refused requests are kept in `log`.
async function launch({ modules, chromium, profileDir }) {
  const puppeteer = require(path.join(modules, 'puppeteer-core'));
  const browser = await puppeteer.launch({
    executablePath: chromium,
    headless: true,
    userDataDir: profileDir,
    defaultViewport: { width: 1400, height: 1000 },
    timeout: 60000,
    protocolTimeout: 120000,
    // Root in a network namespace of its own: no sandbox; nothing that would
    // reach out (updates, metrics, sync) and nothing shared in /dev/shm.
    args: ['--no-sandbox', '--disable-dev-shm-usage', '--disable-gpu', '--no-first-run',
           '--no-default-browser-check', '--disable-background-networking', '--disable-component-update',
           '--disable-sync', '--disable-extensions', '--metrics-recording-only', '--mute-audio'],
  });
  const page = await browser.newPage();
  const log = { lines: [], errors: [] };
  const note = (line, isError) => {
    log.lines.push(line);
    if (isError) log.errors.push(line);
  };
  page.on('console', (m) => {
    const where = m.location() && m.location().url ? ' (' + m.location().url + ':' + m.location().lineNumber + ')' : '';
    note('console.' + m.type() + ': ' + m.text() + where, m.type() === 'error' || m.type() === 'assert');
  });
  page.on('pageerror', (e) => note('page error: ' + (e && e.message ? e.message : String(e)), true));
  page.on('requestfailed', (r) => note('request failed: ' + r.url() + ' ' + (r.failure() ? r.failure().errorText : ''), true));
  page.on('response', (r) => { if (r.status() >= 400) note('HTTP ' + r.status() + ': ' + r.url(), true); });
  return { browser, page, log };
}

// Waits until FN(...ARGS) is true in the page, polling every 10 ms; fails at
// once, naming it, when the page logs an error meanwhile, and after TIMEOUT_MS
// with WHAT.
async function waitForPage({ page, log }, what, timeoutMs, fn, ...args) {
  const errorsBefore = log.errors.length;
  let timer;
  const error = new Promise((resolve, reject) => {
    timer = setInterval(() => {
      if (log.errors.length > errorsBefore) reject(new Error(what + ': the page logged "' + log.errors[errorsBefore] + '"'));
    }, 20);
  });
  const done = page.waitForFunction(fn, { timeout: timeoutMs, polling: 10 }, ...args)
      .catch(() => { throw new Error(what + ' within ' + timeoutMs + ' ms'); });
  error.catch(() => {});
  done.catch(() => {});
  try {
    await Promise.race([done, error]);
  } finally {
    clearInterval(timer);
  }
}

// Sets `#NAME-slider` of SESSION's page to VALUE (log10 of the gain) and
// dispatches `input`, then waits until the page has redrawn after a reply for
// that gain: pidlab.rendered has advanced and pidlab.lastResult's spec carries
// the gain the slider set, Number(10^value .toPrecision(6)) as the contract
// says. Returns {gain, inputMs} (inputMs: performance.now() at the dispatch).
async function moveSlider(session, name, value, timeoutMs) {
  const moved = await session.page.evaluate((name, value) => {
    const slider = document.getElementById(name + '-slider');
    const before = window.pidlab.rendered;
    slider.value = String(value);
    const inputMs = performance.now();
    slider.dispatchEvent(new Event('input', { bubbles: true }));
    return { before, inputMs, gain: Number(Math.pow(10, Number(slider.value)).toPrecision(6)) };
  }, name, value);
  const index = { kp: 0, ki: 1, kd: 2 }[name];
  await waitForPage(session, 'no redraw for ' + name + ' = ' + moved.gain, timeoutMs, (before, gain, index) => {
    const p = window.pidlab;
    return p.rendered > before && p.lastResult && p.lastResult.spec && p.lastResult.spec.gains &&
        p.lastResult.spec.gains[index] === gain;
  }, moved.before, moved.gain, index);
  return { gain: moved.gain, inputMs: moved.inputMs };
}

// Selects PLANT in `#plant` (a `change` event) and waits for the redraw of its result.
async function selectPlant(session, plant, timeoutMs) {
  const before = await session.page.evaluate((plant) => {
    const select = document.getElementById('plant');
    const before = window.pidlab.rendered;
    select.value = plant;
    select.dispatchEvent(new Event('change', { bubbles: true }));
    return before;
  }, plant);
  await waitForPage(session, 'no redraw for plant ' + plant, timeoutMs, (before, plant) => {
    const p = window.pidlab;
    return p.rendered > before && p.lastResult && p.lastResult.spec && p.lastResult.spec.plant === plant;
  }, before, plant);
}

// A test step: prints "ok   NAME [detail]", or on failure "FAIL NAME: why", the page's console and a
// screenshot (failureShot()), then closes the browser and exits 1.
function makeStep({ browser, log }, failureShot) {
  return async (name, body) => {
    try {
      const detail = await body();
      console.log('ok   ' + name + (detail ? ' [' + detail + ']' : ''));
    } catch (e) {
      console.log('FAIL ' + name + ': ' + (e && e.message ? e.message : String(e)));
      console.log('--- the page\'s console (' + log.lines.length + ' lines):');
      for (const line of log.lines) console.log('  ' + line);
      await failureShot().catch(() => {});
      await browser.close().catch(() => {});
      process.exit(1);
    }
  };
}

module.exports = { parseArgs, launch, waitForPage, moveSlider, selectPlant, makeStep };
