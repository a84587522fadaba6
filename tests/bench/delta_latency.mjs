// Benchmark (not a test): how fast the daemon fans a run's deltas out to many
// viewers, and how long a fresh subscriber waits for the snapshot of a big world.
//
//   node tests/bench/delta_latency.mjs [--exe build/server/sylva] [--viewers 100]
//        [--iterations5 20] [--iterations100 24] [--years 15] [--threads 2]
//        [--serve-threads 1,2] [--only 5|100|hectare] [--detail nodes|stems]
//        [--work-nice N]
//
// Three runs: the five-tree stand (scenarios/stand.json), a generated 100-tree
// stand (igm-fig17b, tropism up, 10 x 10 trees 2 m apart in a 26 x 26 x 14 m world)
// and the growing hectare (400 utdb:NoEast:TICO 5 m apart, --years), the last once
// per --serve-threads value (`sylva serve --threads`; default: the daemon's own), with
// `--work-nice N` when given (default: the daemon's, 10).
// The viewers live in worker threads (--threads of them, each its own event loop)
// and stamp every message on arrival with the system's monotonic clock, which is
// the daemon's CLOCK_MONOTONIC: the daemon writes when each iteration's step
// returned, was stored, its delta encoded and handed to the clients
// (`--trace-iterations`), so the latency is absolute: a viewer's receipt minus the
// iteration's end, as p50/p99/max over every (delta, viewer) pair, the worst per
// delta, and the daemon's own share (handed out minus end: storing, encoding, the
// loop's wait). Viewers the daemon closes as too slow (64 MiB behind) are counted.
// The relative latency is reported too: arrival at a viewer minus the first
// arrival at any viewer (the fan-out spread); plus bytes per delta, and the CPU
// of the daemon, its loop thread and the viewers while growing. After the run, a
// fresh client subscribes and times the snapshot of the final world (sent,
// received and parsed), and asks for the same iteration with `get` (from the store).
// --detail stems: the viewers and the fresh subscriber subscribe with `"detail":
// "stems"` (protocol.md, "subscribe": each stem's stats, no internodes); default
// nodes, every internode.
// Use a release build on a quiet machine; the numbers include the viewers' own
// receive path on the same machine.
import { Worker, isMainThread, parentPort, workerData } from 'node:worker_threads';
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { hectare, stand100 } from './stand100.mjs';

const require = createRequire(new URL('../server/package.json', import.meta.url));
const WebSocket = require('ws');
const now = () => Number(process.hrtime.bigint()) / 1e6; // ms, monotonic, shared by threads

// ---- viewer threads ----------------------------------------------------------------

