// Opens desal's view.html in headless Chromium the way a user does (a file:// URL, no
// server), reads back the skinned vertex positions three.js computes for keyframe k of
// the animation (and for the midpoint to keyframe k + 1, through the interpolation), and
// compares them with desal's own linear blend skinning of the same rigs at the same
// times (`cargo run -p desal-rig --example lbs_positions`). Saves a screenshot at frame k.
// Fails on a mismatch above the tolerance, a load error, a console error, a page error,
// or any request that is not file:// or data: (the page must need no network).
//
// Usage: node tests/gltf/view.mjs VIEW.html FULL.glb SIMPLIFIED.glb LBS_POSITIONS
//          [--frame K] [--screenshot PNG] [--tolerance 1e-5] [--chromium /usr/bin/chromium]
// (after `npm ci` in tests/gltf; LBS_POSITIONS is the built example binary).
import { execFileSync } from 'node:child_process';
import { existsSync } from 'node:fs';
import { resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

const positional = [];
const options = { frame: '5', screenshot: null, tolerance: '1e-5', chromium: '/usr/bin/chromium' };
const argv = process.argv.slice(2);
for (let i = 0; i < argv.length; i++) {
  if (argv[i].startsWith('--')) options[argv[i].slice(2)] = argv[++i];
  else positional.push(argv[i]);
}
if (positional.length !== 4) {
  console.error('usage: node view.mjs VIEW.html FULL.glb SIMPLIFIED.glb LBS_POSITIONS [--frame K] [--screenshot PNG]');
  process.exit(2);
}
const [page, fullGlb, simplifiedGlb, lbs] = positional;
const tolerance = Number(options.tolerance);
const frame = Number(options.frame);
for (const file of [page, fullGlb, simplifiedGlb, lbs, options.chromium]) {
  if (!existsSync(file)) {
    console.error(`error: ${file} does not exist`);
    process.exit(1);
  }
}

const problems = [];
const browser = await chromium.launch({
  executablePath: options.chromium,
  headless: true,
  // WebGL without a GPU: Chromium's software renderer.
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
});
try {
  const tab = await browser.newPage({ viewport: { width: 1200, height: 700 } });
  tab.on('console', (m) => m.type() === 'error' && problems.push(`console error: ${m.text()}`));
  tab.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  tab.on('request', (r) => {
    const url = r.url();
    if (!url.startsWith('file:') && !url.startsWith('data:') && !url.startsWith('blob:')) {
      problems.push(`network request: ${url}`);
    }
  });
  await tab.goto(pathToFileURL(resolve(page)).href);
  await tab.waitForFunction(() => window.desalView && (window.desalView.ready || window.desalView.error), null, {
    timeout: 120000,
  });
  const state = await tab.evaluate(() => ({
    error: window.desalView.error,
    times: window.desalView.keyframeTimes,
    counts: window.desalView.counts,
  }));
  if (state.error) throw new Error(`the page did not load: ${state.error}`);
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
} catch (e) {
  problems.push(String(e && e.message ? e.message : e));
} finally {
  await browser.close();
}
for (const p of problems) console.error(`error: ${p}`);
process.exit(problems.length ? 1 : 0);
