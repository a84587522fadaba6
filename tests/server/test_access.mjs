// Who may use the daemon (docs/protocol.md, "Access"), against the real daemon
// with npm's ws client and raw sockets: the Host allowlist on HTTP and
// WebSocket, the Origin check against the same names, the token on every route
// but /healthz and the viewer's files (or only on changes with --public-read),
// constant-time comparison and throttling of wrong tokens, --token-file and
// SYLVA_TOKEN, and RFC 6455's rules for upgrades and close frames.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { writeFileSync } from 'node:fs';
import { join } from 'node:path';
import net from 'node:net';
import { spawnSync } from 'node:child_process';
import WebSocket from 'ws';
import { SYLVA, ROOT, withDaemon, connect, Client, scenario, tempDir, cleanup, rawCloseCode } from './harness.mjs';

const WEB = ['--web', join(ROOT, 'web')];

// One raw HTTP request; resolves with the whole reply (the daemon closes or the
// timeout ends it).
function raw(port, text, ms = 2000) {
  return new Promise((resolve) => {
    const s = net.connect(port, '127.0.0.1');
    let out = Buffer.alloc(0);
    const done = () => { s.destroy(); resolve(out.toString('latin1')); };
    s.on('data', (b) => { out = Buffer.concat([out, b]); });
    s.on('close', done);
    s.on('error', done);
    s.setTimeout(ms, done);
    s.write(text);
  });
}

const status = (reply) => Number(/^HTTP\/1\.[01] (\d+)/.exec(reply)?.[1]);

function get(port, path, headers = {}) {
  const lines = [`GET ${path} HTTP/1.1`, `Host: ${headers.Host ?? `127.0.0.1:${port}`}`,
    ...Object.entries(headers).filter(([k]) => k !== 'Host').map(([k, v]) => `${k}: ${v}`),
    'Connection: close', '', ''];
  return raw(port, lines.join('\r\n'));
}

function upgrade(port, { path = '/ws', host = `127.0.0.1:${port}`, protocol = 'sylva.v1', origin } = {}) {
  const lines = [`GET ${path} HTTP/1.1`, `Host: ${host}`, 'Upgrade: websocket', 'Connection: Upgrade',
    'Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==', 'Sec-WebSocket-Version: 13',
    ...(protocol ? [`Sec-WebSocket-Protocol: ${protocol}`] : []), ...(origin ? [`Origin: ${origin}`] : []), '', ''];
  return raw(port, lines.join('\r\n'), 1000);
}

test('Host: only the daemon\'s own names, on every route and on upgrades', () => withDaemon({ args: WEB }, async (d) => {
  for (const host of [`127.0.0.1:${d.port}`, `localhost:${d.port}`, 'LOCALHOST', `[::1]:${d.port}`]) {
    assert.equal(status(await get(d.port, '/healthz', { Host: host })), 200, host);
  }
  for (const path of ['/healthz', '/api/runs', '/', '/index.html', '/metrics']) {
    const r = await get(d.port, path, { Host: `evil.example:${d.port}` });
    assert.equal(status(r), 421, `${path} with a foreign Host`);
    assert.match(r, /--allow-host/);
  }
  assert.equal(status(await raw(d.port, 'GET /healthz HTTP/1.0\r\n\r\n')), 421, 'no Host at all');
  // DNS rebinding: a page of evil.example that resolves to 127.0.0.1
  const r = await upgrade(d.port, { host: `evil.example:${d.port}`, origin: `http://evil.example:${d.port}` });
  assert.equal(status(r), 403);
  const ws = new Client(d.url, { headers: { Host: `evil.example:${d.port}` } });
  await assert.rejects(ws.opened());
  assert.match(d.stderr(), /refused a WebSocket upgrade: the Host or the Origin/);
}));

test('--allow-host: a name of the operator\'s, for Host and Origin', () => withDaemon({ args: ['--allow-host', 'trees.example'] }, async (d) => {
  assert.equal(status(await get(d.port, '/healthz', { Host: 'trees.example:8443' })), 200);
  assert.equal(status(await get(d.port, '/healthz', { Host: 'other.example' })), 421);
  const ok = new Client(d.url, { headers: { Host: 'trees.example' }, origin: 'https://trees.example' });
  await ok.opened();
  ok.close();
  assert.equal(status(await upgrade(d.port, { origin: 'http://other.example' })), 403, 'a foreign Origin');
  assert.equal(status(await upgrade(d.port, { origin: `http://localhost:${d.port + 1}` })), 101,
    'a local Origin on another port');
}));

