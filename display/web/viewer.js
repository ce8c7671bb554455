// Tessera web view: shows the farm's frames from the display's WebSocket and sends input
// back through it. Frames: [u32 LE header length][JSON header][PNG or JPEG of the active
// region]. Each drawn frame is acknowledged; the display sends at most 2 unacknowledged.
'use strict';
(() => {
  const canvas = document.getElementById('frame');
  const ctx = canvas.getContext('2d', { alpha: false });
  const kindEl = document.getElementById('kind');
  const statusEl = document.getElementById('status');
  const helpEl = document.getElementById('help');
  const token = (() => { try { return decodeURIComponent(location.hash.slice(1)); } catch (e) { return location.hash.slice(1); } })();
  // What the page saw (tests and the benchmark read it): frames shown, input-to-present times,
  // and each frame's time, kind and bytes; the time from the last release to a lossless frame.
  const state = { shown: -1, kind: 'none', frames: 0, connects: 0, latencies: [], log: [],
                  releaseAt: 0, releaseToLossless: 0 };
  // Input-to-present: each input carries a number; a frame names the first input it answers
  // (if it came from this page: the page's number for this load), timed to the next paint.
  const pageId = 1 + Math.floor(Math.random() * 999999998);
  const sentAt = new Map();  // input number -> when it was sent
  let inputN = 0;
  let ws = null;
  let retry = 250;
  let failures = 0;  // connection attempts in a row that never opened

  // The canvas is shown at the full frame's size in device pixels (smaller only if the view
  // is): a lossless frame's pixels reach the screen unscaled, a reduced frame is scaled up to
  // it. A browser zoom or a move to another screen changes devicePixelRatio (and fires resize).
  let shownSize = null;
  function fitCanvas() {
    if (!shownSize) return;
    canvas.style.width = `${shownSize[0] / devicePixelRatio}px`;
    canvas.style.height = `${shownSize[1] / devicePixelRatio}px`;
  }
  window.addEventListener('resize', fitCanvas);

  function setKind(text, cls) {
    kindEl.textContent = text;
    kindEl.className = cls;
  }

  // Each frame is acknowledged on the socket it came by, also when it cannot be shown.
  async function onFrame(buf, sock) {
    const arrived = performance.now();
    let id = null;
    try {
      const n = new DataView(buf).getUint32(0, true);
      const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, n)));
      id = header.id;
      await show(header, buf, 4 + n, sock, arrived);
    } finally {
      if (id !== null && sock.readyState === WebSocket.OPEN) sock.send(JSON.stringify({ t: 'ack', id }));
    }
  }

  async function show(header, buf, offset, sock, arrived) {
    let bitmap = null;
    if (header.kind === 'png' || header.kind === 'jpeg') {
      const blob = new Blob([new Uint8Array(buf, offset)], { type: 'image/' + header.kind });
      bitmap = await createImageBitmap(blob, { premultiplyAlpha: 'none', colorSpaceConversion: 'none' });
    }
    // Decoding is asynchronous: a frame finished after a newer one, or one from a connection
    // that has since been replaced, is never shown.
    if (sock === ws && header.id > state.shown) {
      if (canvas.width !== header.fw || canvas.height !== header.fh) {
        canvas.width = header.fw;
        canvas.height = header.fh;
      }
      const full = header.full || shownSize || [header.fw, header.fh];
      if (!shownSize || full[0] !== shownSize[0] || full[1] !== shownSize[1]) {
        shownSize = full;
        fitCanvas();
      }
      ctx.fillStyle = `rgb(${header.bg[0]}, ${header.bg[1]}, ${header.bg[2]})`;
      ctx.fillRect(0, 0, canvas.width, canvas.height);
      if (bitmap) ctx.drawImage(bitmap, header.x, header.y);
      state.shown = header.id;
      state.kind = header.moving ? 'moving' : 'lossless';
      state.frames++;
      const now = performance.now();
      state.log.push({ t: now, id: header.id, kind: header.kind, bytes: buf.byteLength, decode: now - arrived,
                       input: header.input && header.input.page === pageId ? header.input.n : 0 });
      if (state.log.length > 10000) state.log.shift();
      if (state.kind === 'lossless' && state.releaseAt) {
        state.releaseToLossless = now - state.releaseAt;
        state.releaseAt = 0;
      }
      const t = header.input && header.input.page === pageId ? sentAt.get(header.input.n) : undefined;
      if (t !== undefined) {
        for (const n of sentAt.keys()) if (n <= header.input.n) sentAt.delete(n); else break;
        requestAnimationFrame(() => {
          const painted = performance.now();
          // When, how long after the input, and how much of that the display saw (from
          // receiving the input to handing the frame to its sinks): the rest is the web view's
          // encoding, the link both ways and the page.
          state.latencies.push([painted, painted - t, header.input.ms || 0]);
          if (state.latencies.length > 10000) state.latencies.shift();
        });
      }
      setKind(state.kind === 'moving' ? 'moving (JPEG)' : 'lossless', state.kind);
      statusEl.textContent = state.status = header.status;
    }
    if (bitmap) bitmap.close();
  }

  function connect() {
    if (!token) {  // the display logs the whole URL: the part after # is the token
      setKind('no token', 'offline');
      statusEl.textContent = 'open the URL the display logged, with its #token';
      return;
    }
    const sock = new WebSocket(`ws://${location.host}/ws?token=${encodeURIComponent(token)}&page=${pageId}`);
    ws = sock;
    sock.binaryType = 'arraybuffer';
    let opened = false;
    sock.onopen = () => {
      opened = true;
      retry = 250;
      failures = 0;
      state.connects++;
      state.shown = -1;  // a restarted display numbers its frames from 0 again
      setKind('connected', 'lossless');
    };
    sock.onmessage = (e) => { if (e.data instanceof ArrayBuffer) onFrame(e.data, sock).catch((err) => console.error(err)); };
    sock.onclose = () => {  // a restart of the display or a lost link: try again, soon
      if (!opened && ++failures >= 3) statusEl.textContent = 'refused or the display is down: check the URL the display logged';
      setKind('reconnecting', 'offline');
      // Soon while a display may be restarting; a page refused a minute long (a wrong token,
      // a display gone) asks every 5 s instead of filling the display's refusal count.
      setTimeout(connect, failures >= 120 ? 5000 : retry);
      retry = Math.min(500, retry * 2);
    };
  }

  // Input: drags are summed and sent once per animation frame, like the window's. The left
  // button's orbits; the right button's sets the colour window ('window').
  let drag = null;
  let pending = { dx: 0, dy: 0 };
  function send(msg) {
    if (!ws || ws.readyState !== WebSocket.OPEN) return;
    msg.n = ++inputN;
    sentAt.set(msg.n, performance.now());
    if (sentAt.size > 1000) sentAt.delete(sentAt.keys().next().value);  // inputs no frame answered
    ws.send(JSON.stringify(msg));
  }
  function flushDrag() {
    if (pending.dx || pending.dy) send({ t: pending.right ? 'window' : 'drag', dx: pending.dx, dy: pending.dy });
    pending = { dx: 0, dy: 0, right: pending.right };
    if (drag) requestAnimationFrame(flushDrag);
  }
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());  // the right button is ours
  canvas.addEventListener('pointerdown', (e) => {
    if ((e.button !== 0 && e.button !== 2) || drag) return;
    drag = { x: e.clientX, y: e.clientY };
    pending.right = e.button === 2;
    canvas.setPointerCapture(e.pointerId);
    canvas.classList.add('dragging');
    requestAnimationFrame(flushDrag);
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    pending.dx += e.clientX - drag.x;
    pending.dy += e.clientY - drag.y;
    drag.x = e.clientX;
    drag.y = e.clientY;
  });
  const release = () => {
    if (!drag) return;
    drag = null;
    canvas.classList.remove('dragging');
    flushDrag();
    send({ t: 'release' });
    state.releaseAt = performance.now();
  };
  canvas.addEventListener('pointerup', release);
  canvas.addEventListener('pointercancel', release);
  // Wheels and trackpads: deltas summed per animation frame, 100 px (3 lines) a notch.
  let notches = 0;
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const scale = e.deltaMode === 1 ? 1 / 3 : e.deltaMode === 2 ? 1 : 1 / 100;
    if (!notches) requestAnimationFrame(() => { if (notches) send({ t: 'wheel', notches }); notches = 0; });
    notches = Math.max(-20, Math.min(20, notches - e.deltaY * scale));
  }, { passive: false });
  window.addEventListener('keydown', (e) => {
    if (e.ctrlKey || e.metaKey || e.altKey) return;  // the browser's own (Ctrl+R reloads)
    if (e.key === 'h') helpEl.style.display = helpEl.style.display === 'block' ? 'none' : 'block';
    else if (['1', '2', '3', 'r', ' ', 'ArrowRight', 'ArrowLeft', 'Home', 'End'].includes(e.key)) {
      e.preventDefault();  // Space and the arrows would scroll the page
      // A held key repeats: only the arrows step on (as in the window); a held Space
      // toggled play and pause on every repeat (found by review).
      if (e.repeat && e.key !== 'ArrowRight' && e.key !== 'ArrowLeft') return;
      send({ t: 'key', key: e.key });
    }
  });

  // For tests and benchmarks: what is shown, and the canvas's pixels (RGBA, base64).
  window.tessera = {
    state,
    drop() { if (ws) ws.close(); },  // as a lost connection: the page reconnects by itself
    pixels() {
      const data = ctx.getImageData(0, 0, canvas.width, canvas.height).data;
      let s = '';
      for (let i = 0; i < data.length; i += 0x8000) s += String.fromCharCode.apply(null, data.subarray(i, i + 0x8000));
      return { id: state.shown, kind: state.kind, width: canvas.width, height: canvas.height, rgba: btoa(s) };
    },
  };
  connect();
})();
