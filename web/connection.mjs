// The page's side of the connection to the daemon: the socket itself lives in a
// worker (socket_worker.mjs) that reconnects by itself and parses off this
// thread. Here: requests with ids and their replies, server pushes to onMessage,
// and the state (connecting, open, closed) to onState; onOpen runs after each
// (re)connection so the page can say hello and resubscribe.

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
        this.pending.get(id).reject(Object.assign(new Error('not connected'), { code: 'closed' }));
        this.pending.delete(id);
      }
      return;
    }
    if (m.warning) {
      console.warn(`sylva: ${m.warning}`);
      return;
    }
    const msg = m.message;
    msg.parseMs = m.parseMs + m.convertMs;
    msg.bytes = m.bytes;
    if (msg.ref !== undefined && this.pending.has(msg.ref)) {
      const p = this.pending.get(msg.ref);
      this.pending.delete(msg.ref);
      if (msg.type === 'error') p.reject(Object.assign(new Error(msg.message), { code: msg.code, msg }));
      else p.resolve(msg);
      return;
    }
    this.onMessage(msg);
  }

  failPending(why) {
    for (const p of this.pending.values()) p.reject(Object.assign(new Error(why), { code: 'closed' }));
    this.pending.clear();
  }

  // Sends a message without waiting for a reply; false when not connected.
  send(msg) {
    if (this.state !== 'open') return false;
    this.worker.postMessage({ send: msg });
    return true;
  }

  // Sends a message with an id; resolves with its reply, rejects with an error
  // (err.code is the protocol's code, or 'closed').
  request(msg) {
    return new Promise((resolve, reject) => {
      const id = String(this.nextId++);
      if (!this.send({ ...msg, id })) {
        reject(Object.assign(new Error('not connected'), { code: 'closed' }));
        return;
      }
      this.pending.set(id, { resolve, reject });
    });
  }
}
