// Drives `gait review` in Debian's headless Chromium over the DevTools protocol (puppeteer-core),
// as a person would: keys, buttons, a drag on the frame, undo/redo, a refused edit, a reload.
// Called by tests/review.rs:  node browser.cjs URL OUT_DIR PLAN_JSON
// Writes OUT_DIR/result.json (what the page shows after the reload, and timings) and
// OUT_DIR/review.png. Exits non-zero with a message when a step does not do what it should.
'use strict';
const fs = require('fs');
const path = require('path');
const puppeteer = require('puppeteer-core');

const [url, outDir, planJson] = process.argv.slice(2);
const plan = JSON.parse(planJson);
const origin = new URL(url).origin;

function check(ok, what) {
  if (!ok) throw new Error(what);
}

const median = (v) => { const s = [...v].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };

async function main() {
  const browser = await puppeteer.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync'],
    defaultViewport: { width: 1600, height: 1300 },
  });
  const problems = [];
  const offsite = [];
  try {
    const page = await browser.newPage();
    page.on('pageerror', (e) => problems.push(String(e)));
    // The one refused edit below answers 400, which Chromium logs; anything else is a fault.
    let refused = 0;
    page.on('console', (m) => {
      if (m.type() !== 'error') return;
      if (m.text().includes('status of 400')) refused += 1;
      else problems.push(m.text());
    });
    page.on('request', (r) => { if (!r.url().startsWith(origin) && !r.url().startsWith('data:')) offsite.push(r.url()); });
    const state = (f) => page.evaluate(f);
    const idle = () => page.waitForFunction(() => !window.gaitReview.busy, { timeout: 60000 });
    const load = async () => {
      await page.evaluate(() => window.gaitReview.ready);
      await page.waitForFunction(() => { const S = window.gaitReview; return S.drawn === S.frame; });
    };

    await page.goto(url, { waitUntil: 'load' });
    await load();
    const timings = { recompute_ms: [], server_ms: [] };
    const recorded = async () => {
      const t = await state(() => [window.gaitReview.lastRecomputeMs, window.gaitReview.an.seconds * 1000]);
      timings.recompute_ms.push(t[0]);
      timings.server_ms.push(t[1]);
    };

    // Step to a frame with the arrow keys; the frame drawn must follow.
    const stepTo = async (target) => {
      for (;;) {
        const f = await state(() => window.gaitReview.frame);
        if (f === target) break;
        const d = target - f;
        const key = d > 0 ? 'ArrowRight' : 'ArrowLeft';
        if (Math.abs(d) >= 10) { await page.keyboard.down('Shift'); await page.keyboard.press(key); await page.keyboard.up('Shift'); }
        else await page.keyboard.press(key);
      }
      await page.waitForFunction((t) => window.gaitReview.drawn === t, {}, target);
      const label = await page.$eval('#frame-label', (e) => e.textContent);
      check(label.startsWith(`frame ${target} `), `the frame label says "${label}" at frame ${target}`);
    };
    await stepTo(plan.step_to);

    // Frame images: a first request may wait for the background decoder; asked again, a frame
    // comes from memory.
    const timeFrames = (frames) => page.evaluate(async (frames) => {
      const token = new URLSearchParams(location.search).get('token');
      const out = [];
      for (const f of frames) {
        const t0 = performance.now();
        const r = await fetch(`/api/frame/${f}?token=${token}`, { cache: 'no-store' });
        await r.arrayBuffer();
        if (!r.ok) throw new Error(`frame ${f}: ${r.status}`);
        out.push(performance.now() - t0);
      }
      return out;
    }, frames);
    timings.first_frame_ms = await timeFrames(plan.frames_to_time);
    timings.frame_ms = await timeFrames(plan.frames_to_time);

    // Swap a range: typed in, then the button.
    const typeRange = async (a, b) => {
      await page.click('#range-first', { clickCount: 3 });
      await page.type('#range-first', String(a));
      await page.click('#range-last', { clickCount: 3 });
      await page.type('#range-last', String(b));
    };
    await typeRange(plan.swap[0], plan.swap[1]);
    await page.click('#swap');
    await idle();
    check(!(await state(() => window.gaitReview.error)), 'the swap was refused');
    await recorded();

    // Add an event at a frame.
    await stepTo(plan.event.frame);
    await page.click(plan.event.button);
    await idle();
    check(!(await state(() => window.gaitReview.error)), 'the event was refused');
    await recorded();
    const added = await state(() => window.gaitReview.an.events.map((e) => `${e.side},${e.event},${e.frame}`));
    check(added.includes(plan.event.expect), `no ${plan.event.expect} among the events after adding it`);

    // Drag a keypoint on the frame, then undo and redo it.
    await stepTo(plan.drag.frame);
    const at = await page.evaluate((n) => window.gaitReview.screenOf(n), plan.drag.name);
    check(at, `no ${plan.drag.name} drawn at frame ${plan.drag.frame}`);
    await page.mouse.move(at.x, at.y);
    await page.mouse.down();
    await page.mouse.move(at.x + plan.drag.dx / 2, at.y + plan.drag.dy / 2, { steps: 4 });
    await page.mouse.move(at.x + plan.drag.dx, at.y + plan.drag.dy, { steps: 4 });
    await page.mouse.up();
    await idle();
    await recorded();
    const kps = () => state(() => window.gaitReview.an.corrections.keypoint || []);
    check((await kps()).length === 1, 'the drag saved no [[keypoint]]');
    const dragged = (await kps())[0];
    await page.keyboard.down('Control'); await page.keyboard.press('z'); await page.keyboard.up('Control');
    await idle();
    check((await kps()).length === 0, 'undo left the [[keypoint]]');
    await page.keyboard.down('Control'); await page.keyboard.press('y'); await page.keyboard.up('Control');
    await idle();
    check((await kps()).length === 1, 'redo did not bring the [[keypoint]] back');

    // An overlapping swap is refused with the entry named, and nothing is saved.
    const before = await state(() => JSON.stringify(window.gaitReview.an.corrections));
    await typeRange(plan.bad_swap[0], plan.bad_swap[1]);
    await page.click('#swap');
    await idle();
    const status = await page.$eval('#status', (e) => [e.textContent, e.className]);
    check(status[1] === 'error' && status[0].includes('overlaps'), `an overlapping swap gave "${status[0]}"`);
    const server = await page.evaluate(async () => {
      const token = new URLSearchParams(location.search).get('token');
      return JSON.stringify((await (await fetch(`/api/analysis?token=${token}`)).json()).corrections);
    });
    check(server === before, 'the refused swap changed the saved corrections');

    await page.screenshot({ path: path.join(outDir, 'review.png') });

    // Reload: the page comes back with the saved corrections and their analysis.
    await page.reload({ waitUntil: 'load' });
    await load();
    const after = await state(() => {
      const S = window.gaitReview;
      return { corrections: S.history[0], first_frame: S.an.first_frame, angles: S.an.angles,
        events: S.an.events, undo_disabled: document.getElementById('undo').disabled,
        checklist: S.an.checklist.map((v) => [v.item.id, v.side, v.status]),
        checklist_panel: document.getElementById('checklist').textContent };
    });
    check(after.undo_disabled, 'undo is offered right after a reload');
    const result = { ...after, dragged, timings, problems, offsite,
      frame_ms_median: median(timings.frame_ms), first_frame_ms_median: median(timings.first_frame_ms), recompute_ms_median: median(timings.recompute_ms) };
    fs.writeFileSync(path.join(outDir, 'result.json'), JSON.stringify(result));
    check(refused === 1, `${refused} requests refused, expected the one overlapping swap`);
    check(problems.length === 0, `the page reported errors: ${problems.join(' | ')}`);
    check(offsite.length === 0, `the page asked for other addresses: ${offsite.join(' ')}`);
  } finally {
    await browser.close();
  }
}

main().catch((e) => { console.error(`browser test: ${e.message}`); process.exit(1); });
