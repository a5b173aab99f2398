// The ldrun monitor page: draws every rung with the IEC 61131-3 symbols (or
// an ST or IL program's source) from /api/program, then follows /api/events
// (Server-Sent Events) to highlight energised paths, closed contacts and
// energised coils, show values, a device table and trends.  Every task's
// values carry the generation of the program they belong to: a reply for
// another program than the one drawn is dropped and the program fetched again
// (an online download), so values never paint over the wrong rungs.
'use strict';
const CW = 8.4, NS = 'http://www.w3.org/2000/svg', FONT_W = 6.7;
let program = null, chosen = [], history = {}, scanHist = [], forced = new Map(), refetching = false;
const colors = ['#1565c0', '#6a1b9a', '#00838f', '#ad1457', '#4e342e', '#558b2f'];
const TREND_MS = 30000;  // the trends show the last 30 s

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
function svgText(parent, x, y, text, cls, anchor) {
  const t = el('text', {x: x, y: y, class: cls || ''}, parent);
  if (anchor) t.setAttribute('text-anchor', anchor);
  t.textContent = text;
  return t;
}

// ---------------------------------------------------------------- geometry
// The grid's columns and rows (ir/ladder.h) scaled to pixels: a column is
// widened where a symbol needs more room than its characters give (a box
// with its pins), a row made as tall as its tallest symbol.

const BOX_PIN = 14;  // px between a box's pins
const OUT_VALUES = 62;  // px right of an output box for its output pins' values
function isBox(e) { return e.k === 'fb' || e.k === 'cmp'; }
function pinLabel(p) { return p[0] + (p[1] ? ' ' + p[1] : ''); }
function boxSides(e) {
  const left = e.p.filter(p => !p[2]), right = e.p.filter(p => p[2]);
  return [left, right];
}
function needWidth(e) {
  if (isBox(e)) {
    const [l, r] = boxSides(e);
    const lw = Math.max(0, ...l.map(p => pinLabel(p).length + 7));  // + its value
    const rw = Math.max(0, ...r.map(p => p[0].length + 2));
    return Math.max((lw + rw) * FONT_W + 24, ((e.inst || '').length + 2) * FONT_W, 70) + (e.o ? OUT_VALUES : 0);
  }
  return Math.max(48, ((e.d || '').length + 1) * FONT_W + 8);
}
// Room above a row's wire (labels, a box's instance and function) and below it.
function needAbove(e) { return isBox(e) ? 42 : 30; }
function needBelow(e) {
  if (isBox(e)) {
    const [l, r] = boxSides(e);
    return (Math.max(l.length, r.length) - 1) * BOX_PIN + 18;
  }
  return 30;
}
function layout(rung) {
  const ncols = Math.max(...rung.rows.map(r => r.length)) + 2;
  const extra = new Array(ncols + 1).fill(0);
  for (const e of rung.elems) {
    const more = needWidth(e) - e.w * CW;
    const last = Math.min(e.c + e.w - 1, ncols - 1);
    if (more > extra[last]) extra[last] = more;
  }
  const xs = [0];
  for (let c = 0; c < ncols; c++) xs.push(xs[c] + CW + extra[c]);
  const above = rung.rows.map(() => 24), below = rung.rows.map(() => 16);
  for (const e of rung.elems) {
    above[e.r] = Math.max(above[e.r], needAbove(e));
    below[e.r] = Math.max(below[e.r], needBelow(e));
  }
  const ys = [];  // the wire of row r runs at ys[r]
  let top = 4;
  rung.rows.forEach((_, r) => { ys.push(top + above[r]); top += above[r] + below[r]; });
  return {X: c => xs[Math.max(0, Math.min(c, ncols))] + 6, Y: r => ys[r], width: xs[ncols] + 40, height: top + 6};
}

// ---------------------------------------------------------------- symbols

