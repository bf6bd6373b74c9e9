// gait review: the page's logic. Written for this project; no framework, no network beyond
// the review server that served it. The server holds the keypoints and recomputes the
// kinematics; the page keeps the corrections' undo history and draws.
'use strict';
(() => {
  // The URL `gait review` printed carries the session's token; the page keeps it for this
  // address (each run folder has its own port), so a report's frame link, which cannot know
  // it, opens the same session.
  const given = new URLSearchParams(location.search).get('token');
  try { if (given) localStorage.setItem('gait-review-token', given); } catch (e) { /* storage off */ }
  const token = given || (() => { try { return localStorage.getItem('gait-review-token'); } catch (e) { return null; } })() || '';
  const api = (path) => path + (path.includes('?') ? '&' : '?') + 'token=' + encodeURIComponent(token);
  const $ = (id) => document.getElementById(id);
  const COLOUR = { left: '#d62728', right: '#1f5fa8', upper: '#e8e8e8' };
  const LEG = ['hip', 'knee', 'ankle', 'heel', 'toe'];
  const JOINTS = ['hip', 'knee', 'ankle'];
  const GRAB_PX = 14;

  // Everything the page knows; exposed for the browser test and for the curious.
  const S = {
    run: null, an: null, frame: 0, first: 0, last: 0, index: new Map(),
    history: [], at: -1, busy: false, playing: false, images: new Map(),
    drag: null, pickSubject: false, error: null, lastRecomputeMs: null,
    drawn: -1,
  };
  window.gaitReview = S;

  // ---- server ----------------------------------------------------------------------------
  async function getJson(path) {
    const r = await fetch(api(path));
    if (!r.ok) throw new Error((await r.text()) || r.statusText);
    return r.json();
  }

  async function postCorrections(doc) {
    const r = await fetch(api('/api/corrections'), {
      method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(doc),
    });
    const body = await r.json().catch(() => ({ error: r.statusText }));
    if (!r.ok) throw new Error(body.error || r.statusText);
    return body;
  }

  // ---- corrections and history -------------------------------------------------------------
  const clone = (doc) => JSON.parse(JSON.stringify(doc));
  const normal = (doc) => ({
    swap: doc.swap || [], event: doc.event || [], exclude: doc.exclude || [], keypoint: doc.keypoint || [],
  });
  const current = () => normal(S.history[S.at] || {});
  const strip = (doc) => {
    const out = {};
    for (const k of ['swap', 'event', 'exclude', 'keypoint']) if (doc[k] && doc[k].length) out[k] = doc[k];
    return out;
  };

  // Sends `doc`; on success it becomes history entry `at`.
  async function apply(doc, at, push) {
    if (S.busy) return false;
    S.busy = true;
    setStatus('recomputing…');
    const t0 = performance.now();
    try {
      const an = await postCorrections(strip(doc));
      if (push) { S.history.length = S.at + 1; S.history.push(normal(doc)); S.at = S.history.length - 1; }
      else S.at = at;
      S.an = an;
      S.error = null;
      drawAll();
      S.lastRecomputeMs = performance.now() - t0;
      const n = ['swap', 'event', 'exclude', 'keypoint'].reduce((a, k) => a + current()[k].length, 0);
      setStatus(`saved ${n} correction${n === 1 ? '' : 's'} to ${S.run.corrections_path}; recomputed in ` +
        `${S.lastRecomputeMs.toFixed(0)} ms (server ${(an.seconds * 1000).toFixed(0)} ms)`, 'ok');
      return true;
    } catch (e) {
      S.error = e.message;
      setStatus(e.message + ' (not saved)', 'error');
      return false;
    } finally {
      S.busy = false;
      updateUndo();
    }
  }

  const change = (edit) => { const doc = clone(current()); edit(doc); return apply(doc, S.at + 1, true); };
  const undo = () => S.at > 0 && apply(S.history[S.at - 1], S.at - 1, false);
  const redo = () => S.at + 1 < S.history.length && apply(S.history[S.at + 1], S.at + 1, false);
  function updateUndo() {
    $('undo').disabled = S.at <= 0;
    $('redo').disabled = S.at + 1 >= S.history.length;
  }

  function setStatus(text, kind) {
    const s = $('status');
    s.textContent = text;
    s.className = kind || '';
  }

  // ---- frames ----------------------------------------------------------------------------
  const clampFrame = (f) => Math.max(S.first, Math.min(S.last, Math.round(f)));
  const sample = (f) => f - S.an.first_frame;

  function setFrame(f) {
    S.frame = clampFrame(f);
    $('scrubber').value = S.frame;
    const t = (S.frame / S.run.fps).toFixed(2);
    $('frame-label').textContent = `frame ${S.frame} (${t} s)`;
    S.images.size > 400 && S.images.clear();
    drawFrame();
    drawPlots();
    markCurrentRows();
  }

  function imageOf(f, kind) {
    const key = kind + f;
    let img = S.images.get(key);
    if (!img) {
      img = new Image();
      img.onload = () => { if (f === S.frame) drawFrame(); };
      img.src = api(`/api/frame/${f}?kind=${kind}`);
      S.images.set(key, img);
    }
    return img;
  }

  function frameKind() {
    return $('show-regenerated').checked && S.run.regenerated.includes(S.frame) ? 'regenerated' : 'original';
  }

  // ---- the frame and its skeleton ----------------------------------------------------------
  function rawPoint(name, f) {
    const j = S.run.names.indexOf(name);
    const i = S.index.get(f);
    if (j < 0 || i === undefined) return null;
    const [x, y, l] = S.run.keypoints[j].map((s) => s[i]);
    return x === null || y === null ? null : { x, y, l };
  }

  // The keypoint as the analysis leaves it (lower limb: cleaned; the rest: the model's).
  function point(name, f) {
    if (S.drag && S.drag.name === name && f === S.frame) return S.drag;
    const s = S.an && S.an.filtered[name];
    if (s) {
      const i = sample(f);
      const x = s[0][i], y = s[1][i];
      return x === null || x === undefined || y === null ? null : { x, y };
    }
    return rawPoint(name, f);
  }

  function drawFrame() {
    const c = $('frame'), g = c.getContext('2d');
    g.fillStyle = '#111';
    g.fillRect(0, 0, c.width, c.height);
    if (!S.run.no_video) {
      const img = imageOf(S.frame, frameKind());
      if (img.complete && img.naturalWidth) g.drawImage(img, 0, 0, c.width, c.height);
      for (let k = 1; k <= 8; k++) if (S.frame + k <= S.last) imageOf(S.frame + k, 'original');
    }
    const dimmed = !inBout(S.frame);
    g.save();
    g.scale(c.width / S.size[0], c.height / S.size[1]);
    const u = S.size[0] / c.width; // image pixels per canvas pixel
    g.lineWidth = 3 * u;
    for (const [a, b] of S.run.skeleton) {
      const p = point(a, S.frame), q = point(b, S.frame);
      if (!p || !q) continue;
      g.strokeStyle = a.startsWith('left_') ? COLOUR.left : a.startsWith('right_') ? COLOUR.right : COLOUR.upper;
      g.globalAlpha = dimmed ? 0.45 : 0.95;
      g.beginPath(); g.moveTo(p.x, p.y); g.lineTo(q.x, q.y); g.stroke();
    }
    const r = 5 * u;
    for (const side of ['left', 'right']) {
      for (const part of LEG) {
        const p = point(`${side}_${part}`, S.frame);
        if (!p) continue;
        g.fillStyle = COLOUR[side];
        g.globalAlpha = 1;
        g.beginPath(); g.arc(p.x, p.y, r, 0, 2 * Math.PI); g.fill();
        g.strokeStyle = '#fff'; g.lineWidth = r / 3; g.stroke();
        if ($('show-raw').checked) {
          const q = rawPoint(`${side}_${part}`, S.frame);
          if (q) { g.strokeStyle = COLOUR[side]; g.beginPath(); g.arc(q.x, q.y, r * 1.6, 0, 2 * Math.PI); g.stroke(); }
        }
      }
    }
    g.restore();
    g.globalAlpha = 1;
    g.font = '600 18px system-ui, sans-serif';
    g.fillStyle = dimmed ? '#ffbf47' : '#fff';
    const label = `frame ${S.frame}` + (frameKind() === 'regenerated' ? ' (regenerated)' : '') +
      (dimmed ? ' - outside the walking bouts' : '');
    const lines = [[label, g.fillStyle]].concat(eventsAt(S.frame).map((e) =>
      [`${e.side === 'left' ? 'L' : 'R'} ${e.event.replace('_', ' ')}`, COLOUR[e.side]]));
    const width = Math.max(...lines.map(([t]) => g.measureText(t).width));
    g.fillStyle = 'rgba(0,0,0,0.6)';
    g.fillRect(6, 6, width + 14, 24 * lines.length + 6);
    lines.forEach(([t, colour], k) => {
      g.fillStyle = k === 0 ? colour : '#fff';
      if (k > 0) { g.fillStyle = colour; g.fillRect(10, 14 + 24 * k, 8, 8); g.fillStyle = '#fff'; }
      g.fillText(t, k === 0 ? 12 : 24, 26 + 24 * k);
    });
    S.drawn = S.frame;
  }

  const eventsAt = (f) => (S.an ? S.an.events.filter((e) => e.frame === f) : []);
  const inBout = (f) => !S.an || S.an.bouts.some((b) => f >= b.first && f <= b.last);

  function canvasPoint(ev) {
    const c = $('frame'), r = c.getBoundingClientRect();
    return { x: (ev.clientX - r.left) / r.width * S.size[0], y: (ev.clientY - r.top) / r.height * S.size[1],
      scale: S.size[0] / r.width };
  }

  // Where keypoint `name` of the current frame is on the screen (for tests and tools).
  S.screenOf = (name) => {
    const q = point(name, S.frame), r = $('frame').getBoundingClientRect();
    return q && { x: r.left + q.x / S.size[0] * r.width, y: r.top + q.y / S.size[1] * r.height };
  };

  function onFrameDown(ev) {
    const p = canvasPoint(ev);
    if (S.pickSubject) { pickSubject(p); return; }
    let best = null;
    for (const side of ['left', 'right']) {
      for (const part of LEG) {
        const name = `${side}_${part}`, q = point(name, S.frame);
        if (!q) continue;
        const d = Math.hypot(q.x - p.x, q.y - p.y) / p.scale;
        if (d <= GRAB_PX && (!best || d < best.d)) best = { name, d };
      }
    }
    if (best && !S.busy) { S.drag = { name: best.name, x: p.x, y: p.y }; drawFrame(); ev.preventDefault(); }
  }

  function onFrameMove(ev) {
    if (!S.drag) return;
    const p = canvasPoint(ev);
    S.drag.x = p.x; S.drag.y = p.y;
    drawFrame();
  }

  function onFrameUp() {
    if (!S.drag) return;
    const d = S.drag, f = S.frame;
    S.drag = null;
    const x = Math.round(d.x * 10) / 10, y = Math.round(d.y * 10) / 10;
    change((doc) => {
      doc.keypoint = doc.keypoint.filter((k) => !(k.frame === f && k.name === d.name));
      doc.keypoint.push({ frame: f, name: d.name, x, y });
    }).then(drawFrame);
  }

  // ---- subject -----------------------------------------------------------------------------
  function drawSubject() {
    const box = $('subject');
    const s = S.run.subject;
    if (!s) { box.textContent = 'No subject pass in this run (one person, or [subject] enabled = false).'; return; }
    const rows = s.tracks.map((t) => `<tr${t.id === s.chosen ? ' class="current"' : ''}><td>${t.id}${t.id === s.chosen ? ' (followed)' : ''}</td>` +
      `<td><a data-frame="${t.first_frame}">${t.first_frame}</a>-<a data-frame="${t.last_frame}">${t.last_frame}</a></td>` +
      `<td>${t.walk.displacement.toFixed(1)} body sizes in ${t.walk.seconds.toFixed(1)} s</td></tr>`).join('');
    box.innerHTML = `<p>${escapeHtml(s.reason)}</p><table><tr><th>track</th><th>frames</th><th>walk</th></tr>${rows}</table>` +
      '<button id="pick-subject">Follow another person…</button> <span id="subject-command" class="hint"></span>';
    $('pick-subject').onclick = () => {
      S.pickSubject = true;
      $('subject-command').textContent = 'Click on the person in the frame.';
    };
  }

  // Another person's poses need the pose model: the page gives the command that runs it.
  function pickSubject(p) {
    S.pickSubject = false;
    const person = `pose.person={ frame = ${S.frame}, x = ${p.x.toFixed(0)}, y = ${p.y.toFixed(0)} }`;
    $('subject-command').textContent = `To follow that person, run: ${S.run.rerun} --set '${person}'` +
      ' (the pose model runs again on their frames; the corrections of this person do not carry over)';
  }

  // ---- lists ---------------------------------------------------------------------------------
  const escapeHtml = (s) => String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
  const frameLink = (f) => `<a data-frame="${f}">${f}</a>`;

  function describe(kind, e) {
    switch (kind) {
      case 'swap': return `swap left/right, frames ${e.first}-${e.last}`;
      case 'exclude': return `exclude frames ${e.first}-${e.last}`;
      case 'event': return `${e.action} ${e.side} ${e.kind.replace('_', ' ')} at frame ${e.frame}`;
      default: return `${e.name} at frame ${e.frame} set to (${e.x}, ${e.y})`;
    }
  }

  function drawLists() {
    const doc = current();
    const items = [];
    for (const kind of ['swap', 'event', 'exclude', 'keypoint']) {
      doc[kind].forEach((e, k) => items.push(`<li>${escapeHtml(describe(kind, e))} ` +
        `<button data-kind="${kind}" data-k="${k}" class="delete">delete</button> ${frameLink(e.frame ?? e.first)}</li>`));
    }
    $('corrections').innerHTML = items.join('') || '<li>none</li>';
    const ev = S.an.events.map((e, k) => `<tr data-frame-row="${e.frame}"><td>${frameLink(e.frame)}</td><td>${e.side}</td>` +
      `<td>${e.event.replace('_', ' ')}</td><td><button data-ev="${k}" class="remove-event">remove</button>` +
      `<button data-ev="${k}" class="move-event">move here</button></td></tr>`).join('');
    $('events').innerHTML = `<table><tr><th>frame</th><th>side</th><th>event</th><th></th></tr>${ev}</table>`;
    const cy = S.an.cycles.map((q) => `<tr class="${q.accepted ? '' : 'rejected'}" data-range="${q.first_frame},${q.last_frame}">` +
      `<td>${q.side}</td><td>${frameLink(q.first_frame)}-${frameLink(q.last_frame)}</td>` +
      `<td>${q.accepted ? 'accepted' : 'rejected: ' + q.reasons.join(', ')}</td></tr>`).join('');
    $('cycles').innerHTML = `<p>accepted: left ${S.an.accepted.left}, right ${S.an.accepted.right}; ` +
      `rejected: left ${S.an.rejected.left}, right ${S.an.rejected.right}</p>` +
      `<table><tr><th>side</th><th>frames</th><th>verdict</th></tr>${cy}</table>`;
    const st = S.an.spatiotemporal.map((p) => `<tr><td>${escapeHtml(p.parameter)}</td><td>${escapeHtml(p.side)}</td>` +
      `<td>${p.mean === null ? '–' : p.mean.toFixed(2)}${p.sd === null || p.n < 2 ? '' : ' ± ' + p.sd.toFixed(2)}</td>` +
      `<td>${escapeHtml(p.unit)}</td><td>${p.n}</td></tr>`).join('');
    $('spatiotemporal').innerHTML = st ? `<table><tr><th>parameter</th><th>side</th><th>mean ± SD</th><th>unit</th><th>n</th></tr>${st}</table>` : 'none';
    $('warnings').innerHTML = S.an.warnings.map((w) => `<li>${escapeHtml(w)}</li>`).join('') || '<li>none</li>';
    drawChecklist();
    markCurrentRows();
  }

  // The items present, each with the cycles where it shows (a row is marked while the current
  // frame is inside one of them) and the frame where it shows most; then what was not judged.
  function drawChecklist() {
    const fmt = (x) => (x === null || x === undefined ? '–' : Number(x).toFixed(1));
    const cycleOf = (side, first) => S.an.cycles.find((q) => q.side === side && q.first_frame === first);
    const rows = S.an.checklist.filter((v) => v.status === 'present').map((v) => {
      const ranges = v.cycles.map((f) => { const q = cycleOf(v.side, f); return q ? `${q.first_frame}-${q.last_frame}` : `${f}-${f}`; });
      const spread = v.spread === null || v.n < 2 ? '' : ` ± ${fmt(v.spread)}`;
      return `<tr data-ranges="${ranges.join(';')}"><td>${escapeHtml(v.item.name)}</td><td>${v.side}</td>` +
        `<td>${fmt(v.value)}${spread} ${escapeHtml(v.unit)} (${v.beyond} ${fmt(v.threshold)} ${escapeHtml(v.threshold_unit)}), n = ${v.n}</td>` +
        `<td>${v.frames.map(frameLink).join(', ') || '–'}</td></tr>`;
    }).join('');
    const count = (status) => S.an.checklist.filter((v) => v.status === status).length;
    const absent = count('absent'), unjudged = count('not_assessable');
    $('checklist').innerHTML = (rows
      ? `<table><tr><th>present</th><th>side</th><th>measure (threshold)</th><th>frames</th></tr>${rows}</table>`
      : '<p>no deviation present</p>') +
      `<p class="hint">absent: ${absent} item-sides; not assessable here: ${unjudged} (the view or keypoints they need)</p>`;
  }

  function markCurrentRows() {
    document.querySelectorAll('[data-frame-row]').forEach((tr) =>
      tr.classList.toggle('current', Number(tr.dataset.frameRow) === S.frame));
    document.querySelectorAll('[data-ranges]').forEach((tr) =>
      tr.classList.toggle('current', tr.dataset.ranges.split(';').some((r) => {
        const [a, b] = r.split('-').map(Number);
        return S.frame >= a && S.frame <= b;
      })));
  }

  function removeEvent(e) {
    return (doc) => {
      const k = doc.event.findIndex((x) => x.action === 'add' && x.side === e.side && x.kind === e.event && x.frame === e.frame);
      if (k >= 0) doc.event.splice(k, 1);
      else doc.event.push({ side: e.side, kind: e.event, frame: e.frame, action: 'remove' });
    };
  }

  function addEvent(side, kind, f) {
    return (doc) => {
      const k = doc.event.findIndex((x) => x.action === 'remove' && x.side === side && x.kind === kind && x.frame === f);
      if (k >= 0) doc.event.splice(k, 1);
      else doc.event.push({ side, kind, frame: f, action: 'add' });
    };
  }

  // ---- plots ---------------------------------------------------------------------------------
  function plotSeries(id) {
    const an = S.an, out = [];
    if (id === 'plot-keypoints' || id === 'plot-keypoints-y') {
      const axis = id === 'plot-keypoints' ? 0 : 1;
      for (const side of ['left', 'right']) {
        for (const part of LEG) {
          const s = an.filtered[`${side}_${part}`];
          if (s) out.push({ v: s[axis], colour: COLOUR[side], alpha: part === 'ankle' ? 1 : 0.45 });
        }
      }
      return out;
    }
    const joint = id.replace('plot-', '');
    for (const side of ['left', 'right']) out.push({ v: an.angles[`${side}_${joint}`], colour: COLOUR[side], alpha: 1 });
    return out;
  }

  const xOf = (c, f) => 40 + (f - S.first) / Math.max(1, S.last - S.first) * (c.width - 50);
  const frameOfX = (c, x) => S.first + (x - 40) / (c.width - 50) * Math.max(1, S.last - S.first);

  function shade(g, c, first, last, colour) {
    const a = xOf(c, first - 0.5), b = xOf(c, last + 0.5);
    g.fillStyle = colour;
    g.fillRect(a, 0, b - a, c.height - 14);
  }

  function drawPlot(c) {
    const ratio = window.devicePixelRatio || 1;
    const w = Math.round(c.clientWidth * ratio), h = Math.round(c.clientHeight * ratio);
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    const g = c.getContext('2d');
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.clearRect(0, 0, c.width, c.height);
    g.scale(ratio, ratio);
    const cw = { width: c.width / ratio, height: c.height / ratio };
    const doc = current();
    for (const b of S.an.bouts) shade(g, cw, b.first, b.last, 'rgba(60,160,80,0.16)');
    for (const q of S.an.cycles) if (!q.accepted) shade(g, cw, q.first_frame, q.last_frame, 'rgba(220,60,40,0.18)');
    for (const r of doc.exclude) shade(g, cw, r.first, r.last, 'rgba(90,90,90,0.25)');
    for (const r of doc.swap) shade(g, cw, r.first, r.last, 'rgba(140,70,200,0.22)');
    const series = plotSeries(c.id);
    let lo = Infinity, hi = -Infinity;
    for (const s of series) for (const v of s.v) if (v !== null) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (!(hi > lo)) { lo = (isFinite(lo) ? lo : 0) - 1; hi = lo + 2; }
    const pad = (hi - lo) * 0.06, top = 16, bottom = cw.height - 16;
    const yOf = (v) => bottom - (v - lo + pad) / (hi - lo + 2 * pad) * (bottom - top);
    g.lineWidth = 1.4;
    for (const s of series) {
      g.strokeStyle = s.colour; g.globalAlpha = s.alpha; g.beginPath();
      let pen = false;
      s.v.forEach((v, i) => {
        if (v === null) { pen = false; return; }
        const x = xOf(cw, S.an.first_frame + i), y = yOf(v);
        pen ? g.lineTo(x, y) : g.moveTo(x, y);
        pen = true;
      });
      g.stroke();
    }
    g.globalAlpha = 1;
    for (const e of S.an.events) {
      const x = xOf(cw, e.frame);
      g.strokeStyle = COLOUR[e.side];
      g.setLineDash(e.event === 'toe_off' ? [4, 3] : []);
      g.beginPath(); g.moveTo(x, top); g.lineTo(x, bottom); g.stroke();
    }
    g.setLineDash([]);
    const cx = xOf(cw, S.frame);
    g.strokeStyle = '#000'; g.lineWidth = 1.5;
    g.beginPath(); g.moveTo(cx, 0); g.lineTo(cx, cw.height - 14); g.stroke();
    g.fillStyle = '#333'; g.font = '12px system-ui, sans-serif';
    g.fillText(c.dataset.title, 44, 12);
    g.fillText(hi.toFixed(0), 2, top + 4);
    g.fillText(lo.toFixed(0), 2, bottom);
    g.fillText(String(S.first), 40, cw.height - 2);
    const lastLabel = String(S.last);
    g.fillText(lastLabel, cw.width - 10 - g.measureText(lastLabel).width, cw.height - 2);
  }

  // A front or back view has frontal measures instead of sagittal angles: its plots are shown.
  function drawPlots() {
    if (!S.an) return;
    const frontal = S.an.view !== 'sagittal';
    for (const joint of JOINTS) $(`plot-${joint}`).style.display = frontal ? 'none' : '';
    document.querySelectorAll('canvas.plot.frontal').forEach((c) => { c.style.display = frontal ? '' : 'none'; });
    document.querySelectorAll('canvas.plot').forEach((c) => { if (c.style.display !== 'none') drawPlot(c); });
  }

  function drawAll() {
    drawFrame();
    drawPlots();
    drawLists();
  }

  // ---- playback ------------------------------------------------------------------------------
  function play() {
    S.playing = !S.playing;
    $('play').textContent = S.playing ? 'Pause' : 'Play';
    if (!S.playing) return;
    const start = performance.now(), from = S.frame >= S.last ? S.first : S.frame;
    const tick = (now) => {
      if (!S.playing) return;
      const f = from + Math.floor((now - start) / 1000 * S.run.fps);
      if (f > S.last) { play(); return; }
      if (f !== S.frame) setFrame(f);
      requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  }

  // ---- wiring --------------------------------------------------------------------------------
  function rangeOf() {
    let a = Number($('range-first').value), b = Number($('range-last').value);
    if (!Number.isFinite(a) || $('range-first').value === '') a = S.frame;
    if (!Number.isFinite(b) || $('range-last').value === '') b = a;
    return { first: Math.min(a, b), last: Math.max(a, b) };
  }

  function wire() {
    $('scrubber').oninput = (e) => setFrame(Number(e.target.value));
    $('prev').onclick = () => setFrame(S.frame - 1);
    $('next').onclick = () => setFrame(S.frame + 1);
    $('play').onclick = play;
    $('undo').onclick = undo;
    $('redo').onclick = redo;
    $('show-regenerated').onchange = drawFrame;
    $('show-raw').onchange = drawFrame;
    $('swap').onclick = () => { const r = rangeOf(); change((d) => d.swap.push(r)); };
    $('exclude').onclick = () => { const r = rangeOf(); change((d) => d.exclude.push(r)); };
    document.querySelectorAll('.add-event').forEach((b) => {
      b.onclick = () => change(addEvent(b.dataset.side, b.dataset.kind, S.frame));
    });
    document.body.addEventListener('click', (ev) => {
      const t = ev.target;
      if (t.dataset.frame !== undefined) setFrame(Number(t.dataset.frame));
      else if (t.classList.contains('delete')) change((d) => d[t.dataset.kind].splice(Number(t.dataset.k), 1));
      else if (t.classList.contains('remove-event')) change(removeEvent(S.an.events[Number(t.dataset.ev)]));
      else if (t.classList.contains('move-event')) {
        const e = S.an.events[Number(t.dataset.ev)];
        if (e.frame !== S.frame) change((d) => { removeEvent(e)(d); addEvent(e.side, e.event, S.frame)(d); });
      }
    });
    document.querySelectorAll('canvas.plot').forEach((c) => {
      c.onclick = (ev) => {
        const r = c.getBoundingClientRect();
        setFrame(frameOfX({ width: r.width }, ev.clientX - r.left));
      };
    });
    const canvas = $('frame');
    canvas.onmousedown = onFrameDown;
    window.addEventListener('mousemove', onFrameMove);
    window.addEventListener('mouseup', onFrameUp);
    window.addEventListener('resize', drawPlots);
    window.addEventListener('keydown', (ev) => {
      if (ev.target.tagName === 'INPUT' && ev.target.type === 'number') return;
      const step = ev.shiftKey ? 10 : 1;
      if ((ev.ctrlKey || ev.metaKey) && ev.key.toLowerCase() === 'z') { ev.shiftKey ? redo() : undo(); }
      else if ((ev.ctrlKey || ev.metaKey) && ev.key.toLowerCase() === 'y') redo();
      else if (ev.key === 'ArrowRight') setFrame(S.frame + step);
      else if (ev.key === 'ArrowLeft') setFrame(S.frame - step);
      else if (ev.key === 'Home') setFrame(S.first);
      else if (ev.key === 'End') setFrame(S.last);
      else if (ev.key === ' ') play();
      else if (ev.key === '[') $('range-first').value = S.frame;
      else if (ev.key === ']') $('range-last').value = S.frame;
      else return;
      ev.preventDefault();
    });
  }

  async function start() {
    S.run = await getJson('/api/run');
    S.an = await getJson('/api/analysis');
    S.run.frames.forEach((f, i) => S.index.set(f, i));
    S.first = S.run.frames.length ? Math.min(...S.run.frames) : 0;
    S.last = S.run.frames.length ? Math.max(...S.run.frames) : 0;
    S.size = S.run.frame_size || [960, 540];
    const c = $('frame');
    c.width = Math.min(S.size[0], 1280);
    c.height = Math.round(c.width * S.size[1] / S.size[0]);
    S.history = [normal(S.an.corrections)];
    S.at = 0;
    document.title = `gait review: ${S.run.title}`;
    $('title').textContent = `gait review: ${S.run.title}`;
    $('saved-path').textContent = `(${S.run.corrections_path})`;
    $('rerun').textContent = `The run's files (angles.csv, report.html, …) are written again with these corrections by: ${S.run.rerun}`;
    if (S.run.no_video) { $('no-video').hidden = false; $('no-video').textContent = S.run.no_video; }
    $('show-regenerated').disabled = !S.run.regenerated.length;
    $('show-regenerated').checked = S.run.regenerated.length > 0;
    const sc = $('scrubber');
    sc.min = S.first; sc.max = S.last;
    drawSubject();
    wire();
    // `gait review RUN --frame N` (a checklist's frame) opens at that frame.
    const asked = Number(new URLSearchParams(location.search).get('frame'));
    setFrame(Number.isFinite(asked) && asked > 0 ? asked : (S.an.bouts.length ? S.an.bouts[0].first : S.first));
    drawLists();
    updateUndo();
    setStatus(`${S.run.frames.length} frames; corrections are saved to ${S.run.corrections_path} after each change`, 'ok');
  }

  S.ready = start().catch((e) => { setStatus('could not load the run: ' + e.message, 'error'); throw e; });
})();
