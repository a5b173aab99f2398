// The ldrun monitor page: draws every rung (or an ST or IL program's source)
// from /api/program, then follows
// /api/events (Server-Sent Events) to highlight powered wires, closed contacts
// and energized outputs, show values, a device table and trends.
'use strict';
const CW = 8.4, RH = 26, PAD = 14, NS = 'http://www.w3.org/2000/svg';
let program = null, chosen = [], history = {}, scanHist = [], forced = new Set();
const colors = ['#1565c0', '#6a1b9a', '#00838f', '#ad1457', '#4e342e', '#558b2f'];

function el(tag, attrs, parent) {
  const e = document.createElementNS(NS, tag);
  for (const k in attrs) e.setAttribute(k, attrs[k]);
  if (parent) parent.appendChild(e);
  return e;
}
function h(tag, text, parent, cls) {
  const e = document.createElement(tag);
  if (text !== undefined && text !== null) e.textContent = text;
  if (cls) e.className = cls;
  if (parent) parent.appendChild(e);
  return e;
}
const X = c => c * CW, Y = r => PAD + r * RH + RH / 2;

function drawRung(task, ti, rung, ri, parent) {
  const box = h('div', null, parent, 'rung');
  const head = (rung.labels && rung.labels.length ? 'label ' + rung.labels.join(', ') + ' \u00b7 ' : '') +
               'rung ' + (ri + 1) + ' \u00b7 line ' + rung.line + (rung.title ? ' \u00b7 ' + rung.title : '');
  h('div', head, box, 'title');
  if (!rung.rows) {
    h('pre', 'no ladder form: ' + rung.why + '\n' + rung.il.join('\n'), box);
    return null;
  }
  const cols = Math.max(...rung.rows.map(r => r.length)) + 2;
  const svg = el('svg', {class: 'ladder', width: X(cols) + 10, height: PAD + rung.rows.length * RH + 4,
                         id: 'rung-' + ti + '-' + ri}, box);
  const parts = {wires: [], elems: []};
  el('line', {x1: X(0.5), y1: 4, x2: X(0.5), y2: PAD + rung.rows.length * RH, class: 'rail'}, svg);
  for (const [r, c0, c1, n] of rung.wires)
    parts.wires.push([el('line', {x1: X(c0), y1: Y(r), x2: X(c1 + 1), y2: Y(r), 'data-net': n}, svg), n]);
  for (const [c, r0, r1, n] of rung.links)
    parts.wires.push([el('line', {x1: X(c + 0.5), y1: Y(r0), x2: X(c + 0.5), y2: Y(r1), 'data-net': n}, svg), n]);
  rung.elems.forEach((e, k) => {
    const g = el('g', {class: 'elem ' + (e.o ? 'output' : 'input'), 'data-elem': k}, svg);
    el('rect', {x: X(e.c), y: Y(e.r) - 9, width: X(e.w), height: 18, rx: e.o ? 9 : 0}, g);
    const t = el('text', {x: X(e.c) + 4, y: Y(e.r) + 4}, g);
    t.textContent = e.t.slice(1, -1);
    const v = el('text', {x: X(e.c) + 2, y: Y(e.r) - 11, class: 'val'}, g);
    parts.elems.push([g, v]);
  });
  return parts;
}

// An ST or IL program: its source as written, line by line, and after each
// assigned variable a box with its live value.  Text goes in as textContent
// only (the source is never parsed as HTML).
function drawSource(t, ti, parent) {
  const box = h('div', null, parent, 'source');
  box.id = 'source-' + ti;
  const els = [];
  t.source.forEach((pieces, li) => {
    const line = h('div', null, box, 'sl');
    h('span', String(li + 1), line, 'ln');
    for (const p of pieces) {
      if (typeof p === 'string') { h('span', p, line); continue; }
      for (const w of p) {
        const v = h('span', '', line, 'stv');
        v.title = t.watch[w];
        v.dataset.watch = w;
        els.push([v, w]);
      }
    }
  });
  return els;
}

