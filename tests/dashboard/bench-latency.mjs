// Benchmark: how long after a fault event is written does the dashboard's page show it?
// `usv-fdi emulate` writes FdiStatus for N vessels and fault events at a steady rate; the
// dashboard pushes its board to a headless Chromium page, where a MutationObserver notes when
// each event's row first appears. Latency = that moment - the event's source timestamp (same
// host clock). Prints count, median, p90, p99 and max.
//
//   node bench-latency.mjs [--vessels 100] [--event-rate 5] [--seconds 60] [--warmup 5]
// and the same for the steady state: the events written --warmup s or more after the start.
// Environment as dashboard.test.mjs (USV_FDI_EXE, USV_FDI_QOS, CHROMIUM, OUT_DIR).
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { chromium } from 'playwright-core';

const opt = { vessels: 100, 'event-rate': 5, seconds: 60, warmup: 5 };
for (let i = 2; i < process.argv.length; i += 2) {
  const k = process.argv[i].replace(/^--/, '');
  if (!(k in opt) || !(Number(process.argv[i + 1]) > 0)) {
    console.error(`bench-latency: bad option ${process.argv[i]} ${process.argv[i + 1]}`);
    process.exit(64);
  }
  opt[k] = Number(process.argv[i + 1]);
}
const exe = process.env.USV_FDI_EXE;
const out = process.env.OUT_DIR || fs.mkdtempSync('/tmp/usv_fdi_dash_bench_');
fs.mkdirSync(out, { recursive: true });
const part = `usv_fdi_dash_bench_${process.pid}`;
const dds = ['--domain', process.env.USV_FDI_DOMAIN || String(150 + (process.pid % 40)),
             '--qos', process.env.USV_FDI_QOS, '--participant-profile',
             'usv_fdi_participant_loopback', '--partition', part];
const procs = [];
function start(name, args) {
  const fd = fs.openSync(path.join(out, name + '.log'), 'w');
  const p = spawn(exe, args, { stdio: ['ignore', fd, fd] });
  procs.push(p);
  return path.join(out, name + '.log');
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
let browser;
try {
  const log = start('bench-dashboard', ['dashboard', ...dds, '--listen', '127.0.0.1:0']);
  let url = null;
  for (let i = 0; i < 300 && !url; ++i) {
    const m = fs.readFileSync(log, 'utf8').match(/dashboard on (http:\/\/127\.0\.0\.1:\d+\/)/);
    url = m && m[1];
    if (!url) await sleep(100);
  }
  if (!url) throw new Error('the dashboard did not start: ' + fs.readFileSync(log, 'utf8'));
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
  const page = await browser.newPage();
  await page.addInitScript(() => {
    window.__seen = {};
    new MutationObserver(() => {
      const now = Date.now();
      for (const tr of document.querySelectorAll('#events tbody tr')) {
        const k = `${tr.dataset.mmsi}/${tr.dataset.sensor}/${tr.dataset.sequence}`;
        if (!(k in window.__seen)) window.__seen[k] = now;
      }
    }).observe(document, { childList: true, subtree: true });
  });
  await page.goto(url);
  await page.waitForSelector('#link.up');
  const loaded = Date.now() / 1000;
  start('bench-emulate', ['emulate', ...dds, '--vessels', String(opt.vessels),
                          '--event-rate', String(opt['event-rate']),
                          '--duration', String(opt.seconds)]);
  await sleep(opt.seconds * 1000 + 3000);
  const board = await page.evaluate(async () => (await fetch('/api/board')).json());
  await sleep(2000);  // every event of that board has had time to be pushed and drawn
  const seen = await page.evaluate(() => window.__seen);
  const lat = [];
  const at = [];  // [latency, written - loaded]
  let missing = 0;
  for (const e of board.events) {
    if (e.written <= loaded) continue;
    const t = seen[`${e.mmsi}/${e.sensor}/${e.sequence}`];
    if (t === undefined) { ++missing; continue; }
    lat.push(t / 1000 - e.written);
    at.push([t / 1000 - e.written, e.written - loaded]);
  }
  lat.sort((a, b) => a - b);
  // The slowest five, with when they were written (s after the page loaded, just before the
  // emulator started): a tail at the start is the fleet's discovery, one later is steady state.
  at.sort((a, b) => b[0] - a[0]);
  const slow = at.slice(0, 5).map(([l, w]) => `${(l * 1000).toFixed(0)} ms at ${w.toFixed(1)} s`);
  const q = (p) => lat[Math.min(lat.length - 1, Math.floor(p * lat.length))];
  const f = (x) => (x === undefined ? 'n/a' : (x * 1000).toFixed(0) + ' ms');
  console.log(`dashboard event latency (write -> shown in the browser), ${opt.vessels} vessels, ` +
              `${opt['event-rate']} events/s, ${opt.seconds} s: ${lat.length} events, ` +
              `median ${f(q(0.5))}, p90 ${f(q(0.9))}, p99 ${f(q(0.99))}, max ${f(lat[lat.length - 1])}` +
              `, ${missing} never shown; slowest: ${slow.join(', ')}`);
  // Steady state: the events written once the fleet has arrived (--warmup s after the emulator
  // started: its 1000 vessels' discovery and first statuses come in the first 2 s).
  const steady = at.filter(([, w]) => w >= opt.warmup).map(([l]) => l).sort((a, b) => a - b);
  const qs = (p) => steady[Math.min(steady.length - 1, Math.floor(p * steady.length))];
  console.log(`steady state (written ${opt.warmup} s or more after the start): ${steady.length} ` +
              `events, median ${f(qs(0.5))}, p90 ${f(qs(0.9))}, p99 ${f(qs(0.99))}, ` +
              `max ${f(steady[steady.length - 1])}`);
  if (lat.length === 0 || missing > 0) process.exitCode = 1;
} catch (e) {
  console.error(String(e));
  process.exitCode = 1;
} finally {
  if (browser) await browser.close();
  for (const p of procs) p.kill('SIGTERM');
}
