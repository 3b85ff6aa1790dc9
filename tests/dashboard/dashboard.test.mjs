// Browser tests of `usv-fdi dashboard`: Debian's headless Chromium driven by playwright-core,
// against the real sidecar, simulator and fleet emulator on loopback (separate processes, real
// Fast DDS participants, a partition of their own).
//
// Environment (set by ctest, tests/dashboard/CMakeLists.txt): USV_FDI_EXE, USV_FDI_QOS,
// USV_FDI_PAPER_CONFIG, USV_FDI_DOMAIN, CHROMIUM (default /usr/bin/chromium), OUT_DIR (logs and
// screenshots).
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import https from 'node:https';
import path from 'node:path';
import { chromium } from 'playwright-core';

if (Number(process.versions.node.split('.')[0]) < 20) {
  throw new Error(`Node.js ${process.versions.node}: playwright-core needs 20 or later`);
}
const exe = process.env.USV_FDI_EXE;
const qos = process.env.USV_FDI_QOS;
const paper = process.env.USV_FDI_PAPER_CONFIG;
const domain = process.env.USV_FDI_DOMAIN || String(150 + (process.pid % 40));
const out = process.env.OUT_DIR || fs.mkdtempSync('/tmp/usv_fdi_dashboard_');
fs.mkdirSync(out, { recursive: true });
for (const [k, v] of Object.entries({ USV_FDI_EXE: exe, USV_FDI_QOS: qos, USV_FDI_PAPER_CONFIG: paper })) {
  if (!v || !fs.existsSync(v)) throw new Error(`${k} must name an existing file (got '${v}')`);
}

const children = [];
function start(name, args) {
  const log = path.join(out, name + '.log');
  const fd = fs.openSync(log, 'w');
  const p = spawn(exe, args, { stdio: ['ignore', fd, fd] });
  fs.closeSync(fd);
  const child = { name, p, log, exited: new Promise((r) => p.on('exit', (code) => r(code))) };
  children.push(child);
  return child;
}
const readLog = (c) => fs.readFileSync(c.log, 'utf8');
async function waitFor(what, fn, seconds) {
  const end = Date.now() + seconds * 1000;
  for (;;) {
    const v = await fn();
    if (v) return v;
    if (Date.now() > end) throw new Error(`${what}: not within ${seconds} s`);
    await new Promise((r) => setTimeout(r, 50));
  }
}
const waitLog = (c, text, s = 30) =>
  waitFor(`'${text}' in ${c.name}.log:\n${readLog(c)}`, () => readLog(c).includes(text), s);
async function stop(c) {
  if (c.p.exitCode === null) c.p.kill('SIGTERM');
  const t = setTimeout(() => c.p.kill('SIGKILL'), 10000);
  const code = await c.exited;
  clearTimeout(t);
  return code;
}
let browser = null;
after(async () => {
  if (browser) await browser.close();
  for (const c of children) await stop(c);
});
async function launch() {
  if (browser) return browser;
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
  return browser;
}
async function newPage(options = {}) {
  const ctx = await (await launch()).newContext({ viewport: { width: 1400, height: 900 }, ...options });
  const page = await ctx.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  // (the refusals the tests provoke on purpose, 400, 403 and 415, are logged by the browser too)
  page.on('console', (m) => {
    if (m.type() === 'error' && !/status of (400|401|403|415)/.test(m.text())) errors.push(m.text());
  });
  page.errors = errors;
  return page;
}

function dds(partition) {
  return ['--domain', domain, '--qos', qos, '--participant-profile',
          'usv_fdi_participant_loopback', '--partition', partition];
}
async function dashboard(name, partition, extra = []) {
  const d = start(name, ['dashboard', ...dds(partition), '--listen', '127.0.0.1:0', ...extra]);
  await waitLog(d, ': running', 30);
  const m = readLog(d).match(/dashboard on (https?:\/\/127\.0\.0\.1:\d+\/)/);
  assert.ok(m, readLog(d));
  d.url = m[1];
  return d;
}
const cell = (mmsi, sensor) => `td[data-mmsi="${mmsi}"][data-sensor="${sensor}"] .cell`;

