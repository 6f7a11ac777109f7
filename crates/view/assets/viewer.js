// anima view: plays a finished run's animation.glb (written by `anima run --export gltf`) with plots of
// its per-frame numbers. Served by anima-view; everything it loads comes from that server.
//
// The glTF's keyframes are the run's frames: frame k is shown at the time of the k-th distinct key
// time of the animation. Fixed-topology cloth moves by morph targets, remeshed cloth is a node per
// frame shown by a STEP scale track, figures are node hierarchies (anima_viz::gltf says why).
//
// For tests and scripts the page exposes window.anima: frames, times, setFrame(k), play(), pause(),
// shown() (the positions on screen now, in glTF's world axes: y up, metres) and positions(k) (frame k's,
// computed from the file's data). With ?test=K it plays, scrubs the timeline to frame K and writes
// {errors, played, frame, shown} as JSON into <pre id="result">; with ?frame=K it shows frame K paused.

import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const errors = [];
window.addEventListener('error', (e) => errors.push(String(e.message)));
window.addEventListener('unhandledrejection', (e) => errors.push(String(e.reason)));
const consoleError = console.error.bind(console);
console.error = (...args) => {
  errors.push(args.map(String).join(' '));
  consoleError(...args);
};

const $ = (id) => document.getElementById(id);
const query = new URLSearchParams(location.search);

// ---- the 3-D view ----------------------------------------------------------------------------------

