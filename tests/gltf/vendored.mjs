// Checks that the three.js files desal vendors (crates/rig/viewer/three/, embedded in
// view.html) are byte for byte the files of the npm package pinned in package-lock.json,
// and that VERSION is that package's version.
//
// Usage: node tests/gltf/vendored.mjs   (after `npm ci` in tests/gltf)
import { readFileSync, readdirSync, statSync } from 'node:fs';
import { join, relative } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = fileURLToPath(new URL('.', import.meta.url));
const vendored = join(here, '../../crates/rig/viewer/three');
const npm = join(here, 'node_modules/three');

function files(dir) {
  return readdirSync(dir).flatMap((name) => {
    const path = join(dir, name);
    return statSync(path).isDirectory() ? files(path) : [path];
  });
}

const pinned = JSON.parse(readFileSync(join(npm, 'package.json'), 'utf8')).version;
let failed = false;
let compared = 0;
for (const path of files(vendored)) {
  const name = relative(vendored, path);
  if (name === 'VERSION') {
    const version = readFileSync(path, 'utf8').trim();
    if (version !== pinned) {
      console.error(`error: VERSION says three ${version}, npm ci installed ${pinned}`);
      failed = true;
    }
    continue;
  }
  let original;
  try {
    original = readFileSync(join(npm, name));
  } catch {
    console.error(`error: ${name} is vendored but not in npm three ${pinned}`);
    failed = true;
    continue;
  }
  if (!original.equals(readFileSync(path))) {
    console.error(`error: vendored ${name} differs from npm three ${pinned}'s`);
    failed = true;
  }
  compared++;
}
if (compared < 7) {
  console.error(`error: only ${compared} vendored files found under ${vendored}`);
  failed = true;
}
console.log(`three ${pinned}: ${compared} vendored files compared with the npm package${failed ? ', MISMATCH' : ', all equal'}`);
process.exit(failed ? 1 : 0);
