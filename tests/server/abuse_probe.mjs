// The outside observer of the abuse suite (test_abuse.mjs), a process of its own so
// that the abuse the test process makes cannot delay its clock: every ~50 ms it
// asks GET /healthz on a fresh TCP connection and samples the daemon's VmRSS and
// CPU time from /proc; it follows the watched run with npm's ws client and notes
// when each delta arrives. Started by abuse_lib.mjs's Probe with fork(): its one
// argument is {port, pid, run, token, warm}; it sends {type: 'ready'} once the
// watched run is past iteration `warm`, and answers {cmd: 'stop'} with every
// sample ({type: 'samples', ...}), then exits.
import { request } from 'node:http';
import { readFileSync } from 'node:fs';
import WebSocket from 'ws';

const cfg = JSON.parse(process.argv[2]);
// To the test process, while it listens (it may be gone at the end).
function send(m) {
  try {
    if (process.connected) process.send(m);
  } catch { /* the channel closed */ }
}
// Whatever goes wrong here is told and measuring goes on: the test must get its
// samples (Probe.stop) rather than wait for a probe that died.
process.on('uncaughtException', (e) => send({ type: 'error', message: `probe: ${e.stack || e}` }));
const now = () => performance.timeOrigin + performance.now();
const PERIOD = 50;
const TIMEOUT = 5000;

const healthz = []; // {t, ms, status, error}
const mem = [];     // {t, rss, cpu, loop}: bytes; clock ticks of the process and its main thread
const deltas = [];  // {t, seq, iteration, type}
let inFlight = 0;

function healthzOnce() {
  const t = now();
  const sample = { t, ms: null, status: 0 };
  healthz.push(sample);
  inFlight++;
  let done = false;
  const finish = (error) => {
    if (done) return;
    done = true;
    inFlight--;
    sample.ms = now() - t;
    if (error) sample.error = error;
  };
  const req = request({ host: '127.0.0.1', port: cfg.port, path: '/healthz', agent: false,
    headers: { Connection: 'close' } }, (res) => {
    sample.status = res.statusCode;
    res.resume();
    res.on('end', () => finish(res.statusCode === 200 ? undefined : `HTTP ${res.statusCode}`));
    res.on('error', (e) => finish(e.code || e.message));
  });
  req.setTimeout(TIMEOUT, () => { req.destroy(); finish('timeout'); });
  req.on('error', (e) => finish(e.code || e.message));
  req.end();
}

function ticks(path) {
  // fields after the command's closing parenthesis: utime and stime are the 12th and 13th
  const f = readFileSync(path, 'utf8').split(') ')[1].split(' ');
  return Number(f[11]) + Number(f[12]);
}

function memOnce() {
  try {
    const status = readFileSync(`/proc/${cfg.pid}/status`, 'utf8');
    const rss = Number(/^VmRSS:\s+(\d+) kB/m.exec(status)[1]) * 1024;
    mem.push({ t: now(), rss, cpu: ticks(`/proc/${cfg.pid}/stat`), loop: ticks(`/proc/${cfg.pid}/task/${cfg.pid}/stat`) });
  } catch { /* the daemon is gone */ }
}

let ready = false;
const ws = new WebSocket(`ws://127.0.0.1:${cfg.port}/ws`, 'sylva.v1', { perMessageDeflate: false });
ws.on('message', (data) => {
  const t = now();
  const head = data.toString('latin1', 0, Math.min(data.length, 160));
  const type = (/^\{"type":"(\w+)"/.exec(head) || [])[1];
  if (type === 'welcome') {
    if (/"ref"/.test(head)) return; // the answer to the hello below
    if (cfg.token) ws.send(JSON.stringify({ type: 'hello', token: cfg.token, id: 'h' }));
    if (cfg.run) ws.send(JSON.stringify({ type: 'subscribe', run: cfg.run }));
    else { ready = true; process.send({ type: 'ready' }); }
    return;
  }
  if (type === 'delta' || type === 'snapshot') {
    const m = /"seq":(\d+),"iteration":(\d+)/.exec(head);
    if (!m) {
      send({ type: 'error', message: `watcher: a ${type} without seq and iteration: ${head}` });
      return;
    }
    deltas.push({ t, type, seq: Number(m[1]), iteration: Number(m[2]) });
    if (!ready && Number(m[2]) >= (cfg.warm || 0)) {
      ready = true;
      process.send({ type: 'ready' });
    }
  } else if (type === 'error') {
    send({ type: 'error', message: data.toString() });
  }
});
let wsClosed = null;
ws.on('close', (code) => { wsClosed = { t: now(), code }; });
ws.on('error', (e) => send({ type: 'error', message: `watcher: ${e.message}` }));

const timer = setInterval(() => { healthzOnce(); memOnce(); }, PERIOD);

process.on('message', async (m) => {
  if (m.cmd !== 'stop') return;
  clearInterval(timer);
  const end = now() + TIMEOUT + 500;
  while (inFlight > 0 && now() < end) await new Promise((r) => setTimeout(r, 20));
  ws.terminate();
  // a large message is still being written when send returns: going before it is
  // written lost it now and then, and the test waited for it in vain
  process.send({ type: 'samples', healthz, mem, deltas, wsClosed }, () => {
    process.disconnect();
    setTimeout(() => process.exit(0), 50);
  });
});
process.on('disconnect', () => process.exit(0));
