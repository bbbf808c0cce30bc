// ctest web.browser: the WebAssembly page (build-web/site, scripts/web) in Debian's headless
// Chromium. Loads the page from a server of its own on 127.0.0.1, clicks Strike, lets it run,
// reads the live figures from the page and checks that the struck ball moved away from the
// manipulator (+x) and stayed finite, that the canvas shows the body (WebGL2 drawing), and saves
// a screenshot. Fails (never skips) when the page, the browser or WebGL2 is missing.
//   node browser_test.mjs SITE_DIR [--screenshot FILE]
import assert from 'node:assert/strict';
import { serve, launch } from './browser.mjs';

const site = process.argv[2];
const shotIndex = process.argv.indexOf('--screenshot');
const screenshot = shotIndex > 0 ? process.argv[shotIndex + 1] : null;
assert.ok(site, 'usage: node browser_test.mjs SITE_DIR [--screenshot FILE]');

const SIM_SECONDS = 0.6;  // simulated time after the strike (the manipulator hits at ~0.1 s)

const srv = await serve(site);
const { browser, close } = await launch();
const errors = [];
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 720 } });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.goto(srv.url);
  await page.waitForSelector('body[data-ready="1"]', { timeout: 60000 });
  const gl = await page.evaluate(() => {
    const c = document.createElement('canvas').getContext('webgl2');
    return c ? c.getParameter(c.VERSION) : null;
  });
  assert.ok(gl, 'no WebGL2 in this Chromium (SwiftShader missing?)');
  console.log(`WebGL: ${gl}`);

  const text = (id) => page.$eval('#' + id, (e) => e.textContent);
  const simTime = async () => parseFloat(await text('fig-time'));
  const com = async () => (await text('fig-com')).trim().split(/\s+/).map(Number);

  // Strike, paused at t = 0 to read where the ball starts; then run.
  await page.click('#pause');
  await page.click('#strike');
  await page.waitForFunction(() => document.getElementById('fig-time').textContent.startsWith('0.000'), null, { timeout: 30000 });
  await page.waitForTimeout(400);  // one more figure update of the paused scene
  const start = await com();
  await page.click('#pause');
  await page.waitForFunction((t) => parseFloat(document.getElementById('fig-time').textContent) >= t, SIM_SECONDS,
                             { timeout: 120000, polling: 200 });
  await page.waitForTimeout(300);
  const figures = {};
  for (const id of ['steps', 'rtf', 'fps', 'elements', 'vertices', 'time', 'stress', 'com']) figures[id] = await text('fig-' + id);
  console.log('figures:', JSON.stringify(figures));
  const end = await com();
  console.log(`centre of mass: start ${start.join(' ')}, end ${end.join(' ')} (t = ${await simTime()} s)`);

  // Physics: the strike comes from -x and sends the ball towards +x; nothing blew up.
  assert.ok(start.length === 3 && end.length === 3 && [...start, ...end].every(Number.isFinite), 'centre of mass not finite');
  assert.ok(end[0] - start[0] > 0.02, `the ball did not move away from the manipulator: dx = ${end[0] - start[0]} m`);
  assert.ok(Math.abs(end[1] - start[1]) < 0.05 && Math.abs(end[2] - start[2]) < 0.05, 'the ball left the strike line');
  assert.equal(await page.evaluate(() => window.gradel.demo.finite()), true, 'positions not finite');
  assert.equal(Number(figures.elements), 123, 'the paper\'s 12^3 sphere has 123 elements (gradational)');
  assert.equal(Number(figures.vertices), 826);
  assert.ok(Number(figures.steps) > 0 && Number(figures.rtf) > 0, 'no simulation steps reported');
  assert.ok(Number.isFinite(parseFloat(figures.stress)) && parseFloat(figures.stress) > 0, 'no stress after the strike');

  // The canvas shows the body: many pixels off the background, and warm (body / stress) ones.
  const pixels = await page.evaluate(() => {
    const src = document.getElementById('view'), c = document.createElement('canvas');
    c.width = src.width, c.height = src.height;
    const g = c.getContext('2d');
    g.drawImage(src, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let off = 0, warm = 0;
    const bg = [237, 240, 245];
    for (let i = 0; i < d.length; i += 4) {
      if (Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]) > 40) ++off;
      if (d[i] - d[i + 2] > 25) ++warm;
    }
    return { total: d.length / 4, off, warm };
  });
  console.log('canvas pixels:', JSON.stringify(pixels));
  assert.ok(pixels.off > 0.02 * pixels.total, 'the canvas is (nearly) all background');
  assert.ok(pixels.warm > 500, 'no body-coloured pixels on the canvas');

  if (screenshot) {
    await page.screenshot({ path: screenshot });
    console.log(`screenshot: ${screenshot}`);
  }
  assert.deepEqual(errors, [], 'errors on the page');
  console.log('web.browser: ok');
} finally {
  await close();
  await srv.close();
}
