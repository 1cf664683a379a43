// The studio page: parameters -> /studio/api/mesh (binary, see rmt_server::studio::wire) ->
// three.js view; compare mode (two scenes, one camera); sculpt mode (rays picked here, brush on
// the server, only the re-meshed chunks come back); LOD mode (a fly camera over a multiresolution
// world: the server re-meshes what the viewer's move changed, levels coloured on demand, strokes
// at any distance). State for tests is in window.studio.
import * as THREE from './three.module.min.js';
import { OrbitControls } from './OrbitControls.js';

const $ = (id) => document.getElementById(id);
const BACKGROUND = 0xe9ecf1;

// ---- state visible to tests and to the user --------------------------------------------------
const studio = {
  mode: 'object',
  ready: false, // first mesh shown
  meshes: 0, // meshes shown so far
  triangles: [null, null], // A, B
  lastUpdateMs: null, // parameter change -> updated frame, last one
  lastBytes: null, // bytes of the last mesh reply
  edits: 0, // sculpt edits shown
  lastEditMs: null, // stroke sent -> updated frame
  lastChunks: null,
  sculptTriangles: null,
  busy: 0,
  error: null,
  swapped: false,
  // LOD mode: chunks and triangles shown, per level; viewer moves and strokes answered.
  lod: { chunks: 0, triangles: 0, levels: [], moves: 0, lastMoveMs: null, lastRemeshed: null, strokes: 0, lastStrokeMs: null, viewer: null, worlds: 0 },
};
window.studio = studio;

// ---- wire format ----------------------------------------------------------------------------
const LITTLE = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;

function decode(buffer) {
  const dv = new DataView(buffer);
  const magic = String.fromCharCode(...new Uint8Array(buffer, 0, 4));
  if (magic !== 'RMTS') throw new Error('not a studio mesh reply');
  if (dv.getUint32(4, true) !== 1) throw new Error('unknown mesh format version');
  const jsonLen = dv.getUint32(8, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 12, jsonLen)));
  let at = 12 + jsonLen;
  const count = dv.getUint32(at, true);
  at += 4;
  const f32 = (n) => {
    let a;
    if (LITTLE) a = new Float32Array(buffer, at, n);
    else { a = new Float32Array(n); for (let i = 0; i < n; i++) a[i] = dv.getFloat32(at + 4 * i, true); }
    at += 4 * n;
    return a;
  };
  const u32 = (n) => {
    let a;
    if (LITTLE) a = new Uint32Array(buffer, at, n);
    else { a = new Uint32Array(n); for (let i = 0; i < n; i++) a[i] = dv.getUint32(at + 4 * i, true); }
    at += 4 * n;
    return a;
  };
  const parts = [];
  for (let p = 0; p < count; p++) {
    const id = dv.getUint32(at, true), v = dv.getUint32(at + 4, true);
    const t = dv.getUint32(at + 8, true), flags = dv.getUint32(at + 12, true);
    at += 16;
    const positions = f32(3 * v);
    const normals = flags & 1 ? f32(3 * v) : null;
    const indices = u32(3 * t);
    const ratios = flags & 2 ? f32(t) : null;
    parts.push({ id, positions, normals, indices, ratios });
  }
  return { header, parts };
}

async function fetchMesh(url, options) {
  const response = await fetch(url, options);
  const buffer = await response.arrayBuffer();
  if (!response.ok) {
    let message = `${response.status} ${response.statusText}`;
    try { message = JSON.parse(new TextDecoder().decode(buffer)).error || message; } catch (_) { /* not JSON */ }
    const err = new Error(message);
    err.status = response.status;
    throw err;
  }
  const decoded = decode(buffer);
  decoded.bytes = buffer.byteLength;
  return decoded;
}

function showError(message) {
  studio.error = message;
  const box = $('error');
  box.textContent = message || '';
  box.hidden = !message;
}

// ---- three.js view ----------------------------------------------------------------------------
const canvas = $('view3d');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
renderer.setClearColor(BACKGROUND, 1);
renderer.setScissorTest(true);
const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);
camera.position.set(2.2, 1.6, 3.0);
const controls = new OrbitControls(camera, canvas);
controls.enableDamping = false;
controls.addEventListener('change', () => requestRender());

function makeScene() {
  const scene = new THREE.Scene();
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8f99, 1.6));
  // A key light that follows the camera (placed at it on every draw): every side is lit.
  const follow = new THREE.DirectionalLight(0xffffff, 1.6);
  scene.add(follow, follow.target);
  scene.userData.follow = follow;
  return scene;
}
const scenes = [makeScene(), makeScene(), makeScene(), makeScene()]; // A, B, sculpt, LOD
const shown = [null, null]; // current THREE.Group per compare side

let renderQueued = false;
const frameWaiters = [];
function requestRender() {
  if (renderQueued) return;
  renderQueued = true;
  requestAnimationFrame(() => {
    renderQueued = false;
    draw();
    const done = frameWaiters.splice(0);
    done.forEach((f) => f(performance.now()));
  });
}
function nextFrame() {
  return new Promise((resolve) => { frameWaiters.push(resolve); requestRender(); });
}

function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) || canvas.height !== Math.floor(h * renderer.getPixelRatio())) {
    renderer.setSize(w, h, false);
  }
  return [w, h];
}
window.addEventListener('resize', () => requestRender());

