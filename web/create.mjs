// The new-run panel: choose a ready scenario (the daemon's `--scenarios`), or
// paste or upload a scenario file; the scenario is shown as fields, one per
// value (scenario_form.mjs); edit any of them and create. A refusal appears next
// to the field it names, or next to the name.
import { $ } from './dom.mjs';
import { createErrorPlace, parseScenario } from './helpers.mjs';
import { ScenarioForm } from './scenario_form.mjs';

export class CreatePanel {
  // open({run, name}): watches the new run and refreshes the run list.
  constructor({ session, open }) {
    this.session = session;
    this.open = open;
    this.form = new ScenarioForm($('scenario-form'));
    $('scenario-select').onchange = () => this.loadReady($('scenario-select').value);
    $('scenario-load').onclick = () => this.loadText($('scenario-text').value);
    $('scenario-file').onchange = async () => {
      const f = $('scenario-file').files[0];
      if (!f) return;
      const text = await f.text();
      $('scenario-text').value = text;
      this.loadText(text);
    };
    $('create-button').onclick = () => this.create();
  }

  // The ready scenarios, into the select (keeping the one chosen).
  async loadScenarios() {
    try {
      const r = await this.session.request({ type: 'scenarios' });
      const sel = $('scenario-select');
      const keep = sel.value;
      sel.length = 1;
      for (const s of r.scenarios) sel.add(new Option(`${s.title} (${s.name})`, s.name));
      sel.value = keep;
    } catch { /* shown by the connection state */ }
  }

  async loadReady(name) {
    if (!name) return;
    try {
      const res = await this.session.fetch(`api/scenarios/${encodeURIComponent(name)}`);
      if (!res.ok) throw new Error(`${name}: ${res.status} ${res.statusText}`);
      const text = await res.text();
      $('scenario-text').value = text;
      this.loadDocument(JSON.parse(text));
    } catch (e) {
      this.session.message(e.message, true);
    }
  }

  loadText(text) {
    const err = $('scenario-text-error');
    try {
      const doc = parseScenario(text);
      err.hidden = true;
      this.loadDocument(doc);
    } catch (e) {
      err.textContent = `not a scenario: ${e.message}`;
      err.hidden = false;
    }
  }

  loadDocument(doc) {
    this.form.load(doc);
    $('create-name').value = typeof doc.name === 'string' ? doc.name : '';
    $('create-button').disabled = false;
    $('create-name-error').hidden = true;
  }

  async create() {
    const name = $('create-name').value.trim();
    const nameError = $('create-name-error');
    nameError.hidden = true;
    this.form.clearError();
    let c;
    try {
      c = await this.session.change({ type: 'create', scenario: this.form.doc, ...(name ? { name } : {}),
        start: $('create-start').checked });
    } catch (e) {
      const place = createErrorPlace(e.message, !!e.msg);
      if (place === 'name') {
        nameError.textContent = e.message;
        nameError.hidden = false;
      } else if (place === 'form') {
        this.form.showError(e.message);
      } else {
        this.session.message(e.message, true);
      }
      return;
    }
    await this.open(c);
    this.session.message(`created ${c.name}`);
  }
}
