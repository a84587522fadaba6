// Helpers of the abuse suite (test_abuse.mjs): the watched run's scenario, the
// outside probe (abuse_probe.mjs, a process of its own), the numbers taken from its
// samples, raw HTTP and WebSocket clients for what npm's ws will not send, /proc
// readers and the store's integrity check.
import { fork, spawnSync } from 'node:child_process';
import { randomBytes } from 'node:crypto';
import { readFileSync, readdirSync, readlinkSync } from 'node:fs';
import { connect as netConnect } from 'node:net';
import { fileURLToPath } from 'node:url';

export const now = () => performance.timeOrigin + performance.now();
export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
export const MiB = 2 ** 20;

// ---- the watched run ------------------------------------------------------------

// Every ready scenario ends by its growth equations by iteration 23, in well under a
// second, so none can be watched through an abuse. This one grows as long as asked,
// at a steady cost: 600 seedlings of a Weibull growth whose rate stays near 3
// internodes an iteration for 10^5 iterations (so no stem ever finishes), in a
// world 4 m high.
// The leaders reach the top by iteration ~15 and stop lengthening; from then on each
// iteration costs the same (the light, the delta of 600 stems' stats, the store's
// transaction with a snapshot of ~25k nodes): about 12 ms, 80 to 90 deltas a
// second on one core, steady to within a few % from one 5 s window to the next
// (a branching tree's cost drifts by tens of %). Each iteration stores ~270 KB.
// Its world's estimate is small (the grid of a 12 x 8 x 4 m box in 0.1 m voxels,
// 11 MiB).
// `iterations` bounds it (a test that hangs must not fill the disk).
export function watchedScenario({ name = 'watched', cols = 30, rows = 20, height = 4, iterations = 6000 } = {}) {
  const plants = [];
  for (let i = 0; i < cols; i++) {
    for (let j = 0; j < rows; j++) {
      plants.push({ id: `p${i}-${j}`, species: 'seedling',
        roots: [[Number((-5.8 + i * 0.4).toFixed(1)), Number((-3.8 + j * 0.4).toFixed(1)), 0]] });
    }
  }
  return {
    format: 'sylva.scenario/1', name, seed: 7, iterations,
    world: { min: [-6, -4, 0], max: [6, 4, height], voxel: 0.1 },
    species: { seedling: { growth: { equation: 'weibull', omega1: 1000000, omega2: 0.000003, omega3: 1 } } },
    plants,
  };
}

// ---- the probe -------------------------------------------------------------------

const PROBE = fileURLToPath(new URL('./abuse_probe.mjs', import.meta.url));

// The outside observer of one daemon: start() resolves once the watched run (if any)
// is past iteration `warm`; stop() resolves with every sample.
export class Probe {
  constructor(d, { run = null, token = null, warm = 0 } = {}) {
    this.d = d;
    this.errors = [];
    this.child = fork(PROBE, [JSON.stringify({ port: d.port, pid: d.proc.pid, run, token, warm })],
      { stdio: ['ignore', 'inherit', 'inherit', 'ipc'] });
    this.ready = new Promise((resolve, reject) => {
      const timer = setTimeout(() => reject(new Error('the probe did not get ready (the watched run not growing?)')), 120000);
      this.child.on('message', (m) => {
        if (m.type === 'ready') { clearTimeout(timer); resolve(); }
        if (m.type === 'error') this.errors.push(m.message);
        if (m.type === 'samples') this.onSamples?.(m);
      });
      this.child.on('exit', (code) => { clearTimeout(timer); reject(new Error(`the probe exited ${code}`)); });
    });
  }

