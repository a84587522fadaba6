// Test harness for the sylva daemon: starts the real binary on 127.0.0.1 with a
// fresh store, and talks to it with the `ws` package (a client this project did
// not write).
import { spawn, spawnSync } from 'node:child_process';
import { mkdtempSync, rmSync, readFileSync } from 'node:fs';
import { createServer, connect as tcpConnect } from 'node:net';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import WebSocket from 'ws';

export const SYLVA = process.env.SYLVA_EXE;
export const ROOT = process.env.SYLVA_ROOT;
if (!SYLVA || !ROOT) throw new Error('set SYLVA_EXE and SYLVA_ROOT (meson does)');
// The sanitizer build is slower: scale waits.
export const SLOW = Number(process.env.SYLVA_SLOW || '1');

export function freePort() {
  return new Promise((resolve, reject) => {
    const s = createServer();
    s.once('error', reject);
    s.listen(0, '127.0.0.1', () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}

// A fresh directory for a store, under SYLVA_TEST_TMPDIR when it is set.
export function tempDir() {
  return mkdtempSync(join(process.env.SYLVA_TEST_TMPDIR || tmpdir(), 'sylva-serve-'));
}

// Starts `sylva serve`; resolves when it listens. Returns {proc, port, url, stderr()}.
export async function startDaemon({ dir, port, args = [], wrapper = [] } = {}) {
  dir ??= tempDir();
  port ??= await freePort();
  const db = join(dir, 'runs.db');
  const argv = [...wrapper, SYLVA, 'serve', '--db', db, '--listen', `127.0.0.1:${port}`,
    '--scenarios', join(ROOT, 'scenarios'), ...args];
  const proc = spawn(argv[0], argv.slice(1), { stdio: ['ignore', 'pipe', 'pipe'] });
  let err = '';
  proc.stderr.on('data', (d) => { err += d; });
  await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`daemon did not start: ${err}`)), 60000 * SLOW);
    const check = () => {
      if (err.includes('listening on')) { clearTimeout(timer); resolve(); }
    };
    proc.stderr.on('data', check);
    proc.on('exit', (code) => { clearTimeout(timer); reject(new Error(`daemon exited ${code}: ${err}`)); });
    check();
  });
  proc.removeAllListeners('exit');
  return { proc, port, dir, db, url: `ws://127.0.0.1:${port}/ws`, http: `http://127.0.0.1:${port}`,
    stderr: () => err };
}

// Runs fn(daemon) on a daemon of its own (options as for startDaemon), then stops
// it with SIGTERM, which must end it with status 0 (so a sanitizer's report at exit
// fails the test), and removes its directory.
export async function withDaemon(options, fn) {
  const d = await startDaemon(options);
  let result;
  try {
    result = await fn(d);
  } catch (e) {
    await stopDaemon(d);
    cleanup(d.dir);
    throw e;
  }
  const exit = await stopDaemon(d);
  cleanup(d.dir);
  if (exit.code !== 0)
    throw new Error(`the daemon ended with ${JSON.stringify(exit)}: ${d.stderr().slice(-3000)}`);
  return result;
}

export function stopDaemon(d, signal = 'SIGTERM') {
  return new Promise((resolve) => {
    if (d.proc.exitCode !== null || d.proc.signalCode !== null) {
      resolve({ code: d.proc.exitCode, signal: d.proc.signalCode });
      return;
    }
    d.proc.once('exit', (code, sig) => resolve({ code, signal: sig }));
    d.proc.kill(signal);
  });
}

// A protocol client: queues every message; next(pred) waits for the first match.
export class Client {
  constructor(url, opts = {}) {
    this.ws = new WebSocket(url, 'sylva.v1', opts);
    this.messages = [];
    this.waiters = [];
    this.closed = null;
    this.ws.on('message', (data, isBinary) => {
      const msg = JSON.parse(isBinary ? data : data.toString());
      this.messages.push(msg);
      this.flush();
    });
    this.ws.on('close', (code, reason) => {
      this.closed = { code, reason: reason.toString() };
      this.flush();
    });
    this.ws.on('error', (e) => { this.error = e; this.flush(); });
  }

  opened() {
    return new Promise((resolve, reject) => {
      if (this.ws.readyState === WebSocket.OPEN) return resolve();
      this.ws.once('open', resolve);
      this.ws.once('error', reject);
      this.ws.once('unexpected-response', (req, res) => reject(new Error(`HTTP ${res.statusCode}`)));
    });
  }

  send(obj) { this.ws.send(typeof obj === 'string' ? obj : JSON.stringify(obj)); }

