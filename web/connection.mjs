// The WebSocket to the daemon (/ws, subprotocol sylva.v1): requests with ids and
// their replies, server pushes, and reconnection with backoff. The state
// (connecting, open, closed) is reported to onState; onOpen runs after each
// (re)connection so the page can say hello and resubscribe.

export class Connection {
  constructor(url, { onMessage, onState, onOpen }) {
    this.url = url;
    this.onMessage = onMessage;
    this.onState = onState;
    this.onOpen = onOpen;
    this.nextId = 1;
    this.pending = new Map();   // id -> {resolve, reject}
    this.delay = 250;
    this.state = 'connecting';
    this.retryAt = 0;
    this.connect();
  }

  setState(state, detail = '') {
    this.state = state;
    this.onState(state, detail);
  }

  connect() {
    this.setState('connecting');
    let ws;
    try {
      ws = new WebSocket(this.url, 'sylva.v1');
    } catch (e) {
      this.retry(String(e));
      return;
    }
    this.ws = ws;
    ws.onopen = () => {
      this.delay = 250;
      this.setState('open');
      this.onOpen();
    };
    ws.onmessage = (ev) => {
      let msg;
      const t0 = performance.now();
      try {
        msg = JSON.parse(ev.data);
        msg.parseMs = performance.now() - t0;
        msg.bytes = ev.data.length;
      } catch (e) {
        console.warn('sylva: a message that is not JSON', e);
        return;
      }
      if (msg.ref !== undefined && this.pending.has(msg.ref)) {
        const p = this.pending.get(msg.ref);
        this.pending.delete(msg.ref);
        if (msg.type === 'error') p.reject(Object.assign(new Error(msg.message), { code: msg.code, msg }));
        else p.resolve(msg);
        return;
      }
      this.onMessage(msg);
    };
    ws.onclose = (ev) => {
      if (this.ws !== ws) return;
      for (const p of this.pending.values()) p.reject(Object.assign(new Error('connection lost'), { code: 'closed' }));
      this.pending.clear();
      this.retry(ev.code ? `closed (${ev.code}${ev.reason ? ': ' + ev.reason : ''})` : 'closed');
    };
  }

  retry(detail) {
    this.ws = null;
    const wait = this.delay;
    this.delay = Math.min(this.delay * 2, 4000);
    this.retryAt = Date.now() + wait;
    this.setState('closed', detail);
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.connect(), wait);
  }

  // Sends a message without waiting for a reply.
  send(msg) {
    if (!this.ws || this.ws.readyState !== WebSocket.OPEN) return false;
    this.ws.send(JSON.stringify(msg));
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