if (!isMainThread) {
  const { url, run, count, detail } = workerData;
  const records = []; // [viewer, type, seq, iteration, bytes, t]
  const dropped = []; // [viewer, close code, reason]: closed by the daemon before the end
  let subscribed = 0;
  let finished = 0;
  const sockets = [];
  const ended = new Set();
  const end = (v) => { // the run finished for this viewer, or the daemon closed it
    if (ended.has(v)) return;
    ended.add(v);
    if (++finished === count) {
      parentPort.postMessage({ records, dropped });
      for (const s of sockets) s.close();
    }
  };
  for (let v = 0; v < count; v++) {
    const ws = new WebSocket(url, 'sylva.v1', { perMessageDeflate: false, maxPayload: 2 ** 31 });
    sockets.push(ws);
    ws.on('close', (code, reason) => {
      if (!ended.has(v)) dropped.push([v, code, String(reason)]);
      end(v);
    });
    ws.on('message', (data) => {
      const t = now();
      const head = data.toString('latin1', 0, Math.min(data.length, 100));
      const type = (head.match(/^\{"type":"(\w+)"/) || [])[1];
      if (type === 'welcome') {
        ws.send(JSON.stringify({ type: 'subscribe', run, detail }));
      } else if (type === 'snapshot' || type === 'delta') {
        const m = head.match(/"seq":(\d+),"iteration":(\d+)/);
        records.push([v, type, Number(m[1]), Number(m[2]), data.length, t]);
        if (type === 'snapshot' && ++subscribed === count) parentPort.postMessage({ subscribed: true });
      } else if (type === 'status' && /"status":"(finished|failed)"/.test(head)) {
        end(v);
      }
    });
    ws.on('error', (e) => parentPort.postMessage({ error: String(e) }));
  }
}

// ---- main ---------------------------------------------------------------------------

function arg(name, def) {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 ? process.argv[i + 1] : def;
}

async function startDaemon(exe, root, extra) {
  const dir = mkdtempSync(join(tmpdir(), 'sylva-bench-'));
  const port = 20000 + Math.floor(Math.random() * 20000);
  const trace = join(dir, 'iterations.trace');
  const proc = spawn(exe, ['serve', '--db', join(dir, 'runs.db'), '--listen', `127.0.0.1:${port}`,
    '--scenarios', join(root, 'scenarios'), '--max-message', String(1 << 26),
    '--trace-iterations', trace, ...extra],
  { stdio: ['ignore', 'ignore', 'pipe'] });
  let err = '';
  proc.stderr.on('data', (d) => { err += d; });
  await new Promise((ok, fail) => {
    const timer = setInterval(() => {
      if (err.includes('listening on')) { clearInterval(timer); ok(); }
      if (proc.exitCode !== null) { clearInterval(timer); fail(new Error(err)); }
    }, 20);
  });
  return { proc, dir, port, trace, url: `ws://127.0.0.1:${port}/ws`, http: `http://127.0.0.1:${port}`, log: () => err };
}

// A client that parses everything (for the control connection and the fresh subscriber).
function client(url) {
  const ws = new WebSocket(url, 'sylva.v1', { perMessageDeflate: false, maxPayload: 2 ** 31 });
  const queue = [];
  const waiters = [];
  ws.on('message', (data) => {
    const t = now();
    queue.push({ data, t });
    for (const w of [...waiters]) w();
  });
  // closed by the daemon (a `get` of a world larger than a client's 64 MiB backlog):
  // what the waiter gets is an error naming the close
  ws.on('close', (code, reason) => {
    const data = Buffer.from(JSON.stringify({ type: 'error', code: 'closed', message: `closed ${code} ${reason}` }));
    queue.push({ data, t: now() });
    for (const w of [...waiters]) w();
  });
  const next = (pred) => new Promise((ok) => {
    const check = () => {
      const i = queue.findIndex((x) => pred(x));
      if (i < 0) return false;
      waiters.splice(waiters.indexOf(check), 1);
      ok(queue.splice(i, 1)[0]);
      return true;
    };
    waiters.push(check);
    check();
  });
  const opened = new Promise((ok, fail) => { ws.once('open', ok); ws.once('error', fail); });
  return { ws, next, opened, send: (o) => ws.send(JSON.stringify(o)) };
}

const headType = (x) => (x.data.toString('latin1', 0, 40).match(/^\{"type":"(\w+)"/) || [])[1];

function quantile(sorted, q) {
  if (!sorted.length) return NaN;
  return sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))];
}