// -| |-, -|/|-, -|P|-, -|N|-: two plates and what is between them.
function contact(g, e, x0, x1, y) {
  const m = (x0 + x1) / 2;
  el('line', {x1: x0, y1: y, x2: m - 7, y2: y, class: 'sym'}, g);
  el('line', {x1: m + 7, y1: y, x2: x1, y2: y, class: 'sym'}, g);
  el('rect', {x: m - 7, y: y - 11, width: 14, height: 22, class: 'gap'}, g);
  el('line', {x1: m - 7, y1: y - 11, x2: m - 7, y2: y + 11, class: 'plate'}, g);
  el('line', {x1: m + 7, y1: y - 11, x2: m + 7, y2: y + 11, class: 'plate'}, g);
  if (e.k === 'nc') el('line', {x1: m - 5, y1: y + 9, x2: m + 5, y2: y - 9, class: 'plate'}, g);
  if (e.k === 'p' || e.k === 'n') svgText(g, m, y + 4, e.k.toUpperCase(), 'mark', 'middle');
  svgText(g, m, y - 16, e.d || '', 'dev', 'middle');
}

// -( )-, -(/)-, -(S)-, -(R)-: two arcs and what is between them.
function coil(g, e, x0, x1, y) {
  const m = (x0 + x1) / 2;
  el('line', {x1: x0, y1: y, x2: m - 9, y2: y, class: 'sym'}, g);
  el('path', {d: `M ${m - 5} ${y - 10} A 12 12 0 0 0 ${m - 5} ${y + 10}`, class: 'arc'}, g);
  el('path', {d: `M ${m + 5} ${y - 10} A 12 12 0 0 1 ${m + 5} ${y + 10}`, class: 'arc'}, g);
  const inner = {ncoil: '/', set: 'S', reset: 'R'}[e.k];
  if (inner) svgText(g, m, y + 4, inner, 'mark', 'middle');
  svgText(g, m, y - 16, e.d || '', 'dev', 'middle');
}

// A function block or compare box: its function on top, its instance above
// it, the pins at its sides (the first left pin on the rung's wire), the
// live value of each pin beside its name.
function box(g, e, x0, x1, y) {
  const [left, right] = boxSides(e);
  const bx0 = x0 + 8, bx1 = x1 - (e.o ? OUT_VALUES : 8);
  const n = Math.max(left.length, right.length);
  const top = y - 22, bottom = y + (n - 1) * BOX_PIN + 10;
  el('line', {x1: x0, y1: y, x2: bx0, y2: y, class: 'sym'}, g);
  if (!e.o) el('line', {x1: bx1, y1: y, x2: x1, y2: y, class: 'sym'}, g);
  el('rect', {x: bx0, y: top, width: bx1 - bx0, height: bottom - top, class: 'box'}, g);
  svgText(g, (bx0 + bx1) / 2, top + 11, e.f || '', 'fn', 'middle');
  if (e.inst) svgText(g, (bx0 + bx1) / 2, top - 4, e.inst, 'dev', 'middle');
  const vals = [];
  e.p.forEach(p => {
    const side = p[2] ? right : left, k = side.indexOf(p), py = y + k * BOX_PIN + 4;
    if (p[2]) {  // an output's value right of the box; a compare's result is its colour
      svgText(g, bx1 - 3, py, p[0], 'pin', 'end');
      vals.push(e.o ? svgText(g, bx1 + 4, py, '', 'val') : {textContent: ''});
    } else {
      const t = svgText(g, bx0 + 3, py, '', 'pin');
      t.textContent = pinLabel(p);
      vals.push(svgText(g, bx0 + 6 + pinLabel(p).length * FONT_W, py, '', 'val'));
    }
  });
  return vals;
}

