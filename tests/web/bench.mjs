// The web view as a user drags in it (tessera-interaction-bench --web runs it beside the
// window): opens URL in Debian's chromium, waits for the lossless frame, drags across the
// canvas at 60 events a second for SECONDS, releases, waits for the lossless frame, and
// prints one JSON line of what the page measured: frames shown while dragging and their rate,
// input-to-present times (the page sending an input to the paint after the first frame that
// answers it; over the drag and in its first and last quarter), bytes per moving and
// per lossless frame, and the time from the release to the lossless frame.
// With MODE "watch" the page only watches: it writes OUTDIR/watching once it shows the lossless
// frame, and when OUTDIR/stop-watching appears prints the frames it showed and their rate.
// Both also print the CPU the browser (all its processes) and this driver used over the drag
// or the watch, in cores. With "idle" the page takes, times and acknowledges every frame as
// usual but neither decodes nor draws it (its decoding and drawing calls do nothing): what the
// browser costs for a page that shows nothing.
//   node bench.mjs URL SECONDS OUTDIR [drag|watch] [idle]
import fs from 'node:fs';
import path from 'node:path';
import { launch } from './browser.mjs';

const [url, seconds, outdir, mode, pageMode] = process.argv.slice(2);
const { browser, close } = await launch(outdir, 1100);

// CPU seconds of a process and all its descendants, from /proc (utime + stime, 100 ticks a second).
function treeCpu(root) {
  const parent = new Map(), ticks = new Map();
  for (const d of fs.readdirSync('/proc')) {
    if (!/^[0-9]+$/.test(d)) continue;
    try {
      const f = fs.readFileSync(`/proc/${d}/stat`, 'utf8');
      const rest = f.slice(f.lastIndexOf(')') + 2).split(' ');  // from field 3 (state) on
      parent.set(Number(d), Number(rest[1]));
      ticks.set(Number(d), Number(rest[11]) + Number(rest[12]));
    } catch { /* gone meanwhile */ }
  }
  let sum = 0;
  for (const [pid, t] of ticks) {
    for (let p = pid; p > 1; p = parent.get(p) ?? 0)
      if (p === root) { sum += t; break; }
  }
  return sum / 100;
}
// Starts a CPU clock of the browser and of this driver; returns a function giving their cores.
function cpuClock() {
  const pid = browser.process().pid, b0 = treeCpu(pid), d0 = process.cpuUsage(), t0 = performance.now();
  return () => {
    const s = (performance.now() - t0) / 1000, d = process.cpuUsage(d0);
    return { browser_cores: (treeCpu(pid) - b0) / s, driver_cores: (d.user + d.system) / 1e6 / s };
  };
}
const median = (v) => (v.length ? [...v].sort((a, b) => a - b)[Math.floor((v.length - 1) / 2)] : 0);
const p95 = (v) => (v.length ? [...v].sort((a, b) => a - b)[Math.round(0.95 * (v.length - 1))] : 0);

async function watch(page) {
  const from = await page.evaluate(() => window.tessera.state.log.length);
  fs.writeFileSync(path.join(outdir, 'watching'), '');
  const cpu = cpuClock();
  for (let i = 0; i < 4 * Number(seconds) * 20 + 1200 && !fs.existsSync(path.join(outdir, 'stop-watching')); ++i)
    await new Promise((r) => setTimeout(r, 50));
  const log = (await page.evaluate(() => window.tessera.state.log)).slice(from);
  const moving = log.filter((f) => f.kind === 'jpeg');
  console.log(JSON.stringify({ frames: log.length,
                               fps: moving.length > 1 ? (moving.length - 1) * 1000 / (moving[moving.length - 1].t - moving[0].t) : 0,
                               ...cpu() }));
}

