// usv-fdi dashboard: renders the fleet board the dashboard pushes (server-sent events on
// /api/stream: the whole board first, then on every change and once a second the change since
// the board before) and posts acknowledgements to /api/ack. No framework, no network beyond
// the dashboard itself.
'use strict';

let board = null;
let me = { name: null, role: 'observer', can_ack: false };  // /api/me: the signed-in account
const sent = new Set();  // mmsi/sensor/sequence acknowledged from this page
let changed = null;      // MMSIs whose entry changed since the last drawing (null: all)
let holding = false;     // a pointer is down: the board waits, so that a click is not lost
let stale = false;       // a board arrived while holding

function sensorCell(v, sensor) {
  const r = v.sensors[sensor];
  const td = el('td', { 'data-mmsi': v.mmsi, 'data-sensor': sensor });
  if (!r) {
    td.append(el('div', { class: 'cell alert-normal', 'data-presentation': 'normal' }, 'normal'));
    return td;
  }
  const cell = el('div', {
    class: 'cell alert-' + r.presentation,
    'data-presentation': r.presentation,
    'data-state': r.state,
    'data-sequence': r.sequence,
    'data-written': r.written,
  });
  // The board is rebuilt on every push: the flashing keeps its phase on the wall clock, so a
  // rebuild does not restart it (an active-unacknowledged alert flashes however often it comes).
  if (r.presentation === 'active-unacknowledged') {
    cell.style.animationDelay = `-${Date.now() % 1000}ms`;
  }
  cell.append(el('div', { class: 'state' }, STATE_WORDS[r.presentation] || r.presentation));
  cell.append(el('div', { class: 'detail' },
    `${r.kind} · C_a ${fixed(r.c_a, 2)} · C_g ${fixed(r.c_g, 2)} · #${r.sequence} · `,
    el('span', { class: 'age' }, age(r.age_s) + ' ago')));
  if (!r.alive) cell.append(el('div', { class: 'detail' }, 'sidecar gone: last known state'));
  const ackable = r.state === 'raised' || r.state === 'cleared';
  if (ackable && board.can_ack && me.can_ack) {
    const b = el('button', { class: 'ack', 'data-mmsi': v.mmsi, 'data-sensor': sensor,
                             'data-sequence': r.sequence }, 'Acknowledge #' + r.sequence);
    b.disabled = sent.has(`${v.mmsi}/${sensor}/${r.sequence}`);
    b.addEventListener('click', () => acknowledge(v.mmsi, sensor, r.sequence, b));
    cell.append(b);
  }
  td.append(cell);
  return td;
}

function detector(s) {
  if (!s) return 'no status yet';
  const parts = [s.converged ? 'converged' : 'not converged', s.armed ? 'armed' : 'not armed'];
  if (!s.ins_healthy) parts.push('INS unhealthy');
  if (!s.rudder_healthy) parts.push('rudder unhealthy');
  if (s.input_flags) parts.push(s.input_flags);
  if (s.isolation_paused) parts.push('isolation paused: ' + s.isolation_paused);
  return parts.join(' · ');
}

// The page rebuilds only the rows that changed (a board of 1000 vessels and 1000 events would
// otherwise be rebuilt several times a second); the others only move their ages on.
const shownRows = new Map();    // mmsi -> { key, tr }: the board's rows as drawn
const shownEvents = new Map();  // event key -> tr: the event list's rows as drawn
let shownFilter = null;
// The ages of rows not redrawn move on once a second, not on every push: at 1000 vessels a
// push comes 5 times a second, and writing every row's ages each time (a relayout of the whole
// table) held the next event's drawing up to 0.3 s.
let agesDrawnAt = 0;

function heardText(v) {
  return v.never_heard ? 'never heard' : (v.silent ? 'SILENT ' : '') + age(v.heard_age_s) + ' ago';
}

// What a row shows besides its ages: the sensors' cells, the detector's words, the liveness (a
// status every second that changes none of them redraws nothing).
function shownEntry(v) {
  const sensors = SENSORS.map((s) => JSON.stringify(v.sensors[s] || null,
    (k, x) => (k === 'age_s' ? undefined : x)));
  return JSON.stringify([v.mmsi, v.silent, v.never_heard, detector(v.status), sensors]);
}