function drawElem(svg, e, k, L) {
  const g = el('g', {class: 'elem ' + (e.o ? 'output' : 'input'), 'data-elem': k, 'data-kind': e.k || ''}, svg);
  const x0 = L.X(e.c), x1 = L.X(e.c + e.w), y = L.Y(e.r);
  let pins = [], val = null;
  if (e.k === 'no' || e.k === 'nc' || e.k === 'p' || e.k === 'n') contact(g, e, x0, x1, y);
  else if (e.k === 'coil' || e.k === 'ncoil' || e.k === 'set' || e.k === 'reset') coil(g, e, x0, x1, y);
  else if (isBox(e) && e.p) pins = box(g, e, x0, x1, y);
  else if (e.k === 'true') el('line', {x1: x0, y1: y, x2: x1, y2: y, class: 'sym'}, g);
  else {  // jumps, END, and anything else: its text in a frame
    el('line', {x1: x0, y1: y, x2: x0 + 6, y2: y, class: 'sym'}, g);
    el('rect', {x: x0 + 6, y: y - 10, width: x1 - x0 - 6, height: 20, rx: 3, class: 'box'}, g);
    svgText(g, x0 + 10, y + 4, e.k === 'jmp' ? '>> ' + e.d : e.t.slice(1, -1), 'fn');
  }
  if (!isBox(e)) val = svgText(g, (x0 + x1) / 2, y + 24, '', 'val', 'middle');
  const mark = el('g', {class: 'forcemark hidden'}, g);  // under the contact: forced, and to what
  const mx = (x0 + x1) / 2;
  el('rect', {x: mx - 16, y: y + 14, width: 32, height: 13, rx: 2}, mark);
  const mt = svgText(mark, mx, y + 24, 'F', '', 'middle');
  if (e.dv) {
    g.dataset.device = e.dv;
    g.addEventListener('click', () => clickContact(e, g));
    g.style.cursor = 'pointer';
  }
  return {g, val, pins, mark, markText: mt, e};
}

function drawRung(task, ti, rung, ri, parent) {
  const box = h('div', null, parent, 'rung');
  const head = (rung.labels && rung.labels.length ? 'label ' + rung.labels.join(', ') + ' \u00b7 ' : '') +
               'rung ' + (ri + 1) + ' \u00b7 line ' + rung.line + (rung.title ? ' \u00b7 ' + rung.title : '');
  h('div', head, box, 'title');
  if (!rung.rows) {
    h('pre', 'no ladder form: ' + rung.why + '\n' + rung.il.join('\n'), box);
    return null;
  }
  const L = layout(rung);
  const svg = el('svg', {class: 'ladder', width: L.width, height: L.height, id: 'rung-' + ti + '-' + ri}, box);
  const parts = {wires: [], elems: []};
  el('line', {x1: L.X(0) + 2, y1: 4, x2: L.X(0) + 2, y2: L.height - 4, class: 'rail'}, svg);
  for (const [r, c0, c1, n] of rung.wires)
    parts.wires.push([el('line', {x1: L.X(c0), y1: L.Y(r), x2: L.X(c1 + 1), y2: L.Y(r), 'data-net': n}, svg), n]);
  for (const [c, r0, r1, n] of rung.links) {
    const x = (L.X(c) + L.X(c + 1)) / 2;
    parts.wires.push([el('line', {x1: x, y1: L.Y(r0), x2: x, y2: L.Y(r1), 'data-net': n}, svg), n]);
  }
  rung.elems.forEach((e, k) => parts.elems.push(drawElem(svg, e, k, L)));
  return parts;
}

// ---------------------------------------------------------------- clicking a contact
// With --monitor-write a click on the contact or coil of an input, output or
// relay forces it to the other value, a second click releases it (a forced
// output or relay holds its value at every scan boundary, docs/runtime.md);
// a timer's or counter's bit is set by its block.

function say(text) { document.getElementById('reply').textContent = text; }
function currentBit(ti, dv) {
  const t = program.tasks[ti];
  const di = t.devIndex[dv];
  return di === undefined || !t.lastDev ? null : t.lastDev[di];
}
function clickContact(e, g) {
  const ti = Number(g.closest('.task').dataset.task), t = program.tasks[ti], dv = e.dv;
  if (!program.write) {
    say('read-only monitor: start ldrun with --monitor-write to force ' + dv + ' by clicking it');
    return;
  }
  const task = '&task=' + encodeURIComponent(t.name);
  const cur = currentBit(ti, dv);
  const other = cur === '1' ? '0' : '1';
  if (/^(X|Y|M|K)\d+$/.test(dv)) {
    if (forced.has(dv)) post('/api/write', 'device=' + dv + '&force=0' + task);
    else post('/api/write', 'device=' + dv + '&value=' + other + '&force=1' + task);
  } else {
    say(dv + (/\.Q$/.test(dv) ? ' is the done bit of its ' + (dv[0] === 'T' ? 'timer' : 'counter') +
              ': its block sets it, it cannot be forced' : ' cannot be forced from the monitor'));
  }
}