async function bench(label, scenario, opts) {
  const d = await startDaemon(opts.exe, opts.root, opts.daemonArgs || []);
  try {
    const ctl = client(d.url);
    await ctl.opened;
    ctl.send({ type: 'create', name: 'bench', start: false, scenario });
    const created = JSON.parse((await ctl.next((x) => headType(x) === 'created')).data);
    const run = created.run;
    const per = Math.ceil(opts.viewers / opts.threads);
    const workers = [];
    const results = [];
    const dropped = [];
    for (let k = 0, left = opts.viewers; left > 0; k++, left -= per) {
      const count = Math.min(per, left);
      const w = new Worker(fileURLToPath(import.meta.url), { workerData: { url: d.url, run, count, detail: opts.detail } });
      const sub = new Promise((ok, fail) => {
        w.on('message', (m) => {
          if (m.error) fail(new Error(m.error));
          if (m.subscribed) ok();
          if (m.records) results.push(m.records.map((r) => [r[0] + k * per, ...r.slice(1)]));
          if (m.dropped) dropped.push(...m.dropped);
        });
        w.on('error', fail);
      });
      workers.push({ w, sub, done: new Promise((ok) => w.on('exit', ok)) });
    }
    await Promise.all(workers.map((x) => x.sub));
    const t0 = now();
    const cpu0 = process.cpuUsage(); // this process: the viewers' threads and the control
    ctl.send({ type: 'control', run, action: 'start' });
    // the run's end from /api/runs: a subscribed control client could fall behind and
    // be closed as too slow (as viewers can), and then never hear of it
    for (;;) {
      const runs = await (await fetch(`${d.http}/api/runs`)).json();
      if (/^(finished|failed)$/.test(runs.find((x) => x.run === run).status)) break;
      await new Promise((ok) => setTimeout(ok, 100));
    }
    const grow = now() - t0;
    await Promise.all(workers.map((x) => x.done));
    const cpu = (path) => { // utime + stime, seconds (the fields after the command's ')')
      const f = readFileSync(path, 'utf8').split(') ')[1].split(' ');
      return (Number(f[11]) + Number(f[12])) / 100;
    };
    const cpuAll = cpu(`/proc/${d.proc.pid}/stat`);
    const cpuLoop = cpu(`/proc/${d.proc.pid}/task/${d.proc.pid}/stat`); // the libuv loop
    const used = process.cpuUsage(cpu0);
    const cpuViewers = (used.user + used.system) / 1e6;
    const records = results.flat();
    const deltaBytes = records.reduce((n, x) => n + (x[1] === 'delta' ? x[4] : 0), 0);
    // the daemon's trace: iteration -> [step returned, stored, encoded, handed out], ms
    const traced = new Map();
    for (const line of readFileSync(d.trace, 'utf8').split('\n')) {
      const [id, it, ...times] = line.split(' ').map(Number);
      if (id === run) traced.set(it, times.map((t) => t * 1e3));
    }

    // per delta: arrivals at every viewer
    const bySeq = new Map();
    for (const [v, type, seq, it, bytes, t] of records) {
      if (type !== 'delta') continue;
      if (!bySeq.has(seq)) bySeq.set(seq, { it, bytes, arrivals: [] });
      bySeq.get(seq).arrivals.push(t);
      void v;
    }
    const rel = [];
    const spreads = [];
    const abs = []; // receipt at a viewer - the iteration's end in the daemon
    const worst = [];
    const shares = [];
    const rows = [];
    let incomplete = 0;
    for (const [seq, x] of [...bySeq].sort((a, b) => a[0] - b[0])) {
      if (x.arrivals.length !== opts.viewers) incomplete++;
      const first = Math.min(...x.arrivals);
      const last = Math.max(...x.arrivals);
      const r = x.arrivals.map((t) => t - first).sort((a, b) => a - b);
      rel.push(...r);
      spreads.push(last - first);
      const [end, stored, encoded, out] = traced.get(x.it) || [NaN, NaN, NaN, NaN];
      abs.push(...x.arrivals.map((t) => t - end));
      worst.push(last - end);
      shares.push(out - end);
      rows.push({ seq, iteration: x.it, bytes: x.bytes, p50: quantile(r, 0.5), p99: quantile(r, 0.99), spread: last - first,
        share: out - end, store: stored - end, encode: encoded - stored, wait: out - encoded, absP50: quantile(x.arrivals.map((t) => t - end).sort((a, b) => a - b), 0.5), worst: last - end });
    }
    for (const a of [rel, spreads, abs, worst, shares]) a.sort((p, q) => p - q);

    // a fresh subscriber of the final world, and `get` of the same iteration
    const snaps = [];
    for (let i = 0; i < 3; i++) {
      const f = client(d.url);
      await f.opened;
      await f.next((x) => headType(x) === 'welcome');
      const s0 = now();
      f.send({ type: 'subscribe', run, detail: opts.detail });
      const msg = await f.next((x) => headType(x) === 'snapshot' || headType(x) === 'error');
      const tArrive = msg.t;
      const snap = JSON.parse(msg.data);
      if (snap.type === 'error') {
        snaps.push({ kind: 'subscribe', arrive: tArrive - s0, parsed: now() - s0, bytes: msg.data.length, nodes: snap.message, iteration: '-' });
        break;
      }
      const tParsed = now();
      let nodes = 0;
      for (const p of snap.plants) for (const s of p.stems) nodes += s.nodes?.length ?? 0;
      snaps.push({ kind: 'subscribe', arrive: tArrive - s0, parsed: tParsed - s0, bytes: msg.data.length, nodes, iteration: snap.iteration });
      const g0 = now();
      f.send({ type: 'get', run, iteration: snap.iteration, id: 'g' });
      const gm = await f.next((x) => headType(x) === 'snapshot' || headType(x) === 'error');
      const gParsed = JSON.parse(gm.data);
      snaps.push({ kind: 'get', arrive: gm.t - g0, parsed: now() - g0, bytes: gm.data.length,
        nodes: gParsed.plants ? gParsed.plants.reduce((n, p) => n + p.stems.reduce((m, s) => m + s.nodes.length, 0), 0) : gParsed.message, iteration: gParsed.iteration ?? '-' });
      f.ws.close();
      if (gParsed.type === 'error') break; /* the same again */
    }
    const metrics = await (await fetch(`${d.http}/metrics`)).text();
    const pick = (n) => (metrics.match(new RegExp(`^${n} (\\S+)$`, 'm')) || [])[1];
    const status = readFileSync(`/proc/${d.proc.pid}/status`, 'utf8');
    const hwm = Number(status.match(/VmHWM:\s+(\d+)/)[1]) / 1024;
    ctl.ws.close();
    return { label, detail: opts.detail, grow, rows, rel, spreads, abs, worst, shares, incomplete, snaps, hwm, cpuAll, cpuLoop, cpuViewers, deltaBytes, dropped,
      iterSeconds: Number(pick('sylva_iteration_seconds_total')), sent: Number(pick('sylva_bytes_sent_total')) };
  } finally {
    d.proc.kill('SIGTERM');
    await new Promise((ok) => d.proc.once('exit', ok));
    rmSync(d.dir, { recursive: true, force: true });
  }
}