test('upgrades: only /ws with the subprotocol sylva.v1', () => withDaemon({}, async (d) => {
  assert.equal(status(await upgrade(d.port, {})), 101);
  for (const [what, opts] of [['no subprotocol', { protocol: null }], ['protocol http', { protocol: 'http' }],
    ['another path', { path: '/api/runs' }], ['the root', { path: '/' }], ['an unknown protocol', { protocol: 'chat' }]]) {
    const r = await upgrade(d.port, opts);
    assert.notEqual(status(r), 101, what);
    assert.doesNotMatch(r, /101 Switching/, what);
  }
}));

test('close frames: an invalid code or a one-byte payload closes with 1002', () => withDaemon({}, async (d) => {
  // codes 5000, 65535, 1004, 2000; one byte; a reason that is not UTF-8
  for (const payload of [Buffer.from([0x13, 0x88]), Buffer.from([0xff, 0xff]), Buffer.from([0x03]),
    Buffer.from([0x03, 0xec]), Buffer.from([0x07, 0xd0]), Buffer.from([0x03, 0xe8, 0x61, 0xc0, 0xaf])]) {
    const code = await rawCloseCode(d.port, (s) => {
      const mask = Buffer.from([1, 2, 3, 4]);
      const body = Buffer.from(payload.map((c, i) => c ^ mask[i % 4]));
      s.write(Buffer.concat([Buffer.from([0x88, 0x80 | payload.length]), mask, body]));
    }, 3000);
    assert.equal(code, 1002, `close payload ${payload.toString('hex')}`);
  }
  // a valid close is echoed
  const c = await connect(d.url);
  const closed = new Promise((resolve) => c.ws.on('close', (code) => resolve(code)));
  c.ws.close(4000, 'bye');
  assert.equal(await closed, 4000);
}));

test('text messages must be UTF-8: otherwise 1007, small or large; a character split across fragments is fine', () => withDaemon({}, async (d) => {
  // a list whose id holds a character split between two fragments
  const c = await connect(d.url);
  const text = Buffer.from('{"type":"list","id":"été"}');
  const cut = text.indexOf(0xc3) + 1;
  c.ws.send(text.subarray(0, cut), { binary: false, fin: false });
  c.ws.send(text.subarray(cut), { binary: false, fin: true });
  assert.equal((await c.next((m) => m.type === 'runs')).ref, 'été');
  c.close();
  for (const size of [100, 100000]) { // checked on the loop, and on a thread with the parse
    const bad = await connect(d.url);
    const closed = bad.whenClosed();
    const body = Buffer.from(`{"type":"list","id":"${'a'.repeat(size)}\u0000"}`);
    body[body.length - 3] = 0xff; // a byte of the escape becomes 0xFF: not UTF-8
    bad.ws.send(body, { binary: false });
    const { code } = await closed;
    assert.equal(code, 1007, `a message of ${size} bytes`);
  }
}));

test('a token: every route and message but /healthz, the viewer\'s files and hello needs it', () => withDaemon({ args: [...WEB, '--token', 's3cret'] }, async (d) => {
  assert.equal(status(await get(d.port, '/healthz')), 200);
  assert.equal(status(await get(d.port, '/index.html')), 200);
  for (const path of ['/api/runs', '/metrics', '/api/scenarios/wall', '/api/runs/x/stats.csv']) {
    const r = await get(d.port, path);
    assert.equal(status(r), 401, path);
    assert.match(r, /www-authenticate: Bearer/i, path);
    assert.equal(status(await get(d.port, path, { Authorization: 'Bearer wrong' })), 401, path);
  }
  assert.equal(status(await get(d.port, '/api/runs', { Authorization: 'Bearer s3cret' })), 200);
  assert.equal(status(await get(d.port, '/api/scenarios/wall', { Authorization: 'bearer s3cret' })), 200);
  const c = await connect(d.url);
  for (const msg of [{ type: 'list' }, { type: 'scenarios' }, { type: 'subscribe', run: 1 },
    { type: 'create', scenario: scenario('shrub.json') }]) {
    c.send(msg);
    assert.equal((await c.type('error')).code, 'unauthorized', msg.type);
  }
  c.send({ type: 'hello', token: 's3cret', id: 1 });
  const w = await c.type('welcome');
  assert.equal(w.auth, true);
  assert.equal(w.public_read, false);
  c.send({ type: 'list' });
  await c.type('runs');
  c.close();
}));