// ---------------------------------------------------------------- an ST or IL source

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

// ---------------------------------------------------------------- the page

function clock(ms) { return new Date(ms).toLocaleTimeString(); }

// The banner: each task that an online download switched, and when.
function showBanner() {
  const b = document.getElementById('banner');
  b.textContent = '';
  const switched = program.tasks.filter(t => t.switched_ms > 0);
  b.classList.toggle('hidden', switched.length === 0);
  for (const t of switched)
    h('div', 'task ' + t.name + ': new program downloaded at ' + clock(t.switched_ms) + ' (download ' + t.gen +
      '); the rungs below are the new program', b);
}

function render() {
  const root = document.getElementById('tasks');
  root.textContent = '';
  program.tasks.forEach((t, ti) => {
    const sec = h('div', null, root, 'task');
    sec.dataset.task = ti;
    sec.dataset.gen = t.gen;
    const head = h('h2', 'task ' + t.name + ' \u00b7 period ' + (t.period_us / 1000) + ' ms ', sec);
    t.stateEl = h('span', '', head, 'state');
    t.noteEl = h('span', '', head, 'pending');
    if (program.write && program.tasks.length > 1) {
      const task = encodeURIComponent(t.name);
      h('button', 'RUN', head).addEventListener('click', () => post('/api/run', 'task=' + task));
      h('button', 'STOP', head).addEventListener('click', () => post('/api/stop', 'task=' + task));
    }
    if (t.source_note) h('p', t.source_note, sec, 'note');
    t.srcEls = t.source ? drawSource(t, ti, sec) : [];
    t.view = t.rungs.map((r, ri) => drawRung(t, ti, r, ri, sec));
    t.devIndex = {};
    t.devices.forEach(([name], di) => { t.devIndex[name] = di; });
  });
  if (program.write) {
    document.getElementById('controls').classList.remove('hidden');
    document.getElementById('writeform').classList.remove('hidden');
  }
  showBanner();
  buildTable();
}

