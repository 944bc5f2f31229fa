// Opens desal's view.html in headless Chromium the way a user does (a file:// URL, no
// server), reads back the skinned vertex positions three.js computes for keyframe k of
// the animation (and for the midpoint to keyframe k + 1, through the interpolation), and
// compares them with desal's own linear blend skinning of the same rigs at the same
// times (`cargo run -p desal-rig --example lbs_positions`). Saves a screenshot at frame k.
// Fails on a mismatch above the tolerance, a load error, a console error, a page error,
// or a request the page should not make.
//
// With the positions, three checks of what the page draws, on its canvas's pixels:
// - framing: at every keyframe (up to 12), at the --viewport size and at 1280x720 and
//   480x900, nothing is drawn within 2 pixels of either view's border (the whole body
//   shows) and the drawn region spans at least half the view's height or width (it is
//   not tiny);
// - morph targets: the page has one slider per name in FULL.glb's `extras.targetNames`,
//   and each target at weight 1 moves some vertex of the input by more than 0.1 mm;
// - with --textures, that textures show: at keyframe k, the page drawn with its materials'
//   texture maps and without them (`setTextures(false)`: base colours only) must differ
//   by more than 24 (of 255, in some channel) at half of the drawn pixels of each view,
//   and the textured pixels must be coloured (mean HSV saturation above 0.25): a flat
//   grey or untextured page fails both (the flat colours of an untextured rig have 0.17).
//
// Two pages (crates/rig/src/viewer.rs):
// - the offline page (`DESAL_THREE=.../node_modules/three desal run ...`): three.js is
//   inlined, and any request that is not file:// or data: fails the check;
// - the default page, with --route-three DIR: its import map loads the pinned three.js
//   from the CDN (crates/rig/viewer/three-pin.json) with integrity hashes; those URLs are
//   routed to DIR's files (no network is used), any other request fails the check, and
//   every pinned module must have been fetched. With --tamper-each too, the page is
//   loaded once per pinned module with that module's last byte changed (its newline made
//   a space: still valid JavaScript, only its hash differs), and each load must be
//   blocked by the integrity check (Chromium's console error naming the URL) and the page
//   must report that it could not load three.js; the skinning check is then not run.
//
// Usage: node tests/gltf/view.mjs VIEW.html FULL.glb SIMPLIFIED.glb LBS_POSITIONS
//          [--frame K] [--screenshot PNG] [--tolerance 1e-5] [--chromium /usr/bin/chromium]
//          [--route-three DIR [--tamper-each]] [--textures] [--viewport 1200x700]
// (after `npm ci` in tests/gltf; LBS_POSITIONS is the built example binary).
import { execFileSync } from 'node:child_process';
import { existsSync, readFileSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

const positional = [];
const options = {
  frame: '5',
  screenshot: null,
  tolerance: '1e-5',
  chromium: '/usr/bin/chromium',
  'route-three': null,
  viewport: '1200x700',
};
const flags = new Set(['tamper-each', 'textures']);
const argv = process.argv.slice(2);
for (let i = 0; i < argv.length; i++) {
  if (flags.has(argv[i].slice(2))) options[argv[i].slice(2)] = true;
  else if (argv[i].startsWith('--')) options[argv[i].slice(2)] = argv[++i];
  else positional.push(argv[i]);
}
if (positional.length !== 4 || (options['tamper-each'] && !options['route-three'])) {
  console.error(
    'usage: node view.mjs VIEW.html FULL.glb SIMPLIFIED.glb LBS_POSITIONS [--frame K] [--screenshot PNG] [--route-three DIR [--tamper-each]]',
  );
  process.exit(2);
}
const [page, fullGlb, simplifiedGlb, lbs] = positional;
const viewport = (text) => {
  const [width, height] = text.split('x').map(Number);
  if (!(width > 0 && height > 0)) throw new Error(`--viewport ${text} is not WIDTHxHEIGHT`);
  return { width, height };
};
const tolerance = Number(options.tolerance);
const frame = Number(options.frame);
const threeDir = options['route-three'];
for (const file of [page, fullGlb, simplifiedGlb, lbs, options.chromium, ...(threeDir ? [threeDir] : [])]) {
  if (!existsSync(file)) {
    console.error(`error: ${file} does not exist`);
    process.exit(1);
  }
}

// The pinned CDN URLs of the default page, as desal-rig builds them: cdn + three@version/ + path.
const pin = JSON.parse(readFileSync(new URL('../../crates/rig/viewer/three-pin.json', import.meta.url), 'utf8'));
const cdnBase = `${pin.cdn}three@${pin.version}/`;
const pinnedModules = Object.keys(pin.sha384).filter((path) => path.endsWith('.js'));

// Opens the page in a new tab; collects problems, console errors and the pinned modules
// served. With `threeDir`, the pinned URLs are answered from that folder (`tampered`: the
// path whose last byte is changed) and every other http(s) request is refused.
async function open(browser, tampered = null) {
  const tab = await browser.newPage({ viewport: viewport(options.viewport) });
  const seen = { problems: [], consoleErrors: [], served: [] };
  tab.on('console', (m) => m.type() === 'error' && seen.consoleErrors.push(m.text()));
  tab.on('pageerror', (e) => seen.problems.push(`page error: ${e.message}`));
  const pinnedPath = (url) => {
    const path = url.startsWith(cdnBase) ? url.slice(cdnBase.length) : null;
    return path !== null && pinnedModules.includes(path) ? path : null;
  };
  tab.on('request', (r) => {
    const url = r.url();
    const allowed = ['file:', 'data:', 'blob:'].some((s) => url.startsWith(s)) || (threeDir && pinnedPath(url));
    if (!allowed) seen.problems.push(`network request: ${url}`);
  });
  if (threeDir) {
    await tab.route(/^https?:/, async (route) => {
      const path = pinnedPath(route.request().url());
      if (!path) {
        await route.abort();
        return;
      }
      let body = readFileSync(join(threeDir, path));
      if (path === tampered) {
        body = Buffer.from(body);
        body[body.length - 1] = 0x20;
      }
      seen.served.push(path);
      await route.fulfill({
        status: 200,
        contentType: 'text/javascript; charset=utf-8',
        headers: { 'access-control-allow-origin': '*' },
        body,
      });
    });
  }
  await tab.goto(pathToFileURL(resolve(page)).href);
  await tab.waitForFunction(() => window.desalView && (window.desalView.ready || window.desalView.error), null, {
    timeout: 120000,
  });
  return { tab, seen };
}

// Each pinned module, changed by one byte, must stop the page (see the header).
async function tamperEach(browser) {
  const problems = [];
  for (const path of pinnedModules) {
    const { tab, seen } = await open(browser, path);
    const state = await tab.evaluate(() => ({ ready: window.desalView.ready, error: window.desalView.error }));
    const url = cdnBase + path;
    const blocked = seen.consoleErrors.some((e) => e.includes('integrity') && e.includes(url));
    const ok = !state.ready && /could not be loaded/.test(state.error ?? '') && blocked && seen.served.includes(path);
    console.log(`${path} with one byte changed: ${ok ? 'blocked by its integrity hash, the page did not load' : 'NOT BLOCKED'}`);
    if (!ok) {
      problems.push(
        `tampered ${path}: ready=${state.ready}, error=${state.error}, served=${seen.served}, console=${seen.consoleErrors.join(' | ')}`,
      );
    }
    problems.push(...seen.problems);
    await tab.close();
  }
  return problems;
}

// The names in `extras.targetNames` of every mesh of a .glb, in mesh order, once each.
function targetNames(file) {
  const bytes = readFileSync(file);
  if (bytes.toString('latin1', 0, 4) !== 'glTF') return [];
  const json = JSON.parse(bytes.toString('utf8', 20, 20 + bytes.readUInt32LE(12)));
  const names = [];
  for (const mesh of json.meshes ?? []) for (const n of mesh.extras?.targetNames ?? []) if (!names.includes(n)) names.push(n);
  return names;
}

// Runs in the page: the canvas's pixels, split into its two views, each summarised by the
// drawn region (pixels that are not the background, #f4f4f2): its bounds, whether it
// comes within 2 pixels of the view's border, and its pixels' RGB (when `keep`).
function readViews(keep) {
  const canvas = document.getElementById('canvas');
  const copy = document.createElement('canvas');
  [copy.width, copy.height] = [canvas.width, canvas.height];
  const context = copy.getContext('2d');
  context.drawImage(canvas, 0, 0);
  const { data, width, height } = context.getImageData(0, 0, copy.width, copy.height);
  const half = Math.floor(width / 2);
  return [0, 1].map((side) => {
    const view = { width: half, height, drawn: 0, touches: false, top: height, bottom: -1, left: half, right: -1, pixels: keep ? [] : null };
    for (let y = 0; y < height; y++) {
      for (let x = side * half; x < (side + 1) * half; x++) {
        const i = 4 * (y * width + x);
        const [r, g, b] = [data[i], data[i + 1], data[i + 2]];
        const background = Math.abs(r - 244) + Math.abs(g - 244) + Math.abs(b - 242) <= 12;
        if (keep) view.pixels.push(background ? -1 : (r << 16) | (g << 8) | b);
        if (background) continue;
        view.drawn++;
        const lx = x - side * half;
        view.top = Math.min(view.top, y);
        view.bottom = Math.max(view.bottom, y);
        view.left = Math.min(view.left, lx);
        view.right = Math.max(view.right, lx);
        if (lx < 2 || lx >= half - 2 || y < 2 || y >= height - 2) view.touches = true;
      }
    }
    return view;
  });
}

// Resizes the tab and waits for the page's animation loop to draw at the new size.
async function resize(tab, size) {
  await tab.setViewportSize(size);
  await tab.evaluate(() => new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done))));
}