const view = $('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
view.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf2f2ee);
scene.add(new THREE.HemisphereLight(0xffffff, 0x7a7a70, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(3, 6, 4);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;

function resize() {
  const w = Math.max(1, view.clientWidth);
  const h = Math.max(1, view.clientHeight);
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();

// ---- the run ---------------------------------------------------------------------------------------

async function getJson(url) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  return r.json();
}

const listing = await getJson('/run/');
const summary = listing.files.includes('summary.json') ? await getJson('/run/summary.json') : null;
// A run may write per-frame series ({time_s: [...], series: [{name, unit, values}]}); the page plots
// them when present, and otherwise what it can tell from the animation itself.
const series = listing.files.includes('series.json') ? await getJson('/run/series.json') : null;
const gltf = await new GLTFLoader().loadAsync('/run/animation.glb');
scene.add(gltf.scene);

// Cloth is seen from both sides.
gltf.scene.traverse((o) => {
  if (o.isMesh) o.material.side = THREE.DoubleSide;
});

// Key times of every track, distinct and sorted: the run's frames.
const times = Array.from(
  new Set(gltf.animations.flatMap((clip) => clip.tracks.flatMap((t) => Array.from(t.times)))),
).sort((a, b) => a - b);
if (times.length === 0) times.push(0);

const mixer = new THREE.AnimationMixer(gltf.scene);
const actions = gltf.animations.map((clip) => {
  const a = mixer.clipAction(clip);
  a.setLoop(THREE.LoopOnce);
  a.clampWhenFinished = true;
  a.play();
  return a;
});

// What moves, from the tracks: morphing meshes, remeshed frames (scale tracks), figure links.
const morphing = [];
const remeshedFrames = [];
const links = [];
gltf.scene.traverse((o) => {
  if (o.isMesh && o.morphTargetInfluences && o.geometry.morphAttributes.position) morphing.push(o);
});
for (const clip of gltf.animations) {
  for (const track of clip.tracks) {
    const { nodeName, propertyName } = THREE.PropertyBinding.parseTrackName(track.name);
    const node = gltf.scene.getObjectByName(nodeName);
    if (!node) continue;
    if (propertyName === 'scale' && !remeshedFrames.includes(node)) remeshedFrames.push(node);
    if (propertyName === 'position' && !links.some((l) => l.node === node)) links.push({ node });
  }
}
// A figure's root link: a link whose parent is not a link. The camera follows the first.
const linkNodes = new Set(links.map((l) => l.node));
const roots = links.filter((l) => !linkNodes.has(l.node.parent));

// ---- frames ----------------------------------------------------------------------------------------

let time = times[0];
let playing = !query.has('frame') && !query.has('test');

function showTime(t) {
  time = t;
  for (const a of actions) {
    a.enabled = true;
    a.paused = false;
    a.time = t;
  }
  mixer.update(0);
  gltf.scene.updateMatrixWorld(true);
}

function frameAt(t) {
  let k = 0;
  while (k + 1 < times.length && times[k + 1] <= t) k += 1;
  return k;
}

// The world positions of a mesh as displayed: base plus the weighted morph targets (glTF's are
// relative), through the mesh's world matrix.
function meshPositions(mesh) {
  const base = mesh.geometry.attributes.position;
  const targets = mesh.geometry.morphAttributes.position || [];
  const weights = mesh.morphTargetInfluences || [];
  const out = new Array(base.count * 3);
  const v = new THREE.Vector3();
  for (let i = 0; i < base.count; i++) {
    v.fromBufferAttribute(base, i);
    for (let j = 0; j < targets.length; j++) {
      const w = weights[j];
      if (w) {
        v.x += w * targets[j].getX(i);
        v.y += w * targets[j].getY(i);
        v.z += w * targets[j].getZ(i);
      }
    }
    v.applyMatrix4(mesh.matrixWorld);
    out[3 * i] = v.x;
    out[3 * i + 1] = v.y;
    out[3 * i + 2] = v.z;
  }
  return out;
}

// What the screen shows now: every moving mesh's vertices and every link's origin, in world axes.
function shown() {
  const meshes = morphing.map((m) => ({ name: m.name, positions: meshPositions(m) }));
  for (const node of remeshedFrames) {
    if (node.scale.x === 0) continue;
    node.traverse((o) => {
      if (o.isMesh) meshes.push({ name: node.name, positions: meshPositions(o) });
    });
  }
  const figureLinks = links.map(({ node }) => {
    const p = node.getWorldPosition(new THREE.Vector3());
    return { name: node.name, root: !linkNodes.has(node.parent), position: [p.x, p.y, p.z] };
  });
  return { time, frame: frameAt(time), meshes, links: figureLinks };
}

// Frame k's state, from the file's data (the same as shown() once frame k is displayed).
function positions(k) {
  const kept = time;
  showTime(times[k]);
  const s = shown();
  showTime(kept);
  return s;
}

// ---- plots -----------------------------------------------------------------------------------------

// Per-frame numbers: the run's series when it wrote them, else what the animation tells.
function derivedSeries() {
  const n = times.length;
  const out = [];
  const states = [];
  for (let k = 0; k < n; k++) states.push(positions(k));
  const speed = (a, b, k) => (k === 0 ? 0 : Math.hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]) / (times[k] - times[k - 1]));
  if (roots.length > 0) {
    const root = (s) => s.links.find((l) => l.root).position;
    out.push({ name: `${roots[0].node.name} height`, unit: 'm', values: states.map((s) => root(s)[1]) });
    out.push({
      name: `${roots[0].node.name} speed`,
      unit: 'm/s',
      values: states.map((s, k) => (k === 0 ? 0 : speed(root(states[k - 1]), root(s), k))),
    });
  }
  const cloth = states.filter((s) => s.meshes.length > 0);
  if (cloth.length === n) {
    const ys = (s) => s.meshes.flatMap((m) => m.positions.filter((_, i) => i % 3 === 1));
    out.push({ name: 'lowest point', unit: 'm', values: states.map((s) => Math.min(...ys(s))) });
    out.push({ name: 'mean height', unit: 'm', values: states.map((s) => ys(s).reduce((a, b) => a + b, 0) / ys(s).length) });
    // Mean vertex speed between frames: only for a fixed topology, where vertex i stays vertex i.
    if (morphing.length > 0) {
      out.push({
        name: 'mean vertex speed',
        unit: 'm/s',
        values: states.map((s, k) => {
          if (k === 0) return 0;
          const a = states[k - 1].meshes[0].positions;
          const b = s.meshes[0].positions;
          let sum = 0;
          for (let i = 0; i < b.length; i += 3) sum += speed(a.slice(i, i + 3), b.slice(i, i + 3), k);
          return sum / (b.length / 3);
        }),
      });
    }
  }
  return { time_s: times, series: out };
}

const plotted = series ?? derivedSeries();
const plots = plotted.series.map((s) => {
  const canvas = document.createElement('canvas');
  $('plots').appendChild(canvas);
  return { canvas, s };
});