  // The samples; fails when the probe is gone or does not answer in 20 s.
  stop() {
    return new Promise((resolve, reject) => {
      const fail = (why) => reject(new Error(`the probe ${why}; its errors: ${this.errors.join(' | ')}`));
      if (this.child.exitCode !== null || this.child.signalCode !== null) {
        fail(`had exited (${this.child.exitCode ?? this.child.signalCode})`);
        return;
      }
      const timer = setTimeout(() => fail('sent no samples within 20 s'), 20000);
      // 'close', not 'exit': a message may still be read from the channel after 'exit'
      this.child.once('close', (code, signal) => { clearTimeout(timer); fail(`exited (${code ?? signal}) before its samples`); });
      this.onSamples = (m) => { clearTimeout(timer); resolve(new Samples(m)); };
      this.child.send({ cmd: 'stop' });
    });
  }

  kill() { if (this.child.exitCode === null) this.child.kill(); }
}

export function percentile(sorted, p) {
  if (!sorted.length) return NaN;
  return sorted[Math.min(sorted.length - 1, Math.ceil((p / 100) * sorted.length) - 1)];
}

// What the probe saw, cut into time windows (ms since the epoch, high resolution).
export class Samples {
  constructor(m) { Object.assign(this, m); }

  // /healthz latencies of the requests sent in [from, to): {n, p50, p99, max, failed}.
  // A request that failed or had no answer counts as an infinite latency.
  healthzIn(from, to) {
    const xs = this.healthz.filter((s) => s.t >= from && s.t < to);
    const ms = xs.map((s) => (s.error || s.ms === null ? Infinity : s.ms)).sort((a, b) => a - b);
    return { n: ms.length, p50: percentile(ms, 50), p99: percentile(ms, 99), max: ms[ms.length - 1],
      failed: xs.filter((s) => s.error || s.ms === null).map((s) => s.error || 'no answer') };
  }

  // The n slowest /healthz requests sent in [from, to), slowest first: [{t, ms}].
  slowestIn(from, to, n) {
    return this.healthz.filter((s) => s.t >= from && s.t < to)
      .map((s) => ({ t: s.t, ms: s.error || s.ms === null ? Infinity : s.ms }))
      .sort((a, b) => b.ms - a.ms).slice(0, n);
  }

  // Deltas of the watched run that arrived in [from, to), per second.
  rateIn(from, to) {
    return this.deltas.filter((x) => x.type === 'delta' && x.t >= from && x.t < to).length / ((to - from) / 1000);
  }

  lastIteration() { return this.deltas.length ? this.deltas[this.deltas.length - 1].iteration : -1; }

  rssPeak(from = -Infinity, to = Infinity) {
    return Math.max(0, ...this.mem.filter((s) => s.t >= from && s.t < to).map((s) => s.rss));
  }

  rssAt(t) {
    let best = null;
    for (const s of this.mem) if (s.t <= t) best = s;
    return best ? best.rss : NaN;
  }

  // CPU of the daemon in [from, to), in % of one core: {all, loop} (loop: its main
  // thread, the libuv loop).
  cpuIn(from, to) {
    const xs = this.mem.filter((s) => s.t >= from && s.t < to);
    if (xs.length < 2) return { all: NaN, loop: NaN };
    const a = xs[0], b = xs[xs.length - 1];
    const secs = (b.t - a.t) / 1000;
    return { all: (b.cpu - a.cpu) / secs, loop: (b.loop - a.loop) / secs }; // 100 ticks a second
  }
}

// ---- /proc -----------------------------------------------------------------------

export function rssOf(pid) {
  const m = /^VmRSS:\s+(\d+) kB/m.exec(readFileSync(`/proc/${pid}/status`, 'utf8'));
  return m ? Number(m[1]) * 1024 : NaN;
}

export function fdsOf(pid) {
  return readdirSync(`/proc/${pid}/fd`).map((fd) => {
    try { return readlinkSync(`/proc/${pid}/fd/${fd}`); } catch { return ''; }
  });
}

