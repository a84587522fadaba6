// The page's side of the connection to the daemon: the socket itself lives in a
// worker (socket_worker.mjs) that reconnects by itself and parses off this
// thread. Here: requests with ids and their replies, server pushes to onMessage
// (with what the worker measured), and the state (connecting, open, closed) to
// onState; onOpen runs after each (re)connection so the page can say hello and
// resubscribe.

// A request that failed: `code` is the protocol's error code, or 'closed' when
// the connection was not open or was lost; `msg` is the daemon's `error`
// message, null when there was none.
export class RequestError extends Error {
  constructor(message, code, msg = null) {
    super(message);
    this.code = code;
    this.msg = msg;
  }
}

export class Connection {
  constructor(url, { onMessage, onState, onOpen }) {
    this.onMessage = onMessage;
    this.onState = onState;
    this.onOpen = onOpen;
    this.nextId = 1;
    this.pending = new Map();   // id -> {resolve, reject}
    this.state = 'connecting';
    this.worker = new Worker(new URL('./socket_worker.mjs', import.meta.url), { type: 'module' });
    this.worker.onmessage = (ev) => this.receive(ev.data);
    this.worker.postMessage({ connect: url });
  }

  receive(m) {
    if (m.state) {
      this.state = m.state;
      if (m.state === 'closed') this.failPending('connection lost');
      this.onState(m.state, m.detail);
      if (m.state === 'open') this.onOpen();
      return;
    }
    if (m.unsent) {
      const id = m.unsent.id;
      if (id !== undefined && this.pending.has(id)) {
        this.pending.get(id).reject(new RequestError('not connected', 'closed'));
        this.pending.delete(id);
      }
      return;
    }
    if (m.warning) {
      console.warn(`sylva: ${m.warning}`);
      return;
    }
    const msg = m.message;
    if (msg.ref !== undefined && this.pending.has(msg.ref)) {
      const p = this.pending.get(msg.ref);
      this.pending.delete(msg.ref);
      if (msg.type === 'error') p.reject(new RequestError(msg.message, msg.code, msg));
      else p.resolve(msg);
      return;
    }
    // what the worker measured: parsing and conversion time, and the text's length
    this.onMessage(msg, { parseMs: m.parseMs + m.convertMs, bytes: m.bytes });
  }

  failPending(why) {
    for (const p of this.pending.values()) p.reject(new RequestError(why, 'closed'));
    this.pending.clear();
  }

  // Sends a message without waiting for a reply; false when not connected.
  send(msg) {
    if (this.state !== 'open') return false;
    this.worker.postMessage({ send: msg });
    return true;
  }

  // Sends a message with an id; resolves with its reply, rejects with a
  // RequestError.
  request(msg) {
    return new Promise((resolve, reject) => {
      const id = String(this.nextId++);
      if (!this.send({ ...msg, id })) {
        reject(new RequestError('not connected', 'closed'));
        return;
      }
      this.pending.set(id, { resolve, reject });
    });
  }
}
