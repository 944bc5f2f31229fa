// desal's rig viewer (view.html): the full (input) rig and the simplified rig side by
// side, one clock driving both animations, a wireframe toggle and a caption with the
// vertex counts. desal-rig's `viewer` module inlines this file and both .glb files
// (base64, in #desal-data) into one page, so it works opened from file:// with no
// server; its import map loads three.js from the pinned CDN URLs (with integrity
// hashes), or, for an offline page, from data: URLs of a local copy.
//
// three.js skins with JOINTS_0/WEIGHTS_0 only (four influences a vertex), and GLTFLoader
// normalises those four to sum to 1. glTF allows more sets (JOINTS_1/WEIGHTS_1, ...), and
// desal writes as many as a vertex needs: a kept vertex keeps its exact weights. So the
// page carries the extra sets itself: weights normalised over every set, a vertex shader
// that adds the extra sets' bones, and positions summed over three.js's own skinning of
// each set of four (skinning is linear in the weights).
//
// Test hook, `window.desalView`: `ready` (both rigs loaded and drawn), `error` (the load
// error's text, or null), `keyframeTimes` (the first animation's keyframe times, in
// seconds), `duration`, `counts`, `pose(time)` (stops playback, poses both skeletons at
// `time`, draws, and returns the world-space positions of every vertex of each mesh as
// flat [x, y, z, ...] arrays, skinned by three.js itself: SkinnedMesh.getVertexPosition,
// which applies the bone transforms) and `play()`.
import {
  AmbientLight,
  Box3,
  Color,
  DirectionalLight,
  DoubleSide,
  LoopOnce,
  MeshStandardMaterial,
  PerspectiveCamera,
  Scene,
  ShaderChunk,
  SkinnedMesh,
  Vector3,
  WebGLRenderer,
  AnimationMixer,
} from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const view = { ready: false, error: null, keyframeTimes: [], duration: 0, counts: null };
window.desalView = view;

const data = JSON.parse(document.getElementById('desal-data').textContent);

// The index k of every extra influence set (JOINTS_k/WEIGHTS_k, k >= 1) of a geometry;
// GLTFLoader keeps them as attributes `joints_k`/`weights_k`.
function extraSets(geometry) {
  const sets = [];
  while (geometry.attributes[`joints_${sets.length + 1}`] && geometry.attributes[`weights_${sets.length + 1}`]) {
    sets.push(sets.length + 1);
  }
  return sets;
}

// GLTFLoader calls this on every skinned mesh: normalise over all sets, not the first four.
SkinnedMesh.prototype.normalizeSkinWeights = function normalizeAllSets() {
  const weights = [this.geometry.attributes.skinWeight, ...extraSets(this.geometry).map((k) => this.geometry.attributes[`weights_${k}`])];
  for (let i = 0; i < weights[0].count; i++) {
    let total = 0;
    for (const w of weights) total += w.getX(i) + w.getY(i) + w.getZ(i) + w.getW(i);
    if (total === 0) continue;
    for (const w of weights) w.setXYZW(i, w.getX(i) / total, w.getY(i) / total, w.getZ(i) / total, w.getW(i) / total);
  }
};

// three's skinning shader chunks with the extra sets' bones added.
function skinExtraSets(material, sets) {
  if (sets.length === 0) return;
  const anchor = (chunk, at, extra) => {
    if (!chunk.includes(at)) throw new Error(`three.js's skinning chunk has changed: no '${at}'`);
    return chunk.replace(at, `${extra}\n\t${at}`);
  };
  const each = (line) => sets.flatMap((k) => ['x', 'y', 'z', 'w'].map((c) => line(k, c))).join('\n\t');
  const position = anchor(
    ShaderChunk.skinning_vertex,
    'transformed = ( bindMatrixInverse',
    each((k, c) => `skinned += getBoneMatrix( joints_${k}.${c} ) * skinVertex * weights_${k}.${c};`),
  );
  const normal = anchor(
    ShaderChunk.skinnormal_vertex,
    'skinMatrix = bindMatrixInverse',
    each((k, c) => `skinMatrix += weights_${k}.${c} * getBoneMatrix( joints_${k}.${c} );`),
  );
  const attributes = sets.map((k) => `attribute vec4 joints_${k};\nattribute vec4 weights_${k};`).join('\n');
  material.onBeforeCompile = (shader) => {
    shader.vertexShader = `${attributes}\n${shader.vertexShader}`
      .replace('#include <skinning_vertex>', position)
      .replace('#include <skinnormal_vertex>', normal);
  };
  material.customProgramCacheKey = () => `desal-extra-skin-sets-${sets.length}`;
}

