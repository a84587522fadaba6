// A scenario shown as fields, one per value, each tagged with its JSON pointer, so
// that the daemon's validation errors ("/plants/0/roots/0: expected [x, y, z]")
// appear next to the field they name. Edits go back into the document; a value
// typed as a number stays a number, anything else is sent as typed so the daemon
// can say what is wrong with it.

const escapeToken = (k) => String(k).replace(/~/g, '~0').replace(/\//g, '~1');

export class ScenarioForm {
  constructor(container) {
    this.container = container;
    this.doc = null;
  }

  // Shows a parsed scenario document.
  load(doc) {
    this.doc = doc;
    this.container.textContent = '';
    this.clearError();
    this.container.appendChild(this.render(doc, '', 'scenario'));
  }

  render(value, pointer, key) {
    if (Array.isArray(value) && value.length <= 4 && value.every((v) => typeof v === 'number')) {
      // a vector: one row of numbers
      const row = this.field(key, pointer);
      value.forEach((v, i) => row.box.appendChild(this.input(v, `${pointer}/${i}`)));
      return row.el;
    }
    if (value !== null && typeof value === 'object') {
      const fs = document.createElement('fieldset');
      fs.dataset.pointer = pointer;
      const legend = document.createElement('legend');
      legend.textContent = key;
      fs.appendChild(legend);
      const entries = Array.isArray(value) ? value.map((v, i) => [i, v]) : Object.entries(value);
      for (const [k, v] of entries) fs.appendChild(this.render(v, `${pointer}/${escapeToken(k)}`, String(k)));
      return fs;
    }
    const row = this.field(key, pointer);
    row.box.appendChild(this.input(value, pointer));
    return row.el;
  }

  field(key, pointer) {
    const el = document.createElement('div');
    el.className = 'field';
    el.dataset.pointer = pointer;
    const name = document.createElement('span');
    name.className = 'field-name';
    name.textContent = key;
    const box = document.createElement('span');
    box.className = 'field-box';
    el.append(name, box);
    return { el, box };
  }

  input(value, pointer) {
    const inp = document.createElement('input');
    inp.dataset.pointer = pointer;
    if (typeof value === 'boolean') {
      inp.type = 'checkbox';
      inp.checked = value;
      inp.addEventListener('change', () => this.set(pointer, inp.checked));
    } else {
      inp.type = 'text';
      inp.value = value === null ? 'null' : String(value);
      inp.size = typeof value === 'number' ? 6 : 18;
      inp.addEventListener('input', () => {
        const t = inp.value.trim();
        let v = inp.value;
        if (typeof value === 'number' && t !== '' && Number.isFinite(Number(t))) v = Number(t);
        else if (t === 'null') v = null;
        this.set(pointer, v);
      });
    }
    return inp;
  }

  set(pointer, value) {
    const parts = pointer.split('/').slice(1).map((t) => t.replace(/~1/g, '/').replace(/~0/g, '~'));
    let o = this.doc;
    for (const p of parts.slice(0, -1)) o = o[p];
    o[parts[parts.length - 1]] = value;
  }

  // The element that shows the value at a pointer, or its nearest ancestor's.
  elementFor(pointer) {
    let p = pointer;
    for (;;) {
      const el = this.container.querySelector(`[data-pointer="${CSS.escape(p)}"]:not(input)`);
      if (el) return el;
      if (p === '') return null;
      p = p.slice(0, p.lastIndexOf('/'));
    }
  }

  clearError() {
    for (const el of this.container.querySelectorAll('.field-error')) el.remove();
    for (const el of this.container.querySelectorAll('.invalid')) el.classList.remove('invalid');
  }

  // Shows a daemon error message next to the field it names. Returns the element.
  showError(message) {
    this.clearError();
    const m = /^(\/[^:]*|):?\s*(.*)$/s.exec(message);
    let pointer = m && message.startsWith('/') ? m[1] : '';
    if (pointer.startsWith('/scenario')) pointer = pointer.slice('/scenario'.length);
    const el = this.elementFor(pointer) || this.container;
    const note = document.createElement('div');
    note.className = 'field-error';
    note.setAttribute('role', 'alert');
    note.textContent = message;
    el.classList.add('invalid');
    // the one number of a vector that is wrong
    this.container.querySelector(`input[data-pointer="${CSS.escape(pointer)}"]`)?.classList.add('invalid');
    if (el.tagName === 'FIELDSET') el.insertBefore(note, el.children[1] || null);
    else el.appendChild(note);
    note.scrollIntoView({ block: 'nearest' });
    return note;
  }
}