function setText(node, text) {
  if (node && node.textContent !== text) node.textContent = text;
}

function renderBoard() {
  const body = document.querySelector('#board tbody');
  const order = [];
  const seen = new Set();
  // (900 ms: a quiet fleet's pushes come once a second, and one at 999 ms must not skip a second)
  const drawAges = Date.now() - agesDrawnAt >= 900;
  if (drawAges) agesDrawnAt = Date.now();
  for (const v of board.vessels) {
    seen.add(v.mmsi);
    // what the row shows besides its ages: the vessel, the buttons this page may show
    const mine = [...sent].filter((k) => k.startsWith(v.mmsi + '/')).join();
    let row = shownRows.get(v.mmsi);
    const entry = row && changed && !changed.has(v.mmsi) ? row.entry : shownEntry(v);
    const key = entry + `|${board.can_ack}|${me.can_ack}|${mine}`;
    if (!row || row.key !== key) {
      const tr = el('tr', { 'data-mmsi': v.mmsi, class: v.silent || v.never_heard ? 'silent' : '' });
      tr.append(el('td', { class: 'vessel' },
        el('a', { href: `/vessel.html?mmsi=${v.mmsi}`, title: 'this vessel\'s page: the curves behind the verdicts' }, v.mmsi)));
      tr.append(el('td', { class: 'heard', 'data-silent': v.silent }, heardText(v)));
      tr.append(el('td', { class: 'detector' }, detector(v.status)));
      for (const s of SENSORS) tr.append(sensorCell(v, s));
      if (row) row.tr.replaceWith(tr);
      row = { key, entry, tr };
      shownRows.set(v.mmsi, row);
    } else if (drawAges) {
      // the same row: only its ages move on
      setText(row.tr.querySelector('td.heard'), heardText(v));
      for (const s of SENSORS) {
        const r = v.sensors[s];
        if (r) setText(row.tr.querySelector(`td[data-sensor="${s}"] .age`), age(r.age_s) + ' ago');
      }
    }
    order.push(row.tr);
  }
  for (const [m, row] of shownRows) {
    if (!seen.has(m)) {
      row.tr.remove();
      shownRows.delete(m);
    }
  }
  // the rows in the board's order (moved, not rebuilt, when a vessel comes or goes)
  const now = [...body.children];
  if (now.length !== order.length || order.some((tr, k) => now[k] !== tr)) body.replaceChildren(...order);
  changed = new Set();
  const active = board.vessels.reduce((n, v) => n + SENSORS.filter(
    (s) => v.sensors[s] && v.sensors[s].presentation === 'active-unacknowledged').length, 0);
  const silent = board.vessels.filter((v) => v.silent).length;
  document.getElementById('summary').textContent =
    `${board.vessels.length} vessel(s) · ${active} unacknowledged active alert(s) · ${silent} silent`;
}

function eventRow(e) {
  return el('tr', { 'data-mmsi': e.mmsi, 'data-sensor': e.sensor, 'data-state': e.state,
                    'data-sequence': e.sequence },
    el('td', {}, utc(e.written)), el('td', {}, e.mmsi), el('td', {}, e.sensor),
    el('td', {}, e.state), el('td', {}, e.kind), el('td', {}, fixed(e.c_a, 2)),
    el('td', {}, fixed(e.c_g, 2)), el('td', {}, e.sequence), el('td', {}, e.message));
}

