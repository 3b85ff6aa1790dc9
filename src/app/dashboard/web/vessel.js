// usv-fdi dashboard, a vessel's page: its latched faults and detector status from the board the
// dashboard pushes (/api/stream), and the curves behind the verdicts from /api/vessel (J_N per
// channel against its raise and leave thresholds, C_a and C_g, Â), drawn with uPlot (npm,
// pinned in package-lock.json, carried in the binary). After each push, the points newer than
// the last one shown are fetched and appended.
'use strict';

const mmsi = Number(new URLSearchParams(location.search).get('mmsi'));
const haveCharts = typeof uPlot !== 'undefined';
const charts = {};
let data = null;     // the columns of /api/vessel
let fetching = false;

function problem(text) {
  const p = document.getElementById('problem');
  p.hidden = !text;
  p.textContent = text || '';
}

// One chart: time on x, the given series of `data` on y.
function chart(id, title, series, yRange) {
  const box = document.getElementById(id);
  const opts = {
    title, width: Math.max(320, box.clientWidth || 600), height: 220,
    scales: { x: { time: true }, y: yRange ? { range: yRange } : {} },
    series: [{ label: 'time' }, ...series.map((s) => ({
      label: s.label, stroke: s.stroke, width: s.width || 1.5, dash: s.dash, spanGaps: false,
      value: (u, v) => (v === null || v === undefined ? '–' : Number(v).toPrecision(4)),
    }))],
    axes: [{ stroke: '#8a97a6', grid: { stroke: '#2a3440' } },
           { stroke: '#8a97a6', grid: { stroke: '#2a3440' }, size: 60 }],
  };
  const u = new uPlot(opts, columns(series), box);
  u.keys = series.map((s) => s.key);
  box.dataset.series = series.map((s) => s.key).join(',');
  charts[id] = u;
}
function columns(series) { return [data.t, ...series.map((s) => data[s.key])]; }

function build() {
  const thr = (c, name) => [
    { key: 'j_' + c, label: `J_N ${name}`, stroke: '#dfe6ee', width: 2 },
    { key: 'raise_' + c, label: 'raise threshold', stroke: '#e23b3b', dash: [6, 4] },
    { key: 'leave_' + c, label: 'leave threshold', stroke: '#e6a23c', dash: [2, 4] },
  ];
  chart('chart-j-a', 'accelerometer channel', thr('a', 'accelerometer'));
  chart('chart-j-g', 'gyro channel', thr('g', 'gyro'));
  chart('chart-c', 'C_a and C_g', [
    { key: 'c_a', label: 'C_a (accelerometer)', stroke: '#4aa3ff' },
    { key: 'c_g', label: 'C_g (gyro)', stroke: '#e6a23c' },
  ], [0, 1]);
  chart('chart-a', 'Â entries', [
    { key: 'a11', label: 'a11', stroke: '#4aa3ff' }, { key: 'a12', label: 'a12', stroke: '#3fa56a' },
    { key: 'a21', label: 'a21', stroke: '#e6a23c' }, { key: 'a22', label: 'a22', stroke: '#d46ad4' },
  ]);
}

function redraw() {
  for (const u of Object.values(charts)) u.setData([data.t, ...u.keys.map((k) => data[k])]);
  document.body.dataset.points = data.t.length;
}

async function update() {
  if (fetching || !haveCharts) return;
  fetching = true;
  try {
    const since = data && data.t.length ? data.t[data.t.length - 1] : 0;
    const r = await fetch(`/api/vessel?mmsi=${mmsi}&since=${since}`);
    const j = await r.json();
    if (!r.ok) { problem(j.error); return; }
    problem('');
    if (!data) {
      data = j;
      build();
    } else {
      for (const k of Object.keys(j)) if (Array.isArray(j[k])) data[k].push(...j[k]);
      // the page keeps what the dashboard keeps
      const extra = data.t.length - j.capacity;
      if (extra > 0) for (const k of Object.keys(data)) if (Array.isArray(data[k])) data[k].splice(0, extra);
    }
    redraw();
  } finally {
    fetching = false;
  }
}

