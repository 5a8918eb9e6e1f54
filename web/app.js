// The viewer of `latticebuild watch --serve`: fetches /api/state after every server-sent
// `state` event, redraws the side panel, and replaces only the geometries whose mesh version
// changed, so the camera stays where the user left it. Meshes arrive in the compact binary
// form of src/serve/mesh.rs (`LBM1`: u16-quantized positions, u32 indices).
import * as THREE from './three.module.js';
import { OrbitControls } from './OrbitControls.js';

const view = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.localClippingEnabled = true;
const BACKGROUND = 0xfafafa;
renderer.setClearColor(BACKGROUND);
view.appendChild(renderer.domElement);

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
camera.position.set(2, -3, 2);
camera.up.set(0, 0, 1);
scene.add(camera);
scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 1.6));
const light = new THREE.DirectionalLight(0xffffff, 1.8);
light.position.set(1, 1.5, 2);
camera.add(light); // a headlight: the lit side follows the view
const controls = new OrbitControls(camera, renderer.domElement);
controls.addEventListener('change', draw);

const PALETTE = [0x4e79a7, 0xf28e2b, 0x59a14f, 0xe15759, 0x76b7b2, 0xedc948, 0xb07aa1, 0xff9da7];
const clipPlane = new THREE.Plane(new THREE.Vector3(0, 0, -1), 0);
const shown = new Map(); // output name -> { mesh, version, visible }
const bounds = new THREE.Box3();
let fitted = false;

// What the browser test reads.
window.__lattice = {
  pageId: Math.random().toString(36).slice(2),
  generation: 0,
  drawn: 0,
  firstDrawMs: null,
  camera: () => camera.position.toArray(),
};

function resize() {
  const w = view.clientWidth, h = view.clientHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
  draw();
}
window.addEventListener('resize', resize);

function draw() {
  renderer.render(scene, camera);
}

function decode(buffer) {
  const d = new DataView(buffer);
  const magic = String.fromCharCode(d.getUint8(0), d.getUint8(1), d.getUint8(2), d.getUint8(3));
  if (magic !== 'LBM1') throw new Error('not a latticebuild mesh');
  const nv = d.getUint32(8, true), nt = d.getUint32(12, true);
  const origin = [0, 1, 2].map(a => d.getFloat32(20 + 4 * a, true));
  const step = [0, 1, 2].map(a => d.getFloat32(32 + 4 * a, true));
  const q = new Uint16Array(buffer, 44, 3 * nv);
  const positions = new Float32Array(3 * nv);
  for (let i = 0; i < 3 * nv; i++) positions[i] = origin[i % 3] + q[i] * step[i % 3];
  const at = Math.ceil((44 + 6 * nv) / 4) * 4;
  const index = new Uint32Array(buffer, at, 3 * nt);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setIndex(new THREE.BufferAttribute(index, 1));
  geometry.computeVertexNormals();
  geometry.computeBoundingBox();
  return geometry;
}

function fmt(x, digits = 4) {
  if (x === null || x === undefined || Number.isNaN(x)) return '–';
  return Number(x).toPrecision(digits).replace(/(\.\d*?)0+$/, '$1').replace(/\.$/, '');
}

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v; else if (k === 'text') e.textContent = v; else e.setAttribute(k, v);
  }
  for (const c of children) if (c) e.appendChild(c);
  return e;
}

function figureRow(table, key, label, text, cls) {
  const value = el('td', { 'data-figure': key, text });
  if (cls) value.className = cls;
  table.appendChild(el('tr', {}, el('td', { text: label }), value));
}

function spread(s, units) {
  return s ? `${fmt(s.median)} ${units} (${fmt(s.min)}–${fmt(s.max)})` : null;
}

function renderOutputs(state) {
  const list = document.getElementById('outputs');
  list.replaceChildren();
  state.outputs.forEach((o, i) => {
    const r = o.report;
    const color = '#' + PALETTE[i % PALETTE.length].toString(16).padStart(6, '0');
    const box = el('input', { type: 'checkbox' });
    box.checked = shown.get(o.name)?.visible ?? true;
    box.addEventListener('change', () => {
      const s = shown.get(o.name);
      if (s) { s.visible = box.checked; s.mesh.visible = box.checked; draw(); }
    });
    const swatch = el('span', { class: 'swatch' });
    swatch.style.background = color;
    const head = el('label', {}, box, swatch, document.createTextNode(o.name));
    const table = el('table', { class: 'figures' });
    const units = r.units || '';
    figureRow(table, 'volume_fraction', r.planar ? 'area fraction' : 'volume fraction', Number(r.volume_fraction).toFixed(4));
    figureRow(table, 'components', 'components', String(r.components), r.components > 1 ? 'bad' : '');
    if (r.wall_thickness) figureRow(table, 'wall_thickness', 'wall thickness', spread(r.wall_thickness, units));
    if (r.pore_size) figureRow(table, 'pore_size', 'pore size', spread(r.pore_size, units));
    if (r.thinnest_wall !== undefined && r.thinnest_wall !== null) figureRow(table, 'thinnest_wall', 'thinnest wall', `${fmt(r.thinnest_wall)} ${units}`);
    const ok = r.watertight && r.manifold;
    figureRow(table, 'checks', 'mesh', ok ? 'watertight, manifold' : (r.defects || []).join('; ') || 'defective', ok ? '' : 'bad');
    let tris = `${r.triangles.toLocaleString('en')}`;
    if (o.mesh && o.mesh.decimated) tris += ` (shown: ${o.mesh.triangles.toLocaleString('en')})`;
    figureRow(table, 'triangles', 'triangles', tris);
    const card = el('div', { class: 'output' + (state.building ? ' stale' : ''), 'data-output': o.name }, head, table);
    for (const w of r.warnings || []) card.appendChild(el('div', { class: 'warning', text: '⚠ ' + w }));
    if (o.mesh_error) card.appendChild(el('div', { class: 'note', text: o.mesh_error }));
    list.appendChild(card);
  });
}

