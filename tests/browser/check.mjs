// Drives headless Chromium against a running `latticebuild watch --serve` (tests/serve.rs runs
// it). Checks, failing with a message and exit code 1:
//  1. the page draws the model: enough pixels of the viewer's screenshot differ from its
//     background (the PNG is decoded here, independently of the page);
//  2. the report's volume fraction of OUTPUT appears in the page (to 4 decimals);
//  3. after the camera is dragged and the manifest edited (--edit FILE --from A --to B), the page
//     shows a new volume fraction without reloading (same page id) and with the same camera;
//  4. with --broken TEXT, writing TEXT to FILE shows the error with its file:line, and writing
//     the edited manifest back clears it.
// Prints one JSON line: load time (first model drawn, ms since navigation), pixel counts, the
// fractions shown.
//
// usage: node check.mjs URL --output NAME --expect-vf X [--edit FILE --from A --to B]
//        [--broken TEXT] [--screenshot FILE] [--chromium PATH] [--timeout-ms N]
import { chromium } from 'playwright-core';
import fs from 'node:fs';
import zlib from 'node:zlib';

const args = process.argv.slice(2);
const url = args[0];
const opt = name => {
  const i = args.indexOf('--' + name);
  return i > 0 ? args[i + 1] : undefined;
};
const output = opt('output');
const expectVf = Number(opt('expect-vf'));
const timeout = Number(opt('timeout-ms') || 30000);
const executablePath = opt('chromium') || process.env.CHROMIUM || '/usr/bin/chromium';

function fail(message) {
  console.error('check.mjs: ' + message);
  process.exit(1);
}

// A minimal PNG decoder (8-bit RGB/RGBA, not interlaced: what Chromium's screenshots are).
function decodePng(buffer) {
  if (buffer.readUInt32BE(0) !== 0x89504e47) fail('screenshot is not a PNG');
  let at = 8, width = 0, height = 0, channels = 0;
  const data = [];
  while (at < buffer.length) {
    const length = buffer.readUInt32BE(at);
    const type = buffer.toString('ascii', at + 4, at + 8);
    const body = buffer.subarray(at + 8, at + 8 + length);
    if (type === 'IHDR') {
      width = body.readUInt32BE(0); height = body.readUInt32BE(4);
      const depth = body[8], color = body[9], interlace = body[12];
      if (depth !== 8 || interlace !== 0 || (color !== 2 && color !== 6)) fail(`unexpected PNG kind ${depth}/${color}/${interlace}`);
      channels = color === 6 ? 4 : 3;
    } else if (type === 'IDAT') data.push(body);
    at += 12 + length;
  }
  const raw = zlib.inflateSync(Buffer.concat(data));
  const stride = width * channels;
  const pixels = Buffer.alloc(height * stride);
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    const line = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let x = 0; x < stride; x++) {
      const a = x >= channels ? pixels[y * stride + x - channels] : 0;
      const b = y > 0 ? pixels[(y - 1) * stride + x] : 0;
      const c = x >= channels && y > 0 ? pixels[(y - 1) * stride + x - channels] : 0;
      let v = line[x];
      if (filter === 1) v += a;
      else if (filter === 2) v += b;
      else if (filter === 3) v += (a + b) >> 1;
      else if (filter === 4) {
        const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
        v += pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      pixels[y * stride + x] = v & 255;
    }
  }
  return { width, height, channels, pixels };
}