function render() {
  const root = document.getElementById('tasks');
  root.textContent = '';
  program.tasks.forEach((t, ti) => {
    const sec = h('div', null, root, 'task');
    const head = h('h2', 'task ' + t.name + ' \u00b7 period ' + (t.period_us / 1000) + ' ms ', sec);
    t.stateEl = h('span', '', head, 'state');
    if (program.write && program.tasks.length > 1) {
      const task = encodeURIComponent(t.name);
      h('button', 'RUN', head).addEventListener('click', () => post('/api/run', 'task=' + task));
      h('button', 'STOP', head).addEventListener('click', () => post('/api/stop', 'task=' + task));
    }
    if (t.source_note) h('p', t.source_note, sec, 'note');
    t.srcEls = t.source ? drawSource(t, ti, sec) : [];
    t.view = t.rungs.map((r, ri) => drawRung(t, ti, r, ri, sec));
  });
  if (program.write) {
    document.getElementById('controls').classList.remove('hidden');
    document.getElementById('writeform').classList.remove('hidden');
  }
  buildTable();
}

function buildTable() {
  const tb = document.querySelector('#devices tbody');
  tb.textContent = '';
  program.tasks.forEach((t, ti) => {
    t.rowsEl = t.devices.map(([name, alias], di) => {
      const tr = h('tr', null, tb);
      tr.dataset.search = (t.name + ' ' + name + ' ' + alias).toLowerCase();
      const cb = h('input', null, h('td', null, tr));
      cb.type = 'checkbox';
      cb.addEventListener('change', () => {
        const key = ti + ':' + di;
        if (cb.checked) { chosen.push({key, ti, di, label: (alias || name)}); history[key] = []; }
        else chosen = chosen.filter(c => c.key !== key);
      });
      h('td', program.tasks.length > 1 ? t.name + '.' + name : name, tr);
      h('td', alias, tr);
      tr.dataset.device = name;
      tr.dataset.alias = alias;
      return h('td', '', tr, 'v');
    });
  });
  applyFilter();
}

function applyFilter() {
  const f = document.getElementById('filter').value.toLowerCase();
  for (const tr of document.querySelectorAll('#devices tbody tr'))
    tr.classList.toggle('hidden', f !== '' && !tr.dataset.search.includes(f));
}

function poly(svg, series, color, lo, hi) {
  if (series.length < 2) return;
  const n = series.length, span = (hi - lo) || 1;
  const pts = series.map((v, i) => (i * 400 / (n - 1)).toFixed(1) + ',' + (115 - (v - lo) * 110 / span).toFixed(1));
  el('polyline', {points: pts.join(' '), stroke: color}, svg);
}

function plotTrends(state) {
  const t0 = state.tasks[0];
  if (t0 && t0.scan_us) scanHist.push([t0.scan_us.median, t0.scan_us.p99, t0.scan_us.max]);
  if (scanHist.length > 300) scanHist.shift();
  const st = document.getElementById('scantrend');
  st.textContent = '';
  const all = scanHist.flat().filter(v => v !== null);
  if (all.length) {
    const hi = Math.max(...all);
    ['#2e7d32', '#ef6c00', '#c62828'].forEach((c, k) => poly(st, scanHist.map(s => s[k] || 0), c, 0, hi));
  }
  document.getElementById('scanstats').textContent = state.tasks.map(t => t.scan_us ?
      t.name + ': scan median ' + t.scan_us.median + ' \u00b5s, p99 ' + t.scan_us.p99 + ' \u00b5s, max ' + t.scan_us.max +
      ' \u00b5s; jitter p99 ' + t.jitter_us.p99 + ' \u00b5s; ' + t.scans + ' scans' : t.name).join(' | ');
  const tr = document.getElementById('trend');
  tr.textContent = '';
  let lo = Infinity, hi = -Infinity;
  for (const c of chosen) {
    const v = parseFloat(state.tasks[c.ti].dev[c.di]);
    history[c.key].push(v);
    if (history[c.key].length > 300) history[c.key].shift();
    for (const x of history[c.key]) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
  }
  chosen.forEach((c, k) => poly(tr, history[c.key], colors[k % colors.length], lo, hi));
  const lg = document.getElementById('trendlegend');
  if (chosen.length) {
    lg.textContent = '';
    chosen.forEach((c, k) => { const s = h('span', c.label + ' ', lg); s.style.color = colors[k % colors.length]; });
    h('span', '(' + lo + ' .. ' + hi + ')', lg);
  }
}

