// Validates glTF files with the Khronos glTF-Validator (npm `gltf-validator`) and fails
// when any has an error, or a warning about skinning, joints, weights or animations.
//
// Usage: node tests/gltf/validate.mjs FILE.glb...   (after `npm ci` in tests/gltf)
// Prints one summary line per file, and every issue of warning severity or worse.
import { readFileSync } from 'node:fs';
import validator from 'gltf-validator';

// Issue codes (and JSON pointers) that concern the skin: a warning among these fails.
const SKINNING = /SKIN|JOINT|WEIGHT|ANIMATION|INVERSE_BIND|NODE_SKINNED/;
const SEVERITY = ['error', 'warning', 'info', 'hint'];

let failed = false;
for (const file of process.argv.slice(2)) {
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), { maxIssues: 0 });
  const { numErrors, numWarnings, numInfos, numHints, messages } = report.issues;
  const skinning = messages.filter(
    (m) => m.severity === 1 && (SKINNING.test(m.code) || /skin|joint|weight|animation/i.test(m.pointer ?? '')),
  );
  console.log(
    `${file}: ${numErrors} errors, ${numWarnings} warnings (${skinning.length} about skinning), ${numInfos} infos, ${numHints} hints; validator ${report.validatorVersion}`,
  );
  for (const m of messages.filter((m) => m.severity <= 1)) {
    console.log(`  ${SEVERITY[m.severity]} ${m.code} ${m.pointer ?? ''}: ${m.message}`);
  }
  if (numErrors > 0 || skinning.length > 0) failed = true;
}
if (process.argv.length < 3) {
  console.error('usage: node validate.mjs FILE.glb...');
  process.exit(2);
}
process.exit(failed ? 1 : 0);