const browser = await chromium.launch({
  executablePath,
  headless: true,
  args: [
    '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync',
    '--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
  ],
});
const result = {};
try {
  const page = await browser.newPage({ viewport: { width: 1000, height: 700 } });
  const logs = [];
  page.on('console', m => logs.push(`${m.type()}: ${m.text()}`));
  page.on('pageerror', e => logs.push(`pageerror: ${e.message}`));
  let navigations = 0;
  page.on('framenavigated', f => { if (f === page.mainFrame()) navigations++; });
  const started = Date.now();
  await page.goto(url);
  try {
    await page.waitForFunction(() => window.__lattice && window.__lattice.firstDrawMs !== null, null, { timeout });
  } catch (e) {
    fail(`no model drawn within ${timeout} ms\n${logs.join('\n')}`);
  }
  result.loadMs = await page.evaluate(() => window.__lattice.firstDrawMs);
  result.wallMs = Date.now() - started;

  // 1. The model is drawn.
  const shot = await page.locator('#view').screenshot();
  if (opt('screenshot')) fs.writeFileSync(opt('screenshot'), shot);
  const png = decodePng(shot);
  let drawn = 0;
  for (let i = 0; i < png.width * png.height; i++) {
    const p = i * png.channels;
    const d = Math.max(...[0, 1, 2].map(c => Math.abs(png.pixels[p + c] - 250)));
    if (d > 24) drawn++;
  }
  result.pixels = png.width * png.height;
  result.drawnPixels = drawn;
  if (drawn < 0.02 * result.pixels) fail(`only ${drawn} of ${result.pixels} pixels differ from the background`);

  // 2. The report's figure is in the page.
  const vfText = async () => page.evaluate(
    name => document.querySelector(`[data-output="${name}"] [data-figure="volume_fraction"]`)?.textContent ?? null,
    output);
  const shown = await vfText();
  result.vfShown = Number(shown);
  if (shown === null || Math.abs(Number(shown) - expectVf) > 6e-5) fail(`volume fraction shown ${shown}, report says ${expectVf}`);
  result.figures = await page.evaluate(
    name => [...document.querySelectorAll(`[data-output="${name}"] [data-figure]`)].map(e => e.dataset.figure),
    output);

  // 3. A live update keeps the page and the camera.
  const file = opt('edit');
  if (file) {
    const box = await page.locator('#view canvas').boundingBox();
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
    await page.mouse.down();
    await page.mouse.move(box.x + box.width / 2 + 120, box.y + box.height / 2 + 40, { steps: 5 });
    await page.mouse.up();
    const before = await page.evaluate(() => ({ id: window.__lattice.pageId, camera: window.__lattice.camera(), generation: window.__lattice.generation }));
    const text = fs.readFileSync(file, 'utf8');
    if (!text.includes(opt('from'))) fail(`--from text not in ${file}`);
    const edited = text.replace(opt('from'), opt('to').replace(/\\n/g, '\n'));
    const saved = Date.now();
    fs.writeFileSync(file, edited);
    try {
      await page.waitForFunction(([name, old]) => {
        const e = document.querySelector(`[data-output="${name}"] [data-figure="volume_fraction"]`);
        return e && e.textContent !== old && !document.querySelector('.output.stale');
      }, [output, shown], { timeout });
    } catch (e) {
      fail(`the page did not show a new volume fraction within ${timeout} ms of the save\n${logs.join('\n')}`);
    }
    result.updateMs = Date.now() - saved;
    result.vfAfter = Number(await vfText());
    const after = await page.evaluate(() => ({ id: window.__lattice.pageId, camera: window.__lattice.camera(), generation: window.__lattice.generation }));
    if (after.id !== before.id || navigations !== 1) fail('the page reloaded');
    if (after.generation <= before.generation) fail('the generation did not advance');
    const moved = before.camera.some((c, i) => Math.abs(c - after.camera[i]) > 1e-9);
    if (moved) fail(`the camera moved on update: ${before.camera} -> ${after.camera}`);
    result.camera = after.camera;

    // 4. A broken manifest shows its error, a fixed one clears it.
    const broken = opt('broken');
    if (broken !== undefined) {
      fs.writeFileSync(file, broken.replace(/\\n/g, '\n'));
      const name = file.split('/').pop();
      try {
        await page.waitForFunction(n => {
          const e = document.getElementById('error');
          return e.classList.contains('shown') && new RegExp(n.replace('.', '\\.') + ':\\d+:\\d+').test(e.textContent);
        }, name, { timeout });
      } catch (e) {
        fail(`no error with ${name}:LINE:COLUMN shown for the broken manifest`);
      }
      result.errorShown = await page.evaluate(() => document.getElementById('error').textContent);
      fs.writeFileSync(file, edited);
      try {
        await page.waitForFunction(() => !document.getElementById('error').classList.contains('shown'), null, { timeout });
      } catch (e) {
        fail('the error stayed after the manifest was fixed');
      }
      if ((await page.evaluate(() => window.__lattice.pageId)) !== before.id) fail('the page reloaded');
    }
  }
  console.log(JSON.stringify(result));
} finally {
  await browser.close();
}