function renderEvents() {
  const fv = document.getElementById('f-vessel');
  const known = new Set([...fv.options].map((o) => o.value));
  for (const v of board.vessels) {
    if (!known.has(String(v.mmsi))) fv.append(el('option', { value: v.mmsi }, v.mmsi));
  }
  const want = { mmsi: fv.value, sensor: document.getElementById('f-sensor').value,
                 state: document.getElementById('f-state').value };
  const filter = JSON.stringify(want);
  const body = document.querySelector('#events tbody');
  if (filter !== shownFilter) {
    body.replaceChildren();
    shownEvents.clear();
    shownFilter = filter;
  }
  // Newest first: the events not drawn yet go above the newest drawn; those gone from the
  // dashboard's history go away.
  const keep = new Set();
  const fresh = [];
  for (const e of board.events) {
    if (want.mmsi && String(e.mmsi) !== want.mmsi) continue;
    if (want.sensor && e.sensor !== want.sensor) continue;
    if (want.state && e.state !== want.state) continue;
    const key = `${e.mmsi}/${e.sensor}/${e.sequence}/${e.written}/${e.state}`;
    keep.add(key);
    if (!shownEvents.has(key)) {
      const tr = eventRow(e);
      shownEvents.set(key, tr);
      fresh.push(tr);
    }
  }
  for (const [key, tr] of shownEvents) {
    if (!keep.has(key)) {
      tr.remove();
      shownEvents.delete(key);
    }
  }
  if (fresh.length) body.prepend(...fresh);
}

function renderAcks() {
  const body = document.querySelector('#acks tbody');
  body.replaceChildren();
  for (const a of board.acks) {
    const outcome = a.state === 'refused' ? 'refused: ' + a.reason : a.state;
    body.append(el('tr', { 'data-mmsi': a.mmsi, 'data-sensor': a.sensor, 'data-state': a.state },
      el('td', {}, utc(a.sent)), el('td', {}, a.operator), el('td', {}, a.mmsi),
      el('td', {}, a.sensor), el('td', {}, a.sequence),
      el('td', { class: a.state }, outcome)));
  }
}

function render() {
  // Signed in: acknowledgements carry the account's name; otherwise the operator types it.
  document.getElementById('operator-box').hidden = !(board.can_ack && me.can_ack) || !!me.name;
  const account = document.getElementById('account');
  account.hidden = !me.name;
  account.textContent = me.name ? `signed in as ${me.name} (${me.role})` : '';
  renderBoard();
  renderEvents();
  renderAcks();
  alertSignal();
}

// The audible signal of IEC 62923-1: while any alert is active and unacknowledged, a tone every
// 2 s, once the operator has switched the sound on (a browser plays nothing before a click);
// Silence stops it for 30 s, a new raise sounds at once. The tab's title counts the alerts.
const SILENCE_S = 30;
let sound = { on: false, ctx: null, silencedUntil: 0, timer: null, known: new Set() };
function unacknowledged() {
  const out = [];
  for (const v of board.vessels) {
    for (const s of SENSORS) {
      const r = v.sensors[s];
      if (r && r.presentation === 'active-unacknowledged') out.push(`${v.mmsi}/${s}/${r.sequence}`);
    }
  }
  return out;
}
function beep() {
  if (!sound.ctx) return;
  try {
    const o = sound.ctx.createOscillator(), g = sound.ctx.createGain();
    o.frequency.value = 880;
    g.gain.value = 0.2;
    o.connect(g).connect(sound.ctx.destination);
    o.start();
    o.stop(sound.ctx.currentTime + 0.3);
  } catch (e) { /* no audio device: the page still says it is sounding */ }
}
function alertSignal() {
  const alerts = unacknowledged();
  document.title = (alerts.length ? `(${alerts.length}) ` : '') + 'usv-fdi fleet';
  // a raise not seen before ends a silence
  if (alerts.some((a) => !sound.known.has(a))) sound.silencedUntil = 0;
  sound.known = new Set(alerts);
  const silenced = Date.now() < sound.silencedUntil;
  const sounding = sound.on && alerts.length > 0 && !silenced;
  document.body.dataset.sounding = sounding;
  const silence = document.getElementById('silence');
  silence.hidden = !(sound.on && alerts.length > 0);
  silence.textContent = silenced ? `silenced (${Math.ceil((sound.silencedUntil - Date.now()) / 1000)} s)` : 'Silence';
  if (sounding && !sound.timer) {
    beep();
    sound.timer = setInterval(() => { if (document.body.dataset.sounding === 'true') beep(); }, 2000);
  } else if (!sounding && sound.timer) {
    clearInterval(sound.timer);
    sound.timer = null;
  }
}
document.getElementById('sound').addEventListener('click', (e) => {
  sound.on = !sound.on;
  if (sound.on && !sound.ctx) {
    try { sound.ctx = new AudioContext(); } catch (err) { sound.ctx = null; }
  }
  e.target.textContent = sound.on ? 'Sound on' : 'Sound off';
  e.target.dataset.on = sound.on;
  if (board) alertSignal();
});
document.getElementById('silence').addEventListener('click', () => {
  sound.silencedUntil = Date.now() + SILENCE_S * 1000;
  if (board) alertSignal();
});