function fmtMs(x) { return x < 10 ? x.toFixed(2) : x.toFixed(0); }
function fmtBytes(x) { return x >= 2 ** 20 ? `${(x / 2 ** 20).toFixed(1)} MiB` : `${(x / 1024).toFixed(1)} KiB`; }

function report(r, viewers) {
  console.log(`\n== ${r.label}: ${viewers} viewers at detail ${r.detail} ==`);
  console.log(`grew ${r.rows.length} iterations in ${(r.grow / 1000).toFixed(2)} s (${r.iterSeconds.toFixed(2)} s of it growing, the rest fan-out and scheduling); ${fmtBytes(r.sent)} sent; daemon peak RSS ${r.hwm.toFixed(0)} MiB; deltas missing at some viewer: ${r.incomplete}`);
  if (r.dropped.length) {
    const why = [...new Set(r.dropped.map((x) => `${x[1]} ${x[2]}`))].join('; ');
    console.log(`viewers closed by the daemon before the end: ${r.dropped.length} (${why}); the figures below are of the deltas that arrived`);
  }
  console.log(`by the end of growth: daemon CPU ${r.cpuAll.toFixed(1)} s, of which the loop thread ${r.cpuLoop.toFixed(1)} s for ${fmtBytes(r.deltaBytes)} of deltas (${(r.cpuLoop / (r.deltaBytes / 2 ** 30)).toFixed(2)} s per GiB); the viewers ${r.cpuViewers.toFixed(1)} s`);
  console.log('                   the daemon: store + encode + loop       a viewer since the end    since the first arrival');
  console.log('iter  delta bytes   share ms  store ms encode ms  wait ms        p50 ms  last ms          p50 ms   p99 ms  spread ms');
  const col = (x, w) => fmtMs(x).padStart(w);
  for (const x of r.rows) {
    console.log(`${String(x.iteration).padStart(4)}  ${fmtBytes(x.bytes).padStart(11)}  ${col(x.share, 9)} ${col(x.store, 9)} ${col(x.encode, 9)} ${col(x.wait, 8)}     ${col(x.absP50, 9)} ${col(x.worst, 8)}        ${col(x.p50, 8)} ${col(x.p99, 8)} ${col(x.spread, 10)}`);
  }
  const max = (a) => a[a.length - 1];
  console.log(`receipt - iteration end, all deltas x viewers: p50 ${fmtMs(quantile(r.abs, 0.5))} ms, p99 ${fmtMs(quantile(r.abs, 0.99))} ms, max ${fmtMs(max(r.abs))} ms; the last viewer per delta: p50 ${fmtMs(quantile(r.worst, 0.5))} ms, max ${fmtMs(max(r.worst))} ms`);
  const med = (k) => fmtMs(quantile(r.rows.map((x) => x[k]).sort((a, b) => a - b), 0.5));
  console.log(`the daemon's share (delta handed out - iteration end): p50 ${fmtMs(quantile(r.shares, 0.5))} ms, max ${fmtMs(max(r.shares))} ms; medians: storing ${med('store')} ms, encoding ${med('encode')} ms, the loop's wait ${med('wait')} ms`);
  console.log(`arrival - first arrival, all deltas x viewers: p50 ${fmtMs(quantile(r.rel, 0.5))} ms, p99 ${fmtMs(quantile(r.rel, 0.99))} ms; spread per delta: p50 ${fmtMs(quantile(r.spreads, 0.5))} ms, p99 ${fmtMs(quantile(r.spreads, 0.99))} ms, max ${fmtMs(max(r.spreads))} ms`);
  console.log('final world, fresh client: kind       iteration  nodes      bytes        arrived ms  parsed ms');
  for (const s of r.snaps) {
    console.log(`                           ${s.kind.padEnd(10)} ${String(s.iteration).padStart(9)}  ${String(s.nodes).padEnd(9)}  ${fmtBytes(s.bytes).padStart(11)}  ${fmtMs(s.arrive).padStart(10)}  ${fmtMs(s.parsed).padStart(9)}`);
  }
}