function drawPlot({ canvas, s }) {
  const dpr = window.devicePixelRatio || 1;
  const w = canvas.clientWidth;
  const h = canvas.clientHeight;
  if (canvas.width !== w * dpr) {
    canvas.width = w * dpr;
    canvas.height = h * dpr;
  }
  const g = canvas.getContext('2d');
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, w, h);
  const ts = plotted.time_s;
  const vs = s.values;
  const finite = vs.filter(Number.isFinite);
  let lo = finite.length > 0 ? Math.min(...finite) : 0;
  let hi = finite.length > 0 ? Math.max(...finite) : 1;
  if (!(hi > lo)) {
    lo -= 0.5;
    hi += 0.5;
  }
  const t0 = ts[0];
  const t1 = ts[ts.length - 1] > t0 ? ts[ts.length - 1] : t0 + 1;
  const left = 56;
  const top = 18;
  const x = (t) => left + ((t - t0) / (t1 - t0)) * (w - left - 8);
  const y = (v) => top + (1 - (v - lo) / (hi - lo)) * (h - top - 18);
  g.fillStyle = '#333';
  g.font = '12px system-ui, sans-serif';
  g.fillText(`${s.name} (${s.unit})`, left, 12);
  g.fillStyle = '#777';
  g.font = '10px system-ui, sans-serif';
  g.fillText(hi.toPrecision(4), 2, top + 8);
  g.fillText(lo.toPrecision(4), 2, h - 18);
  g.fillText(`${t0.toFixed(2)} s`, left, h - 4);
  g.fillText(`${t1.toFixed(2)} s`, w - 44, h - 4);
  g.strokeStyle = '#ccc';
  g.strokeRect(left, top, w - left - 8, h - top - 18);
  g.strokeStyle = '#2a6fb0';
  g.lineWidth = 1.5;
  g.beginPath();
  // A missing value (null: not had at that frame) breaks the line.
  let drawing = false;
  vs.forEach((v, k) => {
    if (!Number.isFinite(v)) {
      drawing = false;
    } else if (drawing) {
      g.lineTo(x(ts[k]), y(v));
    } else {
      g.moveTo(x(ts[k]), y(v));
      drawing = true;
    }
  });
  g.stroke();
  g.strokeStyle = '#c33';
  g.beginPath();
  g.moveTo(x(time), top);
  g.lineTo(x(time), h - 18);
  g.stroke();
}

// ---- the summary -----------------------------------------------------------------------------------

if (summary) {
  $('title').textContent = `${String(summary.scene).split(/[\\/]/).pop()} (${summary.kind})`;
  const facts = [
    ['steps', summary.steps],
    ['frames', summary.frames],
    ['simulated', `${summary.simulated_seconds} s`],
    ['wall', `${Number(summary.wall_seconds).toFixed(2)} s`],
    ['all finite', summary.all_finite],
    ['self-intersections (most)', summary.self_intersections],
    ['error', summary.error],
  ];
  for (const [name, value] of facts) {
    if (value === null || value === undefined) continue;
    const row = $('facts').insertRow();
    row.insertCell().textContent = name;
    row.insertCell().textContent = String(value);
  }
  for (const w of summary.warnings || []) {
    const row = $('facts').insertRow();
    row.insertCell().textContent = 'warning';
    row.insertCell().textContent = w;
  }
}
$('status').textContent = series ? '' : 'plots from the animation (the run wrote no series.json)';

// ---- camera ----------------------------------------------------------------------------------------

