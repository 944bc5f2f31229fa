// Opens desal's view.html in headless Chromium the way a user does (a file:// URL, no
// server), reads back the skinned vertex positions three.js computes for keyframe k of
// the animation (and for the midpoint to keyframe k + 1, through the interpolation), and
// compares them with desal's own linear blend skinning of the same rigs at the same
// times (`cargo run -p desal-rig --example lbs_positions`). Saves a screenshot at frame k.
// Fails on a mismatch above the tolerance, a load error, a console error, a page error,
// or a request the page should not make.
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
//          [--route-three DIR [--tamper-each]]
// (after `npm ci` in tests/gltf; LBS_POSITIONS is the built example binary).
import { execFileSync } from 'node:child_process';
import { existsSync, readFileSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

const positional = [];
const options = { frame: '5', screenshot: null, tolerance: '1e-5', chromium: '/usr/bin/chromium', 'route-three': null };
const flags = new Set(['tamper-each']);
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
  const tab = await browser.newPage({ viewport: { width: 1200, height: 700 } });
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