// The framing check (see the header).
async function framing(tab, times) {
  const problems = [];
  const step = Math.max(1, Math.ceil(times.length / 12));
  const sampled = times.filter((_, i) => i % step === 0);
  const sizes = [viewport(options.viewport), { width: 1280, height: 720 }, { width: 480, height: 900 }].filter(
    (size, i, all) => all.findIndex((s) => s.width === size.width && s.height === size.height) === i,
  );
  for (const size of sizes) {
    await resize(tab, size);
    let smallest = 1;
    for (const t of sampled) {
      await tab.evaluate((time) => void window.desalView.pose(time), t);
      const views = await tab.evaluate(readViews, false);
      views.forEach((v, side) => {
        const which = side === 0 ? 'input' : 'simplified';
        const share = Math.max((v.bottom - v.top + 1) / v.height, (v.right - v.left + 1) / v.width);
        smallest = Math.min(smallest, share);
        if (v.drawn === 0) problems.push(`framing at ${size.width}x${size.height}, t = ${t}: the ${which} view is empty`);
        else if (v.touches) problems.push(`framing at ${size.width}x${size.height}, t = ${t}: the ${which} rig reaches the view's border (cut off)`);
        else if (share < 0.5) problems.push(`framing at ${size.width}x${size.height}, t = ${t}: the ${which} rig spans ${share.toFixed(2)} of the view`);
      });
    }
    const failed = problems.filter((p) => p.startsWith(`framing at ${size.width}x${size.height},`)).length;
    console.log(
      `framing at ${size.width}x${size.height}: ${sampled.length} keyframes, ${failed ? `${failed} views cut off, empty or tiny` : 'both rigs inside each view'}, spanning at least ${(100 * smallest).toFixed(0)}% of its height or width`,
    );
  }
  await resize(tab, viewport(options.viewport));
  return problems;
}

