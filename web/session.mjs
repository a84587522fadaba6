// The page's session with the daemon: the connection (its socket lives in a
// worker), the connection badge in the header, the token (asked for in a dialog
// when the daemon has one and kept for the tab's session: before anything when
// reading needs it too, else before the first change), changing requests, the
// daemon's HTTP routes with the token, and the message line under the controls.
import { Connection } from './connection.mjs';
import { $ } from './dom.mjs';
import { connectionLabel, wsAddress } from './helpers.mjs';

export class Session {
  // onOpen runs after each (re)connection; onMessage(msg, meta) gets what the
  // daemon pushes (meta: the worker's parse time and the text's length).
  constructor({ onOpen, onMessage }) {
    this.auth = false;     // the daemon needs a token
    this.publicRead = true; // reading needs none
    this.authed = false;   // this connection said hello with a token that works
    this.token = sessionStorage.getItem('sylva.token') || '';
    this.conn = new Connection(wsAddress(location.protocol, location.host), {
      onState: (state, detail) => {
        const el = $('connection');
        el.dataset.state = state;
        el.textContent = connectionLabel(state, detail);
      },
      onOpen: async () => {
        await this.hello().catch(() => {});
        if (!this.publicRead) await this.ensureAuth().catch(() => {});
        onOpen();
      },
      onMessage,
    });
  }

  get state() { return this.conn.state; }

  // A message without a reply; false when not connected.
  send(msg) { return this.conn.send(msg); }

  // A message that changes nothing; resolves with its reply.
  request(msg) { return this.conn.request(msg); }

  // The daemon's welcome, on connect.
  welcome(msg) {
    this.auth = msg.auth;
    this.publicRead = msg.public_read !== false;
  }

  async hello() {
    try {
      const w = await this.conn.request({ type: 'hello', ...(this.token ? { token: this.token } : {}) });
      this.welcome(w);
      this.authed = true;
    } catch (e) {
      if (e.code !== 'unauthorized') throw e;
      this.auth = true;
      this.authed = false;
    }
  }

  // Asks for the token when the daemon needs one and the page has none that works.
  ensureAuth() {
    if (!this.auth || this.authed) return Promise.resolve();
    return new Promise((resolve, reject) => {
      const dlg = $('token-dialog');
      $('token-input').value = this.token;
      $('token-error').hidden = !this.token;
      $('token-error').textContent = this.token ? 'That token was refused.' : '';
      dlg.onclose = async () => {
        if (dlg.returnValue !== 'ok') { reject(new Error('a token is needed for this')); return; }
        this.token = $('token-input').value;
        sessionStorage.setItem('sylva.token', this.token);
        await this.hello().catch(() => {});
        if (this.authed) resolve(); else this.ensureAuth().then(resolve, reject);
      };
      dlg.showModal();
    });
  }

  // Sends a changing message (asking for the token first when needed); resolves
  // with its reply.
  async change(msg) {
    await this.ensureAuth();
    try {
      return await this.conn.request(msg);
    } catch (e) {
      if (e.code === 'unauthorized') {
        this.authed = false;
        await this.ensureAuth();
        return this.conn.request(msg);
      }
      throw e;
    }
  }

  // GET of one of the daemon's HTTP routes, with the token when the page has one
  // that works.
  fetch(path) {
    const headers = this.auth && this.authed && this.token ? { Authorization: `Bearer ${this.token}` } : {};
    return fetch(path, { headers });
  }

  // Saves what a route returns as a file (a link cannot carry the token).
  async download(path) {
    try {
      const res = await this.fetch(path);
      if (!res.ok) throw new Error(`${res.status}: ${(await res.text()).trim()}`);
      const name = /filename="([^"]+)"/.exec(res.headers.get('content-disposition') || '')?.[1] || 'export';
      const a = document.createElement('a');
      a.href = URL.createObjectURL(await res.blob());
      a.download = name;
      a.click();
      setTimeout(() => URL.revokeObjectURL(a.href), 60000);
    } catch (e) {
      this.message(`export: ${e.message}`, true);
    }
  }

  // Shows a line of news or an error under the controls ('' clears it).
  message(text, isError = false) {
    const el = $('message');
    el.textContent = text;
    el.classList.toggle('error', isError);
  }

  // Sends a changing message and shows `done` (a function of the reply) or the
  // error on the message line; resolves with the reply, or null when it failed.
  async act(msg, done) {
    try {
      const reply = await this.change(msg);
      this.message(done(reply));
      return reply;
    } catch (e) {
      this.message(e.message, true);
      return null;
    }
  }
}