// Bytes the kernel holds between a server on port `server` and the clients on
// these local ports (IPv4, /proc/net/tcp): the client side's receive queue plus
// the server side's send queue, for each client port. What a client that stopped
// reading has not taken.
export function unreadBytes(server, ports) {
  const want = new Set(ports);
  const out = new Map(ports.map((p) => [p, 0]));
  for (const line of readFileSync('/proc/net/tcp', 'utf8').split('\n').slice(1)) {
    const f = line.trim().split(/\s+/);
    if (f.length < 5) continue;
    const local = parseInt(f[1].split(':')[1], 16), remote = parseInt(f[2].split(':')[1], 16);
    const [tx, rx] = f[4].split(':').map((x) => parseInt(x, 16));
    if (want.has(local) && remote === server) out.set(local, out.get(local) + rx);
    if (local === server && want.has(remote)) out.set(remote, out.get(remote) + tx);
  }
  return out;
}

// CPU time used by every process on the machine but these, in ticks (for telling
// whether other work on the machine changed between two windows).
export function cpuTicksTotal() {
  const f = readFileSync('/proc/stat', 'utf8').split('\n')[0].trim().split(/\s+/).slice(1).map(Number);
  return f[0] + f[1] + f[2] + f[5] + f[6] + f[7]; // user nice system irq softirq steal
}

// ---- the store -------------------------------------------------------------------