async function main() {
  const root = resolve(dirname(fileURLToPath(import.meta.url)), '..', '..');
  const opts = {
    root,
    exe: resolve(arg('exe', process.env.SYLVA_EXE || join(root, 'build', 'server', 'sylva'))),
    viewers: Number(arg('viewers', '100')),
    threads: Number(arg('threads', '2')),
    detail: arg('detail', 'nodes'),
  };
  if (!['nodes', 'stems'].includes(opts.detail)) throw new Error(`--detail: nodes or stems, not ${opts.detail}`);
  const only = arg('only', null);
  const stand = JSON.parse(readFileSync(join(root, 'scenarios', 'stand.json'), 'utf8'));
  if (!only || only === '5') {
    report(await bench('five-tree stand (scenarios/stand.json)', { ...stand, iterations: Number(arg('iterations5', '20')) }, opts), opts.viewers);
  }
  if (!only || only === '100') {
    report(await bench('100-tree stand (igm-fig17b, 10 x 10, 2 m)', { ...stand100(), iterations: Number(arg('iterations100', '24')) }, opts), opts.viewers);
  }
  if (!only || only === 'hectare') {
    const years = Number(arg('years', '15'));
    for (const n of arg('serve-threads', '').split(',')) {
      // its worlds' estimate (400 stems) passes the default budget of 4096 MiB
      const nice = arg('work-nice', null);
      const daemonArgs = ['--memory-budget', '8192', ...(n ? ['--threads', n] : []),
        ...(nice !== null ? ['--work-nice', nice] : [])];
      report(await bench(`growing hectare (400 utdb:NoEast:TICO, 5 m apart), ${years} years, daemon --threads ${n || 'default'}${nice !== null ? ` --work-nice ${nice}` : ''}`,
        hectare(years), { ...opts, daemonArgs }), opts.viewers);
    }
  }
}

if (isMainThread) await main();