async function acknowledge(mmsi, sensor, sequence, button) {
  const out = document.getElementById('ack-result');
  const operator = me.name || document.getElementById('operator').value.trim();
  if (!operator) {
    out.textContent = 'Give your name (Operator) before acknowledging.';
    out.className = 'refused';
    return;
  }
  if (!me.name) localStorage.setItem('usv-fdi-operator', operator);
  const key = `${mmsi}/${sensor}/${sequence}`;
  if (sent.has(key)) return;
  sent.add(key);
  button.disabled = true;
  const r = await fetch('/api/ack', {
    method: 'POST', headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify({ mmsi, sensor, sequence, operator }),
  });
  const reply = await r.json().catch(() => ({ error: r.statusText }));
  if (!r.ok) sent.delete(key);
  out.textContent = r.ok ? `Acknowledgement of ${mmsi} ${sensor} #${sequence} sent.`
                         : `Not sent: ${reply.error}`;
  out.className = r.ok ? 'accepted' : 'refused';
}

// A delta (BoardFrame::delta in src/app/dashboard/board.hpp): the vessels whose entry changed
// come whole; the others keep theirs, with the heard ages given and every sensor's age from
// its written time; the events added go on top, as many kept as the dashboard keeps.
function applyDelta(d) {
  const vessels = new Map(board.vessels.map((v) => [v.mmsi, v]));
  for (const m of d.removed) vessels.delete(m);
  for (const v of d.vessels) {
    vessels.set(v.mmsi, v);
    if (changed) changed.add(v.mmsi);
  }
  // a status that changed none of the words of its vessel's entry: only its numbers
  for (const [m, nums] of Object.entries(d.status_numbers || {})) {
    const v = vessels.get(Number(m));
    if (v && v.status) Object.assign(v.status, nums);
  }
  for (const v of vessels.values()) {
    const heard = d.heard_age[v.mmsi];
    if (heard !== undefined) v.heard_age_s = heard;
    for (const s of SENSORS) {
      const r = v.sensors[s];
      if (r) r.age_s = d.now - r.written;
    }
  }
  board.vessels = [...vessels.values()].sort((a, b) => a.mmsi - b.mmsi);
  board.events = d.events.concat(board.events).slice(0, d.event_capacity);
  for (const k of ['now', 'silent_after', 'conflicts', 'acks', 'can_ack', 'revision']) board[k] = d[k];
}

function connect() {
  const link = document.getElementById('link');
  const es = new EventSource('/api/stream');
  es.onopen = () => { link.textContent = 'live'; link.className = 'link up'; };
  es.onmessage = (m) => {
    const msg = JSON.parse(m.data);
    if (board && reopenOnMissedDelta(msg, board.revision, es, link, connect)) return;
    if (msg.delta && board) {
      applyDelta(msg);
    } else {
      board = msg;
      changed = null;
    }
    if (holding) stale = true; else render();
  };
  es.onerror = () => { link.textContent = 'reconnecting'; link.className = 'link down'; };
}

for (const id of ['f-vessel', 'f-sensor', 'f-state']) {
  document.getElementById(id).addEventListener('change', () => board && renderEvents());
}
document.addEventListener('pointerdown', () => { holding = true; });
// A press ends with pointerup, or with pointercancel when the browser takes it over (a touch
// that scrolls, a long press): either way the board is drawn again.
for (const type of ['pointerup', 'pointercancel']) {
  document.addEventListener(type, () => {
    holding = false;
    // after the click event of this press has run
    setTimeout(() => { if (stale && !holding) { stale = false; render(); } }, 0);
  });
}
document.getElementById('operator').value = localStorage.getItem('usv-fdi-operator') || '';
fetch('/api/me').then((r) => (r.ok ? r.json() : null)).then((m) => {
  if (m) me = m;
  if (board) render();
}).catch(() => {}).finally(connect);
