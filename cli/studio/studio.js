// fivebar studio: the page (docs/studio.md). Hand-written, no framework: the server computes every
// figure (fivebar/studio.hpp); this script draws them, turns drags and sliders into edits (key
// path -> value), coalesces requests (one in flight, the newest state next) and drops stale answers.
'use strict';
(function () {
  const token = new URLSearchParams(location.search).get('token') || '';
  const $ = (id) => document.getElementById(id);
  const NS = 'http://www.w3.org/2000/svg';
  const COLOUR = { lower: '200,40,40', upper: '40,90,200', shared: '120,60,160' };

  const st = {
    controls: null, file: '', sha256: '', station: '',
    edits: new Map(), undo: [], redo: [],
    cursor: { lower: null, upper: null },
    seq: 0, shownSeq: 0, rev: 0, inflight: 0, queued: false, oldestEvent: null,
    fullTimer: null, fullAbort: null, fullRev: -1, figures: null, latencies: [], split: [], errors: 0, view: null,
    priorityAbort: null, priorityTimer: null, priorityLatencies: [], lastEdit: 0,
    pattern: null, frame: 0, playing: false, patternTimer: null,  // the pattern played (fivebar pattern's samples)
    regions: new Map(),  // region id -> loops: the server leaves out the loops of the ones listed here
    // This page's id: the server answers a priority request that a newer drag request of the same
    // page has overtaken with "stale", without its search.
    page: Array.from(crypto.getRandomValues(new Uint8Array(8)), (b) => b.toString(16).padStart(2, '0')).join(''),
  };
  window.studio = st;  // for the browser test (test/studio_browser.py) and the curious

  async function api(path, body, signal) {
    const init = { method: body === undefined ? 'GET' : 'POST', headers: { 'X-Fivebar-Token': token }, signal };
    if (body !== undefined) { init.body = JSON.stringify(body); init.headers['Content-Type'] = 'application/json'; }
    const res = await fetch(path, init);
    const timing = /dur=([0-9.]+)/.exec(res.headers.get('Server-Timing') || '');
    const doc = await res.json().catch(() => ({ error: 'HTTP ' + res.status }));
    if (doc && typeof doc === 'object') doc.server_ms = timing ? Number(timing[1]) : null;  // the server's own time
    if (!res.ok) throw new Error(doc.error || ('HTTP ' + res.status));
    return doc;
  }
  function status(text, bad) { const s = $('status'); s.textContent = text; s.className = bad ? 'bad' : ''; }
  function editsList() { return Array.from(st.edits, ([key, value]) => ({ key, value })); }
  function controlsOf(station) { return st.controls.stations.find((s) => s.station === station).keys; }
  function valueOf(key) {
    if (st.edits.has(key)) return st.edits.get(key);
    for (const s of st.controls.stations) for (const k of s.keys) if (k.key === key) return k.value;
    return undefined;
  }
  function fmt(v, d) { return v === null || v === undefined ? '—' : Number(v).toFixed(d); }

  // --- Edits, undo and redo ------------------------------------------------------------------------
  function snapshot() { return JSON.stringify(Array.from(st.edits)); }
  function checkpoint() { st.undo.push(snapshot()); st.redo = []; buttons(); }
  function restore(snap) { st.edits = new Map(JSON.parse(snap)); st.rev++; patternStale(); syncControls(); request(performance.now()); buttons(); }
  function undo() { if (st.undo.length) { st.redo.push(snapshot()); restore(st.undo.pop()); } }
  function redo() { if (st.redo.length) { st.undo.push(snapshot()); restore(st.redo.pop()); } }
  function buttons() { $('undo').disabled = !st.undo.length; $('redo').disabled = !st.redo.length; }
  function setEdit(key, value, eventTime) {
    st.edits.set(key, value);
    st.rev++;
    patternStale();
    syncControl(key);
    request(eventTime);
  }

  // --- Requests: one in flight, the newest state queued, stale answers dropped ----------------------
  // A drag's answer comes in two parts (docs/studio.md "Speed"): the regions, coverage, poses and
  // tolerance bands ("quick"), then the priority rule, whose search is most of the time, in a
  // second request that the next edit cancels; until it arrives the rule says "not certified yet".
  // Two drag requests at most in flight: the server answers them on two threads (this machine's two
  // cores), and an edit that arrives while one is computed need not wait for it.
  const MAX_INFLIGHT = 2;
  const PRIORITY_PAUSE = 40;  // ms without an edit before the priority rule is asked for
  function request(eventTime) {
    if (st.oldestEvent === null) st.oldestEvent = eventTime;
    st.lastEdit = performance.now();
    if (st.priorityTimer) { clearTimeout(st.priorityTimer); st.priorityTimer = null; }
    if (st.fullAbort) { st.fullAbort.abort(); st.fullAbort = null; }  // its answer would be stale
    if (st.priorityAbort) { st.priorityAbort.abort(); st.priorityAbort = null; }
    if (st.inflight >= (st.maxInflight || MAX_INFLIGHT)) { st.queued = true; return; }
    send();
  }
  async function send() {
    st.inflight++; st.queued = false;
    const seq = ++st.seq, rev = st.rev, since = st.oldestEvent, sent = performance.now();
    st.oldestEvent = null;
    clearTimeout(st.fullTimer);
    let fig;
    try {
      fig = await api("/api/figures", body(st.dragFigures || "quick", seq));
    } catch (e) {
      if (!st.queued) { status(e.message, true); markInvalid(); }
      st.inflight--;
      if (st.queued) send();
      return;
    }
    // The next request (edits that arrived meanwhile) leaves before this answer is drawn.
    st.inflight--;
    if (st.queued) send();
    if (seq <= st.shownSeq) return;  // an older answer than the one shown
    if (!fillRegions(fig)) { st.regions.clear(); request(performance.now()); return; }
    const answered = performance.now(), server = fig.server_ms;
    st.shownSeq = seq;
    st.figures = fig;
    draw(fig);
    const drawn = performance.now();
    if ($('status').className === 'bad') status('');
    requestAnimationFrame(() => {
      if (since === null) return;
      const now = performance.now();
      st.latencies.push(now - since);
      // Where the time went: waiting to be sent, the request, drawing, the frame.
      st.split.push({ queued: sent - since, request: answered - sent, server, draw: drawn - answered, frame: now - drawn });
    });
    if (rev !== st.rev) return;
    if (typeof fig.priority === 'string') {
      // Not while the drag goes on: its search would take a core from the next drag answer
      // (measured: p95 1.5 times longer). Once no edit has come for PRIORITY_PAUSE ms.
      const wait = Math.max(0, st.lastEdit + (st.priorityPause ?? PRIORITY_PAUSE) - performance.now());
      st.priorityTimer = setTimeout(() => { st.priorityTimer = null; if (rev === st.rev) priority(rev, seq, since); }, wait);
    }
    st.fullTimer = setTimeout(() => full(rev), 120);
  }
  async function priority(rev, seq, since) {
    const abort = new AbortController();
    st.priorityAbort = abort;
    try {
      const ans = await api('/api/figures', body('priority', seq), abort.signal);
      if (ans.stale || rev !== st.rev || st.shownSeq !== seq) return;
      st.figures.priority = ans.priority;
      tables(st.figures);
      requestAnimationFrame(() => { if (since !== null) st.priorityLatencies.push(performance.now() - since); });
    } catch (e) {
      // Aborted by a newer edit, or refused: the quick answer already reported that.
    } finally {
      if (st.priorityAbort === abort) st.priorityAbort = null;
    }
  }
  function body(figures, seq) {
    return { edits: editsList(), station: st.station, cursor: cursorBody(), figures, seq, page: st.page,
      have_regions: Array.from(st.regions.keys()) };
  }
  // The loops of the regions the answer left out (the page holds them), and the new ones kept.
  // False when one is missing (dropped here meanwhile): the page then asks again.
  function fillRegions(fig) {
    const regions = fig.mechanisms.map((m) => m.region);
    if (fig.shared_region) regions.push(fig.shared_region);
    let ok = true;
    for (const r of regions) {
      if (r.loops_mm === null) {
        const loops = st.regions.get(r.id);
        if (loops === undefined) { ok = false; continue; }
        r.loops_mm = loops;
        st.regions.delete(r.id);  // newest last
      }
      st.regions.set(r.id, r.loops_mm);
    }
    while (st.regions.size > 24) st.regions.delete(st.regions.keys().next().value);
    return ok;
  }
  function cursorBody() {
    const c = {};
    if (st.cursor.lower) c.lower = st.cursor.lower;
    if (st.cursor.upper) c.upper = st.cursor.upper;
    return c;
  }
  async function full(rev) {
    if (rev !== st.rev) return;
    if (st.inflight || st.priorityAbort || st.priorityTimer) { st.fullTimer = setTimeout(() => full(rev), 60); return; }
    const abort = new AbortController();
    st.fullAbort = abort;
    try {
      const fig = await api('/api/figures', body('full', st.seq), abort.signal);
      if (rev === st.rev && fillRegions(fig)) { st.fullRev = rev; st.figures = fig; draw(fig); }
    } catch (e) {
      // Aborted by a newer edit, or refused: the live answer already reported that.
    } finally {
      if (st.fullAbort === abort) st.fullAbort = null;
    }
  }
  function markInvalid() {
    for (const td of document.querySelectorAll('#coverage td')) td.classList.add('pending');
  }

  // --- Drawing -----------------------------------------------------------------------------------
  function el(name, attrs, parent) {
    const e = document.createElementNS(NS, name);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
    if (parent) parent.appendChild(e);
    return e;
  }
  function path(loops) {
    return loops.map((l) => 'M' + l.map((p) => p[0] + ',' + p[1]).join('L') + 'Z').join('');
  }
  function fitView(fig) {
    let xs = [], ys = [];
    for (const m of fig.mechanisms) {
      for (const l of m.region.loops_mm) for (const p of l) { xs.push(p[0]); ys.push(p[1]); }
      for (const b of m.bases_mm) { xs.push(b[0]); ys.push(b[1]); }
    }
    for (const p of fig.target.outline_mm) { xs.push(p[0]); ys.push(p[1]); }
    const pad = 3, x0 = Math.min(...xs) - pad, x1 = Math.max(...xs) + pad, y0 = Math.min(...ys) - pad, y1 = Math.max(...ys) + pad;
    return { x0, y0, w: x1 - x0, h: y1 - y0 };
  }
  function draw(fig) {
    const svg = $('svg');
    if (!st.view || st.viewStation !== fig.station) { st.view = fitView(fig); st.viewStation = fig.station; }
    const v = st.view;
    svg.setAttribute('viewBox', `${v.x0} ${-(v.y0 + v.h)} ${v.w} ${v.h}`);
    if ($('truescale').checked) { svg.setAttribute('width', v.w + 'mm'); svg.setAttribute('height', v.h + 'mm'); }
    else { svg.removeAttribute('width'); svg.removeAttribute('height'); }
    svg.classList.toggle('truescale', $('truescale').checked);
    svg.replaceChildren();
    const g = el('g', { transform: 'scale(1,-1)', id: 'world' }, svg);
    drawFields(fig, g);
    for (const m of fig.mechanisms) {
      el('path', { d: path(m.region.loops_mm), fill: `rgba(${COLOUR[m.mechanism]},0.12)`, stroke: `rgb(${COLOUR[m.mechanism]})`,
        'stroke-width': 0.1, 'fill-rule': 'evenodd' }, g);
    }
    if (fig.shared_region) {
      el('path', { d: path(fig.shared_region.loops_mm), fill: `rgba(${COLOUR.shared},0.15)`, stroke: 'none', 'fill-rule': 'evenodd' }, g);
    }
    el('path', { d: path([fig.target.outline_mm]), fill: 'rgba(0,0,0,0.05)', stroke: '#000', 'stroke-width': 0.12 }, g);
    for (const m of fig.mechanisms) drawMechanism(m, g);
    drawWitnesses(fig, g);
    el('g', { id: 'patternlayer' }, g);
    drawHandles(fig, g);
    el('line', { x1: v.x0 + 1, y1: v.y0 + 1, x2: v.x0 + 6, y2: v.y0 + 1, stroke: '#000', 'stroke-width': 0.2 }, g);
    const t = el('text', { x: v.x0 + 1, y: -(v.y0 + 1.5), 'font-size': 1.2 }, svg);
    t.textContent = '5 mm';
    tables(fig);
    drawFrame();
  }
  function drawFields(fig, g) {
    if (Array.isArray(fig.lci_field)) {
      for (const f of fig.lci_field) {
        const c = COLOUR[f.mechanism];
        for (let j = 0; j < f.ny; ++j) for (let i = 0; i < f.nx; ++i) {
          const v = f.lci_sampled[j * f.nx + i];
          if (v === null) continue;
          el('rect', { x: f.origin_mm[0] + (i - 0.5) * f.spacing_mm, y: f.origin_mm[1] + (j - 0.5) * f.spacing_mm,
            width: f.spacing_mm, height: f.spacing_mm, fill: `rgba(${c},${(0.25 * (1 - v)).toFixed(3)})` }, g);
        }
      }
    }
    if (fig.collision_map && typeof fig.collision_map === 'object') {
      for (const p of fig.collision_map.lower_colliding_against_centre_mm) el('circle', { cx: p[0], cy: p[1], r: 0.12, fill: '#b00020' }, g);
      for (const p of fig.collision_map.lower_free_against_centre_mm) el('circle', { cx: p[0], cy: p[1], r: 0.08, fill: '#126b24' }, g);
    }
  }
  function drawMechanism(m, g) {
    const c = COLOUR[m.mechanism];
    if (m.outline) {
      for (const part of m.outline) for (const cap of part.capsules) {
        el('line', { x1: cap.a_mm[0], y1: cap.a_mm[1], x2: cap.b_mm[0], y2: cap.b_mm[1], stroke: `rgba(${c},0.18)`,
          'stroke-width': 2 * cap.radius_mm, 'stroke-linecap': 'round' }, g);
      }
    }
    const t = m.tolerance;
    if (t && t.status === 'ok') {  // the 3-sigma ellipse (first order) around the tactor point
      el('ellipse', { cx: t.at_mm[0], cy: t.at_mm[1], rx: t.three_sigma_first_order_mm, ry: t.three_sigma_minor_first_order_mm,
        transform: `rotate(${t.three_sigma_angle_first_order_deg} ${t.at_mm[0]} ${t.at_mm[1]})`, fill: `rgba(${c},0.25)`,
        stroke: `rgb(${c})`, 'stroke-width': 0.05 }, g);
    }
    if (m.pose.points_mm) {
      el('polyline', { points: m.pose.points_mm.map((p) => p.join(',')).join(' '), fill: 'none', stroke: `rgb(${c})`, 'stroke-width': 0.35,
        'stroke-linejoin': 'round' }, g);
    }
  }
  function drawWitnesses(fig, g) {
    for (const r of coverageRows(fig)) {
      if (!r.worst_point_mm) continue;
      const c = COLOUR[r.name] || '0,0,0';
      el('circle', { cx: r.worst_point_mm[0], cy: r.worst_point_mm[1], r: 0.45, fill: 'none', stroke: `rgb(${c})`, 'stroke-width': 0.15,
        'stroke-dasharray': '0.3 0.2' }, g);
    }
  }
  function handle(g, shape, x, y, colour, onMove, label) {
    let h;
    if (shape === 'square') h = el('rect', { x: x - 0.6, y: y - 0.6, width: 1.2, height: 1.2, fill: colour, class: 'handle' }, g);
    else if (shape === 'ring') h = el('circle', { cx: x, cy: y, r: 0.7, fill: 'rgba(255,255,255,0.4)', stroke: colour, 'stroke-width': 0.3, class: 'handle' }, g);
    else h = el('path', { d: `M${x - 0.9},${y}h1.8M${x},${y - 0.9}v1.8`, stroke: colour, 'stroke-width': 0.45, class: 'handle' }, g);
    h.dataset.handle = label;
    h.addEventListener('pointerdown', (ev) => startDrag(ev, onMove, shape !== 'ring'));
  }
  function drawHandles(fig, g) {
    const prefix = 'stations.' + fig.station;
    for (const m of fig.mechanisms) {
      const mk = prefix + '.mechanisms.' + m.mechanism;
      m.bases_mm.forEach((b, i) => handle(g, 'square', b[0], b[1], `rgb(${COLOUR[m.mechanism]})`, (p, t) => {
        st.edits.set(`${mk}.bases[${i}][0]`, round(p[0])); setEdit(`${mk}.bases[${i}][1]`, round(p[1]), t);
        syncControl(`${mk}.bases[${i}][0]`);
      }, `${m.mechanism}.bases[${i}]`));
      const at = m.cursor_mm;
      handle(g, 'ring', at[0], at[1], `rgb(${COLOUR[m.mechanism]})`, (p, t) => { st.cursor[m.mechanism] = p; st.rev++; request(t); },
        `${m.mechanism}.tactor`);
    }
    const c = fig.target.center_mm;
    handle(g, 'cross', c[0], c[1], '#000', (p, t) => {
      st.edits.set(prefix + '.target.center[0]', round(p[0])); setEdit(prefix + '.target.center[1]', round(p[1]), t);
      syncControl(prefix + '.target.center[0]');
    }, 'target.center');
  }
  function round(v) { return Math.round(v * 1000) / 1000; }  // micrometres: what a file keeps
  function startDrag(ev, onMove, edits) {
    ev.preventDefault();
    if (edits) checkpoint();  // a tactor point is not an edit of the file: no undo step
    // Listeners on the window: every redraw replaces the handle that was pressed.
    const move = (e) => {
      const p = new DOMPoint(e.clientX, e.clientY).matrixTransform($('world').getScreenCTM().inverse());
      onMove([p.x, p.y], e.timeStamp);
    };
    // pointerrawupdate (Chromium) is dispatched as the input arrives; pointermove waits for the next
    // animation frame, up to 16 ms later.
    const kind = 'onpointerrawupdate' in window ? 'pointerrawupdate' : 'pointermove';
    const up = () => { window.removeEventListener(kind, move); window.removeEventListener('pointerup', up); };
    window.addEventListener(kind, move);
    window.addEventListener('pointerup', up);
  }

  // --- Tables --------------------------------------------------------------------------------------
  function coverageRows(fig) {
    const rows = fig.coverage.mechanisms.map((r) => Object.assign({ name: r.mechanism }, r));
    if (fig.coverage.shared) rows.push(Object.assign({ name: 'shared' }, fig.coverage.shared));
    return rows;
  }
  function tables(fig) {
    const tb = document.querySelector('#coverage tbody');
    tb.replaceChildren();
    for (const r of coverageRows(fig)) {
      const tr = document.createElement('tr');
      const verdict = !r.decided ? 'UNDECIDED' : r.covered ? 'covered' : 'NOT COVERED';
      const cells = [r.name, verdict, fmt(r.margin_mm, 4), r.worst_point_mm ? `(${fmt(r.worst_point_mm[0], 3)}, ${fmt(r.worst_point_mm[1], 3)})` : '—',
        fmt(r.min_lci, 4)];
      cells.forEach((text, k) => {
        const td = document.createElement('td');
        td.textContent = text;
        if (k === 1) td.className = r.covered ? 'good' : 'bad';
        if (k === 2) td.id = 'margin-' + r.name;
        tr.appendChild(td);
      });
      tb.appendChild(tr);
    }
    const pr = fig.priority;
    $('priority').textContent = typeof pr === 'string' ? 'priority rule at the tactor points: ' + pr
      : pr ? `priority rule at the tactor points: ${pr.status}${pr.moved_mm ? `, lower moved ${fmt(pr.moved_mm, 3)} mm` : ''} — ${pr.reason}`
        : 'priority rule: needs both mechanisms and a geometry: section';
    $('priority').className = typeof pr === 'string' ? 'pending' : '';
    const cm = fig.collision_map;
    $('collision').textContent = typeof cm === 'string' ? 'collision map: ' + cm
      : cm ? `collision map (sampled, ${fmt(cm.spacing_mm, 2)} mm grid): ${fmt(100 * cm.colliding_fraction, 2)} % of ${cm.pairs} pairs collide; every pair farther apart than ${fmt(cm.max_colliding_separation_mm, 3)} mm is free; green dots: lower positions free with the upper at the centre`
        : 'collision map: needs both mechanisms and a geometry: section';
    $('collision').className = typeof cm === 'string' ? 'pending' : '';
    const lci = fig.lci_field;
    $('lci').textContent = typeof lci === 'string' ? 'LCI field: ' + lci
      : 'LCI field (sampled): shaded where conditioning is poor; LCI at the tactor points: ' +
        fig.mechanisms.map((m) => `${m.mechanism} ${fmt(m.pose.lci, 4)}`).join(', ');
    $('lci').className = typeof lci === 'string' ? 'pending' : '';
    $('tolerance').textContent = '3-sigma tactor error at the tactor points (first order, as fivebar tolerance): ' +
      fig.mechanisms.map((m) => m.tolerance.status !== 'ok' ? `${m.mechanism} ${m.tolerance.status}`
        : `${m.mechanism} ${fmt(m.tolerance.three_sigma_first_order_mm, 4)} mm (worst case ${fmt(m.tolerance.worst_case_first_order_mm, 4)} mm)` +
          (m.tolerance.near_singular ? ' [near singular]' : '')).join(', ');
  }

  // --- Pattern ---------------------------------------------------------------------------------------
  // The design's pattern of the chosen kind, computed by the server for the current edits with the
  // library call of `fivebar pattern` (the priority rule applied sample by sample), played on the
  // drawing: the two linkages at the commanded points, the targets as small crosses.
  async function play() {
    if (st.playing) { pause(); return; }
    const kind = $('patternkind').value;
    const key = JSON.stringify([snapshot(), st.station, kind]);  // the state it is computed for
    if (!st.pattern || st.pattern.key !== key) {
      $('patternstatus').textContent = 'pattern: computing ' + kind + '…';
      $('patternstatus').className = 'pending';
      try {
        const p = await api('/api/pattern', { edits: editsList(), station: st.station, pattern: kind });
        if (key !== JSON.stringify([snapshot(), st.station, $('patternkind').value])) { patternStale(); return; }
        p.key = key;
        st.pattern = p;
        st.frame = 0;
        const scrub = $('scrub');
        scrub.max = p.samples.length - 1; scrub.value = 0; scrub.disabled = false;
      } catch (e) { $('patternstatus').textContent = 'pattern: ' + e.message; $('patternstatus').className = 'bad'; return; }
    }
    if (st.frame >= st.pattern.samples.length - 1) st.frame = 0;
    st.playing = true;
    $('play').textContent = 'Pause';
    const dt = 1000 / st.pattern.spec.rate_hz;  // real time: one sample per controller period
    const t0 = performance.now() - st.frame * dt;
    const tick = () => {
      if (!st.playing || !st.pattern) return;
      st.frame = Math.min(st.pattern.samples.length - 1, Math.floor((performance.now() - t0) / dt));
      drawFrame();
      if (st.frame >= st.pattern.samples.length - 1) { pause(); return; }
      st.patternTimer = requestAnimationFrame(tick);
    };
    st.patternTimer = requestAnimationFrame(tick);
  }
  function pause() {
    st.playing = false;
    if (st.patternTimer) cancelAnimationFrame(st.patternTimer);
    st.patternTimer = null;
    $('play').textContent = 'Play';
  }
  function patternStale() {
    if (!st.pattern) return;
    pause();
    st.pattern = null;
    $('scrub').disabled = true;
    $('patternstatus').textContent = 'pattern: not certified yet for the current state (press Play to compute it)';
    $('patternstatus').className = 'pending';
    const layer = $('patternlayer');
    if (layer) layer.replaceChildren();
  }
  function drawFrame() {
    const layer = $('patternlayer');
    const p = st.pattern;
    if (!layer || !p) return;
    layer.replaceChildren();
    const k = Math.min(st.frame, p.samples.length - 1);
    const sample = p.samples[k], frame = p.frames[k];
    for (const m of sample.mechanisms) {
      const c = COLOUR[m.mechanism];
      const joints = frame[m.mechanism];
      if (joints) {
        el('polyline', { points: joints.map((q) => q.join(',')).join(' '), fill: 'none', stroke: `rgb(${c})`, 'stroke-width': 0.25,
          'stroke-dasharray': '0.6 0.3' }, layer);
      }
      const [tx, ty] = m.target_mm;
      el('path', { d: `M${tx - 0.4},${ty - 0.4}l0.8,0.8M${tx - 0.4},${ty + 0.4}l0.8,-0.8`, stroke: `rgb(${c})`, 'stroke-width': 0.12 }, layer);
      el('circle', { cx: m.point_mm[0], cy: m.point_mm[1], r: 0.5, fill: `rgb(${c})`, 'data-pattern-tactor': m.mechanism }, layer);
    }
    $('scrub').value = k;
    const statuses = sample.mechanisms.map((m) => `${m.mechanism} ${m.status}`).join(', ');
    const verdict = p.passed ? 'renderable' : `NOT renderable (first failure: sample ${p.first_failure.index}, ${p.first_failure.mechanism} ${p.first_failure.status})`;
    $('patternstatus').textContent = `${p.pattern}: sample ${k} of ${p.samples.length - 1}, t = ${fmt(sample.time_s, 3)} s: ${statuses}` +
      (sample.moved_mm > 0 ? `; priority rule moved the lower ${fmt(sample.moved_mm, 3)} mm` : '') + ` — ${verdict}`;
    $('patternstatus').className = p.passed ? '' : 'bad';
  }

  // --- Controls ------------------------------------------------------------------------------------
  function controls() {
    const box = $('controls');
    box.replaceChildren();
    for (const k of controlsOf(st.station)) {
      const row = document.createElement('div');
      row.className = 'row';
      const label = document.createElement('label');
      label.textContent = k.key.replace('stations.' + st.station + '.', '');
      label.title = k.key;
      row.appendChild(label);
      if (k.choices) {
        const sel = document.createElement('select');
        for (const c of k.choices) { const o = document.createElement('option'); o.value = o.textContent = c; sel.appendChild(o); }
        sel.dataset.key = k.key;
        sel.addEventListener('change', (e) => { checkpoint(); setEdit(k.key, sel.value, e.timeStamp); });
        row.appendChild(sel);
        row.appendChild(document.createElement('span'));
      } else {
        const range = document.createElement('input');
        Object.assign(range, { type: 'range', min: k.min, max: k.max, step: 'any' });
        range.dataset.key = k.key;
        const num = document.createElement('input');
        Object.assign(num, { type: 'number', step: 0.1 });
        num.dataset.key = k.key;
        range.addEventListener('pointerdown', () => checkpoint());
        range.addEventListener('keydown', () => checkpoint());
        range.addEventListener('input', (e) => setEdit(k.key, round(Number(range.value)), e.timeStamp));
        num.addEventListener('change', (e) => {
          if (num.value === '' || !isFinite(Number(num.value))) return;
          checkpoint(); setEdit(k.key, Number(num.value), e.timeStamp);
        });
        row.appendChild(range);
        row.appendChild(num);
      }
      box.appendChild(row);
    }
    syncControls();
  }
  function syncControl(key) {
    for (const e of document.querySelectorAll(`#controls [data-key="${CSS.escape(key)}"]`)) {
      const v = valueOf(key);
      if (document.activeElement !== e || e.type === 'range') e.value = v;
    }
  }
  function syncControls() { for (const k of controlsOf(st.station)) syncControl(k.key); }

  // --- Save, reload, run ---------------------------------------------------------------------------
  async function save() {
    try {
      const p = await api('/api/preview', { edits: editsList() });
      $('difffile').textContent = p.file;
      const pre = $('diff');
      pre.replaceChildren();
      for (const c of p.changes) {
        for (const [cls, sign, text] of [['del', '-', c.before], ['add', '+', c.after]]) {
          if (text === null) continue;
          const line = document.createElement('div');
          line.className = cls;
          line.textContent = `${sign}${String(c.line).padStart(4)}: ${text}`;
          pre.appendChild(line);
        }
      }
      $('diffnote').textContent = p.changes.length ? `${p.changes.length} line(s) change; every other line, comments included, stays as it is.` : 'Nothing to save.';
      $('confirmsave').disabled = !p.changes.length;
      $('diffdialog').showModal();
    } catch (e) { status(e.message, true); }
  }
  async function confirmSave() {
    $('diffdialog').close();
    try {
      const r = await api('/api/save', { edits: editsList(), sha256: st.sha256 });
      if (!r.saved) { status(r.reason, true); return; }
      await loadState();
      st.edits = new Map();
      st.rev++;
      syncControls();
      status('saved ' + st.file);
      request(performance.now());
    } catch (e) { status(e.message, true); }
  }
  async function reload() {
    try { await loadState(); st.edits = new Map(); st.undo = []; st.redo = []; buttons(); st.rev++; patternStale(); controls(); request(performance.now()); status('reloaded'); }
    catch (e) { status(e.message, true); }
  }
  async function run() {
    const products = $('products').value.split(',').map((s) => s.trim()).filter((s) => s);
    try {
      await api('/api/run', { products });
      $('runlog').hidden = false;
      $('runlink').textContent = '';
      poll();
    } catch (e) { status(e.message, true); }
  }
  async function poll() {
    const r = await api('/api/run');
    $('runlines').textContent = r.lines.join('\n');
    if (r.running) { setTimeout(poll, 500); return; }
    const o = r.outcome || {};
    const p = $('runlink');
    p.replaceChildren();
    if (o.index_html) {
      const a = document.createElement('a');
      a.href = o.index_html + '?token=' + encodeURIComponent(token);
      a.target = '_blank';
      a.textContent = 'open the products page';
      p.append((o.ok ? 'run passed: ' : 'run finished with a failed check: '), a);
    } else { p.textContent = 'run failed: ' + (o.error || 'unknown'); p.className = 'bad'; }
  }
  async function loadState() {
    const s = await api('/api/state');
    st.controls = s; st.file = s.file; st.sha256 = s.sha256;
    $('file').textContent = s.file;
    const sel = $('station');
    if (!sel.options.length) {
      for (const x of s.stations) { const o = document.createElement('option'); o.value = o.textContent = x.station; sel.appendChild(o); }
    }
    if (!st.station) st.station = s.stations.length ? s.stations[0].station : '';
    sel.value = st.station;
  }

  async function main() {
    $('undo').addEventListener('click', undo);
    $('redo').addEventListener('click', redo);
    $('save').addEventListener('click', save);
    $('confirmsave').addEventListener('click', confirmSave);
    $('cancelsave').addEventListener('click', () => $('diffdialog').close());
    $('reload').addEventListener('click', reload);
    $('run').addEventListener('click', run);
    $('play').addEventListener('click', play);
    $('patternkind').addEventListener('change', () => { pause(); if (st.pattern) patternStale(); });
    $('scrub').addEventListener('input', () => { pause(); st.frame = Number($('scrub').value); drawFrame(); });
    $('truescale').addEventListener('change', () => st.figures && draw(st.figures));
    $('station').addEventListener('change', (e) => {
      st.station = $('station').value; st.cursor = { lower: null, upper: null }; st.rev++; patternStale(); controls(); request(e.timeStamp);
    });
    document.addEventListener('keydown', (e) => {
      if ((e.ctrlKey || e.metaKey) && e.key.toLowerCase() === 'z') { e.preventDefault(); (e.shiftKey ? redo : undo)(); }
    });
    try { await loadState(); controls(); request(performance.now()); }
    catch (e) { status(e.message, true); }
  }
  main();
})();