// The morph-target check (see the header).
async function morphs(tab, time) {
  const problems = [];
  const expected = targetNames(fullGlb);
  const state = await tab.evaluate(() => ({
    names: window.desalView.morphTargets,
    sliders: [...document.querySelectorAll('#morphs input[type=range]')].map((s) => s.dataset.morph),
  }));
  if (JSON.stringify(state.names) !== JSON.stringify(expected) || JSON.stringify(state.sliders) !== JSON.stringify(expected)) {
    problems.push(`morph sliders ${JSON.stringify(state.sliders)} (page: ${JSON.stringify(state.names)}), ${fullGlb} names ${JSON.stringify(expected)}`);
    return problems;
  }
  if (!expected.length) return problems;
  const rest = await tab.evaluate((t) => window.desalView.pose(t).full, time);
  const moved = [];
  for (const name of expected) {
    const posed = await tab.evaluate(
      ([n, t]) => {
        window.desalView.setMorph(n, 1);
        const out = window.desalView.pose(t).full;
        window.desalView.setMorph(n, null);
        return out;
      },
      [name, time],
    );
    let most = 0;
    for (let i = 0; i < rest.length; i++) most = Math.max(most, Math.abs(posed[i] - rest[i]));
    moved.push(`${name} ${(1000 * most).toFixed(1)} mm`);
    if (!(most > 1e-4)) problems.push(`morph target ${name} at weight 1 moves no vertex of the input (${most} m)`);
  }
  console.log(`morph sliders: ${expected.length} (${fullGlb}'s targetNames); largest move at weight 1: ${moved.join(', ')}`);
  return problems;
}