test('a sidecar\'s faults on the board: raise, late browser, acknowledge, observer', async () => {
  const mmsi = 257000071;
  const part = `usv_fdi_dash_${process.pid}_a`;
  const svc = start('sidecar', ['run', '--config', paper, '--mmsi', String(mmsi), '--reliable-inputs',
                                ...dds(part)]);
  await waitLog(svc, 'waiting for INS and rudder');
  const dash = await dashboard('dashboard', part);
  const page = await newPage();
  await page.goto(dash.url);
  // Once the sidecar's status is heard, its vessel has a row, every sensor normal.
  await page.waitForSelector(`tr[data-mmsi="${mmsi}"]`, { timeout: 30000 });
  assert.equal(await page.textContent('#link'), 'live');

  // WHEN the simulator publishes the paper's scenario (gyro bias 20-40 s, accelerometer 60-80 s)
  const sim = start('sim', ['sim', '--publish', '--mmsi', String(mmsi), '--vessel', 'otter',
                            '--scenario', 'paper', '--noise-scale', '0', '--speed', '4',
                            '--reliable', '--linger', '0.5', ...dds(part)]);
  // THEN the gyro's raise shows, flashing, soon after the sidecar wrote it
  const raised = `${cell(mmsi, 'gyro')}[data-state="raised"][data-sequence="1"]`;
  await page.waitForSelector(raised, { timeout: 90000 });
  const shownAt = Date.now() / 1000;
  const written = Number(await page.getAttribute(raised, 'data-written'));
  const latency = shownAt - written;
  console.log(`raise shown ${latency.toFixed(3)} s after the sidecar wrote it`);
  fs.writeFileSync(path.join(out, 'raise_latency.txt'), `${latency}\n`);
  assert.ok(latency >= -0.05 && latency < 3.0, `raise shown after ${latency} s`);
  assert.equal(await page.getAttribute(raised, 'data-presentation'), 'active-unacknowledged');
  const anim = await page.$eval(raised, (e) => getComputedStyle(e).animationName);
  assert.equal(anim, 'flash', 'active-unacknowledged flashes');
  assert.match(await page.textContent(`${cell(mmsi, 'gyro')} .detail`), /C_g 1\.00/);
  // and the accelerometer's, then both clear
  await page.waitForSelector(`${cell(mmsi, 'accelerometer')}[data-state="raised"]`, { timeout: 90000 });
  assert.equal(await sim.exited, 0, readLog(sim));
  await page.waitForSelector('#events tbody tr[data-sensor="accelerometer"][data-sequence="2"]',
                             { timeout: 30000 });
  // AND once the simulator has stopped, both INS channels are raised stale (#3) an input_timeout
  // later; nothing changes after that until an acknowledgement. (Waited for here: a late page
  // compared with a board that has not drawn them yet would wait for a state that is gone.)
  for (const s of ['gyro', 'accelerometer']) {
    await page.waitForSelector(`${cell(mmsi, s)}[data-state="raised"][data-sequence="3"]`,
                               { timeout: 30000 });
  }
  assert.match(await page.textContent(`${cell(mmsi, 'gyro')} .detail`), /stale/);
  await page.screenshot({ path: path.join(out, 'board.png'), fullPage: true });
  // The event list has every event, newest first, and filters by sensor.
  const seqs = await page.$$eval('#events tbody tr', (rows) => rows.map((r) => r.dataset.sensor + r.dataset.sequence));
  assert.ok(seqs.indexOf('gyro1') > seqs.indexOf('gyro2') && seqs.indexOf('gyro2') > seqs.indexOf('accelerometer1'), seqs.join());
  await page.selectOption('#f-sensor', 'gyro');
  const shown = await page.$$eval('#events tbody tr', (rows) => rows.map((r) => r.dataset.sensor));
  assert.ok(shown.length >= 2 && shown.every((s) => s === 'gyro'), shown.join());

  // WHEN a browser connects late, THEN it shows the latched state at once
  const late = await newPage();
  const t0 = Date.now();
  await late.goto(dash.url);
  // (A generous bound: on a machine busy with other tests the page can take seconds to load;
  // the time it took is printed.)
  await late.waitForSelector(`${cell(mmsi, 'gyro')}[data-state="raised"][data-sequence="3"]`,
                             { timeout: 30000 });
  console.log(`late browser had the latched state after ${(Date.now() - t0) / 1000} s`);

  // WHEN the operator acknowledges the gyro's event with the button
  const seq = await page.getAttribute(cell(mmsi, 'gyro'), 'data-sequence');
  await page.fill('#operator', 'alice');
  await page.click(`button.ack[data-mmsi="${mmsi}"][data-sensor="gyro"]`);
  // THEN the sidecar accepts it (logged with the operator) and the board moves on
  await page.waitForSelector(`#acks tbody tr[data-sensor="gyro"][data-state="accepted"]`, { timeout: 30000 });
  await page.waitForSelector(`${cell(mmsi, 'gyro')}[data-sequence="${Number(seq) + 1}"]`, { timeout: 10000 });
  assert.notEqual(await page.getAttribute(cell(mmsi, 'gyro'), 'data-presentation'), 'active-unacknowledged');
  await waitLog(svc, 'by alice accepted', 10);
  assert.match(readLog(svc), new RegExp(`gyro #${Number(seq) + 1} \\w+ .*acknowledged by alice`));
  // AND the dashboard's Prometheus text says the same (refreshed once a second)
  const metric = (text, line) => new RegExp(`^${line.replace(/[{}"]/g, '\\$&')} (\\S+)$`, 'm').exec(text);
  const scrape = async () => (await fetch(`${dash.url}metrics`)).text();
  const lbl = `mmsi="${mmsi}",sensor="gyro"`;
  const text = await waitFor('the acknowledgement in /metrics', async () => {
    const t = await scrape();
    const u = metric(t, `usv_fdi_fleet_fault_unacknowledged{${lbl}}`);
    return u && u[1] === '0' && metric(t, 'usv_fdi_dashboard_acks{state="accepted"}')?.[1] === '1'
      ? t : null;
  }, 10);
  assert.ok(Number(metric(text, `usv_fdi_fleet_raises_total{${lbl}}`)?.[1]) >= 1,
            `a gyro raise counted:\n${text}`);
  assert.match(metric(text, `usv_fdi_fleet_fault_active{${lbl}}`)?.[1] ?? '', /^[01]$/,
               `the gyro instance's activity:\n${text}`);
  assert.equal(metric(text, `usv_fdi_fleet_silent{mmsi="${mmsi}"}`)?.[1], '0', text);
  assert.match(text, /# TYPE usv_fdi_fleet_raises_total counter/);

  // The vessel's page (a link on the board): the curves behind the verdicts, drawn with uPlot
  await page.click(`tr[data-mmsi="${mmsi}"] td.vessel a`);
  await page.waitForURL(/vessel\.html\?mmsi=/);
  await page.waitForSelector('#chart-j-g canvas', { timeout: 10000 });
  const curves = await (await fetch(`${dash.url}api/vessel?mmsi=${mmsi}`)).json();
  const over = (c) => curves.t.some((_, i) => curves['j_' + c][i] > curves['raise_' + c][i] &&
                                             curves['raise_' + c][i] > 0);
  assert.ok(curves.t.length >= 3, JSON.stringify(curves));
  assert.ok(over('g'), `the gyro fault's J_N above its raise threshold: ${JSON.stringify(curves)}`);
  assert.ok(over('a'), `the accelerometer fault's J_N above its threshold: ${JSON.stringify(curves)}`);
  assert.ok(curves.armed.includes(1) && curves.c_g.some((c) => c > 0.9), JSON.stringify(curves));
  assert.ok(curves.t.every((t, i) => i === 0 || t > curves.t[i - 1]), 'time runs forward');
  await waitFor('every point on the page', async () =>
    Number(await page.getAttribute('body', 'data-points')) >= curves.t.length, 10);
  assert.match(await page.textContent('#chart-j-g'), /J_N gyro.*raise threshold.*leave threshold/s);
  assert.equal(await page.textContent('#detector tr[data-key="armed"] td'), 'armed');
  // the gyro's event, acknowledged above, is no longer active-unacknowledged here either
  assert.notEqual(await page.getAttribute('#faults tr[data-sensor="gyro"]', 'data-presentation'),
                  'active-unacknowledged');
  await page.screenshot({ path: path.join(out, 'vessel.png'), fullPage: true });
  // A wrong address says what is wrong.
  const wrong = await fetch(`${dash.url}api/vessel?mmsi=12x`);
  assert.equal(wrong.status, 400);
  assert.match((await wrong.json()).error, /mmsi/);
  assert.equal((await fetch(`${dash.url}api/vessel?mmsi=5`)).status, 404);
  await page.goto(dash.url);
  await page.waitForSelector(`tr[data-mmsi="${mmsi}"]`, { timeout: 10000 });

  // WHEN an observer's dashboard (--read-only) shows the same fleet
  const obs = await dashboard('observer', part, ['--read-only']);
  const op = await newPage();
  await op.goto(obs.url);
  await op.waitForSelector(`${cell(mmsi, 'accelerometer')}[data-state]`, { timeout: 30000 });
  // THEN it has no acknowledge button, and a forged request is refused
  assert.equal(await op.$$eval('button.ack', (b) => b.length), 0);
  assert.equal(await op.isVisible('#operator'), false);
  const forged = await op.evaluate(async ([m]) => {
    const r = await fetch('/api/ack', { method: 'POST', body: JSON.stringify(
      { mmsi: m, sensor: 'accelerometer', sequence: 2, operator: 'mallory' }) });
    return [r.status, (await r.json()).error];
  }, [mmsi]);
  assert.equal(forged[0], 403);
  assert.match(forged[1], /read-only/);
  await new Promise((r) => setTimeout(r, 1000));
  assert.ok(!readLog(svc).includes('mallory'), 'the sidecar never saw the forged ack');
  // A malformed request to the operator's dashboard is refused with what was wrong.
  const post = (body, headers) => page.evaluate(async ([b, h]) => {
    const r = await fetch('/api/ack', { method: 'POST', body: b, headers: h });
    return [r.status, (await r.json()).error];
  }, [body, headers]);
  const json = { 'Content-Type': 'application/json' };
  const bad = await post('{"mmsi": 1, "sensor": "gyroscope", "sequence": 1, "operator": "a"}', json);
  assert.equal(bad[0], 400);
  assert.match(bad[1], /sensor/);
  // Not JSON (what a cross-site form or a "simple" cross-origin fetch would send): refused.
  const plain = await post(`{"mmsi": ${mmsi}, "sensor": "accelerometer", "sequence": 2, "operator": "x"}`,
                           { 'Content-Type': 'text/plain' });
  assert.equal(plain[0], 415);
  // Another site's page (Origin) or another host name (DNS rebinding): refused.
  const port = new URL(dash.url).port;
  const foreign = await fetch(`${dash.url}api/ack`, { method: 'POST', headers: {
    ...json, Origin: 'http://evil.example' }, body: `{"mmsi": ${mmsi}, "sensor": "accelerometer", "sequence": 2, "operator": "x"}` });
  assert.equal(foreign.status, 403);
  const rebound = await new Promise((resolve, reject) => {
    http.get({ host: '127.0.0.1', port, path: '/api/board', headers: { Host: `evil.example:${port}` } },
             (r) => { r.resume(); resolve(r.statusCode); }).on('error', reject);
  });
  assert.equal(rebound, 421);
  assert.ok(!readLog(svc).includes('by x'), 'the sidecar never saw the refused requests');
  assert.deepEqual(page.errors, [], 'no script errors');
});

test('a board of 100 emulated vessels loads and stays responsive', async () => {
  const part = `usv_fdi_dash_${process.pid}_b`;
  const dash = await dashboard('dashboard100', part);
  start('emulate', ['emulate', ...dds(part), '--vessels', '100', '--first-mmsi', '990000001',
                    '--status-rate', '1', '--event-rate', '5']);
  const page = await newPage();
  const t0 = Date.now();
  await page.goto(dash.url);
  await waitFor('100 vessel rows', async () =>
    (await page.$$eval('#board tbody tr', (r) => r.length)) === 100, 60);
  console.log(`100 vessels on the board ${(Date.now() - t0) / 1000} s after loading`);
  await waitFor('100 vessels in /metrics', async () =>
    /^usv_fdi_fleet_vessels 100$/m.test(await (await fetch(`${dash.url}metrics`)).text()), 10);
  // Responsive: a filter applies while updates keep arriving, and the page answers at once.
  // a vessel with events (the emulator's events go to random vessels)
  const target = await waitFor('an event in the list', () => page.$eval(
    '#events tbody tr', (r) => r.dataset.mmsi).catch(() => null), 30);
  await page.selectOption('#f-vessel', target);
  const t1 = Date.now();
  const probe = await page.evaluate(() => new Promise((r) => {
    const s = performance.now();
    requestAnimationFrame(() => r(performance.now() - s));
  }));
  const rows = await page.$$eval('#events tbody tr', (r) => r.map((x) => x.dataset.mmsi));
  assert.ok(rows.length > 0 && rows.every((m) => m === target), rows.join());
  console.log(`frame after ${probe.toFixed(1)} ms, filter applied in ${Date.now() - t1} ms`);
  assert.ok(probe < 2000, `a frame took ${probe} ms`);
  // The page redraws only what changed: after many pushes no event is drawn twice, and the list
  // holds what the dashboard holds.
  await page.selectOption('#f-vessel', '');
  await new Promise((r) => setTimeout(r, 2000));
  const drawn = await page.evaluate(async () => {
    const keys = [...document.querySelectorAll('#events tbody tr')].map(
      (r) => `${r.dataset.mmsi}/${r.dataset.sensor}/${r.dataset.sequence}/${r.dataset.state}`);
    return keys;
  });
  assert.equal(new Set(drawn).size, drawn.length, 'no event drawn twice');
  assert.ok(drawn.length > 10 && drawn.length <= 1000, `${drawn.length} events drawn`);
  // After the first board the page is sent only what changed (deltas): the board it has put
  // together is the dashboard's own (ages aside) at the same revision, while updates keep
  // arriving. The page keeps its board at every revision while /api/board is asked (a busy
  // machine answers after several more deltas); a page that gets a whole board instead, or
  // does not reach the revision within 5 s, asks again.
  const cmp = await waitFor('the page\'s board at the revision of /api/board',
    () => page.evaluate(async () => {
      const bare = (b) => JSON.stringify({ vessels: b.vessels, events: b.events, acks: b.acks },
        (k, x) => (k === 'age_s' || k === 'heard_age_s' ? undefined : x));
      const kept = new Map([[board.revision, bare(board)]]);
      const apply = applyDelta;
      applyDelta = (d) => { apply(d); kept.set(board.revision, bare(board)); };
      let server;
      try {
        server = await (await fetch('/api/board')).json();
        const until = Date.now() + 5000;
        while (board.revision < server.revision && Date.now() < until) {
          await new Promise((r) => setTimeout(r, 20));
        }
      } finally {
        applyDelta = apply;
      }
      const mine = kept.get(server.revision);
      return mine && { revision: server.revision, mine, server: bare(server),
                       vessels: server.vessels.length, kept: kept.size };
    }), 30);
  console.log(`the page's board compared with /api/board at revision ${cmp.revision} ` +
              `(${cmp.kept} revisions kept while asking)`);
  assert.equal(cmp.mine, cmp.server, 'the board the deltas put together is the dashboard\'s');
  assert.equal(cmp.vessels, 100);
  // While a pointer is down the board waits (a click is not lost under a redraw); a press the
  // browser takes over (pointercancel: a touch that scrolls) lets it go on too.
  await page.evaluate(() => document.dispatchEvent(new PointerEvent('pointerdown')));
  await page.waitForFunction(() => stale === true, null, { timeout: 30000 });
  await page.evaluate(() => document.dispatchEvent(new PointerEvent('pointercancel')));
  await page.waitForFunction(() => stale === false && holding === false, null, { timeout: 30000 });
  // The audible signal (IEC 62923): off until the operator switches it on; then sounding while
  // an alert is active and unacknowledged (the tab's title counts them); Silence stops it.
  assert.equal(await page.getAttribute('body', 'data-sounding'), 'false', 'no sound before a click');
  await page.waitForFunction(() => /^\(\d+\) usv-fdi fleet$/.test(document.title), null, { timeout: 30000 });
  const on = await page.evaluate(() => {
    document.getElementById('sound').click();  // (in one task: no board arrives in between)
    const n = Number((/^\((\d+)\)/.exec(document.title) || [0, 0])[1]);
    return [n, document.body.dataset.sounding];
  });
  assert.equal(on[1], String(on[0] > 0), `sounding with ${on[0]} unacknowledged alert(s)`);
  await page.waitForSelector('body[data-sounding="true"]', { timeout: 30000 });
  const silenced = await page.evaluate(() => {
    document.getElementById('silence').click();
    return [document.body.dataset.sounding, document.getElementById('silence').textContent];
  });
  assert.equal(silenced[0], 'false');
  assert.match(silenced[1], /^silenced \(30 s\)$/);
  await page.screenshot({ path: path.join(out, 'board100.png') });
  assert.deepEqual(page.errors, [], 'no script errors');
});

test('signed in over HTTPS: operators acknowledge under their own name, observers only look', async () => {
  const mmsi = 257000072;
  const part = `usv_fdi_dash_${process.pid}_c`;
  // A self-signed certificate for 127.0.0.1, and two accounts made with usv-fdi dashboard-account.
  const cert = path.join(out, 'tls_cert.pem'), key = path.join(out, 'tls_key.pem');
  const accounts = path.join(out, 'accounts.yaml');
  const tool = (cmd, args, input) => {
    const r = spawnSync(cmd, args, { input, encoding: 'utf8' });
    assert.equal(r.status, 0, `${cmd} ${args.join(' ')}: ${r.stderr}`);
    return r;
  };
  tool('openssl', ['req', '-x509', '-newkey', 'ec', '-pkeyopt', 'ec_paramgen_curve:P-256', '-nodes',
                   '-keyout', key, '-out', cert, '-days', '2', '-subj', '/CN=127.0.0.1',
                   '-addext', 'subjectAltName=IP:127.0.0.1']);
  fs.rmSync(accounts, { force: true });
  tool(exe, ['dashboard-account', 'carol', '--role', 'operator', '--file', accounts], 'correct horse battery\n');
  tool(exe, ['dashboard-account', 'dave', '--role', 'observer', '--file', accounts], 'staple: paper clip\n');
  assert.equal(fs.statSync(accounts).mode & 0o777, 0o600);
  assert.ok(!fs.readFileSync(accounts, 'utf8').includes('correct horse'), 'no password in clear');

  const svc = start('sidecar_tls', ['run', '--config', paper, '--mmsi', String(mmsi), '--reliable-inputs',
                                    ...dds(part)]);
  await waitLog(svc, 'waiting for INS and rudder');
  const dash = await dashboard('dashboard_tls', part, ['--accounts', accounts, '--tls-cert', cert,
                                                       '--tls-key', key]);
  assert.match(dash.url, /^https:/);
  // Without credentials, or with a wrong password, nothing is served (verified TLS: our own CA).
  const get = (p, auth) => new Promise((resolve, reject) => {
    const u = new URL(p, dash.url);
    https.get({ host: u.hostname, port: u.port, path: u.pathname, ca: fs.readFileSync(cert),
                headers: auth ? { Authorization: 'Basic ' + Buffer.from(auth).toString('base64') } : {} },
              (r) => { let b = ''; r.on('data', (c) => { b += c; });
                       r.on('end', () => resolve({ status: r.statusCode, headers: r.headers, body: b })); })
      .on('error', reject);
  });
  for (const p of ['/', '/api/board', '/api/stream', '/metrics']) {
    const r = await get(p);
    assert.equal(r.status, 401, `${p} without credentials`);
    assert.match(r.headers['www-authenticate'], /^Basic realm="usv-fdi dashboard"/);
    assert.equal(r.headers['x-frame-options'], 'DENY', 'no other site may frame it');
    assert.match(r.headers['strict-transport-security'] ?? '', /max-age=/);
  }
  assert.equal((await get('/api/board', 'carol:correct horse')).status, 401, 'a wrong password');
  assert.equal((await get('/api/board', 'mallory:correct horse battery')).status, 401, 'no such account');
  const scraped = await get('/metrics', 'dave:staple: paper clip');
  assert.equal(scraped.status, 200);
  assert.match(scraped.body, /^usv_fdi_fleet_vessels /m);
  // Plain HTTP on the HTTPS port gets no page.
  const plain = await new Promise((resolve) => {
    http.get(dash.url.replace('https:', 'http:') + 'api/board', (r) => { r.resume(); resolve(r.statusCode); })
      .on('error', () => resolve('refused'));
  });
  assert.notEqual(plain, 200);

  const operator = await newPage({ httpCredentials: { username: 'carol', password: 'correct horse battery' },
                                   ignoreHTTPSErrors: true });
  const observer = await newPage({ httpCredentials: { username: 'dave', password: 'staple: paper clip' },
                                   ignoreHTTPSErrors: true });
  for (const p of [operator, observer]) {
    await p.goto(dash.url);
    await p.waitForSelector(`tr[data-mmsi="${mmsi}"]`, { timeout: 30000 });
  }
  assert.equal(await operator.textContent('#account'), 'signed in as carol (operator)');
  assert.equal(await observer.textContent('#account'), 'signed in as dave (observer)');
  assert.equal(await operator.isVisible('#operator'), false, 'no name to type when signed in');
  assert.equal(await operator.textContent('#link'), 'live');
  assert.equal(await observer.textContent('#link'), 'live');

  const sim = start('sim_tls', ['sim', '--publish', '--mmsi', String(mmsi), '--vessel', 'otter',
                                '--scenario', 'paper', '--noise-scale', '0', '--speed', '4',
                                '--reliable', '--linger', '0.5', ...dds(part)]);
  // (the rectified, unacknowledged state: it waits for an acknowledgement and does not move on)
  const raised = `${cell(mmsi, 'gyro')}[data-state="cleared"]`;
  await operator.waitForSelector(raised, { timeout: 90000 });
  await operator.waitForSelector(`button.ack[data-mmsi="${mmsi}"][data-sensor="gyro"]`, { timeout: 10000 });
  await observer.waitForSelector(raised, { timeout: 30000 });
  // The observer sees the raise but has no button, and a forged request is refused.
  assert.equal(await observer.$$eval('button.ack', (b) => b.length), 0);
  const forged = await observer.evaluate(async ([m, seq]) => {
    const r = await fetch('/api/ack', { method: 'POST', headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify({ mmsi: m, sensor: 'gyro', sequence: seq, operator: 'carol' }) });
    return [r.status, (await r.json()).error];
  }, [mmsi, Number(await observer.getAttribute(raised, 'data-sequence'))]);
  assert.equal(forged[0], 403);
  assert.match(forged[1], /'dave' is an observer/);
  // The operator's button acknowledges under the account's name.
  await operator.click(`button.ack[data-mmsi="${mmsi}"][data-sensor="gyro"]`);
  await operator.waitForSelector('#acks tbody tr[data-sensor="gyro"][data-state="accepted"]', { timeout: 30000 });
  await waitLog(svc, 'acknowledged by carol', 10);
  // A name in the body does not override the account's.
  const accel = `${cell(mmsi, 'accelerometer')}[data-state="cleared"]`;
  await operator.waitForSelector(accel, { timeout: 90000 });
  const named = await operator.evaluate(async ([m, seq]) => {
    const r = await fetch('/api/ack', { method: 'POST', headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify({ mmsi: m, sensor: 'accelerometer', sequence: seq, operator: 'mallory' }) });
    return r.status;
  }, [mmsi, Number(await operator.getAttribute(accel, 'data-sequence'))]);
  assert.equal(named, 202);
  await operator.waitForSelector('#acks tbody tr[data-sensor="accelerometer"][data-state="accepted"]', { timeout: 30000 });
  assert.match(readLog(svc), /accelerometer #\d+ \w+ .*acknowledged by carol/);
  assert.ok(!readLog(svc).includes('mallory'), 'the body\'s name was not used');
  assert.equal(await sim.exited, 0, readLog(sim));
  assert.ok(!readLog(svc).includes('dave'), 'the sidecar never saw the observer\'s request');
  await operator.screenshot({ path: path.join(out, 'board_signed_in.png') });
  assert.deepEqual(operator.errors, [], 'no script errors (operator)');
  assert.deepEqual(observer.errors, [], 'no script errors (observer)');
});