function decodeBase64(text) {
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
  return bytes.buffer;
}

function parseGlb(buffer) {
  return new Promise((resolve, reject) => new GLTFLoader().parse(buffer, '', resolve, reject));
}

// The one skinned mesh desal writes into each file.
function skinnedMeshOf(gltf, which) {
  const meshes = [];
  gltf.scene.traverse((o) => o.isSkinnedMesh && meshes.push(o));
  if (meshes.length !== 1) throw new Error(`the ${which} rig has ${meshes.length} skinned meshes, not 1`);
  return meshes[0];
}

// One side of the page: a scene, its skinned mesh and an animation mixer.
function side(gltf, which, colour) {
  const scene = new Scene();
  scene.background = new Color(0xf4f4f2);
  scene.add(new AmbientLight(0xffffff, 0.9));
  const sun = new DirectionalLight(0xffffff, 1.6);
  sun.position.set(1, 2, 3);
  scene.add(sun);
  scene.add(gltf.scene);
  const mesh = skinnedMeshOf(gltf, which);
  mesh.material = new MeshStandardMaterial({ color: colour, roughness: 0.85, side: DoubleSide });
  const sets = extraSets(mesh.geometry);
  skinExtraSets(mesh.material, sets);
  // Skinned vertices move outside the bind pose's bounds.
  mesh.frustumCulled = false;
  const mixer = new AnimationMixer(gltf.scene);
  // LoopOnce and clamping: time t of the clip is exactly t (a repeating action wraps its
  // end time to 0); the page loops by choosing t itself.
  const actions = gltf.animations.slice(0, 1).map((clip) => {
    const action = mixer.clipAction(clip);
    action.setLoop(LoopOnce, 1);
    action.clampWhenFinished = true;
    action.play();
    return action;
  });
  return { scene, mesh, sets, mixer, actions };
}

function setTime(sides, time) {
  for (const s of sides) {
    for (const action of s.actions) {
      action.paused = false;
      action.enabled = true;
      action.time = time;
    }
    s.mixer.update(0);
    s.scene.updateMatrixWorld(true);
  }
}

// World positions of every vertex, skinned by three.js (getVertexPosition applies the
// bone transforms of skinIndex/skinWeight): once per influence set, summed. Each pass
// ends with bindMatrixInverse, an affine map, so each extra set's pass carries its
// translation once too many, taken off here.
function worldPositions(s) {
  const { mesh, sets } = s;
  const attributes = mesh.geometry.attributes;
  const count = attributes.position.count;
  const sum = new Float64Array(3 * count);
  const v = new Vector3();
  const translation = new Vector3().applyMatrix4(mesh.bindMatrixInverse);
  const [skinIndex, skinWeight] = [attributes.skinIndex, attributes.skinWeight];
  try {
    for (const k of [0, ...sets]) {
      if (k > 0) [attributes.skinIndex, attributes.skinWeight] = [attributes[`joints_${k}`], attributes[`weights_${k}`]];
      for (let i = 0; i < count; i++) {
        mesh.getVertexPosition(i, v);
        if (k > 0) v.sub(translation);
        sum[3 * i] += v.x;
        sum[3 * i + 1] += v.y;
        sum[3 * i + 2] += v.z;
      }
    }
  } finally {
    [attributes.skinIndex, attributes.skinWeight] = [skinIndex, skinWeight];
  }
  const out = new Array(3 * count);
  for (let i = 0; i < count; i++) {
    v.set(sum[3 * i], sum[3 * i + 1], sum[3 * i + 2]).applyMatrix4(mesh.matrixWorld);
    out[3 * i] = v.x;
    out[3 * i + 1] = v.y;
    out[3 * i + 2] = v.z;
  }
  return out;
}