  flush() {
    this.waiters = this.waiters.filter((w) => {
      const i = this.messages.findIndex(w.pred);
      if (i >= 0) {
        const [m] = this.messages.splice(i, 1);
        clearTimeout(w.timer);
        w.resolve(m);
        return false;
      }
      if (this.closed || this.error) {
        clearTimeout(w.timer);
        w.reject(new Error(`closed while waiting: ${JSON.stringify(this.closed)} ${this.error}`));
        return false;
      }
      return true;
    });
  }

  next(pred = () => true, ms = 30000) {
    return new Promise((resolve, reject) => {
      const w = { pred, resolve, reject };
      w.timer = setTimeout(() => {
        this.waiters = this.waiters.filter((x) => x !== w);
        reject(new Error(`timed out waiting; have ${JSON.stringify(this.messages.map((m) => m.type))}`));
      }, ms * SLOW);
      this.waiters.push(w);
      this.flush();
    });
  }

  type(t, ms) { return this.next((m) => m.type === t, ms); }

  close() { this.ws.close(); }

  whenClosed(ms = 10000) {
    return new Promise((resolve, reject) => {
      if (this.closed) return resolve(this.closed);
      const timer = setTimeout(() => reject(new Error('not closed')), ms * SLOW);
      this.ws.once('close', (code, reason) => { clearTimeout(timer); resolve({ code, reason: reason.toString() }); });
    });
  }
}

export async function connect(url, opts) {
  const c = new Client(url, opts);
  await c.opened();
  await c.type('welcome');
  return c;
}

// A fresh subscriber's snapshot of a run (on a connection of its own).
export async function serverSnapshot(d, run) {
  const c = await connect(d.url);
  c.send({ type: 'subscribe', run });
  const snap = await c.type('snapshot');
  c.close();
  return snap;
}

export function scenario(name, overrides = {}) {
  const s = JSON.parse(readFileSync(join(ROOT, 'scenarios', name), 'utf8'));
  return { ...s, ...overrides };
}

// The test scenario of years (tests/scenario/years.json): two trees of a species
// with years (aged 0 and 3 at planting), an IGM tree, a lane zone, from 2027.
export const YEARS_FILE = join(ROOT, 'tests', 'scenario', 'years.json');
export function yearsScenario(overrides = {}) {
  return { ...JSON.parse(readFileSync(YEARS_FILE, 'utf8')), ...overrides };
}

// A skeleton held by a client: snapshot, then deltas.
export class Model {
  constructor(snapshot) {
    this.iteration = snapshot.iteration;
    this.seq = snapshot.seq;
    this.plants = snapshot.plants.map((p) => ({ id: p.id, stems: p.stems.map((s) => ({ root: s.root, nodes: new Map(s.nodes.map((n) => [n[0], n.slice()])) })) }));
    // id -> leaves of every node bearing leaves (protocol.md, "snapshot": leaves)
    this.leaves = new Map((snapshot.leaves ?? []).map(([id, n]) => [id, n]));
  }

  apply(delta) {
    if (delta.seq !== this.seq + 1) throw new Error(`gap: have ${this.seq}, got ${delta.seq}`);
    this.seq = delta.seq;
    this.iteration = delta.iteration;
    const where = new Map();
    this.plants.forEach((p) => p.stems.forEach((s) => s.nodes.forEach((n, id) => where.set(id, s))));
    for (const [id, parent, plant, stem, x, y, z, radius] of delta.added) {
      const s = this.plants[plant].stems[stem];
      s.nodes.set(id, [id, parent, x, y, z, radius, delta.iteration]);
      where.set(id, s);
    }
    for (const [id, radius] of delta.radii) {
      const s = where.get(id);
      if (!s) throw new Error(`radius of unknown node ${id}`);
      s.nodes.get(id)[5] = radius;
    }
    for (const root of delta.shed) {
      const s = where.get(root);
      if (!s) throw new Error(`shed of unknown node ${root}`);
      const gone = new Set([root]);
      let grew = true;
      while (grew) {
        grew = false;
        for (const [id, n] of s.nodes) if (!gone.has(id) && gone.has(n[1])) { gone.add(id); grew = true; }
      }
      for (const id of gone) {
        s.nodes.delete(id);
        this.leaves.delete(id);
      }
    }
    for (const [id, n] of delta.leaves) {
      if (!where.has(id) || !where.get(id).nodes.has(id)) throw new Error(`leaves of unknown node ${id}`);
      if (n > 0) this.leaves.set(id, n);
      else this.leaves.delete(id);
    }
  }

  // The leaves held, as a snapshot lists them: [[id, n], ...] in id order.
  leavesList() {
    return [...this.leaves].sort((a, b) => a[0] - b[0]);
  }

  // The plants part of a skeleton, nodes in id order, as JSON.
  plantsJSON() {
    return JSON.stringify(this.plants.map((p) => ({ id: p.id, stems: p.stems.map((s) => ({ root: s.root, nodes: [...s.nodes.values()].sort((a, b) => a[0] - b[0]) })) })));
  }
}

