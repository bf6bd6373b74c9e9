// A checklist finding followed from the report into `gait review`, in Debian's headless
// Chromium: the page is opened once at the URL `gait review` printed (as --open does), then
// the report's frame link, which carries no token, is followed.
// Called by tests/review.rs:  node link.cjs PRINTED_URL REPORT_LINK OUT_JSON
'use strict';
const fs = require('fs');
const puppeteer = require('puppeteer-core');

const [printed, link, outJson] = process.argv.slice(2);

async function main() {
  const browser = await puppeteer.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync'],
  });
  const problems = [];
  try {
    const page = await browser.newPage();
    page.on('pageerror', (e) => problems.push(String(e)));
    const loaded = async () => {
      await page.evaluate(() => window.gaitReview.ready);
      await page.waitForFunction(() => { const S = window.gaitReview; return S.drawn === S.frame; });
    };
    await page.goto(printed, { waitUntil: 'load' });
    await loaded();
    const opened = await page.evaluate(() => window.gaitReview.frame);
    // The report is another page (a file); its link opens in a new tab.
    const tab = await browser.newPage();
    tab.on('pageerror', (e) => problems.push(String(e)));
    await tab.goto(link, { waitUntil: 'load' });
    await tab.evaluate(() => window.gaitReview.ready);
    await tab.waitForFunction(() => { const S = window.gaitReview; return S.drawn === S.frame; });
    const shown = await tab.evaluate(() => ({
      frame: window.gaitReview.frame,
      marked: [...document.querySelectorAll('#checklist tr.current')].map((tr) => tr.textContent),
      url: location.href,
    }));
    fs.writeFileSync(outJson, JSON.stringify({ opened, ...shown, problems }));
  } finally {
    await browser.close();
  }
}

main().catch((e) => { console.error(`link test: ${e.message}`); process.exit(1); });
