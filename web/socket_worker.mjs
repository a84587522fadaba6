// The WebSocket to the daemon, in a worker: it connects and reconnects with
// backoff, parses every message off the page's thread, and hands snapshots and
// deltas over as typed arrays (transferred, not copied).
//
// From the page: {connect: url} once, then {send: object}.
// To the page: {state, detail} and {message, parseMs, bytes}.
import { deltaArrays, snapshotArrays, transferables } from './wire.mjs';

let url, ws = null, delay = 250, timer = 0;

function state(s, detail = '') { postMessage({ state: s, detail }); }

function connect() {
  state('connecting');
  let sock;
  try {
    sock = new WebSocket(url, 'sylva.v1');
  } catch (e) {
    retry(String(e));
    return;
  }
  ws = sock;
  sock.onopen = () => {
    delay = 250;
    state('open');
  };
  sock.onmessage = (ev) => {
    const t0 = performance.now();
    let msg;
    try {
      msg = JSON.parse(ev.data);
    } catch (e) {
      postMessage({ warning: `a message that is not JSON: ${e.message}` });
      return;
    }
    const t1 = performance.now();
    if (msg.type === 'delta') msg = deltaArrays(msg);
    else if (msg.type === 'snapshot') msg = snapshotArrays(msg);
    const t2 = performance.now();
    postMessage({ message: msg, parseMs: t1 - t0, convertMs: t2 - t1, bytes: ev.data.length },
      transferables(msg));
  };
  sock.onclose = (ev) => {
    if (ws !== sock) return;
    retry(ev.code ? `closed (${ev.code}${ev.reason ? ': ' + ev.reason : ''})` : 'closed');
  };
}

function retry(detail) {
  ws = null;
  const wait = delay;
  delay = Math.min(delay * 2, 4000);
  state('closed', detail);
  clearTimeout(timer);
  timer = setTimeout(connect, wait);
}

onmessage = (ev) => {
  const m = ev.data;
  if (m.connect) {
    url = m.connect;
    connect();
  } else if (m.send) {
    if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(m.send));
    else postMessage({ unsent: m.send });
  }
};
