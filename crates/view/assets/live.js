// The page of `anima run SCENE --live`: the run's frames as they arrive over the `/live` WebSocket,
// pause / resume / step, and a slider per controller parameter (a character run). What the run sends
// (see anima_run::live and anima_view::live): a first text message `{"params":[…]}`, JSON notes
// (`{"mesh":…}` before the first frame and when the triangles change, `{"set":…}` when the run took a
// parameter, `{"refused":…}`, `{"warning":…}`, `{"progress":…}`), `ok …` / `error …` replies to the
// page's commands, and binary frames (u32 index, f64 time, f32 x y z per point, little-endian).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const view = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
view.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xfafaf8);
scene.add(new THREE.HemisphereLight(0xffffff, 0x888877, 2.5));
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
camera.position.set(0, 1, 5);

const status = document.getElementById('status');
const log = document.getElementById('log');
const label = document.getElementById('label');
let mesh = null;
// The points the mesh's triangles are over (null: a run that does not say). A remesh sends a new mesh
// ahead of frames of the old one still queued; those are not drawn on it.
let meshPoints = null;
let framed = false;
let lastFrame = -1;
// What the tests read back (crates/cli/tests/viewer.rs).
window.anima = { params: {}, changes: [], frames: 0, replies: [], ready: false };

function resize() {
  const w = view.clientWidth, h = view.clientHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();
renderer.setAnimationLoop(() => { controls.update(); renderer.render(scene, camera); });

function note(text) {
  const line = document.createElement('div');
  line.textContent = text;
  log.prepend(line);
  while (log.childNodes.length > 20) log.lastChild.remove();
}

function setMesh(m) {
  if (mesh) { scene.remove(mesh); mesh.geometry.dispose(); }
  const g = new THREE.BufferGeometry();
  g.setIndex(m.triangles.flat());
  let material;
  if (m.colours) {
    // One colour a body: four points a box, eight a ball, in the order of the triangles' points.
    const n = Math.max(...m.triangles.flat(), 0) + 1;
    const colours = new Float32Array(3 * n);
    let body = -1, seen = -1;
    for (const [a, b, c] of m.triangles) {
      if (a !== seen) { body += 1; seen = a; }
      for (const v of [a, b, c]) colours.set(m.colours[body].map((x) => x / 255), 3 * v);
    }
    g.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    material = new THREE.MeshBasicMaterial({ vertexColors: true, side: THREE.DoubleSide });
  } else {
    material = new THREE.MeshStandardMaterial({ color: 0x6688bb, side: THREE.DoubleSide, flatShading: true });
  }
  meshPoints = Number.isInteger(m.points) ? m.points : null;
  mesh = new THREE.Mesh(g, material);
  mesh.frustumCulled = false;
  scene.add(mesh);
  framed = false;
}

function showFrame(bytes) {
  const dv = new DataView(bytes);
  const index = dv.getUint32(0, true), time = dv.getFloat64(4, true);
  const points = new Float32Array(bytes.slice(12));
  if (!mesh) return;
  if (meshPoints !== null && points.length !== 3 * meshPoints) return;
  mesh.geometry.setAttribute('position', new THREE.BufferAttribute(points, 3));
  mesh.geometry.computeVertexNormals();
  mesh.geometry.computeBoundingSphere();
  if (!framed) {
    const s = mesh.geometry.boundingSphere;
    controls.target.copy(s.center);
    camera.position.copy(s.center).add(new THREE.Vector3(0, 0.3 * s.radius, 3 * s.radius + 0.5));
    framed = true;
  }
  const gap = lastFrame >= 0 && index > lastFrame + 1 ? ` (${index - lastFrame - 1} not shown)` : '';
  lastFrame = index;
  window.anima.frames += 1;
  window.anima.frame = index;
  label.textContent = `frame ${index}, t = ${time.toFixed(3)} s${gap}`;
}

function sliders(params) {
  const box = document.getElementById('params');
  if (params.length) box.append(Object.assign(document.createElement('h1'), { textContent: 'controller parameters' }));
  for (const p of params) {
    window.anima.params[p.name] = p.value;
    const l = document.createElement('label');
    const value = document.createElement('span');
    value.textContent = ` ${p.value}`;
    const input = Object.assign(document.createElement('input'), {
      type: 'range', min: p.min, max: p.max, step: (p.max - p.min) / 1000, value: p.value,
    });
    input.dataset.name = p.name;
    input.addEventListener('change', () => {
      value.textContent = ` ${input.value}`;
      send(`set ${p.name} ${input.value}`);
    });
    l.append(p.name, value, input);
    box.append(l);
  }
}

const socket = new WebSocket(`ws://${location.host}/live`);
socket.binaryType = 'arraybuffer';
function send(text) { if (socket.readyState === WebSocket.OPEN) socket.send(text); }
window.anima.send = send;
for (const id of ['pause', 'resume', 'step']) {
  document.getElementById(id).addEventListener('click', () => send(id));
}
socket.addEventListener('open', () => { status.textContent = 'running'; });
socket.addEventListener('close', () => { status.textContent = 'the run has ended (or another page watches it)'; });
socket.addEventListener('message', (event) => {
  if (typeof event.data !== 'string') { showFrame(event.data); return; }
  const text = event.data;
  if (!text.startsWith('{')) {
    window.anima.replies.push(text);
    if (text.startsWith('error')) note(text);
    if (text === 'ok pause') status.textContent = 'paused';
    if (text === 'ok resume') status.textContent = 'running';
    if (text === 'ok step') status.textContent = 'one frame, then paused';
    return;
  }
  const m = JSON.parse(text);
  if (m.params) { sliders(m.params); window.anima.ready = true; }
  if (m.mesh) setMesh(m.mesh);
  if (m.set) { window.anima.params[m.set.name] = m.set.value; window.anima.changes.push(m.set); note(`${m.set.name} = ${m.set.value} from step ${m.set.step}`); }
  if (m.refused) note(`refused: ${m.refused}`);
  if (m.warning) note(`warning: ${m.warning}`);
  if (m.progress !== undefined) status.textContent = `running: ${(100 * m.progress).toFixed(0)} %`;
  if (m.done) status.textContent = `done: ${m.done}`;
});
