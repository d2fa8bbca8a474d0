// Drives headless Chromium (Debian's /usr/bin/chromium, through its DevTools protocol) against
// the page served at --url, once with WebGPU, once with WebGL2 only, and once with neither, and
// writes what it saw into --out for tests/browser.rs to check: the page's reported state, the
// frames read back from the engine, a compositor screenshot, and the messages shown. Both looks
// are drawn on both APIs (the course look also with `api=webgl`); without
// either API, and with a bad address, the message must still be there seconds later. With
// WebGPU and with WebGL2, elevation data (--dem) is then picked in the file input: the page's
// state, frame and screenshot with it are written too, and the message for a broken elevation
// file (--corrupt-dem).
//
// node browser.mjs --url http://127.0.0.1:PORT --out DIR --corrupt FILE --dem FILE --corrupt-dem FILE
import { readFileSync, writeFileSync } from 'node:fs';
import { basename, join } from 'node:path';
import puppeteer from 'puppeteer-core';

const arg = (name) => {
  const at = process.argv.indexOf(`--${name}`);
  if (at < 0 || at + 1 >= process.argv.length) throw new Error(`missing --${name}`);
  return process.argv[at + 1];
};
const [url, out, corrupt, dem, corruptDem] =
  [arg('url'), arg('out'), arg('corrupt'), arg('dem'), arg('corrupt-dem')];

