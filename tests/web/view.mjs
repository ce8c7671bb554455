// Drives Debian's chromium (headless, through puppeteer-core: never a downloaded browser)
// on the web view, for the tests and the benchmark.
//   node view.mjs URL OUTDIR ACTION...
// Actions, in order; each prints one JSON line:
//   wait-lossless[:ID]  until the page shows a lossless frame with id >= ID (30 s at most);
//                       ID "+": newer than the frame shown when the last drag began
//   wait-frames:N       until the page has shown N frames since it loaded (30 s at most)
//   pixels:NAME         the canvas's RGBA into OUTDIR/NAME.rgba, and its id/kind/size
//   shot:NAME           a screenshot into OUTDIR/NAME.png
//   drag:STEPS          a left-button drag from the canvas's centre, STEPS moves of 6 px, 16 ms apart
//   right-drag:STEPS    the same with the right button (the colour window)
//   reload              reloads the page; prints the ms until it shows a frame again
//   bad-ws              from the page, a second WebSocket (with the token) sends malformed,
//                       unknown, oversized and binary messages, then closes
//   extra:N             opens N more pages on URL (other viewers), each until it shows a frame
//   extras-same         until every extra page shows the main page's frame (lossless); their ids
//   drop                closes the page's connection as a lost link would; prints the ms
//                       until it has reconnected and shows a frame again
//   signal:NAME         creates OUTDIR/NAME (the test waits for it to act, e.g. restart the display)
//   wait-reconnect      until the page has connected again and shown a frame on the new
//                       connection (90 s at most: a restarted farm takes a while to start)
//   sleep:MS, state     wait; print the page's state
import fs from 'node:fs';
import path from 'node:path';
import { launch } from './browser.mjs';

const [url, outdir, ...actions] = process.argv.slice(2);
const { browser, close } = await launch(outdir, 1000);
const say = (o) => console.log(JSON.stringify(o));
let dragFrom = -1;  // the frame shown when the last drag began
const extras = [];  // other viewers' pages
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1200, height: 1000 });
  page.on('console', (m) => { if (m.type() === 'error') say({ console: m.text() }); });
  await page.goto(url, { waitUntil: 'load', timeout: 30000 });
  const state = () => page.evaluate(() => (window.tessera ? { ...window.tessera.state, latencies: undefined } : null));
  for (const action of actions) {
    const [name, arg] = action.split(/:(.*)/s);
    const t0 = Date.now();
    if (name === 'wait-lossless') {
      const id = arg === '+' ? dragFrom + 1 : Number(arg || 0);
      await page.waitForFunction((i) => window.tessera && window.tessera.state.kind === 'lossless' &&
                                 window.tessera.state.shown >= i, { timeout: 30000, polling: 20 }, id);
      say({ action, ms: Date.now() - t0, state: await state() });
    } else if (name === 'wait-frames') {
      await page.waitForFunction((n) => window.tessera && window.tessera.state.frames >= n,
                                 { timeout: 30000, polling: 20 }, Number(arg));
      say({ action, ms: Date.now() - t0, state: await state() });
    } else if (name === 'pixels') {
      const p = await page.evaluate(() => window.tessera.pixels());
      fs.writeFileSync(path.join(outdir, arg + '.rgba'), Buffer.from(p.rgba, 'base64'));
      say({ action, id: p.id, kind: p.kind, width: p.width, height: p.height });
    } else if (name === 'shot') {
      await page.screenshot({ path: path.join(outdir, arg + '.png') });
      say({ action });
    } else if (name === 'drag' || name === 'right-drag') {
      const button = name === 'drag' ? 'left' : 'right';
      dragFrom = (await state()).shown;
      const box = await (await page.$('canvas')).boundingBox();
      let x = box.x + box.width / 2, y = box.y + box.height / 2;
      await page.mouse.move(x, y);
      await page.mouse.down({ button });
      for (let i = 0; i < Number(arg); ++i) {
        x += 6;
        y += 1;
        await page.mouse.move(x, y);
        await new Promise((r) => setTimeout(r, 16));
      }
      await page.mouse.up({ button });
      say({ action, ms: Date.now() - t0, state: await state() });
    } else if (name === 'reload') {
      await page.reload({ waitUntil: 'load' });
      await page.waitForFunction(() => window.tessera && window.tessera.state.frames >= 1, { timeout: 30000, polling: 10 });
      say({ action, ms: Date.now() - t0, state: await state() });
    } else if (name === 'bad-ws') {
      const closed = await page.evaluate(() => new Promise((resolve) => {
        const ws = new WebSocket(`ws://${location.host}/ws?token=${encodeURIComponent(location.hash.slice(1))}`);
        ws.onopen = () => {
          ws.send('not json {');
          ws.send(JSON.stringify({ t: 'launch-missiles' }));
          ws.send(JSON.stringify({ t: 'drag', dx: 'far', dy: 1e300 }));
          ws.send(JSON.stringify({ t: 'key', key: 'x' }));  // a key the view does not steer with
          ws.send(new Uint8Array([1, 2, 3]));
          ws.send('x'.repeat(5000));  // oversized: the display closes this connection
        };
        ws.onclose = () => resolve(true);
        setTimeout(() => resolve(false), 5000);
      }));
      say({ action, closed_by_display: closed, state: await state() });
    } else if (name === 'extra') {
      for (let i = 0; i < Number(arg); ++i) {
        const p = await browser.newPage();
        await p.goto(url, { waitUntil: 'load', timeout: 30000 });
        extras.push(p);
      }
      await Promise.all(extras.map((p) => p.waitForFunction(() => window.tessera && window.tessera.state.frames >= 1,
                                                            { timeout: 30000, polling: 20 })));
      await page.bringToFront();  // a background tab gets no animation frames: the drag's input waits
      say({ action, viewers: 1 + extras.length });
    } else if (name === 'extras-same') {
      const id = (await state()).shown;
      await Promise.all(extras.map((p) => p.waitForFunction((i) => window.tessera.state.shown === i &&
                                                            window.tessera.state.kind === 'lossless',
                                                            { timeout: 30000, polling: 20 }, id)));
      const ids = await Promise.all(extras.map((p) => p.evaluate(() => window.tessera.state.shown)));
      say({ action, id, ids });
    } else if (name === 'drop') {
      const before = await page.evaluate(() => { const s = window.tessera.state; const b = { c: s.connects, f: s.frames }; window.tessera.drop(); return b; });
      await page.waitForFunction((b) => window.tessera.state.connects > b.c && window.tessera.state.frames > b.f,
                                 { timeout: 30000, polling: 10 }, before);
      say({ action, ms: Date.now() - t0, state: await state() });
    } else if (name === 'signal') {
      fs.writeFileSync(path.join(outdir, arg), '');
      say({ action });
    } else if (name === 'wait-reconnect') {
      const c = (await state()).connects;
      await page.waitForFunction((n) => window.tessera.state.connects > n && window.tessera.state.shown >= 0 &&
                                 window.tessera.state.kind === 'lossless',
                                 { timeout: 90000, polling: 20 }, c);
      say({ action, ms: Date.now() - t0, state: await state() });
    } else if (name === 'sleep') {
      await new Promise((r) => setTimeout(r, Number(arg)));
      say({ action, state: await state() });
    } else if (name === 'state') {
      say({ action, state: await state() });
    } else {
      throw new Error('unknown action ' + action);
    }
  }
} catch (e) {
  say({ error: String(e && e.message || e) });
  process.exitCode = 1;
} finally {
  await close();
}
