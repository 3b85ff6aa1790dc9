// usv-fdi dashboard: what its pages share (loaded before app.js and vessel.js): the sensors,
// the words of the IEC 62923 presentation, an element builder and the number, age and time
// formats.
'use strict';

const SENSORS = ['accelerometer', 'gyro', 'unknown'];
const STATE_WORDS = {
  'active-unacknowledged': 'ACTIVE, not acknowledged',
  'active-acknowledged': 'active, acknowledged',
  'rectified-unacknowledged': 'rectified, not acknowledged',
  'normal': 'normal',
};

function el(tag, attrs, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === 'class') e.className = v; else if (k.startsWith('data-')) e.setAttribute(k, v);
    else e[k] = v;
  }
  for (const c of children) e.append(c instanceof Node ? c : document.createTextNode(String(c)));
  return e;
}

function fixed(x, n) { return x === null || x === undefined ? '–' : Number(x).toFixed(n); }
function age(s) {
  if (s === null || s === undefined) return '–';
  if (s < 60) return s.toFixed(1) + ' s';
  if (s < 3600) return Math.floor(s / 60) + ' min ' + Math.floor(s % 60) + ' s';
  return Math.floor(s / 3600) + ' h ' + Math.floor((s % 3600) / 60) + ' min';
}
function utc(t) { return t === null ? '–' : new Date(t * 1000).toISOString().replace('T', ' ').slice(0, 23); }

// A delta other than the next one after `revision` (BoardFrame in src/app/dashboard/board.hpp):
// a board put together from it would drift from the dashboard's. Closes the stream and opens a
// new one (connect), which starts with the whole board; true when it did.
function reopenOnMissedDelta(msg, revision, es, link, connect) {
  if (!msg.delta || revision === null || revision === undefined || msg.revision === revision + 1) {
    return false;
  }
  es.close();
  link.textContent = 'reconnecting'; link.className = 'link down';
  connect();
  return true;
}