function draw() {
  const [w, h] = resize();
  for (const s of scenes) {
    s.userData.follow.position.copy(camera.position);
    s.userData.follow.target.position.copy(controls.target);
  }
  if (studio.mode === 'compare') {
    const half = Math.floor(w / 2);
    camera.aspect = half / h;
    camera.updateProjectionMatrix();
    const left = studio.swapped ? scenes[1] : scenes[0];
    const right = studio.swapped ? scenes[0] : scenes[1];
    renderer.setViewport(0, 0, half, h); renderer.setScissor(0, 0, half, h); renderer.render(left, camera);
    renderer.setViewport(half, 0, w - half, h); renderer.setScissor(half, 0, w - half, h); renderer.render(right, camera);
  } else {
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    renderer.setViewport(0, 0, w, h); renderer.setScissor(0, 0, w, h);
    const scene = { sculpt: scenes[2], lod: scenes[3] }[studio.mode] || scenes[0];
    renderer.render(scene, camera);
  }
}

// ---- materials and meshes ---------------------------------------------------------------------
function shading() { return document.querySelector('input[name=shading]:checked').value; }
function colourByRatio() { return $('colour-ratio').checked; }

const COLOUR = [new THREE.Color(0x9fb3d1), new THREE.Color(0xd1a98f)];
function blindCompare() { return studio.mode === 'compare' && $('blind').checked; }
function surfaceMaterial(side, useVertexColours) {
  const mode = shading();
  return new THREE.MeshStandardMaterial({
    // Blind compare paints both sides alike: a colour per configuration would name the sides.
    color: useVertexColours ? 0xffffff : (blindCompare() ? COLOUR[0] : COLOUR[side] || COLOUR[0]),
    vertexColors: useVertexColours,
    flatShading: mode !== 'smooth',
    roughness: 0.75,
    metalness: 0.0,
    side: THREE.DoubleSide,
    polygonOffset: mode === 'wireframe',
    polygonOffsetFactor: 1,
    polygonOffsetUnits: 1,
  });
}
const wireMaterial = new THREE.MeshBasicMaterial({ color: 0x26324a, wireframe: true, transparent: true, opacity: 0.55 });

// Blue (1, equilateral) -> green -> yellow -> red (>= 3, slivers).
function ratioColour(r, out) {
  const t = r > 0 ? Math.min(Math.max((r - 1) / 2, 0), 1) : 1;
  const stops = [[0.23, 0.44, 0.85], [0.23, 0.85, 0.44], [0.91, 0.82, 0.23], [0.91, 0.33, 0.23]];
  const x = t * 3, i = Math.min(Math.floor(x), 2), f = x - i;
  for (let k = 0; k < 3; k++) out[k] = stops[i][k] * (1 - f) + stops[i + 1][k] * f;
  return out;
}

function geometryOf(part) {
  let g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(part.positions, 3));
  g.setIndex(new THREE.BufferAttribute(part.indices, 1));
  if (part.normals) g.setAttribute('normal', new THREE.BufferAttribute(part.normals, 3));
  else if (part.indices.length) g.computeVertexNormals();
  if (part.ratios && colourByRatio()) {
    g = g.toNonIndexed();
    const colours = new Float32Array(part.ratios.length * 9);
    const c = [0, 0, 0];
    for (let t = 0; t < part.ratios.length; t++) {
      ratioColour(part.ratios[t], c);
      for (let k = 0; k < 3; k++) colours.set(c, 9 * t + 3 * k);
    }
    g.setAttribute('color', new THREE.BufferAttribute(colours, 3));
  }
  g.computeBoundingSphere();
  g.computeBoundingBox();
  return g;
}

function meshObjects(geometry, side) {
  const group = new THREE.Group();
  group.add(new THREE.Mesh(geometry, surfaceMaterial(side, !!geometry.getAttribute('color'))));
  if (shading() === 'wireframe') group.add(new THREE.Mesh(geometry, wireMaterial));
  return group;
}

function disposeGroup(group) {
  if (!group) return;
  group.traverse((o) => {
    if (o.geometry) o.geometry.dispose();
    if (o.material && o.material !== wireMaterial) o.material.dispose();
  });
  group.removeFromParent();
}

function frame(box) {
  const sphere = box.getBoundingSphere(new THREE.Sphere());
  if (!isFinite(sphere.radius) || sphere.radius <= 0) return;
  const dir = camera.position.clone().sub(controls.target).normalize();
  if (dir.lengthSq() === 0) dir.set(0.5, 0.4, 0.75).normalize();
  const dist = sphere.radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 1.05;
  controls.target.copy(sphere.center);
  camera.position.copy(sphere.center).addScaledVector(dir, dist);
  camera.near = dist / 100; camera.far = dist * 10;
  camera.updateProjectionMatrix();
  controls.update();
}

// ---- parameter panels -------------------------------------------------------------------------
let schema = null;
const panels = [];

