// Debian's chromium, headless, through puppeteer-core (never a downloaded browser), with the
// flags a closed network needs and a fresh profile in OUTDIR that close() removes.
import fs from 'node:fs';
import path from 'node:path';
import puppeteer from 'puppeteer-core';

export async function launch(outdir, size) {
  const userDir = fs.mkdtempSync(path.join(outdir, 'chromium-'));
  const browser = await puppeteer.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    userDataDir: userDir,
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update',
           '--disable-sync', '--no-first-run', `--window-size=${size},${size}`],
  });
  return {
    browser,
    async close() {
      await browser.close();
      fs.rmSync(userDir, { recursive: true, force: true });
    },
  };
}