function update(state) {
  const s = document.getElementById('state');
  s.textContent = state.state;
  s.className = 'state ' + state.state;
  forced = new Set(state.forced);
  state.tasks.forEach((ts, ti) => {
    const t = program.tasks[ti];
    if (!t) return;
    const ts_state = state.state === 'RUN' && ts.held ? 'STOP' : state.state;
    if (t.stateEl.textContent !== ts_state) { t.stateEl.textContent = ts_state; t.stateEl.className = 'state ' + ts_state; }
    ts.rungs.forEach((rs, ri) => {
      const v = t.view[ri];
      if (!v || !rs.n) return;
      for (const [line, n] of v.wires) line.classList.toggle('on', rs.n[n] === '1');
      v.elems.forEach(([g, val], k) => {
        g.classList.toggle('on', rs.e[k] === '1');
        val.textContent = rs.v[k] !== undefined ? rs.v[k] : '';
      });
    });
    if (ts.src) for (const [v, w] of t.srcEls) if (v.textContent !== ts.src[w]) v.textContent = ts.src[w];
    ts.dev.forEach((d, di) => {
      const td = t.rowsEl[di];
      if (td.textContent !== d) td.textContent = d;
      td.parentNode.classList.toggle('forced', forced.has(t.devices[di][0]));
    });
  });
  plotTrends(state);
}

// The write token (ldrun --monitor-remote --monitor-write, docs/runtime.md):
// given once in the address (/?token=...), kept by this browser for this
// monitor's origin only, taken out of the address bar and history, and sent
// with every POST.
const TOKEN_KEY = 'ldc-monitor-token';
function takeToken() {
  const q = new URLSearchParams(location.search);
  if (q.has('token')) {
    localStorage.setItem(TOKEN_KEY, q.get('token'));
    window.history.replaceState(null, '', location.pathname);
  }
}
async function post(path, body) {
  const headers = {'X-LDC-Monitor': '1', 'Content-Type': 'application/x-www-form-urlencoded'};
  const token = localStorage.getItem(TOKEN_KEY);
  if (token) headers['X-LDC-Token'] = token;
  const r = await fetch(path, {method: 'POST', headers: headers, body: body});
  document.getElementById('reply').textContent = r.status + ': ' + (await r.text()).trim();
}
function form(force) {
  const d = encodeURIComponent(document.getElementById('wdev').value);
  const v = encodeURIComponent(document.getElementById('wval').value);
  return 'device=' + d + '&value=' + v + (force === undefined ? '' : '&force=' + force);
}

async function main() {
  takeToken();
  program = await (await fetch('/api/program')).json();
  render();
  if (program.write && program.token && !localStorage.getItem(TOKEN_KEY))
    document.getElementById('reply').textContent =
      'writes need the token: open the address ldrun printed at start (.../?token=...) once';
  document.getElementById('filter').addEventListener('input', applyFilter);
  document.getElementById('run').addEventListener('click', () => post('/api/run', ''));
  document.getElementById('stop').addEventListener('click', () => post('/api/stop', ''));
  document.getElementById('wwrite').addEventListener('click', () => post('/api/write', form()));
  document.getElementById('wforce').addEventListener('click', () => post('/api/write', form(1)));
  document.getElementById('wrelease').addEventListener('click', () => post('/api/write', form(0)));
  const es = new EventSource('/api/events');
  es.onmessage = ev => update(JSON.parse(ev.data));
  es.onerror = () => { document.getElementById('state').textContent = 'disconnected'; };
}
main();