function field(container, spec, value) {
  const row = document.createElement('div');
  row.className = 'field';
  row.dataset.name = spec.name;
  const label = document.createElement('label');
  label.textContent = spec.name.replace(/_/g, ' ');
  label.title = spec.help || '';
  let input;
  if (spec.choices) {
    input = document.createElement('select');
    // No default on the command line (e.g. clustering: integrated, or none for marching
    // cubes): an empty choice leaves the option out, as on the command line.
    const choices = spec.default === null || spec.default === undefined ? ['', ...spec.choices] : spec.choices;
    for (const c of choices) {
      const o = document.createElement('option');
      o.value = c;
      o.textContent = c === '' ? '(default)' : c;
      input.appendChild(o);
    }
    input.value = value ?? spec.default ?? '';
  } else {
    input = document.createElement('input');
    input.type = 'text';
    input.value = value ?? spec.default ?? '';
    input.placeholder = spec.default ?? 'default';
    input.spellcheck = false;
  }
  input.name = spec.name;
  input.title = spec.help || '';
  row.append(label, input);
  container.appendChild(row);
  return input;
}

// One configuration's inputs; `onChange` is called (debounced) when any changes.
function buildPanel(container, defaults, onChange, kind) {
  container.querySelectorAll('.field').forEach((e) => e.remove());
  const inputs = {};
  const own = kind === 'sculpt' || kind === 'lod' ? schema[kind] : null;
  const specs = own ? own.parameters : schema.parameters;
  const objects = own ? own.objects : schema.objects;
  const objectSpec = { name: 'object', help: 'the sampled object', choices: objects.map((o) => o.name), default: defaults.object };
  inputs.object = field(container, objectSpec, defaults.object);
  const paramBox = document.createElement('div');
  container.appendChild(paramBox);
  for (const spec of specs) inputs[spec.name] = field(container, spec, defaults[spec.name]);
  const objectParams = {};
  const showObjectParams = () => {
    paramBox.textContent = '';
    const o = objects.find((x) => x.name === inputs.object.value);
    for (const spec of o ? o.parameters : []) {
      objectParams[spec.name] = objectParams[spec.name] || { spec, value: '' };
      const input = field(paramBox, spec, objectParams[spec.name].value);
      input.addEventListener('input', () => { objectParams[spec.name].value = input.value; changed(); });
      input.addEventListener('change', changed);
    }
  };
  let timer = null;
  const changed = () => { clearTimeout(timer); timer = setTimeout(onChange, 250); };
  inputs.object.addEventListener('change', () => { showObjectParams(); changed(); });
  for (const [name, input] of Object.entries(inputs)) {
    if (name === 'object') continue;
    input.addEventListener(input.tagName === 'SELECT' ? 'change' : 'input', changed);
  }
  showObjectParams();
  const query = () => {
    const q = new URLSearchParams();
    q.set('object', inputs.object.value);
    for (const el of paramBox.querySelectorAll('input,select')) if (el.value.trim() !== '') q.set(el.name, el.value.trim());
    for (const [name, input] of Object.entries(inputs)) {
      if (name !== 'object' && input.value.trim() !== '') q.set(name, input.value.trim());
    }
    return q;
  };
  const label = () => {
    const q = query();
    return ['object', 'method', 'lattice', 'clustering', 'resolution'].map((k) => q.get(k)).filter(Boolean).join(' · ');
  };
  return { inputs, query, label };
}

// ---- object and compare modes -----------------------------------------------------------------
const seq = [0, 0];
function fmt(x, digits = 3) { return x === null || x === undefined ? '–' : Number(x).toFixed(digits); }
function kb(b) { return b >= 1048576 ? `${(b / 1048576).toFixed(2)} MiB` : `${(b / 1024).toFixed(1)} KiB`; }

function statsText(h, bytes, updateMs) {
  const s = h.studio || {};
  const st = s.stage_ms || {};
  const lines = [
    `triangles   ${s.triangles}`,
    `vertices    ${s.vertices}`,
    `stages ms   total ${fmt(st.total, 2)}`,
    `  sampling ${fmt(st.sampling, 2)}  vertex ${fmt(st.vertex, 2)}`,
    `  geometry ${fmt(st.geometry, 2)}  normals ${fmt(st.normals, 2)}`,
    `radius ratio mean ${fmt(s.ar_mean)}  p95 ${fmt(s.ar_p95)}`,
    `fidelity    ${s.fidelity_mean_h === null || s.fidelity_mean_h === undefined ? 'n/a' : `mean ${fmt(s.fidelity_mean_h, 4)} h, max ${fmt(s.fidelity_max_h, 3)} h`}`,
    `topology    ${s.closed ? 'closed' : 'open'}, ${s.manifold ? 'manifold' : 'NON-manifold'}, Euler ${s.euler}`,
    `reply       ${kb(bytes)}, server ${fmt(h.server_ms, 1)} ms`,
  ];
  if (updateMs !== null && updateMs !== undefined) lines.push(`update      ${fmt(updateMs, 1)} ms (change to frame)`);
  return lines.join('\n');
}

function overlayFor(side) {
  // The overlay on the screen side where configuration `side` is drawn.
  const onRight = studio.mode === 'compare' && ((side === 1) !== studio.swapped);
  return onRight ? $('overlay-b') : $('overlay-a');
}

function setOverlay(side, label, text) {
  const el = overlayFor(side);
  el.textContent = '';
  if (!$('blind').checked || studio.mode !== 'compare') {
    const l = document.createElement('div');
    l.className = 'label';
    l.textContent = studio.mode === 'compare' ? `${side === 0 ? 'A' : 'B'}: ${label}` : label;
    el.append(l, document.createTextNode(text));
  } else {
    el.textContent = side === overlayIndex(0) ? 'left' : 'right';
  }
}
function overlayIndex(screenSide) { return studio.swapped ? 1 - screenSide : screenSide; }