// The device table: a shared device (X Y M K WX WY: one image for every
// task) once, with every alias the tasks give it; a task's own devices as
// TASK.NAME when there are several tasks.
const SHARED = /^(X|Y|M|K|WX|WY)\d+$/;
function buildTable() {
  const tb = document.querySelector('#devices tbody');
  tb.textContent = '';
  const several = program.tasks.length > 1, rows = {};
  const was = new Set(chosen.map(c => c.key));  // ticked before a redraw: ticked again, history kept
  chosen = [];
  program.tasks.forEach((t, ti) => {
    t.rowsEl = t.devices.map(([name, alias], di) => {
      const shared = SHARED.test(name);
      const row = shared ? rows[name] : undefined;
      if (row) {  // listed already by an earlier task: its alias added, no second row
        if (alias && !row.aliases.includes(alias)) {
          row.aliases.push(alias);
          row.aliasTd.textContent = row.aliases.join(', ');
          row.tr.dataset.search += ' ' + alias.toLowerCase();
        }
        return null;
      }
      const tr = h('tr', null, tb);
      tr.dataset.search = ((shared ? '' : t.name + ' ') + name + ' ' + alias).toLowerCase();
      const cb = h('input', null, h('td', null, tr));
      cb.type = 'checkbox';
      const label = alias || name, key = t.name + ':' + name;
      const choose = () => {
        chosen.push({key, ti, di, label, bit: null});
        if (!history[key]) history[key] = [];
      };
      cb.addEventListener('change', () => {
        if (cb.checked) choose();
        else chosen = chosen.filter(c => c.key !== key);
      });
      if (was.has(key)) { cb.checked = true; choose(); }
      h('td', several && !shared ? t.name + '.' + name : name, tr);
      const aliasTd = h('td', alias, tr);
      tr.dataset.device = name;
      tr.dataset.alias = alias;
      if (shared) rows[name] = {tr, aliasTd, aliases: alias ? [alias] : []};
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

// ---------------------------------------------------------------- trends

function poly(svg, series, color, lo, hi) {
  if (series.length < 2) return;
  const n = series.length, span = (hi - lo) || 1;
  const pts = series.map((v, i) => (i * 400 / (n - 1)).toFixed(1) + ',' + (115 - (v - lo) * 110 / span).toFixed(1));
  el('polyline', {points: pts.join(' '), stroke: color}, svg);
}

// The time axis: seconds before now, a tick every 5 s, at the bottom.
const TREND_W = 400, TREND_L = 62, TREND_R = 8;
function tx(t, now) { return TREND_L + (TREND_W - TREND_L - TREND_R) * (1 - (now - t) / TREND_MS); }
function timeAxis(svg, now, y0, y1) {
  el('line', {x1: TREND_L, y1: y1, x2: TREND_W - TREND_R, y2: y1, class: 'axis'}, svg);
  for (let s = 0; s <= TREND_MS / 1000; s += 5) {
    const x = tx(now - s * 1000, now);
    el('line', {x1: x, y1: y0, x2: x, y2: y1, class: 'grid'}, svg);
    svgText(svg, x, y1 + 10, s === 0 ? 'now' : '-' + s + ' s', 'tick', 'middle');
  }
}

// Bits as steps on a lane each; words each on a lane with its own scale
// (its axis labelled with its lowest and highest value in the window).
function plotDevices(now) {
  const tr = document.getElementById('trend');
  tr.textContent = '';
  const BIT = 20, WORD = 64;
  let y = 4;
  const lanes = chosen.map(c => {
    const hgt = c.bit ? BIT : WORD;
    const lane = {c, y0: y, y1: y + hgt - 4};
    y += hgt;
    return lane;
  });
  const height = Math.max(y, 30) + 16;
  tr.setAttribute('viewBox', '0 0 ' + TREND_W + ' ' + height);
  tr.style.height = height + 'px';
  timeAxis(tr, now, 2, height - 14);
  lanes.forEach((lane, k) => {
    const {c, y0, y1} = lane, color = colors[k % colors.length];
    const pts = history[c.key].filter(([t]) => now - t <= TREND_MS);
    const name = svgText(tr, 2, (y0 + y1) / 2 + 4, c.label.slice(0, 9), 'lane');
    name.setAttribute('fill', color);
    el('line', {x1: TREND_L, y1: y1, x2: TREND_W - TREND_R, y2: y1, class: 'lanebase'}, tr);
    if (!pts.length) return;
    let lo = Math.min(...pts.map(p => p[1])), hi = Math.max(...pts.map(p => p[1]));
    if (c.bit) { lo = 0; hi = 1; }
    const span = hi - lo || 1, Yv = v => y1 - (v - lo) * (y1 - y0 - 2) / span;
    let d = '';
    pts.forEach(([t, v], i) => {
      const x = tx(t, now).toFixed(1), yy = Yv(v).toFixed(1);
      d += i === 0 ? `M ${x} ${yy}` : (c.bit ? ` H ${x} V ${yy}` : ` L ${x} ${yy}`);
    });
    d += ` H ${tx(now, now).toFixed(1)}`;
    el('path', {d: d, stroke: color, class: c.bit ? 'step' : 'word'}, tr);
    if (!c.bit) {  // its own axis
      el('line', {x1: TREND_L, y1: y0, x2: TREND_L, y2: y1, class: 'axis', stroke: color}, tr);
      svgText(tr, TREND_L - 2, y0 + 8, String(hi), 'tick', 'end').setAttribute('fill', color);
      svgText(tr, TREND_L - 2, y1, String(lo), 'tick', 'end').setAttribute('fill', color);
    }
  });
  const lg = document.getElementById('trendlegend');
  if (chosen.length) lg.textContent = 'bits as steps, each word on its own scale; the last ' + TREND_MS / 1000 + ' s';
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
  const now = Date.now();
  for (const c of chosen) {
    const ts = state.tasks[c.ti];
    if (!ts || ts.pending || !ts.dev.length) continue;
    const text = ts.dev[c.di];
    const v = parseFloat(text);
    if (c.bit === null) c.bit = /\.Q$|^(X|Y|M|K|S)\d+$/.test(program.tasks[c.ti].devices[c.di][0]);
    history[c.key].push([now, isNaN(v) ? 0 : v]);
    while (history[c.key].length && now - history[c.key][0][0] > TREND_MS + 1000) history[c.key].shift();
  }
  plotDevices(now);
}

// ---------------------------------------------------------------- values

function paintRung(v, rs) {
  for (const [line, n] of v.wires) line.classList.toggle('on', rs.n[n] === '1');
  v.elems.forEach(({g, val, pins, mark, markText, e}, k) => {
    g.classList.toggle('on', rs.e[k] === '1');
    if (val) val.textContent = rs.v[k] !== undefined ? rs.v[k] : '';
    const pv = rs.p && rs.p[k];
    if (pv) pins.forEach((t, i) => { if (t.textContent !== pv[i]) t.textContent = pv[i]; });
    const f = e.dv !== undefined && forced.has(e.dv);
    mark.classList.toggle('hidden', !f);
    if (f) { g.dataset.forced = forced.get(e.dv); markText.textContent = 'F=' + forced.get(e.dv); }
    else delete g.dataset.forced;
  });
}

function update(state) {
  if (refetching) return;
  // values of another program than the one drawn are dropped: of a newer one
  // (a download), the program is fetched again; of an older one (an event
  // sent before the program was fetched), nothing more
  const drawn = ti => program.tasks[ti] ? program.tasks[ti].gen : 0;
  if (state.tasks.some((ts, ti) => ts.gen > drawn(ti))) {
    refetchProgram();
    return;
  }
  if (state.tasks.some((ts, ti) => ts.gen < drawn(ti))) return;
  const s = document.getElementById('state');
  s.textContent = state.state;
  s.className = 'state ' + state.state;
  forced = new Map(state.forced.map((d, k) => [d, state.fv ? state.fv[k] : 1]));
  state.tasks.forEach((ts, ti) => {
    const t = program.tasks[ti];
    if (!t) return;
    const ts_state = state.state === 'RUN' && ts.held ? 'STOP' : state.state;
    if (t.stateEl.textContent !== ts_state) { t.stateEl.textContent = ts_state; t.stateEl.className = 'state ' + ts_state; }
    t.noteEl.textContent = ts.pending ? 'waiting for the first scan of the new program' : '';
    if (ts.pending) return;
    ts.rungs.forEach((rs, ri) => {
      const v = t.view[ri];
      if (v && rs.n) paintRung(v, rs);
    });
    if (ts.src) for (const [v, w] of t.srcEls) if (v.textContent !== ts.src[w]) v.textContent = ts.src[w];
    t.lastDev = ts.dev;
    ts.dev.forEach((d, di) => {
      const td = t.rowsEl[di];
      if (!td) return;  // a shared device listed by an earlier task
      if (td.textContent !== d) td.textContent = d;
      td.parentNode.classList.toggle('forced', forced.has(t.devices[di][0]));
    });
  });
  plotTrends(state);
}

async function refetchProgram() {
  if (refetching) return;
  refetching = true;
  try {
    program = await (await fetch('/api/program')).json();
    render();
  } finally {
    refetching = false;
  }
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
async function post(path, body, note) {
  const headers = {'X-LDC-Monitor': '1', 'Content-Type': 'application/x-www-form-urlencoded'};
  const token = localStorage.getItem(TOKEN_KEY);
  if (token) headers['X-LDC-Token'] = token;
  const r = await fetch(path, {method: 'POST', headers: headers, body: body});
  say(r.status + ': ' + (await r.text()).trim() + (note && r.status === 200 ? ' (' + note + ')' : ''));
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
    say('writes need the token: open the address ldrun printed at start (.../?token=...) once');
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
