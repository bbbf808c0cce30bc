// The speed of the WebAssembly build in headless Chromium: the page's benchmark mode (?bench=1)
// measures the paper's Table 1 setting as gradel-bench does, for gradational spheres; prints
// gradel-bench's CSV. Compare with `build/gradel-bench --shapes sphere --sizes 12,32
// --layouts gradational --threads 1` on the same machine.
//   node bench.mjs SITE_DIR [--sizes 12,32] [--reps 5] [--min-time 0.2]
import { serve, launch } from './browser.mjs';

const arg = (name, dflt) => { const i = process.argv.indexOf(name); return i > 0 ? process.argv[i + 1] : dflt; };
const srv = await serve(process.argv[2]);
const { browser, close } = await launch();
try {
  const page = await browser.newPage();
  const query = new URLSearchParams({ bench: '1', sizes: arg('--sizes', '12,32'), reps: arg('--reps', '5'), min_time: arg('--min-time', '0.2') });
  await page.goto(`${srv.url}?${query}`);
  await page.waitForSelector('body[data-bench="done"]', { timeout: 600000 });
  process.stdout.write(await page.$eval('#bench', (e) => e.textContent));
} finally {
  await close();
  await srv.close();
}