function renderVessel(v) {
  const faults = document.querySelector('#faults tbody');
  faults.replaceChildren();
  for (const sensor of SENSORS) {
    const r = v.sensors[sensor];
    const tr = el('tr', { 'data-sensor': sensor, 'data-presentation': r ? r.presentation : 'normal' });
    const cell = el('div', { class: 'cell alert-' + (r ? r.presentation : 'normal') },
                    r ? STATE_WORDS[r.presentation] || r.presentation : 'normal');
    tr.append(el('td', {}, sensor), el('td', {}, cell), el('td', {}, r ? r.kind : '–'),
              el('td', {}, fixed(r && r.c_a, 2)), el('td', {}, fixed(r && r.c_g, 2)),
              el('td', {}, r ? r.sequence : '–'), el('td', {}, r ? r.message : ''));
    faults.append(tr);
  }
  const s = v.status;
  const det = document.querySelector('#detector tbody');
  det.replaceChildren();
  const row = (k, val, key) => det.append(el('tr', { 'data-key': key }, el('th', {}, k), el('td', {}, val)));
  row('Last heard', v.never_heard ? 'never' : (v.silent ? 'SILENT, ' : '') + fixed(v.heard_age_s, 1) + ' s ago', 'heard');
  if (!s) { row('Detector', 'no status yet', 'detector'); return; }
  row('Identification', s.converged ? 'converged' : 'not converged', 'converged');
  row('Detection', s.armed ? 'armed' : 'not armed', 'armed');
  row('Model', s.model_mismatch ? 'MISMATCH: the residuals contradict the model (no sensor fault raised from them)' : 'holds', 'model');
  row('Excitation', fixed(s.excitation, 4), 'excitation');
  row('INS', s.ins_healthy ? 'healthy' : 'unhealthy', 'ins');
  row('Rudder', s.rudder_healthy ? 'healthy' : 'unhealthy', 'rudder');
  row('Input problems', s.input_flags || 'none', 'input_flags');
  row('Identification paused', s.identification_paused || 'no', 'identification_paused');
  row('Isolation paused', s.isolation_paused || 'no', 'isolation_paused');
  row('Samples (dropped)', `${s.samples} (${s.dropped})`, 'samples');
  row('Message', s.message || '–', 'message');
}

function connect() {
  const link = document.getElementById('link');
  const es = new EventSource('/api/stream');
  es.onopen = () => { link.textContent = 'live'; link.className = 'link up'; };
  let v = null;  // this vessel's entry on the board
  let revision = null;  // the board's (BoardFrame in src/app/dashboard/board.hpp)
  es.onmessage = (m) => {
    const board = JSON.parse(m.data);
    if (reopenOnMissedDelta(board, revision, es, link, connect)) return;
    revision = board.revision;
    const mine = board.vessels.find((x) => x.mmsi === mmsi);
    if (!board.delta || mine) {
      v = mine || null;  // the whole board, or this vessel's entry changed
    } else if (board.removed.includes(mmsi)) {
      v = null;
    } else if (v) {
      // a change elsewhere, or only this vessel's status numbers: the age and those move on
      if (board.heard_age[mmsi] !== undefined) v.heard_age_s = board.heard_age[mmsi];
      const nums = (board.status_numbers || {})[mmsi];
      if (nums && v.status) Object.assign(v.status, nums);
    }
    document.getElementById('summary').textContent = v ? '' : 'not on the board';
    if (v) renderVessel(v);
    update();
  };
  es.onerror = () => { link.textContent = 'reconnecting'; link.className = 'link down'; };
}

document.getElementById('mmsi').textContent = mmsi || '?';
document.title = `usv-fdi vessel ${mmsi}`;
if (!Number.isInteger(mmsi) || mmsi < 1 || mmsi > 999999999) {
  problem('The address must name a vessel: vessel.html?mmsi=MMSI');
} else if (!haveCharts) {
  problem('This dashboard was built without its chart library (USV_FDI_DASHBOARD_CHARTS=OFF): no charts.');
  connect();
} else {
  connect();
}