const lastReply = [null, null];
function redrawOverlays() {
  for (const side of [0, 1]) {
    if (lastReply[side]) setOverlay(side, panels[side].label(), statsText(lastReply[side].header, lastReply[side].bytes, lastReply[side].updateMs));
  }
}

async function updateSide(side, refit) {
  const panel = panels[side];
  const started = performance.now();
  const mine = ++seq[side];
  const q = panel.query();
  if (colourByRatio()) q.set('ratios', '1');
  studio.busy++;
  $('status').textContent = 'extracting…';
  try {
    const reply = await fetchMesh(`/studio/api/mesh?${q}`);
    if (mine !== seq[side]) return; // a newer request is on its way
    const part = reply.parts[0];
    const group = meshObjects(geometryOf(part), side);
    disposeGroup(shown[side]);
    shown[side] = group;
    scenes[side].add(group);
    if (refit || !studio.ready) frame(group.children[0].geometry.boundingBox);
    await nextFrame();
    const ms = performance.now() - started;
    studio.lastUpdateMs = ms;
    studio.lastBytes = reply.bytes;
    studio.triangles[side] = part.indices.length / 3;
    studio.meshes++;
    studio.ready = true;
    lastReply[side] = { header: reply.header, bytes: reply.bytes, updateMs: ms };
    redrawOverlays();
    showError(null);
    $('status').textContent = `updated in ${fmt(ms, 1)} ms · ${kb(reply.bytes)}`;
  } catch (e) {
    if (mine === seq[side]) { showError(e.message); $('status').textContent = 'error'; }
  } finally {
    studio.busy--;
  }
  updateExportLinks();
}

function refreshAll(refit) {
  updateSide(0, refit);
  if (studio.mode === 'compare') updateSide(1, false);
}

// ---- sculpt mode ------------------------------------------------------------------------------
let sculptPanel = null;
let session = null;
const chunkGroups = new Map();
const sculptRoot = new THREE.Group();
scenes[2].add(sculptRoot);

function setChunk(part) {
  disposeGroup(chunkGroups.get(part.id));
  chunkGroups.delete(part.id);
  if (part.indices.length === 0) return;
  const g = meshObjects(geometryOf({ ...part, ratios: null }), 0);
  g.userData.chunk = part.id;
  chunkGroups.set(part.id, g);
  sculptRoot.add(g);
}

let sculptHeaderCache = null;
function sculptReadout(h, ms) {
  sculptHeaderCache = h;
  const lines = [
    `terrain     ${h.world ? h.world.label : ''}`,
    `chunks      ${h.chunk_count} (${h.chunk_counts.join(' x ')})`,
    `triangles   ${h.triangles}`,
  ];
  if (h.chunks_remeshed !== undefined) {
    lines.push(`last edit   ${fmt(ms, 1)} ms round trip (server ${fmt(h.server_ms, 1)} ms)`);
    lines.push(`re-meshed   ${h.chunks_remeshed} chunk(s), ${h.changed_values} values changed`);
  } else {
    lines.push(`built in    ${fmt(h.server_ms, 1)} ms`);
  }
  lines.push(`history     ${h.undo} undo, ${h.redo} redo`);
  $('overlay-a').textContent = lines.join('\n');
  $('undo').disabled = h.undo === 0;
  $('redo').disabled = h.redo === 0;
}

async function newTerrain() {
  const q = sculptPanel.query();
  studio.busy++;
  $('status').textContent = 'building terrain…';
  try {
    const reply = await fetchMesh(`/studio/api/sculpt?${q}`, { method: 'POST' });
    for (const g of chunkGroups.values()) disposeGroup(g);
    chunkGroups.clear();
    reply.parts.forEach(setChunk);
    session = reply.header.session;
    const box = new THREE.Box3().setFromObject(sculptRoot);
    camera.position.set(0, 3, 5);
    controls.target.set(0, 0, 0);
    frame(box);
    await nextFrame();
    studio.sculptTriangles = reply.header.triangles;
    sculptReadout(reply.header, null);
    showError(null);
    $('status').textContent = `terrain ready · ${kb(reply.bytes)}`;
  } catch (e) {
    showError(e.message);
  } finally {
    studio.busy--;
  }
  updateExportLinks();
}

async function edit(url, body) {
  if (!session) return;
  const started = performance.now();
  studio.busy++;
  try {
    const reply = await fetchMesh(url, { method: 'POST', headers: body ? { 'content-type': 'application/json' } : {}, body: body ? JSON.stringify(body) : undefined });
    reply.parts.forEach(setChunk);
    await nextFrame();
    const ms = performance.now() - started;
    studio.edits++;
    studio.lastEditMs = ms;
    studio.lastChunks = reply.header.chunks_remeshed;
    studio.sculptTriangles = reply.header.triangles;
    sculptReadout(reply.header, ms);
    showError(null);
    $('status').textContent = `edit ${fmt(ms, 1)} ms · ${reply.header.chunks_remeshed} chunk(s) · ${kb(reply.bytes)}`;
  } catch (e) {
    showError(e.status === 404 ? `${e.message}` : e.message);
  } finally {
    studio.busy--;
  }
}

