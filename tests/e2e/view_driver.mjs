// Drives the browser viewer for tests and benchmarks: starts `mebake view DIR --port 0`,
// opens the page in headless Chromium (the system's, through playwright-core; WebGL2 by
// SwiftShader, i.e. software), waits until every chunk is drawn, saves screenshots of the
// given views and prints timings as JSON, then stops the server with SIGINT and checks
// that it exits 0.
//
//   node view_driver.mjs --node-modules DIR --mebake BIN --dir BAKE --size WxH
//        [--shot out.png=QUERY]... [--frames N] [--chromium PATH] [--extra "view args"]
// QUERY is the page's URL query (eye=..&target=..&mode=..; see web/viewer.js).
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import path from 'node:path';

function parseArgs(argv) {
  const a = { shots: [], frames: 0, chromium: '/usr/bin/chromium', extra: '' };
  for (let i = 0; i < argv.length; i += 2) {
    const k = argv[i].replace(/^--/, ''), v = argv[i + 1];
    if (k === 'shot') {
      const eq = v.indexOf('=');
      a.shots.push({ file: v.slice(0, eq), query: v.slice(eq + 1) });
    } else a[k.replace(/-(.)/g, (_, c) => c.toUpperCase())] = v;
  }
  return a;
}

const args = parseArgs(process.argv.slice(2));
const require = createRequire(path.join(path.resolve(args.nodeModules), 'x.js'));
const { chromium } = require('playwright-core');
const [width, height] = args.size.split('x').map(Number);

function startServer() {
  const extra = args.extra ? args.extra.split(' ') : [];
  const child = spawn(args.mebake, ['view', args.dir, '--port', '0', ...extra],
                      { stdio: ['ignore', 'pipe', 'inherit'] });
  return new Promise((resolve, reject) => {
    let out = '';
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/http:\/\/127\.0\.0\.1:(\d+)\//);
      if (m) resolve({ child, url: m[0] });
    });
    child.on('exit', (code) => reject(new Error(`mebake view exited with ${code} before serving`)));
  });
}

function stopServer(child) {
  return new Promise((resolve) => {
    child.removeAllListeners('exit');
    child.on('exit', (code, signal) => resolve({ code, signal }));
    child.kill('SIGINT');
  });
}

const t0 = Date.now();
const { child, url } = await startServer();
const serverMs = Date.now() - t0;
const browser = await chromium.launch({
  executablePath: args.chromium,
  headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
         '--ignore-gpu-blocklist'],
});
const result = { url, serverMs, shots: [] };
try {
  const page = await browser.newPage({ viewport: { width, height }, deviceScaleFactor: 1 });
  const logs = [];
  page.on('console', (m) => logs.push(`${m.type()}: ${m.text()}`));
  page.on('pageerror', (e) => logs.push(`pageerror: ${e.message}`));
  for (const shot of args.shots) {
    await page.goto(`${url}?${shot.query.includes("ui=") ? "" : "ui=0&"}${shot.query}`);
    await page.waitForFunction(
      () => window.mebakeView && (window.mebakeView.readyMs !== null || window.mebakeView.error),
      null, { timeout: 120000, polling: 100 });
    const st = await page.evaluate(() => ({ ...window.mebakeView }));
    if (st.error) throw new Error(`page: ${st.error}\n${logs.join('\n')}`);
    const info = { file: shot.file, moduleMs: st.moduleMs, lightMapMs: st.lightMapMs, mapsMs: st.mapsMs, firstFrameMs: st.firstFrameMs, readyMs: st.readyMs };
    if (Number(args.frames) > 0)
      info.frameMs = await page.evaluate((n) => window.mebakeView.measureFrameTime(n), Number(args.frames));
    await page.screenshot({ path: shot.file });
    result.shots.push(info);
  }
  result.renderer = await page.evaluate(() => {
    const gl = document.querySelector('canvas').getContext('webgl2');
    const ext = gl.getExtension('WEBGL_debug_renderer_info');
    return ext ? gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
  });
  result.console = logs.filter((l) => !l.startsWith('log:') && !l.includes('GPU stall'));
} finally {
  await browser.close();
  const stop = await stopServer(child);
  result.serverExit = stop.code;
}
console.log(JSON.stringify(result));
if (result.serverExit !== 0) process.exit(3);