function fail(error) {
  view.error = String(error && error.stack ? error.stack : error);
  document.getElementById('caption').textContent = `could not load the rigs: ${error}`;
  console.error(error);
}

async function main() {
  const [fullGltf, simplifiedGltf] = await Promise.all([
    parseGlb(decodeBase64(data.full)),
    parseGlb(decodeBase64(data.simplified)),
  ]);
  const sides = [side(fullGltf, 'full', 0xb8a898), side(simplifiedGltf, 'simplified', 0x98a8b8)];
  const [full, simplified] = sides;

  const clip = fullGltf.animations[0];
  const times = new Set();
  for (const track of clip ? clip.tracks : []) for (const t of track.times) times.add(t);
  view.keyframeTimes = [...times].sort((a, b) => a - b);
  view.duration = clip ? clip.duration : 0;

  const vertexCount = (s) => s.mesh.geometry.attributes.position.count;
  const triangleCount = (s) => (s.mesh.geometry.index ? s.mesh.geometry.index.count / 3 : vertexCount(s) / 3);
  view.counts = { full: vertexCount(full), simplified: vertexCount(simplified) };
  view.influenceSets = { full: 1 + full.sets.length, simplified: 1 + simplified.sets.length };
  document.getElementById('label-full').textContent =
    `full (input): ${vertexCount(full)} vertices, ${triangleCount(full)} triangles`;
  document.getElementById('label-simplified').textContent =
    `simplified: ${vertexCount(simplified)} vertices, ${triangleCount(simplified)} triangles`;
  document.getElementById('caption').textContent = data.caption;

  const canvas = document.getElementById('canvas');
  const renderer = new WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setScissorTest(true);

  // One camera for both sides, framed on the full rig's bind pose.
  const box = new Box3().setFromBufferAttribute(full.mesh.geometry.attributes.position);
  box.applyMatrix4(full.mesh.matrixWorld);
  const centre = box.getCenter(new Vector3());
  const size = box.getSize(new Vector3()).length();
  const camera = new PerspectiveCamera(35, 1, size / 100, size * 20);
  camera.position.copy(centre).add(new Vector3(0, 0, 1.4 * size));
  const controls = new OrbitControls(camera, canvas);
  controls.target.copy(centre);
  controls.update();

  function draw() {
    const width = canvas.clientWidth;
    const height = canvas.clientHeight;
    if (canvas.width !== Math.floor(width * renderer.getPixelRatio())) renderer.setSize(width, height, false);
    camera.aspect = width / 2 / height;
    camera.updateProjectionMatrix();
    sides.forEach((s, i) => {
      const left = Math.floor((i * width) / 2);
      renderer.setViewport(left, 0, Math.floor(width / 2), height);
      renderer.setScissor(left, 0, Math.floor(width / 2), height);
      renderer.render(s.scene, camera);
    });
  }

  let playing = true;
  let start = performance.now();
  let shown = 0;
  const button = document.getElementById('play');
  function setPlaying(on) {
    if (on && !playing) start = performance.now() - 1000 * shown;
    playing = on;
    button.textContent = on ? 'pause' : 'play';
  }
  button.addEventListener('click', () => setPlaying(!playing));
  document.getElementById('wireframe').addEventListener('change', (e) => {
    for (const s of sides) s.mesh.material.wireframe = e.target.checked;
    draw();
  });

  renderer.setAnimationLoop(() => {
    if (playing && view.duration > 0) {
      shown = ((performance.now() - start) / 1000) % view.duration;
      setTime(sides, shown);
    }
    draw();
  });

  view.pose = (time) => {
    setPlaying(false);
    shown = time;
    setTime(sides, time);
    draw();
    return { full: worldPositions(full), simplified: worldPositions(simplified) };
  };
  view.play = () => setPlaying(true);
  setTime(sides, 0);
  draw();
  view.ready = true;
}

main().catch(fail);
