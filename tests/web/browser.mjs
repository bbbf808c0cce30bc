// Shared by the browser test and the benchmark: a static server for the built page (build-web/site)
// on 127.0.0.1, and Debian's Chromium launched headless through playwright-core.
import { createServer } from 'node:http';
import { readFile, stat } from 'node:fs/promises';
import { existsSync } from 'node:fs';
import path from 'node:path';
import { chromium } from 'playwright-core';

const TYPES = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css', '.json': 'application/json',
                '.wasm': 'application/wasm', '.png': 'image/png' };

/// Serves `root` on 127.0.0.1 at a free port; returns { url, close }.
export async function serve(root) {
  for (const f of ['index.html', 'gradel.js', 'gradel.wasm'])
    if (!existsSync(path.join(root, f))) throw new Error(`${path.join(root, f)} is missing: build the page first (scripts/web)`);
  const server = createServer(async (req, res) => {
    const rel = decodeURIComponent(new URL(req.url, 'http://x').pathname).replace(/^\/+/, '') || 'index.html';
    const file = path.resolve(root, rel);
    try {
      if (!file.startsWith(path.resolve(root)) || !(await stat(file)).isFile()) throw new Error('not found');
      res.writeHead(200, { 'Content-Type': TYPES[path.extname(file)] || 'application/octet-stream' });
      res.end(await readFile(file));
    } catch {
      res.writeHead(404);
      res.end();
    }
  });
  await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
  return { url: `http://127.0.0.1:${server.address().port}/`, close: () => new Promise((ok) => server.close(ok)) };
}

/// Headless Chromium (GRADEL_CHROMIUM, default /usr/bin/chromium); playwright gives it a fresh
/// temporary profile (--user-data-dir) each time. WebGL2 through ANGLE's SwiftShader (software),
/// so no GPU is needed. Returns { browser, close }.
export async function launch() {
  const executablePath = process.env.GRADEL_CHROMIUM || '/usr/bin/chromium';
  if (!existsSync(executablePath)) throw new Error(`${executablePath} not found (apt-get install chromium; scripts/packages/web.txt)`);
  const browser = await chromium.launch({
    executablePath,
    headless: true,
    args: ['--no-sandbox', '--disable-quic', '--no-first-run', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'].concat(process.env.GRADEL_CHROMIUM_ARGS ? process.env.GRADEL_CHROMIUM_ARGS.split(' ') : []),
  });
  return { browser, close: () => browser.close() };
}