// The box the camera frames: for cloth, what moves over the run (at up to 24 frames) and what does
// not; for figures, the figures at the start (the camera then follows them).
const box = new THREE.Box3();
showTime(times[0]);
if (roots.length > 0) {
  for (const { node } of roots) box.expandByObject(node);
} else {
  const moving = new Set([...morphing, ...remeshedFrames]);
  gltf.scene.traverse((o) => {
    let still = o.isMesh;
    for (let p = o; p; p = p.parent) if (moving.has(p)) still = false;
    if (still) box.expandByObject(o);
  });
  const every = Math.max(1, Math.ceil(times.length / 24));
  const p = new THREE.Vector3();
  for (let k = 0; k < times.length; k += every) {
    for (const m of positions(k).meshes) {
      for (let i = 0; i < m.positions.length; i += 3) box.expandByPoint(p.fromArray(m.positions, i));
    }
  }
}
showTime(times[0]);
const centre = box.getCenter(new THREE.Vector3());
const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 0.1);
camera.position.copy(centre).add(new THREE.Vector3(0.9, 0.6, 1.6).normalize().multiplyScalar(radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 1.15));
camera.near = radius / 100;
camera.far = radius * 200;
camera.updateProjectionMatrix();
controls.target.copy(centre);
controls.update();
// A floor grid under everything, for a sense of up and of scale (1 m squares).
if (roots.length === 0) {
  const grid = new THREE.GridHelper(Math.ceil(radius * 4), Math.ceil(radius * 4), 0xbbbbb4, 0xd8d8d2);
  grid.position.set(centre.x, box.min.y - 0.001, centre.z);
  scene.add(grid);
}
// Figures walk away: the camera keeps the first root link's x.
let followed = roots.length > 0 ? roots[0].node.getWorldPosition(new THREE.Vector3()).x : 0;
function follow() {
  if (roots.length === 0) return;
  const x = roots[0].node.getWorldPosition(new THREE.Vector3()).x;
  camera.position.x += x - followed;
  controls.target.x += x - followed;
  followed = x;
}

// ---- controls --------------------------------------------------------------------------------------

const slider = $('timeline');
slider.max = String(times.length - 1);
const playButton = $('play');
function setPlaying(p) {
  playing = p;
  playButton.textContent = p ? 'Pause' : 'Play';
}
playButton.addEventListener('click', () => setPlaying(!playing));
slider.addEventListener('input', () => {
  setPlaying(false);
  showTime(times[Number(slider.value)]);
});
window.addEventListener('keydown', (e) => {
  if (e.key === ' ') setPlaying(!playing);
});

function setFrame(k) {
  setPlaying(false);
  showTime(times[Math.max(0, Math.min(times.length - 1, k))]);
}

let last = performance.now();
// The frames shown while playing: the self test plays when more than one is seen.
const seenPlaying = new Set();
let ticks = 0;
function tick() {
  // The clock, not the frame's timestamp: a headless browser's virtual time moves the one only.
  const now = performance.now();
  ticks += 1;
  const dt = Math.min((now - last) / 1000, 0.1);
  last = now;
  if (playing && times.length > 1) {
    let t = time + dt;
    if (t > times[times.length - 1]) t = times[0];
    showTime(t);
    seenPlaying.add(frameAt(t));
  }
  const k = frameAt(time);
  slider.value = String(k);
  $('label').textContent = `frame ${k} / ${times.length - 1}, t = ${time.toFixed(3)} s`;
  follow();
  controls.update();
  renderer.render(scene, camera);
  plots.forEach(drawPlot);
  requestAnimationFrame(tick);
}
setPlaying(playing);
requestAnimationFrame(tick);

window.anima = {
  frames: times.length,
  times,
  setFrame,
  play: () => setPlaying(true),
  pause: () => setPlaying(false),
  shown,
  positions,
  errors,
};

// ---- self test -------------------------------------------------------------------------------------

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
if (query.has('frame')) setFrame(Number(query.get('frame')));
if (query.has('test')) {
  const k = Number(query.get('test'));
  seenPlaying.clear();
  setPlaying(true);
  // Until two frames have been shown, for at most 10 s: a headless browser draws few frames. Not a
  // comparison of times: a short run may have looped back to where it started.
  for (let waited = 0; seenPlaying.size < 2 && waited < 10000; waited += 100) await sleep(100);
  const played = seenPlaying.size > 1;
  // As a person would: move the timeline's thumb to frame k.
  slider.value = String(k);
  slider.dispatchEvent(new Event('input'));
  await sleep(200);
  const plotNames = plotted.series.map((p) => p.name);
  const result = { errors, frames: times.length, played, seen: [...seenPlaying], ticks, plots: plotNames, playing, frame: frameAt(time), shown: shown() };
  $('result').textContent = JSON.stringify(result);
  document.title = 'anima view: tested';
}