const raycaster = new THREE.Raycaster();
function pick(event) {
  const r = canvas.getBoundingClientRect();
  const ndc = new THREE.Vector2(((event.clientX - r.left) / r.width) * 2 - 1, -((event.clientY - r.top) / r.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  const hits = raycaster.intersectObjects(sculptRoot.children, true);
  return hits.length ? hits[0].point : null;
}

let painting = false, inFlight = false, pending = null;
async function stroke(point) {
  if (inFlight) { pending = point; return; }
  inFlight = true;
  const mode = document.querySelector('input[name=brush]:checked').value;
  await edit(`/studio/api/sculpt/${session}/brush`, {
    centre: [point.x, point.y, point.z],
    mode,
    radius_cells: Number($('brush-radius').value) || 4,
    strength: Number($('brush-strength').value),
  });
  inFlight = false;
  if (pending && painting) { const p = pending; pending = null; stroke(p); }
}
canvas.addEventListener('pointerdown', (e) => {
  if (studio.mode !== 'sculpt' || e.button !== 0 || !session) return;
  const p = pick(e);
  if (!p) return;
  painting = true;
  canvas.setPointerCapture(e.pointerId);
  stroke(p);
});
canvas.addEventListener('pointermove', (e) => {
  if (!painting) return;
  const p = pick(e);
  if (p) { if (inFlight) pending = p; else stroke(p); }
});
const stopPainting = () => { painting = false; pending = null; };
canvas.addEventListener('pointerup', stopPainting);
canvas.addEventListener('pointercancel', stopPainting);
$('undo').addEventListener('click', () => edit(`/studio/api/sculpt/${session}/undo`));
$('redo').addEventListener('click', () => edit(`/studio/api/sculpt/${session}/redo`));
$('sculpt-new').addEventListener('click', newTerrain);
window.addEventListener('keydown', (e) => {
  if (studio.mode !== 'sculpt' || !(e.ctrlKey || e.metaKey)) return;
  if (e.key === 'z' && !e.shiftKey) { e.preventDefault(); edit(`/studio/api/sculpt/${session}/undo`); }
  if (e.key === 'y' || (e.key === 'z' && e.shiftKey)) { e.preventDefault(); edit(`/studio/api/sculpt/${session}/redo`); }
});

// ---- LOD mode: a fly camera over a multiresolution world ---------------------------------------
// Okabe-Ito, the report's level colours (rmt_report::lod::level_colour): level 0 (finest) first.
const LEVEL_COLOURS = [0x0072b2, 0xe69f00, 0x009e73, 0xcc79a7, 0x56b4e9, 0xd55e00, 0xf0e442];
let lodPanel = null;
let lodSession = null;
let lodWorld = null; // the header's world description
const lodGroups = new Map(); // part id -> THREE.Group (userData.level)
const lodRoot = new THREE.Group();
scenes[3].add(lodRoot);
const fly = { keys: new Set(), yaw: 0, pitch: 0, last: null, looking: null, running: false };

function colourByLevel() { return $('lod-colour').checked; }
function levelColour(level) { return new THREE.Color(LEVEL_COLOURS[level % LEVEL_COLOURS.length]); }
function tintLod(group) {
  const m = group.children[0].material;
  m.color.copy(colourByLevel() ? levelColour(group.userData.level) : COLOUR[0]);
  m.needsUpdate = true;
}
function setLodChunk(part, level) {
  disposeGroup(lodGroups.get(part.id));
  lodGroups.delete(part.id);
  if (part.indices.length === 0) return;
  const g = meshObjects(geometryOf({ ...part, ratios: null }), 0);
  g.userData.level = level;
  g.userData.chunk = part.id;
  tintLod(g);
  lodGroups.set(part.id, g);
  lodRoot.add(g);
}
function applyLod(reply) {
  const h = reply.header;
  for (const id of h.dropped) { disposeGroup(lodGroups.get(id)); lodGroups.delete(id); }
  reply.parts.forEach((p, i) => setLodChunk(p, h.chunks[i].level));
  studio.lod.chunks = h.chunk_count;
  studio.lod.triangles = h.triangles;
  studio.lod.levels = h.chunks_per_level;
  studio.lod.lastRemeshed = h.chunks_remeshed;
}
function lodLegend() {
  const box = $('lod-legend');
  box.textContent = '';
  box.hidden = !colourByLevel() || !lodWorld;
  if (box.hidden) return;
  for (let l = 0; l <= lodWorld.levels; l++) {
    const s = document.createElement('span');
    s.className = 'swatch';
    s.style.background = `#${levelColour(l).getHexString()}`;
    const t = document.createElement('span');
    t.textContent = `level ${l}`;
    box.append(s, t);
  }
}
let lodHeaderCache = null;
function lodReadout(h, what, ms) {
  if (h) lodHeaderCache = h;
  h = lodHeaderCache;
  if (!h) return;
  const p = camera.position;
  const lines = [
    `world       ${h.world.label}`,
    `chunks      ${h.chunk_count} (per level ${h.chunks_per_level.join(' / ')})`,
    `triangles   ${h.triangles} (per level ${h.triangles_per_level.join(' / ')})`,
    `viewer      ${fmt(p.x, 2)} ${fmt(p.y, 2)} ${fmt(p.z, 2)}`,
  ];
  if (what) {
    lines.push(`last ${what.padEnd(6)} ${fmt(ms, 1)} ms round trip (re-mesh ${fmt(h.remesh_ms, 1)} ms)`);
    lines.push(`re-meshed   ${h.chunks_remeshed} chunk(s), ${h.dropped.length} dropped`);
  } else {
    lines.push(`built in    ${fmt(h.server_ms, 1)} ms`);
  }
  if (h.strokes) lines.push(`strokes     ${h.strokes}`);
  $('overlay-a').textContent = lines.join('\n');
}

// The camera's look direction from yaw (about y, 0 looks along -z) and pitch.
function flyForward() {
  return new THREE.Vector3(-Math.sin(fly.yaw) * Math.cos(fly.pitch), Math.sin(fly.pitch), -Math.cos(fly.yaw) * Math.cos(fly.pitch));
}
function flyAim() {
  const ahead = camera.position.clone().add(flyForward());
  camera.up.set(0, 1, 0);
  camera.lookAt(ahead);
  controls.target.copy(ahead); // the key light follows it
  requestRender();
}
function flyLookAt(target) {
  const d = target.clone().sub(camera.position).normalize();
  fly.yaw = Math.atan2(-d.x, -d.z);
  fly.pitch = Math.asin(Math.max(-1, Math.min(1, d.y)));
  flyAim();
}
function worldSpan() {
  const b = lodWorld ? lodWorld.bounds : [-4, -1, -4, 4, 1, 4];
  return Math.max(b[3] - b[0], b[5] - b[2]);
}
function flyTick(now) {
  if (studio.mode !== 'lod' || fly.keys.size === 0) {
    fly.running = false;
    fly.last = null;
    maybeRemesh(true); // where the flight stopped, however short it was
    return;
  }
  // Slow frames (software WebGL) still fly at the chosen speed, up to a quarter second a frame.
  const dt = fly.last === null ? 0 : Math.min((now - fly.last) / 1000, 0.25);
  fly.last = now;
  const k = (c) => (fly.keys.has(c) ? 1 : 0);
  const speed = worldSpan() / 8 * (fly.keys.has('shift') ? 4 : 1);
  const forward = flyForward();
  const right = new THREE.Vector3(-forward.z, 0, forward.x).normalize();
  const move = new THREE.Vector3()
    .addScaledVector(forward, k('w') - k('s'))
    .addScaledVector(right, k('d') - k('a'))
    .addScaledVector(new THREE.Vector3(0, 1, 0), k('e') - k('q'));
  if (move.lengthSq() > 0) camera.position.addScaledVector(move.normalize(), speed * dt);
  flyAim();
  lodReadout(null);
  maybeRemesh();
  requestAnimationFrame(flyTick);
}
const FLY_KEYS = { w: 'w', a: 'a', s: 's', d: 'd', q: 'q', e: 'e', arrowup: 'w', arrowdown: 's', arrowleft: 'a', arrowright: 'd', shift: 'shift' };
window.addEventListener('keydown', (e) => {
  if (studio.mode !== 'lod' || e.ctrlKey || e.metaKey || e.altKey) return;
  if (e.target && (e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT')) return;
  const key = FLY_KEYS[e.key.toLowerCase()];
  if (!key) return;
  e.preventDefault();
  fly.keys.add(key);
  if (!fly.running) { fly.running = true; requestAnimationFrame(flyTick); }
});
window.addEventListener('keyup', (e) => {
  const key = FLY_KEYS[e.key.toLowerCase()];
  if (key) fly.keys.delete(key);
});
window.addEventListener('blur', () => fly.keys.clear());

// Re-mesh requests: one in flight at a time; a new one when the camera has moved a quarter of a
// finest chunk from where the last was asked for (or at all, when the flight stopped).
let lodInFlight = false;
let lodAsked = null;
function lodStep() { return lodWorld ? lodWorld.h * lodWorld.chunk * 0.25 : 0.1; }
function maybeRemesh(stopped = false) {
  if (!lodSession || lodInFlight) return;
  const p = camera.position;
  if (lodAsked && p.distanceTo(lodAsked) < (stopped ? 1e-6 : lodStep())) return;
  moveViewer(p.clone());
}
async function moveViewer(p) {
  lodInFlight = true;
  lodAsked = p;
  const started = performance.now();
  try {
    const reply = await fetchMesh(`/studio/api/lod/${lodSession}/viewer`, {
      method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ viewer: [p.x, p.y, p.z] }),
    });
    applyLod(reply);
    await nextFrame();
    const ms = performance.now() - started;
    studio.lod.moves++;
    studio.lod.lastMoveMs = ms;
    studio.lod.viewer = [p.x, p.y, p.z];
    lodReadout(reply.header, 'move', ms);
    showError(null);
    $('status').textContent = `viewer moved · ${reply.header.chunks_remeshed} chunk(s) re-meshed · ${kb(reply.bytes)}`;
  } catch (e) {
    showError(e.message);
  } finally {
    lodInFlight = false;
  }
  if (studio.mode === 'lod') maybeRemesh(!fly.running);
}

async function newLodWorld() {
  const q = lodPanel.query();
  studio.busy++;
  $('status').textContent = 'building the multiresolution world…';
  try {
    // The camera starts where the server puts the viewer (over the ground near a corner).
    const reply = await fetchMesh(`/studio/api/lod?${q}`, { method: 'POST' });
    for (const g of lodGroups.values()) disposeGroup(g);
    lodGroups.clear();
    lodSession = reply.header.session;
    lodWorld = reply.header.world;
    applyLod(reply);
    const b = lodWorld.bounds;
    camera.position.fromArray(reply.header.viewer);
    camera.near = worldSpan() / 2000; camera.far = worldSpan() * 4;
    camera.updateProjectionMatrix();
    flyLookAt(new THREE.Vector3((b[0] + b[3]) / 2, (b[1] + b[4]) / 2, (b[2] + b[5]) / 2));
    lodAsked = camera.position.clone();
    studio.lod.viewer = reply.header.viewer;
    studio.lod.worlds++;
    await nextFrame();
    lodReadout(reply.header, null, null);
    lodLegend();
    showError(null);
    $('status').textContent = `world ready · ${kb(reply.bytes)}`;
  } catch (e) {
    showError(e.message);
  } finally {
    studio.busy--;
  }
  updateExportLinks();
}

function pickLod(event) {
  const r = canvas.getBoundingClientRect();
  const ndc = new THREE.Vector2(((event.clientX - r.left) / r.width) * 2 - 1, -((event.clientY - r.top) / r.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  const hits = raycaster.intersectObjects(lodRoot.children, true);
  if (!hits.length) return null;
  let o = hits[0].object;
  while (o && o.userData.level === undefined) o = o.parent;
  return { point: hits[0].point, level: o ? o.userData.level : 0 };
}
let lodPainting = false, lodStrokeBusy = false;
async function lodStroke(hit) {
  if (lodStrokeBusy || !lodSession) return;
  lodStrokeBusy = true;
  const started = performance.now();
  // The radius is in cells of the level hit, so a stroke far away is as large on screen.
  const radius = Math.min(32, (Number($('lod-radius').value) || 2) * 2 ** hit.level);
  try {
    const reply = await fetchMesh(`/studio/api/lod/${lodSession}/brush`, {
      method: 'POST',
      headers: { 'content-type': 'application/json' },
      body: JSON.stringify({
        centre: [hit.point.x, hit.point.y, hit.point.z],
        mode: document.querySelector('input[name=lod-brush]:checked').value,
        radius_cells: radius,
        strength: Number($('lod-strength').value),
      }),
    });
    applyLod(reply);
    await nextFrame();
    const ms = performance.now() - started;
    studio.lod.strokes = reply.header.strokes;
    studio.lod.lastStrokeMs = ms;
    lodReadout(reply.header, 'stroke', ms);
    showError(null);
    $('status').textContent = `stroke at level ${hit.level} · ${reply.header.chunks_remeshed} chunk(s) re-meshed`;
  } catch (e) {
    showError(e.message);
  } finally {
    lodStrokeBusy = false;
  }
}
canvas.addEventListener('contextmenu', (e) => { if (studio.mode === 'lod') e.preventDefault(); });
canvas.addEventListener('pointerdown', (e) => {
  if (studio.mode !== 'lod') return;
  if (e.button === 2) {
    fly.looking = { x: e.clientX, y: e.clientY };
    canvas.setPointerCapture(e.pointerId);
  } else if (e.button === 0 && lodSession) {
    const hit = pickLod(e);
    if (!hit) return;
    lodPainting = true;
    canvas.setPointerCapture(e.pointerId);
    lodStroke(hit);
  }
});
canvas.addEventListener('pointermove', (e) => {
  if (studio.mode !== 'lod') return;
  if (fly.looking) {
    fly.yaw -= (e.clientX - fly.looking.x) * 0.004;
    fly.pitch = Math.max(-1.5, Math.min(1.5, fly.pitch - (e.clientY - fly.looking.y) * 0.004));
    fly.looking = { x: e.clientX, y: e.clientY };
    flyAim();
  } else if (lodPainting) {
    const hit = pickLod(e);
    if (hit) lodStroke(hit);
  }
});
const stopLod = () => { fly.looking = null; lodPainting = false; };
canvas.addEventListener('pointerup', stopLod);
canvas.addEventListener('pointercancel', stopLod);
$('lod-new').addEventListener('click', newLodWorld);
$('lod-colour').addEventListener('change', () => {
  for (const g of lodGroups.values()) tintLod(g);
  lodLegend();
  requestRender();
});

// ---- modes, view options, export --------------------------------------------------------------
function setMode(mode) {
  studio.mode = mode;
  document.querySelectorAll('#modes button').forEach((b) => b.classList.toggle('on', b.dataset.mode === mode));
  $('configs').hidden = mode === 'sculpt' || mode === 'lod';
  $('sculpt-panel').hidden = mode !== 'sculpt';
  $('lod-panel').hidden = mode !== 'lod';
  controls.enabled = mode !== 'lod';
  fly.keys.clear();
  $('config-b').hidden = mode !== 'compare';
  $('overlay-b').hidden = mode !== 'compare';
  $('divider').hidden = mode !== 'compare';
  $('colour-ratio').disabled = mode === 'sculpt' || mode === 'lod';
  controls.mouseButtons = mode === 'sculpt'
    ? { LEFT: null, MIDDLE: THREE.MOUSE.DOLLY, RIGHT: THREE.MOUSE.ROTATE }
    : { LEFT: THREE.MOUSE.ROTATE, MIDDLE: THREE.MOUSE.DOLLY, RIGHT: THREE.MOUSE.PAN };
  $('overlay-a').textContent = '';
  $('overlay-b').textContent = '';
  if (mode === 'lod') {
    if (!lodSession) newLodWorld();
    else { flyAim(); lodReadout(null); }
  } else if (mode === 'sculpt') {
    if (!session) newTerrain();
    else { frame(new THREE.Box3().setFromObject(sculptRoot)); sculptReadout({ ...lastSculptHeader() }, null); }
  } else {
    if (shown[0]) frame(shown[0].children[0].geometry.boundingBox);
    redrawOverlays();
    if (mode === 'compare' && !shown[1]) updateSide(1, false);
  }
  updateExportLinks();
  requestRender();
}
function lastSculptHeader() { return sculptHeaderCache || { chunk_count: 0, chunk_counts: [0, 0, 0], triangles: studio.sculptTriangles, undo: 0, redo: 0 }; }

document.querySelectorAll('#modes button').forEach((b) => b.addEventListener('click', () => setMode(b.dataset.mode)));

function rebuildMeshes() {
  // Shading changes rebuild materials from the current geometry; colouring needs new ratios.
  for (const side of [0, 1]) {
    const g = shown[side];
    if (!g) continue;
    const geometry = g.children[0].geometry;
    g.removeFromParent();
    g.children.forEach((c) => { if (c.material !== wireMaterial) c.material.dispose(); });
    shown[side] = meshObjects(geometry, side);
    scenes[side].add(shown[side]);
  }
  for (const [id, g] of chunkGroups) {
    const geometry = g.children[0].geometry;
    g.removeFromParent();
    g.children.forEach((c) => { if (c.material !== wireMaterial) c.material.dispose(); });
    const n = meshObjects(geometry, 0);
    n.userData.chunk = id;
    chunkGroups.set(id, n);
    sculptRoot.add(n);
  }
  for (const [id, g] of lodGroups) {
    const geometry = g.children[0].geometry;
    g.removeFromParent();
    g.children.forEach((c) => { if (c.material !== wireMaterial) c.material.dispose(); });
    const n = meshObjects(geometry, 0);
    n.userData = { ...g.userData };
    tintLod(n);
    lodGroups.set(id, n);
    lodRoot.add(n);
  }
  requestRender();
}
document.querySelectorAll('input[name=shading]').forEach((r) => r.addEventListener('change', rebuildMeshes));
$('colour-ratio').addEventListener('change', () => {
  $('legend').hidden = !colourByRatio();
  refreshAll(false);
});
$('blind').addEventListener('change', () => {
  const on = $('blind').checked;
  studio.swapped = on ? Math.random() < 0.5 : false;
  document.querySelectorAll('.tag').forEach((t) => { t.style.visibility = on ? 'hidden' : 'visible'; });
  $('reveal').hidden = !on;
  $('overlay-a').textContent = ''; $('overlay-b').textContent = '';
  redrawOverlays();
  rebuildMeshes();
});
$('reveal').addEventListener('click', () => {
  $('status').textContent = studio.swapped ? 'left is B, right is A' : 'left is A, right is B';
});

function link(href, text) {
  const a = document.createElement('a');
  a.href = href; a.textContent = text; a.setAttribute('download', '');
  return a;
}
function updateExportLinks() {
  const box = $('export-links');
  box.textContent = '';
  if (studio.mode === 'sculpt') {
    if (!session) return;
    for (const f of ['ply', 'obj', 'glb']) box.appendChild(link(`/studio/api/sculpt/${session}/export?format=${f}`, f.toUpperCase()));
    return;
  }
  if (studio.mode === 'lod') {
    if (!lodSession) return;
    for (const f of ['ply', 'obj', 'glb']) box.appendChild(link(`/studio/api/lod/${lodSession}/export?format=${f}`, f.toUpperCase()));
    return;
  }
  const sides = studio.mode === 'compare' ? [0, 1] : [0];
  for (const side of sides) {
    for (const f of ['ply', 'obj', 'glb']) {
      const q = panels[side].query();
      q.set('format', f);
      const a = link(`/studio/api/export?${q}`, (studio.mode === 'compare' ? (side ? 'B ' : 'A ') : '') + f.toUpperCase());
      a.dataset.side = side; a.dataset.format = f;
      box.appendChild(a);
    }
  }
}

// ---- start --------------------------------------------------------------------------------------
async function start() {
  try {
    const r = await fetch('/studio/api/schema');
    schema = await r.json();
  } catch (e) {
    showError(`could not load the parameters: ${e.message}`);
    return;
  }
  const d = schema.defaults;
  panels[0] = buildPanel($('config-a'), d, () => { updateSide(0, false); }, 'object');
  panels[1] = buildPanel($('config-b'), { ...d, ...schema.compare_defaults }, () => { if (studio.mode === 'compare') updateSide(1, false); }, 'object');
  panels[0].inputs.object.addEventListener('change', () => setTimeout(() => updateSide(0, true), 260));
  sculptPanel = buildPanel($('sculpt-config'), schema.sculpt.defaults, () => {}, 'sculpt');
  lodPanel = buildPanel($('lod-config'), schema.lod.defaults, () => {}, 'lod');
  updateExportLinks();
  await updateSide(0, true);
}
start();