// PRAGMA integrity_check through python3's sqlite3 (node 20 has no SQLite of its own).
export function integrityCheck(db) {
  const r = spawnSync('python3', ['-c',
    'import sqlite3,sys; c=sqlite3.connect(sys.argv[1]); print("\\n".join(r[0] for r in c.execute("PRAGMA integrity_check")))', db],
  { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`python3 sqlite3: ${r.stderr}`);
  return r.stdout.trim();
}

export function sqlite(db, sql) {
  const r = spawnSync('python3', ['-c',
    'import sqlite3,sys,json; c=sqlite3.connect(sys.argv[1]); print(json.dumps([list(r) for r in c.execute(sys.argv[2])]))', db, sql],
  { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`python3 sqlite3: ${r.stderr}`);
  return JSON.parse(r.stdout);
}

// ---- raw clients -------------------------------------------------------------------

// An HTTP request written as given, on a connection of its own. Resolves with
// {status, text, ms, closedBy} once the daemon closes the connection or `ms` pass
// (closedBy 'server' or 'timeout').
export function rawHttp(port, text, ms = 3000) {
  return new Promise((resolve) => {
    const t0 = now();
    const s = netConnect(port, '127.0.0.1');
    let out = Buffer.alloc(0);
    let settled = false;
    const done = (closedBy) => {
      if (settled) return;
      settled = true;
      clearTimeout(timer);
      s.destroy();
      const reply = out.toString('latin1');
      resolve({ status: Number(/^HTTP\/1\.[01] (\d+)/.exec(reply)?.[1]), text: reply, ms: now() - t0, closedBy });
    };
    const timer = setTimeout(() => done('timeout'), ms);
    s.on('data', (b) => { out = Buffer.concat([out, b]); });
    s.on('end', () => done('server'));
    s.on('close', () => done('server'));
    s.on('error', () => done('server'));
    s.write(text);
  });
}

export function upgradeText(port, { path = '/ws', host = `127.0.0.1:${port}`, protocol = 'sylva.v1', origin } = {}) {
  return [`GET ${path} HTTP/1.1`, `Host: ${host}`, 'Upgrade: websocket', 'Connection: Upgrade',
    `Sec-WebSocket-Key: ${randomBytes(16).toString('base64')}`, 'Sec-WebSocket-Version: 13',
    ...(protocol ? [`Sec-WebSocket-Protocol: ${protocol}`] : []), ...(origin ? [`Origin: ${origin}`] : []), '', ''].join('\r\n');
}

// A WebSocket frame: opcode (1 text, 0 continuation, 8 close), fin, masked.
export function frame(opcode, payload, { fin = true, mask = true } = {}) {
  const n = payload.length;
  let head;
  if (n < 126) head = Buffer.from([opcode | (fin ? 0x80 : 0), n | (mask ? 0x80 : 0)]);
  else if (n < 65536) {
    head = Buffer.alloc(4);
    head[0] = opcode | (fin ? 0x80 : 0);
    head[1] = 126 | (mask ? 0x80 : 0);
    head.writeUInt16BE(n, 2);
  } else {
    head = Buffer.alloc(10);
    head[0] = opcode | (fin ? 0x80 : 0);
    head[1] = 127 | (mask ? 0x80 : 0);
    head.writeBigUInt64BE(BigInt(n), 2);
  }
  if (!mask) return Buffer.concat([head, payload]);
  const key = randomBytes(4);
  const body = Buffer.alloc(n);
  for (let i = 0; i < n; i++) body[i] = payload[i] ^ key[i & 3];
  return Buffer.concat([head, key, body]);
}

// A WebSocket by hand: resolves after the handshake with {sock, status, frames()}.
// Frames the daemon sends are parsed into .frames ({t, opcode, fin, payload}: t when
// it arrived); .closed ({t}) is set when the TCP connection ends.
export function rawSocket(port, opts = {}) {
  return new Promise((resolve) => {
    const sock = netConnect(port, '127.0.0.1');
    const r = { sock, status: 0, frames: [], closed: null, buf: Buffer.alloc(0), waiters: [] };
    let upgraded = false;
    const wake = () => { for (const w of r.waiters.splice(0)) w(); };
    sock.on('data', (b) => {
      r.buf = Buffer.concat([r.buf, b]);
      if (!upgraded) {
        const end = r.buf.indexOf('\r\n\r\n');
        if (end < 0) return;
        upgraded = true;
        r.head = r.buf.toString('latin1', 0, end);
        r.status = Number(/^HTTP\/1\.[01] (\d+)/.exec(r.head)?.[1]);
        r.buf = r.buf.subarray(end + 4);
        resolve(r);
      }
      for (;;) {
        if (r.buf.length < 2) break;
        let len = r.buf[1] & 0x7f, at = 2;
        if (len === 126) { if (r.buf.length < 4) break; len = r.buf.readUInt16BE(2); at = 4; }
        else if (len === 127) { if (r.buf.length < 10) break; len = Number(r.buf.readBigUInt64BE(2)); at = 10; }
        if (r.buf.length < at + len) break;
        r.frames.push({ t: now(), opcode: r.buf[0] & 0x0f, fin: !!(r.buf[0] & 0x80), payload: r.buf.subarray(at, at + len) });
        r.buf = r.buf.subarray(at + len);
      }
      wake();
    });
    const closed = () => {
      if (!r.closed) r.closed = { t: now() };
      if (!upgraded) { upgraded = true; resolve(r); }
      wake();
    };
    sock.on('close', closed);
    sock.on('error', closed);
    sock.on('connect', () => sock.write(upgradeText(port, opts)));
  });
}

// Waits until pred(r) holds or ms pass; returns pred(r).
export async function waitFor(r, pred, ms) {
  const end = now() + ms;
  while (!pred(r) && !r.closed && now() < end) {
    await new Promise((resolve) => {
      const timer = setTimeout(resolve, Math.max(1, end - now()));
      r.waiters.push(() => { clearTimeout(timer); resolve(); });
    });
  }
  return pred(r);
}

export function closeCodeOf(r) {
  const f = r.frames.find((x) => x.opcode === 8);
  return f && f.payload.length >= 2 ? f.payload.readUInt16BE(0) : null;
}

// Runs fn(i) for i in [0, n) with at most `width` at once.
export async function inBatches(n, width, fn) {
  const out = new Array(n);
  let next = 0;
  await Promise.all(Array.from({ length: Math.min(width, n) }, async () => {
    while (next < n) {
      const i = next++;
      out[i] = await fn(i);
    }
  }));
  return out;
}