// The bytes `sylva export --format FORMAT -o -` writes (iteration undefined: the
// last; extra: more options, e.g. ['--obstacles']).
export function exportBytes(db, name, format, iteration, extra = []) {
  const args = ['export', '--db', db, '--name', name, '--format', format, '-o', '-', ...extra];
  if (iteration !== undefined) args.push('--iteration', String(iteration));
  const r = spawnSync(SYLVA, args, { maxBuffer: 1 << 30 });
  if (r.status !== 0) throw new Error(`export failed: ${r.stderr}`);
  return r.stdout;
}

export function exportSkeleton(db, name, iteration) {
  return JSON.parse(exportBytes(db, name, 'skeleton', iteration).toString('utf8'));
}

// GET with the path sent as it is (fetch would resolve "..", also "%2e%2e"), over a
// connection of its own; resolves with the whole reply as text.
export function rawGet(port, path) {
  return new Promise((resolve) => {
    const s = tcpConnect(port, '127.0.0.1', () => s.write(
      `GET ${path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n`));
    let buf = '';
    s.on('data', (x) => { buf += x; });
    s.on('close', () => resolve(buf));
    s.on('error', () => resolve(buf));
  });
}

// A raw WebSocket on sylva.v1: once upgraded, send(socket) writes what the test
// wants; resolves with the code of the first close frame the daemon sends, or null
// when the connection ends (or `ms` pass) without one.
// With untilDropped, the client neither answers the close frame nor closes: it
// resolves {code, droppedMs}, the time from the close frame to the daemon ending
// the connection.
export function rawCloseCode(port, send, ms = 15000, { untilDropped = false } = {}) {
  return new Promise((resolve) => {
    const s = tcpConnect(port, '127.0.0.1');
    let buf = Buffer.alloc(0), upgraded = false, closeAt = null, closeCode = null;
    const done = (code) => {
      s.destroy();
      if (!untilDropped) resolve(code);
      else resolve({ code: closeCode, droppedMs: closeAt === null ? null : Date.now() - closeAt });
    };
    s.on('data', (b) => {
      buf = Buffer.concat([buf, b]);
      if (!upgraded) {
        const end = buf.indexOf('\r\n\r\n');
        if (end < 0) return;
        upgraded = true;
        buf = buf.subarray(end + 4);
        send(s);
      }
      const at = buf.indexOf(0x88);
      if (at >= 0 && buf.length >= at + 4 && closeAt === null) {
        if (!untilDropped) return done(buf.readUInt16BE(at + 2));
        closeAt = Date.now();
        closeCode = buf.readUInt16BE(at + 2);
      }
    });
    s.on('close', () => done(null));
    s.on('error', () => done(null));
    s.setTimeout(ms, () => done(null));
    s.write(`GET /ws HTTP/1.1\r\nHost: 127.0.0.1:${port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n` +
      'Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: sylva.v1\r\n\r\n');
  });
}

export function plantsJSON(skeleton) {
  return JSON.stringify(skeleton.plants.map((p) => ({ id: p.id, stems: p.stems.map((s) => ({ root: s.root, nodes: s.nodes })) })));
}

// Sends GET path on a connection of its own and reads nothing; resolves once the
// request is written. leave: the client then closes the connection at once.
export function askOnly(port, path, { leave = false } = {}) {
  return new Promise((resolve) => {
    const s = tcpConnect(port, '127.0.0.1', () => {
      s.write(`GET ${path} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n`, () => {
        if (leave) s.destroy();
        resolve();
      });
    });
    s.on('error', resolve);
  });
}

export function cleanup(dir) { rmSync(dir, { recursive: true, force: true }); }

// The scenario `sylva site` writes from the GIS fixtures of tests/gis/data (three
// buildings at 30 degrees, one with a courtyard, a road zone, trees in lon/lat), as
// tests/gis/test_site_cli.py makes it: written into dir, returned parsed.
export function gisSite(dir) {
  const data = join(ROOT, 'tests', 'gis', 'data');
  const file = join(dir, 'site.json');
  const r = spawnSync(SYLVA, ['site', '--buildings', join(data, 'buildings.geojson'), '--height-field', 'height',
    '--levels-field', 'levels', '--building-id-field', 'id', '--trees', join(data, 'trees.geojson'),
    '--species-field', 'species', '--dbh-field', 'dbh', '--id-field', 'id', '--keep', 'status=alive',
    '--zones', join(data, 'zones.geojson'), '--zone-field', 'clearance', '--start-year', '2027', '-o', file],
  { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`sylva site failed (${r.status}): ${r.stderr}`);
  return JSON.parse(readFileSync(file, 'utf8'));
}