async function drag(page, lossless) {
  const start = await page.evaluate(() => { const s = window.tessera.state; return { n: s.log.length, shown: s.shown, t: performance.now() }; });
  const box = await (await page.$('canvas')).boundingBox();
  const x0 = box.x + box.width / 8, y0 = box.y + box.height / 2;
  await page.mouse.move(x0, y0);
  await page.mouse.down();
  const steps = Math.round(Number(seconds) * 60);
  // Back and forth a whole number of times, 3 px an event: the camera turns through the same
  // views as in the window's drag and ends where it began.
  const half = Math.max(1, Math.floor(steps / (2 * Math.max(1, Math.round(steps / 200)))));
  const began = Date.now();
  const cpu = cpuClock();
  for (let i = 0; i < steps; ++i) {  // 60 events a second on the clock, whatever a move costs
    const p = (i + 1) % (2 * half);
    await page.mouse.move(x0 + 3 * (p < half ? p : 2 * half - p), y0 + (i % 2));
    await new Promise((r) => setTimeout(r, Math.max(0, began + (i + 1) * 1000 / 60 - Date.now())));
  }
  const released = await page.evaluate(() => ({ t: performance.now(), shown: window.tessera.state.shown }));
  const used = cpu();
  await page.mouse.up();
  await lossless(released.shown);
  await new Promise((r) => setTimeout(r, 200));
  const s = await page.evaluate(() => window.tessera.state);
  fs.writeFileSync(path.join(outdir, 'page-state.json'), JSON.stringify({ start, released, state: s }));
  // Input-to-present over the drag, and in its first and last quarter (does it grow?).
  const lat = s.latencies.filter(([t]) => t >= start.t && t <= released.t + 1);
  const quarter = (released.t - start.t) / 4;
  const first = lat.filter(([t]) => t < start.t + quarter).map(([, ms]) => ms);
  const last = lat.filter(([t]) => t > released.t - quarter).map(([, ms]) => ms);
  const during = s.log.slice(start.n).filter((f) => f.t <= released.t + 1);
  const moving = s.log.slice(start.n).filter((f) => f.kind === 'jpeg');
  const still = s.log.slice(start.n).filter((f) => f.kind === 'png');
  console.log(JSON.stringify({
    drag_frames: during.length,
    fps: during.length > 1 ? (during.length - 1) * 1000 / (during[during.length - 1].t - during[0].t) : 0,
    input_ms_median: median(lat.map(([, ms]) => ms)), input_ms_p95: p95(lat.map(([, ms]) => ms)),
    input_ms_first_quarter: median(first), input_ms_last_quarter: median(last),
    display_share_ms_median: median(lat.map(([, , d]) => d)), page_and_link_ms_median: median(lat.map(([, ms, d]) => ms - d)),
    moving_decode_ms_median: median(moving.map((f) => f.decode)),
    moving_bytes_median: median(moving.map((f) => f.bytes)), lossless_bytes: still.length ? still[still.length - 1].bytes : 0,
    release_to_lossless_ms: s.releaseToLossless, ...used,
  }));
}

try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1100, height: 1100 });
  if (pageMode === 'idle') {
    await page.evaluateOnNewDocument(() => {
      window.createImageBitmap = async () => null;
      const nothing = (proto, name) => { proto[name] = () => {}; };
      nothing(CanvasRenderingContext2D.prototype, 'drawImage');
      nothing(CanvasRenderingContext2D.prototype, 'fillRect');
      // The bar's text and class, and the canvas's size: keep them as they are.
      const keep = (proto, name) => Object.defineProperty(proto, name, { set() {}, get: Object.getOwnPropertyDescriptor(proto, name).get });
      keep(Node.prototype, 'textContent');
      keep(Element.prototype, 'className');
      keep(HTMLCanvasElement.prototype, 'width');
      keep(HTMLCanvasElement.prototype, 'height');
    });
  }
  await page.goto(url, { waitUntil: 'load', timeout: 30000 });
  const lossless = (after) => page.waitForFunction((i) => window.tessera && window.tessera.state.kind === 'lossless' &&
                                                   window.tessera.state.shown > i, { timeout: 60000, polling: 10 }, after);
  await lossless(-1);
  if (mode === 'watch') await watch(page);
  else await drag(page, lossless);
} catch (e) {
  console.log(JSON.stringify({ error: String(e && e.message || e) }));
  process.exitCode = 1;
} finally {
  await close();
}
