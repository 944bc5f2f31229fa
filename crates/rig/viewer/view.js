// desal's rig viewer (view.html): the input rig and a simplified level side by side, one
// clock driving every animation, the documents' own materials and textures, a level
// selector, a slider per morph target, a wireframe toggle and a caption. desal-rig's
// `viewer` module inlines this file and every level's .glb (base64, in #desal-data) into
// one page, so it works opened from file:// with no server; its import map loads three.js
// from the pinned CDN URLs (with integrity hashes), or, for an offline page, from data:
// URLs of a local copy.
//
// The page's data (#desal-data): `{"levels": [{"label", "glb"}, ...], "caption"}`. Level
// 0 is the input, shown on the left; levels 1.. are simplified levels (a LOD chain:
// finest first), one at a time on the right, picked by the level selector.
//
// Materials: each primitive keeps the material GLTFLoader builds from its document (base
// colour, textures, double-sidedness); a primitive without a material (desal's own rig
// writer writes none) gets a flat colour per side instead of glTF's default, a metallic
// white that looks black without an environment map.
//
// Skinning: three.js skins with JOINTS_0/WEIGHTS_0 only (four influences a vertex), and
// GLTFLoader normalises those four to sum to 1. A mesh with at most four influences is
// skinned by stock three.js, untouched. glTF allows more sets (JOINTS_1/WEIGHTS_1, ...),
// and desal writes as many as a vertex needs when asked to keep every weight: for a mesh
// with extra sets the page normalises over every set, its vertex shader adds the extra
// sets' bones, and positions are summed over three.js's own skinning of each set of four
// (skinning is linear in the weights).
//
// Framing: one camera for both sides, placed so that the input's skinned bounds over its
// first animation's keyframes fit the view of each side, recomputed whenever the window's
// shape changes (so the whole body shows at any window size).
//
// Test hook, `window.desalView`: `ready` (every level loaded and drawn), `error` (the load
// error's text, or null), `keyframeTimes` (the first animation's keyframe times, in
// seconds), `duration`, `levels` (`{label, vertices, triangles, meshes}` per level),
// `level` (the level on the right), `counts` (`{full, simplified}` vertex counts),
// `morphTargets` (the sliders' names), `pose(time)` (stops playback, poses every level at
// `time`, draws, and returns the world-space positions of every vertex of the input's and
// the shown level's skinned meshes, in the order desal reads them (node order), as flat
// [x, y, z, ...] arrays `{full, simplified}`, skinned by three.js itself:
// SkinnedMesh.getVertexPosition, which applies morph targets and bone transforms),
// `selectLevel(i)`, `setMorph(name, weight)` (null: back to the animation's),
// `setTextures(on)` (false: every material without its texture maps, for the check that
// textures show), `play()`.
import {
  AmbientLight,
  Box3,
  Color,
  DirectionalLight,
  DoubleSide,
  LoopOnce,
  MathUtils,
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

const view = { ready: false, error: null, keyframeTimes: [], duration: 0, counts: null, levels: [], level: 1 };
window.desalView = view;

const data = JSON.parse(document.getElementById('desal-data').textContent);

// Flat colours of primitives without a material: the input's, then the simplified levels'.
const FLAT_COLOURS = [0xb8a898, 0x98a8b8];

// The texture slots of three's standard material that a glTF material fills.
const MAP_SLOTS = ['map', 'normalMap', 'roughnessMap', 'metalnessMap', 'aoMap', 'emissiveMap'];

// The index k of every extra influence set (JOINTS_k/WEIGHTS_k, k >= 1) of a geometry;
// GLTFLoader keeps them as attributes `joints_k`/`weights_k`.
function extraSets(geometry) {
  const sets = [];
  while (geometry.attributes[`joints_${sets.length + 1}`] && geometry.attributes[`weights_${sets.length + 1}`]) {
    sets.push(sets.length + 1);
  }
  return sets;
}

// GLTFLoader calls this on every skinned mesh. Four influences: three's own; more:
// normalise over all sets, not the first four.
const stockNormalize = SkinnedMesh.prototype.normalizeSkinWeights;
SkinnedMesh.prototype.normalizeSkinWeights = function normalizeAllSets() {
  const sets = extraSets(this.geometry);
  if (sets.length === 0) return stockNormalize.call(this);
  const weights = [this.geometry.attributes.skinWeight, ...sets.map((k) => this.geometry.attributes[`weights_${k}`])];
  for (let i = 0; i < weights[0].count; i++) {
    let total = 0;
    for (const w of weights) total += w.getX(i) + w.getY(i) + w.getZ(i) + w.getW(i);
    if (total === 0) continue;
    for (const w of weights) w.setXYZW(i, w.getX(i) / total, w.getY(i) / total, w.getZ(i) / total, w.getW(i) / total);
  }
};

// three's skinning shader chunks with the extra sets' bones added (only called with sets).
function skinExtraSets(material, sets) {
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

// The glTF node an object came from: its own, or its nearest ancestor's (a primitive of a
// mesh with several primitives is a child of the node's group).
function nodeIndexOf(parser, object) {
  for (let o = object; o; o = o.parent) {
    const mapping = parser.associations.get(o);
    if (mapping && mapping.nodes !== undefined) return mapping.nodes;
  }
  return Infinity;
}

// Every skinned mesh of a document, in the order desal reads them: by node, then primitive.
function skinnedMeshesOf(gltf, label) {
  const found = [];
  gltf.scene.traverse((o) => {
    if (!o.isSkinnedMesh) return;
    const mapping = gltf.parser.associations.get(o) || {};
    found.push({ mesh: o, node: nodeIndexOf(gltf.parser, o), gltfMesh: mapping.meshes, primitive: mapping.primitives ?? 0 });
  });
  if (found.length === 0) throw new Error(`the ${label} rig has no skinned mesh`);
  found.sort((a, b) => a.node - b.node || a.primitive - b.primitive);
  return found;
}

// One level: its scene (lights and the document's scene), skinned meshes and mixer.
function loadLevel(gltf, label, index) {
  const scene = new Scene();
  scene.background = new Color(0xf4f4f2);
  scene.add(new AmbientLight(0xffffff, 0.9));
  const sun = new DirectionalLight(0xffffff, 1.6);
  sun.position.set(1, 2, 3);
  scene.add(sun);
  scene.add(gltf.scene);
  const json = gltf.parser.json;
  const meshes = skinnedMeshesOf(gltf, label).map(({ mesh, gltfMesh, primitive }) => {
    const primitiveDef = json.meshes?.[gltfMesh]?.primitives?.[primitive];
    if (!primitiveDef || primitiveDef.material === undefined) {
      mesh.material = new MeshStandardMaterial({
        color: FLAT_COLOURS[Math.min(index, 1)],
        roughness: 0.85,
        side: DoubleSide,
      });
    }
    const sets = extraSets(mesh.geometry);
    if (sets.length > 0) {
      // A material may be shared by meshes of other set counts: this mesh gets its own.
      mesh.material = mesh.material.clone();
      skinExtraSets(mesh.material, sets);
    }
    // Skinned vertices move outside the bind pose's bounds.
    mesh.frustumCulled = false;
    return { mesh, sets };
  });
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
  const vertices = meshes.reduce((n, m) => n + m.mesh.geometry.attributes.position.count, 0);
  const triangles = meshes.reduce((n, { mesh }) => {
    const g = mesh.geometry;
    return n + (g.index ? g.index.count : g.attributes.position.count) / 3;
  }, 0);
  return { label, scene, meshes, mixer, actions, clip: gltf.animations[0], vertices, triangles };
}

// Morph weights the user set with a slider, by target name; the rest follow the animation.
const morphOverrides = new Map();

function applyMorphOverrides(level) {
  for (const { mesh } of level.meshes) {
    if (!mesh.morphTargetDictionary) continue;
    for (const [name, weight] of morphOverrides) {
      const i = mesh.morphTargetDictionary[name];
      if (i !== undefined) mesh.morphTargetInfluences[i] = weight;
    }
  }
}

function setTime(levels, time) {
  for (const level of levels) {
    for (const action of level.actions) {
      action.paused = false;
      action.enabled = true;
      action.time = time;
    }
    level.mixer.update(0);
    applyMorphOverrides(level);
    level.scene.updateMatrixWorld(true);
  }
}

// World positions of every vertex of a level's skinned meshes, skinned by three.js
// (getVertexPosition applies morph targets and the bone transforms of
// skinIndex/skinWeight): once per influence set, summed. Each pass ends with
// bindMatrixInverse, an affine map, so each extra set's pass carries its translation once
// too many, taken off here.
function worldPositions(level) {
  const out = [];
  for (const { mesh, sets } of level.meshes) {
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
    for (let i = 0; i < count; i++) {
      v.set(sum[3 * i], sum[3 * i + 1], sum[3 * i + 2]).applyMatrix4(mesh.matrixWorld);
      out.push(v.x, v.y, v.z);
    }
  }
  return out;
}

// The input's world-space skinned bounds over (at most 64 of) its keyframe times.
function animatedBounds(level, times) {
  const box = new Box3();
  const step = Math.max(1, Math.ceil(times.length / 64));
  const sampled = times.filter((_, i) => i % step === 0);
  for (const t of sampled.length ? sampled : [0]) {
    setTime([level], t);
    for (const { mesh } of level.meshes) {
      mesh.computeBoundingBox();
      box.union(mesh.boundingBox.clone().applyMatrix4(mesh.matrixWorld));
    }
  }
  return box;
}

// Places `camera` on its current line of sight to the box's centre, at the smallest
// distance from which every corner of `box` is inside the view (with a margin): for a
// corner at (x, y, z) in the camera's frame around the centre, |x| <= (d - z) tan(h/2)
// and |y| <= (d - z) tan(v/2).
function frameBox(camera, controls, box, aspect) {
  const centre = box.getCenter(new Vector3());
  const direction = camera.position.clone().sub(controls.target);
  if (direction.lengthSq() === 0) direction.set(0, 0, 1);
  direction.normalize();
  camera.aspect = aspect;
  camera.position.copy(centre).add(direction);
  camera.lookAt(centre);
  camera.updateMatrixWorld(true);
  const toCamera = camera.matrixWorldInverse;
  const tanV = Math.tan(MathUtils.degToRad(camera.fov / 2));
  const tanH = tanV * aspect;
  const margin = 1.06;
  const origin = centre.clone().applyMatrix4(toCamera);
  let distance = 0;
  for (let corner = 0; corner < 8; corner++) {
    const p = new Vector3(
      corner & 1 ? box.max.x : box.min.x,
      corner & 2 ? box.max.y : box.min.y,
      corner & 4 ? box.max.z : box.min.z,
    )
      .applyMatrix4(toCamera)
      .sub(origin);
    // The camera looks down its -z: a corner nearer to it has a larger z.
    distance = Math.max(distance, p.z + (margin * Math.abs(p.x)) / tanH, p.z + (margin * Math.abs(p.y)) / tanV);
  }
  const size = box.getSize(new Vector3()).length();
  camera.position.copy(centre).addScaledVector(direction, distance);
  camera.near = Math.max(distance - size, distance / 100);
  camera.far = distance + 2 * size;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();
}

function fail(error) {
  view.error = String(error && error.stack ? error.stack : error);
  document.getElementById('caption').textContent = `could not load the rigs: ${error}`;
  console.error(error);
}

async function main() {
  if (!Array.isArray(data.levels) || data.levels.length < 2) throw new Error('the page needs the input and at least one simplified level');
  const gltfs = await Promise.all(data.levels.map((level) => parseGlb(decodeBase64(level.glb))));
  const levels = gltfs.map((gltf, i) => loadLevel(gltf, data.levels[i].label, i));
  const input = levels[0];
  let shownLevel = 1;

  const times = new Set();
  for (const track of input.clip ? input.clip.tracks : []) for (const t of track.times) times.add(t);
  view.keyframeTimes = [...times].sort((a, b) => a - b);
  view.duration = input.clip ? input.clip.duration : 0;
  view.levels = levels.map((l) => ({ label: l.label, vertices: l.vertices, triangles: l.triangles, meshes: l.meshes.length }));
  view.influenceSets = levels.map((l) => 1 + Math.max(0, ...l.meshes.map((m) => m.sets.length)));

  // The level selector (levels 1..: the simplified ones).
  const select = document.getElementById('level');
  levels.slice(1).forEach((level, i) => {
    const option = document.createElement('option');
    option.value = String(i + 1);
    option.textContent = `${level.label}: ${level.vertices} vertices`;
    select.appendChild(option);
  });
  document.getElementById('label-full').textContent =
    `${input.label}: ${input.vertices} vertices, ${input.triangles} triangles`;
  function showLevel(i) {
    if (!(i >= 1 && i < levels.length)) throw new Error(`no simplified level ${i} (levels 1 to ${levels.length - 1})`);
    shownLevel = i;
    view.level = i;
    select.value = String(i);
    const level = levels[i];
    view.counts = { full: input.vertices, simplified: level.vertices };
    document.getElementById('label-simplified').textContent =
      `${level.label}: ${level.vertices} vertices, ${level.triangles} triangles`;
  }
  showLevel(1);
  select.addEventListener('change', () => {
    showLevel(Number(select.value));
    draw();
  });

  // A slider per morph target name (over every level's meshes, in order of appearance).
  const morphNames = [];
  for (const level of levels) {
    for (const { mesh } of level.meshes) {
      for (const name of Object.keys(mesh.morphTargetDictionary || {})) if (!morphNames.includes(name)) morphNames.push(name);
    }
  }
  view.morphTargets = morphNames;
  const panel = document.getElementById('morphs');
  for (const name of morphNames) {
    const label = document.createElement('label');
    const slider = document.createElement('input');
    Object.assign(slider, { type: 'range', min: '0', max: '1', step: '0.01', value: '0' });
    slider.dataset.morph = name;
    slider.addEventListener('input', () => setMorph(name, Number(slider.value)));
    label.append(slider, ` ${name}`);
    panel.appendChild(label);
  }
  if (morphNames.length > 0) {
    const reset = document.createElement('button');
    reset.type = 'button';
    reset.textContent = 'animate the face';
    reset.addEventListener('click', () => {
      for (const name of morphNames) setMorph(name, null);
    });
    panel.appendChild(reset);
  }
  panel.hidden = morphNames.length === 0;
  function setMorph(name, weight) {
    if (!morphNames.includes(name)) throw new Error(`no morph target ${name}`);
    if (weight === null) morphOverrides.delete(name);
    else morphOverrides.set(name, weight);
    setTime(levels, shown);
    draw();
  }

  const canvas = document.getElementById('canvas');
  const renderer = new WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setScissorTest(true);

  // One camera for both sides, framed on the input's animated bounds.
  const bounds = animatedBounds(input, view.keyframeTimes);
  const camera = new PerspectiveCamera(30, 1, 0.01, 100);
  camera.position.set(0, 0, 1);
  const controls = new OrbitControls(camera, canvas);
  let framedAspect = null;

  function draw() {
    const width = canvas.clientWidth;
    const height = canvas.clientHeight;
    if (canvas.width !== Math.floor(width * renderer.getPixelRatio()) || canvas.height !== Math.floor(height * renderer.getPixelRatio())) {
      renderer.setSize(width, height, false);
    }
    const aspect = width / 2 / height;
    if (aspect !== framedAspect) {
      frameBox(camera, controls, bounds, aspect);
      framedAspect = aspect;
    }
    [input, levels[shownLevel]].forEach((level, i) => {
      const left = Math.floor((i * width) / 2);
      renderer.setViewport(left, 0, Math.floor(width / 2), height);
      renderer.setScissor(left, 0, Math.floor(width / 2), height);
      renderer.render(level.scene, camera);
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
  const allMaterials = () => levels.flatMap((l) => l.meshes.map((m) => m.mesh.material));
  document.getElementById('wireframe').addEventListener('change', (e) => {
    for (const material of allMaterials()) material.wireframe = e.target.checked;
    draw();
  });

  renderer.setAnimationLoop(() => {
    if (playing && view.duration > 0) {
      shown = ((performance.now() - start) / 1000) % view.duration;
      setTime(levels, shown);
    }
    draw();
  });

  view.pose = (time) => {
    setPlaying(false);
    shown = time;
    setTime(levels, time);
    draw();
    return { full: worldPositions(input), simplified: worldPositions(levels[shownLevel]) };
  };
  view.selectLevel = (i) => {
    showLevel(i);
    draw();
  };
  view.setMorph = setMorph;
  view.setTextures = (on) => {
    for (const material of new Set(allMaterials())) {
      material.userData.desalMaps ??= Object.fromEntries(MAP_SLOTS.map((slot) => [slot, material[slot]]));
      for (const slot of MAP_SLOTS) material[slot] = on ? material.userData.desalMaps[slot] : null;
      material.needsUpdate = true;
    }
    draw();
  };
  view.play = () => setPlaying(true);
  setTime(levels, 0);
  draw();
  document.getElementById('caption').textContent = data.caption;
  view.ready = true;
}

main().catch(fail);