test('--public-read: reading is open, changing needs the token', () => withDaemon({ args: ['--token', 's3cret', '--public-read'] }, async (d) => {
  assert.equal(status(await get(d.port, '/api/runs')), 200);
  const c = await connect(d.url);
  c.send({ type: 'list' });
  await c.type('runs');
  c.send({ type: 'create', scenario: scenario('shrub.json') });
  assert.equal((await c.type('error')).code, 'unauthorized');
  c.send({ type: 'hello', token: 's3cret' });
  const w = await c.type('welcome');
  assert.equal(w.public_read, true);
  c.send({ type: 'create', scenario: scenario('shrub.json') });
  await c.type('created');
  c.close();
}));

test('wrong tokens: three close the socket, and past ten a second none is even compared', () => withDaemon({ args: ['--token', 's3cret'] }, async (d) => {
  const c = await connect(d.url);
  const closed = new Promise((resolve) => c.ws.on('close', (code, reason) => resolve([code, String(reason)])));
  // three at once: the answers to the first two arrive before the close
  for (let i = 0; i < 3; i++) c.send({ type: 'hello', token: `guess${i}`, id: `h${i}` });
  for (let i = 0; i < 2; i++) {
    const m = await c.next((x) => x.ref === `h${i}`);
    assert.equal(m.code, 'unauthorized');
  }
  assert.deepEqual(await closed, [1008, 'too many wrong tokens']);
  // many sockets guessing at once: at most ten failures a second are checked
  const answers = [];
  const clients = await Promise.all(Array.from({ length: 20 }, () => connect(d.url)));
  for (const g of clients) g.send({ type: 'hello', token: 'guess' });
  for (const g of clients) answers.push((await g.type('error')).message);
  assert.ok(answers.filter((m) => /too many wrong tokens/.test(m)).length >= 5, answers.join('\n'));
  // the right token is refused too while the budget is spent, then accepted
  await new Promise((r) => setTimeout(r, 1100));
  const ok = await connect(d.url);
  ok.send({ type: 'hello', token: 's3cret' });
  await ok.type('welcome');
  for (const g of [...clients, ok]) g.close();
}));

test('the token from --token-file or SYLVA_TOKEN stays out of the command line', async () => {
  const dir = tempDir();
  try {
    writeFileSync(join(dir, 'token'), 'from-file\n');
    await withDaemon({ args: ['--token-file', join(dir, 'token')] }, async (d) => {
      assert.equal(status(await get(d.port, '/api/runs', { Authorization: 'Bearer from-file' })), 200);
      assert.equal(status(await get(d.port, '/api/runs')), 401);
    });
    process.env.SYLVA_TOKEN = 'from-env';
    try {
      await withDaemon({}, async (d) => {
        assert.equal(status(await get(d.port, '/api/runs', { Authorization: 'Bearer from-env' })), 200);
        assert.equal(status(await get(d.port, '/api/runs')), 401);
      });
    } finally {
      delete process.env.SYLVA_TOKEN;
    }
    for (const [args, want] of [[['--token-file', join(dir, 'missing')], /--token-file: cannot read/],
      [['--public-read'], /--public-read: there is no token/], [['--allow-host', 'a.example:80'], /--allow-host: expected a host name/],
      [['--trace-iterations', join(dir, 'missing', 'trace')], /--trace-iterations: cannot write/]]) {
      const r = spawnSync(SYLVA, ['serve', '--db', join(dir, 'x.db'), ...args], { encoding: 'utf8', env: { ...process.env, SYLVA_TOKEN: '' } });
      assert.equal(r.status, 2, args.join(' '));
      assert.match(r.stderr, want);
    }
  } finally {
    cleanup(dir);
  }
});
