// Loads glTF files with three.js's GLTFLoader under node (the parse API, no browser) and
// prints what three.js builds from each: its skinned meshes with their triangles and
// morph targets (with names), materials and animations. For a file with `MSFT_lod`
// (desal's `simplified-lods.glb`), three.js, which does not know the extension, shows
// level 0; the lower levels' nodes are outside the scene, so each level's node is also
// loaded as its own scene (`parser.getDependency('node', i)`) to check that three.js
// builds every level. Fails on any load error, a skinned mesh without a skeleton or
// a mesh that lost its morph targets.
//
// Usage: node tests/gltf/lods.mjs FILE.glb...   (three installed as .ci/run does)
import { readFileSync } from 'node:fs';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';

const loader = new GLTFLoader();
// Node has no image decoder (three's loaders need a browser's `self`/`createImageBitmap`):
// textures are not decoded here, only counted from the document; the viewer's Chromium
// check (view.mjs --textures) is where textures are seen drawn.
loader.register(() => ({ name: 'desal_no_image_decoding', loadTexture: () => Promise.resolve(null) }));
let failed = false;
const fail = (message) => {
  console.log(`  FAIL ${message}`);
  failed = true;
};

function describe(object) {
  const meshes = [];
  object.traverse((o) => {
    if (!o.isMesh) return;
    const triangles = (o.geometry.index ? o.geometry.index.count : o.geometry.attributes.position.count) / 3;
    const targets = o.geometry.morphAttributes.position?.length ?? 0;
    const names = Object.keys(o.morphTargetDictionary ?? {});
    if (o.isSkinnedMesh && !o.skeleton) fail(`${o.name}: a skinned mesh without a skeleton`);
    if (targets !== names.length) fail(`${o.name}: ${targets} morph targets, ${names.length} names`);
    meshes.push(`${o.name}${o.isSkinnedMesh ? ' (skinned)' : ''} ${triangles} triangles, targets [${names.join(', ')}]`);
  });
  return meshes;
}

for (const file of process.argv.slice(2)) {
  const bytes = readFileSync(file);
  const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
  try {
    const gltf = await loader.parseAsync(buffer, '');
    const materials = new Set();
    gltf.scene.traverse((o) => o.isMesh && materials.add(o.material.name));
    const textures = gltf.parser.json.textures?.length ?? 0;
    console.log(
      `${file}: ${gltf.animations.length} animations, materials [${[...materials].join(', ')}], ${textures} textures`,
    );
    for (const m of describe(gltf.scene)) console.log(`  ${m}`);
    const nodes = gltf.parser.json.nodes ?? [];
    for (const [i, node] of nodes.entries()) {
      const ids = node.extensions?.MSFT_lod?.ids;
      if (!ids) continue;
      for (const id of ids) {
        const level = await gltf.parser.getDependency('node', id);
        for (const m of describe(level)) console.log(`  MSFT_lod of node ${i}: node ${id}: ${m}`);
      }
    }
  } catch (error) {
    fail(`${file}: ${error.message}`);
  }
}
if (process.argv.length < 3) {
  console.error('usage: node lods.mjs FILE.glb...');
  process.exit(2);
}
process.exit(failed ? 1 : 0);