function renderDag(state) {
  const dag = document.getElementById('dag');
  dag.replaceChildren();
  for (const n of state.dag) {
    const line = el('div', { class: n.status.replace(' ', '-'), 'data-node': n.node, title: n.status },
      document.createTextNode((n.status === 'rebuilt' ? '● ' : n.status === 'cached' ? '○ ' : '· ') + n.node));
    if (n.inputs.length) line.appendChild(el('span', { class: 'inputs', text: ' ← ' + n.inputs.join(', ') }));
    dag.appendChild(line);
  }
}

function applyClip() {
  const on = document.getElementById('clip').checked;
  const axis = 'xyz'.indexOf(document.getElementById('axis').value);
  const t = document.getElementById('cut').value / 1000;
  const normal = new THREE.Vector3(); normal.setComponent(axis, -1);
  const lo = bounds.isEmpty() ? -1 : bounds.min.getComponent(axis);
  const hi = bounds.isEmpty() ? 1 : bounds.max.getComponent(axis);
  clipPlane.normal.copy(normal);
  clipPlane.constant = lo + t * (hi - lo);
  for (const s of shown.values()) s.mesh.material.clippingPlanes = on ? [clipPlane] : [];
  draw();
}
for (const id of ['clip', 'axis', 'cut']) document.getElementById(id).addEventListener('input', applyClip);

function fit() {
  if (bounds.isEmpty()) return;
  const center = bounds.getCenter(new THREE.Vector3());
  const size = bounds.getSize(new THREE.Vector3()).length();
  controls.target.copy(center);
  camera.position.copy(center).add(new THREE.Vector3(0.9, -1.4, 0.8).multiplyScalar(size));
  camera.near = size / 1000; camera.far = size * 20;
  camera.updateProjectionMatrix();
  controls.update();
}

async function loadMesh(o, index) {
  const response = await fetch(`/api/mesh/${encodeURIComponent(o.name)}?v=${o.mesh.version}`);
  if (!response.ok) throw new Error(`mesh ${o.name}: ${response.status}`);
  const geometry = decode(await response.arrayBuffer());
  const old = shown.get(o.name);
  if (old) {
    old.mesh.geometry.dispose();
    old.mesh.geometry = geometry;
    old.version = o.mesh.version;
    return;
  }
  const material = new THREE.MeshStandardMaterial({
    color: PALETTE[index % PALETTE.length], roughness: 0.6, metalness: 0.05, side: THREE.DoubleSide,
  });
  const mesh = new THREE.Mesh(geometry, material);
  scene.add(mesh);
  shown.set(o.name, { mesh, version: o.mesh.version, visible: true });
}

let busy = false, again = false;
async function refresh() {
  if (busy) { again = true; return; }
  busy = true;
  try {
    do {
      again = false;
      const state = await (await fetch('/api/state', { cache: 'no-store' })).json();
      document.getElementById('manifest').textContent = state.manifest ? '— ' + state.manifest : '';
      const status = document.getElementById('status');
      status.textContent = state.building ? 'building…' : `build ${state.generation}: ${state.outputs.length} output(s)`;
      status.className = state.building ? 'building' : '';
      const error = document.getElementById('error');
      error.textContent = state.error || '';
      error.className = state.error ? 'shown' : '';
      const names = new Set(state.outputs.map(o => o.name));
      for (const [name, s] of shown) {
        if (!names.has(name)) { scene.remove(s.mesh); s.mesh.geometry.dispose(); shown.delete(name); }
      }
      let index = 0;
      for (const o of state.outputs) {
        if (o.mesh && shown.get(o.name)?.version !== o.mesh.version) await loadMesh(o, index);
        index++;
      }
      bounds.makeEmpty();
      for (const s of shown.values()) bounds.union(s.mesh.geometry.boundingBox);
      renderOutputs(state);
      renderDag(state);
      if (!fitted && shown.size > 0) { fit(); fitted = true; }
      applyClip();
      window.__lattice.generation = state.generation;
      window.__lattice.drawn = shown.size;
      if (window.__lattice.firstDrawMs === null && shown.size > 0) {
        await new Promise(r => requestAnimationFrame(r));
        window.__lattice.firstDrawMs = performance.now();
      }
    } while (again);
  } catch (e) {
    document.getElementById('status').textContent = 'error: ' + e.message;
  } finally {
    busy = false;
  }
}

resize();
const events = new EventSource('/events');
events.addEventListener('state', refresh);
events.addEventListener('error', () => { document.getElementById('status').textContent = 'disconnected; retrying…'; });
refresh();