// The texture check (see the header).
async function textures(tab, time) {
  const problems = [];
  await tab.evaluate((t) => void window.desalView.pose(t), time);
  const textured = await tab.evaluate(readViews, true);
  await tab.evaluate(() => window.desalView.setTextures(false));
  const plain = await tab.evaluate(readViews, true);
  await tab.evaluate(() => window.desalView.setTextures(true));
  const rgb = (c) => [(c >> 16) & 255, (c >> 8) & 255, c & 255];
  const saturation = ([r, g, b]) => (Math.max(r, g, b) === 0 ? 0 : 1 - Math.min(r, g, b) / Math.max(r, g, b));
  textured.forEach((view, side) => {
    const which = side === 0 ? 'input' : 'simplified';
    let [drawn, differing, saturated] = [0, 0, 0];
    for (let i = 0; i < view.pixels.length; i++) {
      const [a, b] = [view.pixels[i], plain[side].pixels[i]];
      if (a < 0 && b < 0) continue;
      drawn++;
      if (a >= 0) saturated += saturation(rgb(a));
      const [x, y] = [rgb(Math.max(a, 0)), rgb(Math.max(b, 0))];
      if (a < 0 || b < 0 || x.some((c, k) => Math.abs(c - y[k]) > 24)) differing++;
    }
    const share = drawn ? differing / drawn : 0;
    const meanSaturation = view.drawn ? saturated / view.drawn : 0;
    console.log(
      `textures, ${which}: ${drawn} drawn pixels, ${(100 * share).toFixed(1)}% differ from the page without texture maps, mean saturation ${meanSaturation.toFixed(3)}`,
    );
    if (!(share > 0.5)) problems.push(`textures do not show on the ${which} rig: ${(100 * share).toFixed(1)}% of its pixels change without texture maps`);
    if (!(meanSaturation > 0.25)) problems.push(`the ${which} rig is drawn grey: mean saturation ${meanSaturation.toFixed(3)}`);
  });
  return problems;
}

// The skinning check (see the header).
async function skinning(browser) {
  const { tab, seen } = await open(browser);
  const problems = seen.problems;
  const state = await tab.evaluate(() => ({
    error: window.desalView.error,
    times: window.desalView.keyframeTimes,
    counts: window.desalView.counts,
  }));
  if (state.error) throw new Error(`the page did not load: ${state.error} (console: ${seen.consoleErrors.join(' | ')})`);
  if (threeDir) {
    const missing = pinnedModules.filter((p) => !seen.served.includes(p));
    if (missing.length) problems.push(`pinned modules not fetched from the CDN URLs: ${missing.join(', ')}`);
    else console.log(`three ${pin.version}: all ${pinnedModules.length} pinned modules fetched from ${cdnBase} (routed to ${threeDir})`);
  }
  if (!(frame >= 0 && frame + 1 < state.times.length)) {
    throw new Error(`frame ${frame} is not a keyframe with a successor (the animation has ${state.times.length})`);
  }
  const checks = [
    [`keyframe ${frame}`, state.times[frame]],
    [`between keyframes ${frame} and ${frame + 1}`, (state.times[frame] + state.times[frame + 1]) / 2],
  ];
  // The keyframe last, so the screenshot shows frame k.
  for (const [what, time] of checks.reverse()) {
    const three = await tab.evaluate((t) => window.desalView.pose(t), time);
    const desal = JSON.parse(
      execFileSync(lbs, [String(time), fullGlb, simplifiedGlb], { maxBuffer: 1 << 28, encoding: 'utf8' }),
    );
    for (const [mesh, index] of [['full', 0], ['simplified', 1]]) {
      const ours = desal.rigs[index].positions;
      const theirs = three[mesh];
      if (ours.length !== theirs.length) {
        problems.push(`${mesh} at ${what}: three.js has ${theirs.length / 3} vertices, desal ${ours.length / 3}`);
        continue;
      }
      let worst = 0;
      let at = 0;
      for (let i = 0; i < ours.length; i++) {
        const d = Math.abs(ours[i] - theirs[i]);
        if (!(d <= worst)) [worst, at] = [d, Math.floor(i / 3)];
      }
      const ok = worst <= tolerance;
      console.log(
        `${mesh}: ${ours.length / 3} vertices at ${what} (t = ${time} s): max |three.js - desal LBS| = ${worst.toExponential(3)} (vertex ${at}) ${ok ? '<=' : '>'} ${tolerance}`,
      );
      if (!ok) problems.push(`${mesh} at ${what}: three.js and desal differ by ${worst} at vertex ${at}`);
    }
  }
  problems.push(...(await framing(tab, state.times)));
  problems.push(...(await morphs(tab, state.times[frame])));
  if (options.textures) problems.push(...(await textures(tab, state.times[frame])));
  await tab.evaluate((t) => void window.desalView.pose(t), state.times[frame]);
  if (options.screenshot) {
    await tab.screenshot({ path: options.screenshot });
    console.log(`screenshot of keyframe ${frame}: ${options.screenshot}`);
  }
  problems.push(...seen.consoleErrors.map((e) => `console error: ${e}`));
  return problems;
}

const problems = [];
const browser = await chromium.launch({
  executablePath: options.chromium,
  headless: true,
  // WebGL without a GPU: Chromium's software renderer.
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
});
try {
  problems.push(...(await (options['tamper-each'] ? tamperEach(browser) : skinning(browser))));
} catch (e) {
  problems.push(String(e && e.message ? e.message : e));
} finally {
  await browser.close();
}
for (const p of problems) console.error(`error: ${p}`);
process.exit(problems.length ? 1 : 0);