// Quiet, offline, as root in a container.
const common = ['--no-sandbox', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--window-size=800,600'];
const modes = {
  // SwiftShader's WebGPU adapter (the machine has no GPU), composited through Vulkan: with
  // ANGLE on its GL SwiftShader instead, a WebGPU canvas is never shown and buffers can no
  // longer be mapped once it has drawn ("A valid external Instance reference no longer exists").
  webgpu: ['--enable-unsafe-webgpu', '--use-webgpu-adapter=swiftshader', '--enable-features=Vulkan',
    '--use-vulkan=swiftshader', '--use-angle=vulkan'],
  // No WebGPU adapter: the page must fall back to WebGL2 by itself.
  webgl: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  // Neither API: the page must say so.
  none: ['--disable-webgl', '--disable-3d-apis', '--disable-features=WebGPU,Vulkan'],
};
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

async function waitFor(page, what, test, seconds) {
  const until = Date.now() + seconds * 1000;
  for (;;) {
    const value = await page.evaluate(test);
    if (value) return value;
    if (Date.now() > until) throw new Error(`timed out after ${seconds} s waiting for ${what}`);
    await sleep(200);
  }
}

const state = (page) => page.evaluate(() => window.rayterra.state());
const errorShown = () => {
  const box = document.getElementById('error');
  return box && !box.hidden && box.textContent;
};
// What the page shows: its error box (null when hidden), status line and progress line.
const shown = () => ({
  error: (() => {
    const box = document.getElementById('error');
    return box && !box.hidden ? box.textContent : null;
  })(),
  status: document.getElementById('api').textContent,
  progress: !document.getElementById('progress').hidden,
});

async function captureTo(page, name) {
  const frame = await page.evaluate(async () => {
    const { width, height, data } = await window.rayterra.capture();
    let text = '';
    for (let i = 0; i < data.length; i += 0x8000) text += String.fromCharCode(...data.subarray(i, i + 0x8000));
    return { width, height, data: btoa(text) };
  });
  writeFileSync(join(out, `${name}.rgba`), Buffer.from(frame.data, 'base64'));
  return { width: frame.width, height: frame.height };
}

// A frame read back, or why it could not be.
async function tryCapture(page, name) {
  try {
    return await captureTo(page, name);
  } catch (error) {
    return { error: String(error?.message ?? error) };
  }
}

// Opens the page at `query` in `page` (800x600), its errors gathered in `report`.
async function open(page, query, report) {
  await page.setViewport({ width: 800, height: 600 });
  page.on('pageerror', (error) => report.pageErrors.push(error.message));
  await page.goto(`${url}/${query}`);
}

// Waits until the page has drawn 3 frames of `what` (or stopped on an error).
async function firstFrames(page, what) {
  await waitFor(page, `frames of ${what}`, () => {
    const s = window.rayterra?.state?.();
    return s && (s.error || s.frames >= 3);
  }, 180);
}

// Runs `work(page)` in a new tab of `browser` and closes it; returns `report`, where an error
// thrown on the way is its `failure`.
async function inPage(browser, report, work) {
  const page = await browser.newPage();
  try {
    await work(page);
  } catch (error) {
    report.failure = String(error?.stack ?? error);
  } finally {
    await page.close();
  }
  return report;
}

// The page at `query` in a new tab of `browser`: its state after 3 frames (or its stop), and the
// frame it drew, written as NAME-frame.rgba.
async function drawOnce(browser, query, name) {
  const report = { query, console: [], pageErrors: [] };
  return inPage(browser, report, async (page) => {
    page.on('console', (message) => report.console.push(`${message.type()}: ${message.text()}`));
    await open(page, query, report);
    await firstFrames(page, `the world (${query})`);
    report.state = await state(page);
    if (!report.state.error) report.frame = await tryCapture(page, `${name}-frame`);
    // Frames go on being drawn without a stop.
    await sleep(1000);
    report.later = await state(page);
  });
}

// The page at `query` where it cannot draw: the message it shows at first, and what it shows
// a few seconds later (once the worker has built the world, where `world` says it starts one).
async function failOnce(browser, { query, world }) {
  const report = { query, pageErrors: [] };
  return inPage(browser, report, async (page) => {
    await open(page, query, report);
    report.first = await waitFor(page, `the page to say it cannot draw (${query})`, errorShown, 60);
    // The worker finishes its world (which used to clear the message), then time passes.
    if (world) {
      await waitFor(page, `the worker's world (${query})`, () => window.rayterra.worldsBuilt >= 1, 120);
    }
    report.worldsBuilt = await page.evaluate(() => window.rayterra?.worldsBuilt ?? null);
    await sleep(3000);
    report.later = await page.evaluate(shown);
  });
}

// The page at `query` with the elevation data dropped on it once it has drawn the island (a
// drop event carrying the file, as a file dragged from the desktop gives): its state and the
// frame it drew with the data, written as NAME-frame.rgba.
async function demOnce(browser, query, name) {
  const report = { query, pageErrors: [] };
  return inPage(browser, report, async (page) => {
    await open(page, query, report);
    await firstFrames(page, `the island (${query})`);
    await page.evaluate((base64, name) => {
      const bytes = Uint8Array.from(atob(base64), (c) => c.charCodeAt(0));
      const transfer = new DataTransfer();
      transfer.items.add(new File([bytes], name));
      document.body.dispatchEvent(new DragEvent('dragover', { dataTransfer: transfer, bubbles: true, cancelable: true }));
      document.body.dispatchEvent(new DragEvent('drop', { dataTransfer: transfer, bubbles: true, cancelable: true }));
    }, readFileSync(dem).toString('base64'), basename(dem));
    report.state = await waitFor(page, `the elevation data to be drawn (${query})`, () => {
      const s = window.rayterra.state();
      const box = document.getElementById('error');
      if (s.error || !box.hidden) return { failure: s.error ?? box.textContent };
      if (!s.world?.startsWith('elevation data')) return null;
      window.rayterra.demFrames ??= s.frames;
      return s.frames >= window.rayterra.demFrames + 3 ? s : null;
    }, 180);
    if (!report.state.failure) report.frame = await tryCapture(page, `${name}-frame`);
  });
}

// Elevation data with the address's water level above its lowest ground, dropped: a lake, drawn.
const demRuns = {
  webgl: { 'dem-lake': '?size=640x360&paused&time=3&water-level=1500' },
};

// The course look (on WebGL2 also asked for by `api=webgl`: Chromium's WebGPU flags here leave
// it no WebGL2).
const lookRuns = {
  webgpu: { course: '?size=640x360&paused&time=3&look=course' },
  webgl: { course: '?size=640x360&paused&time=3&look=course',
    'course-webgl': '?size=640x360&paused&time=3&look=course&api=webgl' },
  none: {},
};
const failRuns = {
  none: {
    'no-api': { query: '?size=640x360&paused&time=3', world: true },
    'no-webgl': { query: '?api=webgl&look=course', world: true },
    'bad-address': { query: '?seed=one', world: false },
  },
};

async function run(mode) {
  const browser = await puppeteer.launch({
    executablePath: '/usr/bin/chromium',
    headless: true,
    args: [...common, ...modes[mode]],
    userDataDir: join(out, `profile-${mode}`),
  });
  const report = { mode, console: [], pageErrors: [] };
  try {
    for (const [name, query] of Object.entries(failRuns[mode] ?? {})) {
      report[name] = await failOnce(browser, query);
    }
    for (const [name, query] of Object.entries(lookRuns[mode])) {
      report[name] = await drawOnce(browser, query, `${mode}-${name}`);
    }
    for (const [name, query] of Object.entries(demRuns[mode] ?? {})) {
      report[name] = await demOnce(browser, query, `${mode}-${name}`);
    }
    const page = await browser.newPage();
    page.on('console', (message) => report.console.push(`${message.type()}: ${message.text()}`));
    await open(page, '?size=640x360&paused&time=3', report);
    if (mode === 'none') {
      report.error = await waitFor(page, 'the page to say it cannot draw', errorShown, 60);
      return report;
    }
    await firstFrames(page, 'the world');
    report.before = await state(page);
    if (report.before.error) return report;
    report.frame = await captureTo(page, `${mode}-frame`);
    const canvas = await page.$('#terrain');
    await canvas.screenshot({ path: join(out, `${mode}-screenshot.png`) });
    // Hold W: the camera flies forward (toward -z at yaw 0).
    await page.focus('#terrain');
    await page.keyboard.down('KeyW');
    const held = await state(page);
    await sleep(1500);
    await page.keyboard.up('KeyW');
    report.heldFrames = (await state(page)).frames - held.frames;
    await sleep(300);
    report.after = await state(page);
    report.moved = await captureTo(page, `${mode}-moved`);
    // A click captures the mouse (pointer lock); moving it turns the camera.
    await page.mouse.click(320, 180);
    await sleep(300);
    await page.mouse.move(420, 180, { steps: 5 });
    await sleep(500);
    report.turned = await state(page);
    // A corrupt heightmap file: a message on the page, not a crash.
    const input = await page.$('#file');
    await input.uploadFile(corrupt);
    report.corrupt = await waitFor(page, 'the corrupt file to be refused', errorShown, 60);
    report.afterCorrupt = await state(page);
    // Elevation data picked in the file input: the world, its scene and its camera start follow
    // the file. Frames drawn with it, then the frame read back and the compositor's picture.
    // (The corrupt file's message is still shown until the new file is read.)
    await page.evaluate((message) => { window.rayterra.shownBefore = message; }, report.corrupt);
    await input.uploadFile(dem);
    const demState = await waitFor(page, 'the elevation data to be drawn', () => {
      const s = window.rayterra.state();
      if (s.error) return s;
      const box = document.getElementById('error');
      if (!box.hidden && box.textContent !== window.rayterra.shownBefore) return { failure: box.textContent };
      if (!s.world?.startsWith('elevation data')) return null;
      window.rayterra.demFrames ??= s.frames;
      return s.frames >= window.rayterra.demFrames + 3 ? s : null;
    }, 180);
    report.dem = { state: demState, hud: await page.evaluate(() => document.getElementById('world').textContent) };
    if (!demState.error && !demState.failure) {
      report.dem.frame = await tryCapture(page, `${mode}-dem-frame`);
      await canvas.screenshot({ path: join(out, `${mode}-dem-screenshot.png`) });
    }
    // A broken elevation file: its message, naming it; the elevation data stays drawn.
    await input.uploadFile(corruptDem);
    report.dem.corrupt = await waitFor(page, 'the broken elevation file to be refused', errorShown, 60);
    report.dem.afterCorrupt = await state(page);
    return report;
  } catch (error) {
    report.failure = String(error?.stack ?? error);
    return report;
  } finally {
    await browser.close();
  }
}

for (const mode of Object.keys(modes)) {
  const report = await run(mode);
  writeFileSync(join(out, `${mode}.json`), JSON.stringify(report, null, 2));
  console.log(`${mode}: ${report.failure ?? report.before?.api ?? report.error ?? 'done'}`);
}
