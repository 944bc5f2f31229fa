// Checks the three.js pin (crates/rig/viewer/three-pin.json, compiled into desal: the
// version, the CDN, the sha384 of every file view.html uses) against the npm package
// .ci/run installs from it (tests/gltf/node_modules/three): the package's version, each
// pinned file's sha384, and that every static import of a pinned module is the bare
// `three` (the page's import map names it) or a relative import of another pinned module.
// So the page's integrity entries cover every module the browser fetches: a relative
// import resolves to a CDN URL of its own, which needs its own entry. And the README's
// offline recipe (`npm install ... three@VERSION`) names the pinned version.
//
// Usage: node tests/gltf/three-pin.mjs            check (exit 1 on a mismatch)
//        node tests/gltf/three-pin.mjs --version  print the pinned version
//        node tests/gltf/three-pin.mjs --write    rewrite the pin's version and hashes from the
//                                                 installed package, after an upgrade:
//   (cd tests/gltf && npm install --no-save three@NEW) && node tests/gltf/three-pin.mjs --write
import { createHash } from 'node:crypto';
import { existsSync, readFileSync, writeFileSync } from 'node:fs';
import { dirname, join, posix } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const pinFile = join(here, '../../crates/rig/viewer/three-pin.json');
const npm = join(here, 'node_modules/three');
const pin = JSON.parse(readFileSync(pinFile, 'utf8'));

if (process.argv[2] === '--version') {
  console.log(pin.version);
  process.exit(0);
}
if (!existsSync(join(npm, 'package.json'))) {
  console.error(`error: ${npm} is missing: run (cd tests/gltf && npm install --no-save three@${pin.version})`);
  process.exit(1);
}

const sha384 = (bytes) => `sha384-${createHash('sha384').update(bytes).digest('base64')}`;
const installed = JSON.parse(readFileSync(join(npm, 'package.json'), 'utf8')).version;

if (process.argv[2] === '--write') {
  pin.version = installed;
  for (const path of Object.keys(pin.sha384)) pin.sha384[path] = sha384(readFileSync(join(npm, path)));
  writeFileSync(pinFile, `${JSON.stringify(pin, null, 2)}\n`);
  console.log(`three ${installed}: ${Object.keys(pin.sha384).length} hashes written to ${pinFile}`);
  process.exit(0);
}

// The specifiers of a module's static `import ... from '...'` / `export ... from '...'`
// statements (three writes the `from` on the statement's last line, which starts with
// `import`, `export` or `}`), as desal-rig's viewer finds them.
function imports(source) {
  const found = [];
  for (const line of source.split('\n')) {
    const trimmed = line.trimStart();
    if (!['import ', 'export ', '} from'].some((p) => trimmed.startsWith(p))) continue;
    const m = line.match(/from (['"])([^'"]*)\1/);
    if (m) found.push(m[2]);
  }
  return found;
}

const problems = [];
if (installed !== pin.version) problems.push(`the pin says three ${pin.version}, ${npm} is ${installed}`);
let modules = 0;
for (const [path, pinned] of Object.entries(pin.sha384)) {
  const file = join(npm, path);
  if (!existsSync(file)) {
    problems.push(`${path} is pinned but not in npm three ${installed}`);
    continue;
  }
  const bytes = readFileSync(file);
  const found = sha384(bytes);
  if (found !== pinned) problems.push(`${path}: npm three ${installed} has ${found}, the pin ${pinned}`);
  if (!path.endsWith('.js')) continue;
  modules++;
  const source = bytes.toString('utf8');
  if (/\bimport\s*\(/.test(source)) problems.push(`${path} has a dynamic import(), which no integrity entry covers`);
  for (const specifier of imports(source)) {
    if (specifier === 'three') continue;
    const target = posix.normalize(posix.join(posix.dirname(path), specifier));
    if (!specifier.startsWith('.')) problems.push(`${path} imports '${specifier}', which the page's import map lacks`);
    else if (!(target in pin.sha384)) problems.push(`${path} imports ${target}, which is not pinned`);
  }
}
// The README's offline recipe names the version to install: the pinned one.
const readme = readFileSync(join(here, '../../README.md'), 'utf8');
const named = [...readme.matchAll(/three@(\d+\.\d+\.\d+)/g)].map((m) => m[1]);
if (!named.length || named.some((v) => v !== pin.version)) {
  problems.push(`README.md names three@${named.join(', three@') || '(none)'}; the pin is ${pin.version}`);
}
for (const p of problems) console.error(`error: ${p}`);
console.log(
  `three ${pin.version}: ${Object.keys(pin.sha384).length} pinned files (${modules} modules) checked against npm three ${installed}${problems.length ? ', MISMATCH' : ': hashes equal, every import pinned'}`,
);
process.exit(problems.length ? 1 : 0);
