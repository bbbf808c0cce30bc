// ctest web.browser: the WebAssembly page (build-web/site, scripts/web) in Debian's headless
// Chromium. Loads the page from a server of its own on 127.0.0.1, drags the
// free manipulator up (it must follow the mouse), clicks Strike, lets it run,
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

const SHOT_SECONDS = 0.13;  // the picture: the manipulator hits the ball at ~0.1 s
const SIM_SECONDS = 0.6;   // simulated time of the physics checks

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
  const canvasPixels = () => page.evaluate(() => {
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
  const com = async () => (await text('fig-com')).trim().split(/\s+/).map(Number);

  // Dragging the free manipulator of the start scene moves it with the mouse.
  const canvasBox = await page.$eval('#view', (c) => { const r = c.getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; });
  const [mx, my] = await page.evaluate(([w, h]) => Array.from(window.gradel.demo.manipulatorPixel(0, w, h)), canvasBox.slice(2));
  const before = await page.evaluate(() => Array.from(window.gradel.demo.manipulatorPosition(0)));
  await page.mouse.move(canvasBox[0] + mx, canvasBox[1] + my);
  await page.mouse.down();
  for (let k = 1; k <= 10; ++k) {
    await page.mouse.move(canvasBox[0] + mx, canvasBox[1] + my - 8 * k);  // straight up the screen
    await page.waitForTimeout(30);
  }
  const held = await page.evaluate(() => window.gradel.demo.dragging());
  await page.mouse.up();
  await page.waitForTimeout(200);
  const after = await page.evaluate(() => Array.from(window.gradel.demo.manipulatorPosition(0)));
  console.log(`drag: manipulator ${before.map((v) => v.toFixed(3)).join(' ')} -> ${after.map((v) => v.toFixed(3)).join(' ')}`);
  assert.ok(held, 'the mouse did not grab the manipulator');
  assert.ok(after[1] - before[1] > 0.02, 'dragging the manipulator up the screen did not lift it');

  // Strike, paused at t = 0 to read where the ball starts; then run.
  await page.click('#pause');
  await page.click('#strike');
  await page.waitForFunction(() => document.getElementById('fig-time').textContent.startsWith('0.000'), null, { timeout: 30000 });
  await page.waitForTimeout(400);  // one more figure update of the paused scene
  const start = await com();
  await page.click('#pause');
  // The picture: paused just after the hit, the ball dented and stressed at the contact.
  const untilTime = (t) => page.waitForFunction((t) => window.gradel.demo.time() >= t, t,
                                                { timeout: 120000, polling: 'raf' });
  await page.waitForFunction((t) => {  // pauses in the same frame it sees the time
    if (window.gradel.demo.time() < t) return false;
    document.getElementById('pause').click();
    return true;
  }, SHOT_SECONDS, { timeout: 120000, polling: 'raf' });
  await page.waitForTimeout(400);
  const shot = await page.screenshot(screenshot ? { path: screenshot } : {});
  if (screenshot) console.log(`screenshot: ${screenshot} (t = ${await simTime()} s)`);
  const pixels = await canvasPixels();
  await page.click('#pause');
  await untilTime(SIM_SECONDS);
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

  // The canvas showed the body: many pixels off the background, and warm (body / stress) ones.
  console.log('canvas pixels:', JSON.stringify(pixels));
  assert.ok(pixels.off > 0.02 * pixels.total, 'the canvas is (nearly) all background');
  assert.ok(pixels.warm > 500, 'no body-coloured pixels on the canvas');
  assert.ok(shot.length > 10000, 'no screenshot');

  assert.deepEqual(errors, [], 'errors on the page');
  console.log('web.browser: ok');
} finally {
  await close();
  await srv.close();
}
