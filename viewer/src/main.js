// The wlx viewer: draws a model from its generated forward kinematics, plays the runs written by
// `wlx viewer` / `wlx report` (runs/<id>.js), and lets the user drag the base, the foot targets
// and the wheels' ground levels while the limbs follow by wlx's closed-form IK (the WebAssembly
// module built from the generated headers and the runtime's sources, wasm/wlx_<model>.js).
//
// Nothing about a robot is written here: names, the frame tree, limbs, wheels, the clearance box and
// the nominal pose come from the module (wlx_model_info_json). Loading is by <script> tags only,
// so the page works from file:// with no server.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { TransformControls } from 'three/examples/jsm/controls/TransformControls.js';
import { WasmModel } from './wasm_model.js';
import { drawPlot } from './plot.js';

THREE.Object3D.DEFAULT_UP.set(0, 0, 1);  // K0: z up

// --- registration of data scripts (runs/index.js, runs/<id>.js) ------------------------------
const registry = { index: null, runs: new Map(), waiting: new Map() };
const viewer = (window.wlxViewer = window.wlxViewer || {});
viewer.registerIndex = (list) => { registry.index = list; };
viewer.registerRun = (run) => {
  registry.runs.set(run.id, run);
  const resolve = registry.waiting.get(run.id);
  if (resolve) resolve(run);
};

function loadScript(src) {
  return new Promise((resolve, reject) => {
    const el = document.createElement('script');
    el.src = src;
    el.onload = () => resolve();
    el.onerror = () => reject(new Error(`could not load ${src} (is it beside viewer.html?)`));
    document.head.appendChild(el);
  });
}

// File names of runs: the export writes runs/<id>.js with the id as given (ids are checked there).
function runScript(id) { return 'runs/' + encodeURIComponent(id).replace(/%2B/gi, '+') + '.js'; }

async function loadRun(id) {
  if (registry.runs.has(id)) return registry.runs.get(id);
  const done = new Promise((resolve) => registry.waiting.set(id, resolve));
  await loadScript(runScript(id));
  const run = await Promise.race([done, new Promise((r) => setTimeout(() => r(null), 0))]);
  if (!run) throw new Error(`runs/${id}.js did not register run '${id}'`);
  return run;
}

// --- formatting: never NaN on screen -------------------------------------------------------------
function fmt(v, digits = 4) {
  if (!Number.isFinite(v)) return '—';
  const a = Math.abs(v);
  if (a !== 0 && (a < 1e-3 || a >= 1e5)) return v.toExponential(2);
  return v.toFixed(digits);
}

const ui = (id) => document.getElementById(id);

function showMessage(text) {
  const el = ui('message');
  el.textContent = text || '';
  el.style.display = text ? 'block' : 'none';
  app.message = text || '';
}

// --- the application state --------------------------------------------------------------------
const app = {
  model: null,       // WasmModel
  info: null,        // the model's tables
  inputs: null,      // Float64Array(inputCount): the last reachable inputs
  s: null,           // Float64Array(coordinateCount): the pose shown
  branches: null,    // Int32Array(limbs)
  residual: NaN,
  message: '',
  run: null,         // the run being played, with .frames (Float64Array per sample) and .t
  time: 0,
  playing: false,
  speed: 1,
  ikTimes: [],       // ms per IK solve during drags
  handles: [],       // draggable handles
  tracks: [],        // the wheels' ground tracks drawn: start, end, number of distinct points
  selected: null,
};

// --- scene -----------------------------------------------------------------------------------
const sceneEl = ui('scene');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
sceneEl.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xeef1f5);
const camera = new THREE.PerspectiveCamera(45, 1, 0.05, 500);
camera.position.set(9, -11, 7);
const orbit = new OrbitControls(camera, renderer.domElement);
orbit.target.set(0, 0, 1);
orbit.update();
orbit.saveState();  // what resetView() returns to
scene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(5, -8, 12);
scene.add(sun);

const grid = new THREE.GridHelper(40, 40, 0x8890a0, 0xc4c9d2);
grid.rotation.x = Math.PI / 2;  // GridHelper lies in x-z; K0's ground is x-y
scene.add(grid);
const axes = new THREE.AxesHelper(1.0);  // K0: x red, y green, z blue
scene.add(axes);

const materials = {
  base: new THREE.MeshStandardMaterial({ color: 0xf2b33d, roughness: 0.6, transparent: true, opacity: 0.9 }),
  link: new THREE.MeshStandardMaterial({ color: 0x3b4a63, roughness: 0.5 }),
  joint: new THREE.MeshStandardMaterial({ color: 0x6d7f9c }),
  wheel: new THREE.MeshStandardMaterial({ color: 0x222222, roughness: 0.9 }),
  foot: new THREE.MeshStandardMaterial({ color: 0x2a7f62 }),
  com: new THREE.MeshStandardMaterial({ color: 0xd0306a }),
  // Handles are drawn over everything (depthTest off): the base's sits inside the clearance box.
  handle: new THREE.MeshStandardMaterial({ color: 0xff7a1a, transparent: true, opacity: 0.85, depthTest: false }),
  handleSelected: new THREE.MeshStandardMaterial({ color: 0xff2a00, transparent: true, opacity: 0.95, depthTest: false }),
  ground: new THREE.MeshStandardMaterial({ color: 0x8a6d3b, transparent: true, opacity: 0.45, side: THREE.DoubleSide }),
};

const machine = new THREE.Group();
scene.add(machine);
const tracks = new THREE.Group();
scene.add(tracks);
const comGroup = new THREE.Group();
comGroup.visible = false;
scene.add(comGroup);
// A dynamics run's contacts: the ground's force at each contact, the support polygon, the CoM over
// it and the zero-moment point (filled by prepareRun when the run carries them).
const forceGroup = new THREE.Group();
scene.add(forceGroup);

let parts = null;  // meshes made from the model's tables

function frameMatrix(positions, rotations, f, out) {
  const R = rotations, o = 9 * f;
  // rotations are column-major (columns: the frame's axes); Matrix4.set takes rows.
  out.set(R[o], R[o + 3], R[o + 6], positions[3 * f],
          R[o + 1], R[o + 4], R[o + 7], positions[3 * f + 1],
          R[o + 2], R[o + 5], R[o + 8], positions[3 * f + 2],
          0, 0, 0, 1);
  return out;
}

function frameAxis(rotations, f, axis) {
  const o = 9 * f + 3 * axis;
  return new THREE.Vector3(rotations[o], rotations[o + 1], rotations[o + 2]);
}

// The frames whose origin is put at three input targets (feet), and those with a height target
// only (wheel contacts on their ground level), from the closure rows.
function targetsFromClosureRows(info) {
  const byFrame = new Map();
  for (const row of info.closureRows) {
    if (row.kind !== 'point') continue;
    if (!byFrame.has(row.frame)) byFrame.set(row.frame, [-1, -1, -1]);
    byFrame.get(row.frame)[row.axis] = row.target;
  }
  const points = [], grounds = [];
  for (const [frame, targets] of byFrame) {
    if (targets.every((t) => t >= 0)) points.push({ frame, targets });
    else if (targets[2] >= 0 && targets[0] < 0 && targets[1] < 0) grounds.push({ frame, target: targets[2] });
  }
  return { points, grounds };
}

function buildMachine(info) {
  machine.clear();
  comGroup.clear();
  const unitCylinder = new THREE.CylinderGeometry(1, 1, 1, 16);  // along y, scaled per link
  const links = [];
  info.frames.forEach((frame, f) => {
    if (frame.parent < 0) return;
    const mesh = new THREE.Mesh(unitCylinder, materials.link);
    mesh.name = `link ${info.frames[frame.parent].name}-${frame.name}`;
    machine.add(mesh);
    links.push({ mesh, from: frame.parent, to: f });
  });
  const joints = info.frames.map((frame) => {
    const mesh = new THREE.Mesh(new THREE.SphereGeometry(0.09 * app.viewScale, 16, 12), materials.joint);
    mesh.name = `frame ${frame.name}`;
    machine.add(mesh);
    return mesh;
  });
  let base = null;
  if (info.clearanceBox) {
    const [hx, hy, hz] = info.clearanceBox.halfExtents;
    base = new THREE.Mesh(new THREE.BoxGeometry(2 * hx, 2 * hy, 2 * hz), materials.base);
    base.matrixAutoUpdate = false;
    base.add(new THREE.AxesHelper(0.6 * app.viewScale));
    machine.add(base);
  }
  const wheels = info.wheels.map((w) => {
    const disc = new THREE.Mesh(new THREE.CylinderGeometry(w.radius, w.radius, Math.min(0.18, 0.6 * w.radius), 40), materials.wheel);
    disc.name = `wheel ${w.name}`;
    machine.add(disc);
    return { info: w, disc };
  });
  const { points, grounds } = targetsFromClosureRows(info);
  const feet = points.map((p) => {
    const mesh = new THREE.Mesh(new THREE.SphereGeometry(0.14 * app.viewScale, 20, 14), materials.foot);
    machine.add(mesh);
    return { ...p, mesh };
  });
  const coms = info.bodies.map((b) => {
    const mesh = new THREE.Mesh(new THREE.SphereGeometry(0.1 * app.viewScale, 16, 12), materials.com);
    mesh.name = `com ${b.name}`;
    comGroup.add(mesh);
    return mesh;
  });
  parts = { links, joints, base, wheels, feet, grounds, coms };
}

const _m = new THREE.Matrix4(), _a = new THREE.Vector3(), _b = new THREE.Vector3(), _y = new THREE.Vector3(0, 1, 0);

function placeMachine() {
  const info = app.info;
  const { positions, rotations } = app.model.forwardKinematics(app.s);
  const origin = (f) => new THREE.Vector3(positions[3 * f], positions[3 * f + 1], positions[3 * f + 2]);
  for (const link of parts.links) {
    _a.copy(origin(link.from));
    _b.copy(origin(link.to));
    const d = _b.clone().sub(_a);
    const length = d.length();
    link.mesh.visible = length > 1e-9;
    if (!link.mesh.visible) continue;
    link.mesh.position.copy(_a).addScaledVector(d, 0.5);
    link.mesh.quaternion.setFromUnitVectors(_y, d.normalize());
    link.mesh.scale.set(0.055 * app.viewScale, length, 0.055 * app.viewScale);
  }
  parts.joints.forEach((mesh, f) => mesh.position.copy(origin(f)));
  if (parts.base) frameMatrix(positions, rotations, info.clearanceBox.frame, parts.base.matrix);
  for (const w of parts.wheels) {
    // A disc in the contact frame: its axle along the lateral axis, its centre a radius above
    // the contact point along the frame's remaining (normal) axis.
    const f = w.info.contactFrame;
    const lateral = frameAxis(rotations, f, w.info.lateralAxis);
    let normal = frameAxis(rotations, f, 3 - w.info.forwardAxis - w.info.lateralAxis);
    if (normal.z < 0) normal.negate();
    w.disc.position.copy(origin(f)).addScaledVector(normal, w.info.radius);
    w.disc.quaternion.setFromUnitVectors(_y, lateral.normalize());
  }
  for (const foot of parts.feet) foot.mesh.position.copy(origin(foot.frame));
  if (comGroup.visible) {
    const com = app.model.bodyCentres(app.s);
    parts.coms.forEach((mesh, b) => mesh.position.set(com[3 * b], com[3 * b + 1], com[3 * b + 2]));
  }
  app.residual = app.model.closureResidual(app.s);
  placeHandles(positions, rotations);
  updatePanel();
}

// --- handles: base, foot targets, ground levels ------------------------------------------------
const gizmo = new TransformControls(camera, renderer.domElement);
gizmo.setSize(0.8);
scene.add(gizmo.getHelper());
gizmo.addEventListener('dragging-changed', (e) => { orbit.enabled = !e.value; });
gizmo.addEventListener('objectChange', () => { if (app.selected) dragHandleTo(app.selected, app.selected.object); });

function makeHandles(info) {
  for (const h of app.handles) scene.remove(h.object);
  app.handles = [];
  const names = info.coordinates.map((c) => c.name);
  if (info.basePoseInputs) {
    const object = new THREE.Mesh(new THREE.OctahedronGeometry(0.22 * app.viewScale), materials.handle);
    app.handles.push({ id: 'base-move', label: `base: move (${names.slice(0, 3).join(', ')})`, kind: 'base', mode: 'translate', object });
    app.handles.push({ id: 'base-turn', label: `base: turn (${names.slice(3, 6).join(', ')})`, kind: 'base', mode: 'rotate', object });
  }
  const { points, grounds } = targetsFromClosureRows(info);
  for (const p of points) {
    const object = new THREE.Mesh(new THREE.SphereGeometry(0.2 * app.viewScale, 20, 14), materials.handle);
    const frame = info.frames[p.frame].name;
    app.handles.push({ id: `target-${frame}`, label: `target of ${frame} (${p.targets.map((t) => names[t]).join(', ')})`,
                       kind: 'point', mode: 'translate', targets: p.targets, frame: p.frame, object });
  }
  for (const g of grounds) {
    const object = new THREE.Mesh(new THREE.CylinderGeometry(0.45 * app.viewScale, 0.45 * app.viewScale, 0.02 * app.viewScale, 32), materials.ground);
    object.quaternion.setFromUnitVectors(_y, new THREE.Vector3(0, 0, 1));
    const frame = info.frames[g.frame].name;
    app.handles.push({ id: `ground-${frame}`, label: `ground under ${frame} (${names[g.target]})`, kind: 'ground',
                       mode: 'translate', target: g.target, frame: g.frame, object });
  }
  const seen = new Set();
  for (const h of app.handles) {
    h.object.renderOrder = 10;
    if (!seen.has(h.object)) scene.add(h.object);
    seen.add(h.object);
  }
  const box = ui('handles');
  box.textContent = '';
  for (const h of app.handles) {
    const b = document.createElement('button');
    b.textContent = h.label;
    b.style.display = 'block';
    b.style.margin = '2px 0';
    b.dataset.handle = h.id;
    b.onclick = () => selectHandle(h.id);
    box.appendChild(b);
  }
}

// Puts each handle where its inputs say (the last reachable inputs).
function placeHandles(positions, rotations) {
  const q = app.inputs;
  for (const h of app.handles) {
    if (app.selected === h && gizmo.dragging) continue;  // the pointer moves it
    if (h.kind === 'base') {
      h.object.position.set(q[0], q[1], q[2]);
      h.object.rotation.set(q[5], q[4], q[3], 'ZYX');  // R = Rz(yaw) Ry(pitch) Rx(roll), checked by the module
    } else if (h.kind === 'point') {
      h.object.position.set(q[h.targets[0]], q[h.targets[1]], q[h.targets[2]]);
    } else if (h.kind === 'ground') {
      h.object.position.set(positions[3 * h.frame], positions[3 * h.frame + 1], q[h.target]);
    }
  }
}

function selectHandle(id) {
  const h = app.handles.find((x) => x.id === id) || null;
  app.selected = h;
  for (const x of app.handles) x.object.material = x.object === h?.object ? materials.handleSelected : (x.kind === 'ground' ? materials.ground : materials.handle);
  for (const b of ui('handles').children) b.classList.toggle('on', b.dataset.handle === id);
  if (!h) { gizmo.detach(); return; }
  pause();
  gizmo.attach(h.object);
  gizmo.setMode(h.mode);
  gizmo.setSpace(h.mode === 'rotate' ? 'local' : 'world');
  gizmo.showX = gizmo.showY = h.kind !== 'ground';
  gizmo.showZ = true;
}

// The inputs a handle's pose asks for.
function inputsForHandle(h, object) {
  const q = Float64Array.from(app.inputs);
  if (h.kind === 'base') {
    q[0] = object.position.x; q[1] = object.position.y; q[2] = object.position.z;
    const e = new THREE.Euler().setFromQuaternion(object.quaternion, 'ZYX');
    q[3] = e.z; q[4] = e.y; q[5] = e.x;
  } else if (h.kind === 'point') {
    q[h.targets[0]] = object.position.x; q[h.targets[1]] = object.position.y; q[h.targets[2]] = object.position.z;
  } else if (h.kind === 'ground') {
    q[h.target] = object.position.z;
  }
  return q;
}

// Solves the IK for new inputs; on success the pose follows, otherwise the pose stays at the last
// reachable one and the CLI's message is shown. Returns { ok, message }.
function trySolve(q) {
  const t0 = performance.now();
  const result = app.model.solve(q, app.branches);
  app.ikTimes.push(performance.now() - t0);
  if (app.ikTimes.length > 1000) app.ikTimes.shift();
  if (!result.ok) {
    showMessage(result.message);
    placeMachine();  // puts the dragged handle back at the last reachable inputs
    return { ok: false, message: result.message };
  }
  showMessage('');
  app.inputs = Float64Array.from(q);
  app.s = result.s;
  placeMachine();
  return { ok: true, message: '' };
}

function dragHandleTo(h, object) {
  const result = trySolve(inputsForHandle(h, object));
  if (!result.ok && gizmo.dragging) {
    // Keep the gizmo at the last reachable pose: the next pointer move starts from there.
    const keep = app.selected;
    app.selected = null;
    placeHandles(app.model.forwardKinematics(app.s).positions, null);
    app.selected = keep;
  }
  return result;
}

// Picking a handle by clicking it.
const raycaster = new THREE.Raycaster();
renderer.domElement.addEventListener('pointerdown', (event) => {
  if (gizmo.dragging || gizmo.axis) return;
  const rect = renderer.domElement.getBoundingClientRect();
  const pointer = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1, -((event.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(pointer, camera);
  const hit = raycaster.intersectObjects(app.handles.map((h) => h.object), false)[0];
  if (!hit) return;
  const candidates = app.handles.filter((h) => h.object === hit.object);
  // A second click on the base handle switches between moving and turning.
  const next = candidates.length > 1 && candidates.includes(app.selected)
    ? candidates[(candidates.indexOf(app.selected) + 1) % candidates.length] : candidates[0];
  selectHandle(next.id);
});

// --- side panel -----------------------------------------------------------------------------
let valueCells = [];
function buildPanel(info) {
  ui('model-name').textContent = info.name;
  ui('model-description').textContent = info.description;
  const table = ui('coordinates');
  table.textContent = '';
  valueCells = info.coordinates.map((c, k) => {
    const tr = document.createElement('tr');
    tr.className = (k < info.inputCount ? 'input' : 'dependent') + (k === info.inputCount ? ' sep' : '');
    const name = document.createElement('td'); name.textContent = c.name;
    const value = document.createElement('td'); value.className = 'v';
    const unit = document.createElement('td'); unit.className = 'muted';
    const deg = document.createElement('td'); deg.className = 'v muted';
    unit.textContent = c.unit;
    tr.append(name, value, unit, deg);
    table.appendChild(tr);
    return { value, deg, angle: c.unit === 'rad' };
  });
  const branches = ui('branches');
  branches.textContent = '';
  info.limbs.forEach((limb, k) => {
    const label = document.createElement('label');
    label.style.display = 'block';
    const select = document.createElement('select');
    for (let b = 0; b < limb.branches; ++b) select.add(new Option(String(b), String(b)));
    select.value = String(app.branches[k]);
    select.onchange = () => {
      const previous = app.branches[k];
      app.branches[k] = Number(select.value);
      if (!trySolve(app.inputs).ok) { app.branches[k] = previous; select.value = String(previous); }
    };
    label.append(`${limb.title} `, select);
    branches.appendChild(label);
  });
}

function updatePanel() {
  valueCells.forEach((cell, k) => {
    cell.value.textContent = fmt(app.s[k]);
    cell.deg.textContent = cell.angle ? fmt((app.s[k] * 180) / Math.PI, 2) + '°' : '';
  });
  ui('residual').textContent = Number.isFinite(app.residual) ? app.residual.toExponential(2) + ' (m or rad)' : '—';
}

// --- runs: playback, plot, tracks ----------------------------------------------------------------
function prepareRun(run) {
  const info = app.info;
  const missing = info.coordinates.map((c) => c.name).filter((n) => !run.columns[n]);
  if (run.model !== info.name) throw new Error(`run '${run.id}': made with model '${run.model}', the page shows '${info.name}'`);
  if (missing.length) throw new Error(`run '${run.id}': columns missing: ${missing.join(', ')}`);
  const n = run.columns.t.length;
  const frames = [];
  for (let i = 0; i < n; ++i) frames.push(Float64Array.from(info.coordinates, (c) => run.columns[c.name][i]));
  // The wheels' ground tracks: their contact points by the model's forward kinematics.
  tracks.clear();
  app.tracks = [];
  for (const w of info.wheels) {
    const points = frames.map((s) => {
      const p = app.model.forwardKinematics(s).positions;
      const f = w.contactFrame;
      return new THREE.Vector3(p[3 * f], p[3 * f + 1], p[3 * f + 2] + 0.01);
    });
    // A thin tube rather than a line: WebGL draws lines one pixel wide whatever is asked.
    const distinct = points.filter((p, i) => i === 0 || p.distanceTo(points[i - 1]) > 1e-6);
    app.tracks.push({ wheel: w.name, start: points[0].toArray(), end: points[points.length - 1].toArray(), distinct: distinct.length });
    if (distinct.length < 2) continue;  // the wheel did not move
    const path = new THREE.CatmullRomCurve3(distinct, false, 'centripetal');
    const tube = new THREE.Mesh(new THREE.TubeGeometry(path, Math.min(4 * distinct.length, 2000), 0.03, 6, false),
                                new THREE.MeshStandardMaterial({ color: 0x1565c0 }));
    tube.name = `track ${w.name}`;
    tracks.add(tube);
  }
  const prepared = { ...run, frames, t: run.columns.t };
  prepareForces(prepared);
  return prepared;
}

// --- the contacts' overlay -----------------------------------------------------------------------
// Colours by margin: green, orange where it runs low, red where it is gone (a pull on the ground, a
// slip, tipping). "Low": a friction margin under a fifth of mu f_n, a tip-over angle under 10 deg.
const marginColours = { ok: 0x2e9d4a, low: 0xf08c00, gone: 0xd62828 };

function prepareForces(run) {
  forceGroup.clear();
  app.forces = null;
  if (!run.contacts) return;
  const byName = new Map(app.info.contacts.map((c) => [c.name, c]));
  const contacts = run.contacts.map((name) => {
    const c = byName.get(name);
    if (!c) throw new Error(`run '${run.id}': contact '${name}' is not one of model ${app.info.name}'s`);
    return c;
  });
  // N to m: the mean contact's share of the total normal force at the start (the machine's weight
  // when it starts at rest) is drawn one view unit long (a seventh of the machine's size), so any
  // machine's arrows fit beside it.
  const total = contacts.reduce((sum, c) => sum + Math.abs(run.columns['f_n_' + c.name][0]), 0);
  let largest = 0;
  for (const c of contacts)
    for (let i = 0; i < run.columns.t.length; ++i)
      largest = Math.max(largest, Math.hypot(run.columns['f_x_' + c.name][i], run.columns['f_y_' + c.name][i], run.columns['f_n_' + c.name][i]));
  const reference = total > 0 ? total : largest;
  const metresPerNewton = reference > 0 ? (app.viewScale * contacts.length) / reference : 0;
  const arrows = contacts.map((c) => {
    const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 1, marginColours.ok);
    arrow.name = `force ${c.name}`;
    forceGroup.add(arrow);
    return { contact: c, arrow, length: 0, colour: 'ok' };
  });
  const polygon = new THREE.LineLoop(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: marginColours.ok }));
  polygon.name = 'support polygon';
  const fill = new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshBasicMaterial({ color: marginColours.ok, transparent: true, opacity: 0.25, side: THREE.DoubleSide, depthWrite: false }));
  fill.name = 'support polygon area';
  const com = new THREE.Mesh(new THREE.SphereGeometry(0.12 * app.viewScale, 16, 12), new THREE.MeshStandardMaterial({ color: 0x7b2cbf }));
  com.name = 'centre of mass';
  const comDrop = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineDashedMaterial({ color: 0x7b2cbf, dashSize: 0.1, gapSize: 0.06 }));
  const comGround = new THREE.Mesh(new THREE.RingGeometry(0.08 * app.viewScale, 0.13 * app.viewScale, 24), new THREE.MeshBasicMaterial({ color: 0x7b2cbf, side: THREE.DoubleSide }));
  comGround.name = 'centre of mass on the ground';
  const zmp = new THREE.Mesh(new THREE.CircleGeometry(0.1 * app.viewScale, 4), new THREE.MeshBasicMaterial({ color: 0x0077b6, side: THREE.DoubleSide }));
  zmp.name = 'zero-moment point';
  forceGroup.add(polygon, fill, com, comDrop, comGround, zmp);
  forceGroup.visible = ui('show-forces').checked;
  app.forces = { contacts, arrows, polygon, fill, com, comDrop, comGround, zmp, metresPerNewton, vertices: [], tip: NaN };
  ui('forces-panel').style.display = 'block';
  ui('force-scale').textContent = `${fmt(1000 * metresPerNewton, 3)} m per kN`;
}

// The convex hull of points in the ground plane, counter-clockwise (Andrew's monotone chain): the
// support polygon of the contacts carrying load, as the runtime forms it for its margins.
function convexHull(points) {
  const p = points.slice().sort((a, b) => a.x - b.x || a.y - b.y);
  if (p.length < 3) return p;
  const cross = (o, a, b) => (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  const lower = [], upper = [];
  for (const q of p) { while (lower.length >= 2 && cross(lower[lower.length - 2], lower[lower.length - 1], q) <= 0) lower.pop(); lower.push(q); }
  for (const q of p.slice().reverse()) { while (upper.length >= 2 && cross(upper[upper.length - 2], upper[upper.length - 1], q) <= 0) upper.pop(); upper.push(q); }
  return lower.slice(0, -1).concat(upper.slice(0, -1));
}

function placeForces(positions, i) {
  const f = app.forces, cols = app.run.columns;
  const loaded = [];
  let height = 0;
  for (const a of f.arrows) {
    const c = a.contact, o = 3 * c.frame;
    const origin = new THREE.Vector3(positions[o], positions[o + 1], positions[o + 2]);
    const force = new THREE.Vector3(cols['f_x_' + c.name][i], cols['f_y_' + c.name][i], cols['f_n_' + c.name][i]);
    const normal = force.z, margin = cols['friction_margin_' + c.name][i];
    a.colour = (c.supports && normal <= 0) || margin < 0 ? 'gone' : margin < 0.2 * c.friction * Math.max(normal, 0) ? 'low' : 'ok';
    a.length = force.length() * f.metresPerNewton;
    a.arrow.visible = a.length > 1e-9;
    if (a.arrow.visible) {
      // From the contact along the ground's force on the machine (up when it carries load).
      a.arrow.position.copy(origin);
      a.arrow.setDirection(force.clone().normalize());
      a.arrow.setLength(a.length, Math.min(0.25 * a.length, 0.3 * app.viewScale), Math.min(0.12 * a.length, 0.15 * app.viewScale));
      a.arrow.setColor(marginColours[a.colour]);
    }
    if (c.supports && normal > 0) { loaded.push(new THREE.Vector2(origin.x, origin.y)); height += origin.z; }
  }
  height = loaded.length ? height / loaded.length : 0;
  const lift = 0.02 * app.viewScale;  // just above the ground, so the ground's grid does not hide it
  f.vertices = convexHull(loaded);
  f.tip = cols.margin_tip[i];
  const tipColour = !(f.tip > 0) ? 'gone' : f.tip < (10 * Math.PI) / 180 ? 'low' : 'ok';
  f.tipColour = tipColour;
  const ring = f.vertices.map((v) => new THREE.Vector3(v.x, v.y, height + lift));
  f.polygon.geometry.dispose();
  f.polygon.geometry = new THREE.BufferGeometry().setFromPoints(ring);
  f.polygon.material.color.setHex(marginColours[tipColour]);
  f.fill.geometry.dispose();
  f.fill.geometry = ring.length >= 3 ? new THREE.ShapeGeometry(new THREE.Shape(f.vertices)) : new THREE.BufferGeometry();
  f.fill.position.z = height + 0.5 * lift;
  f.fill.material.color.setHex(marginColours[tipColour]);
  const comPoint = new THREE.Vector3(cols.com_x[i], cols.com_y[i], cols.com_z[i]);
  f.com.position.copy(comPoint);
  f.comGround.position.set(comPoint.x, comPoint.y, height + lift);
  f.comDrop.geometry.dispose();
  f.comDrop.geometry = new THREE.BufferGeometry().setFromPoints([comPoint, new THREE.Vector3(comPoint.x, comPoint.y, height + lift)]);
  f.comDrop.computeLineDistances();
  f.zmp.position.set(cols.zmp_x[i], cols.zmp_y[i], height + 1.5 * lift);
  ui('margin-static').textContent = fmt(cols.margin_static[i], 3) + ' m';
  ui('margin-zmp').textContent = fmt(cols.margin_zmp[i], 3) + ' m';
  ui('margin-tip').textContent = fmt((f.tip * 180) / Math.PI, 2) + '°';
  ui('margin-tip').style.color = tipColour === 'ok' ? '' : '#' + marginColours[tipColour].toString(16).padStart(6, '0');
  const rows = ui('contact-rows');
  rows.textContent = '';
  for (const a of f.arrows) {
    const tr = document.createElement('tr');
    const cells = [a.contact.name, fmt(cols['f_n_' + a.contact.name][i] / 1000, 2), fmt(cols['friction_margin_' + a.contact.name][i] / 1000, 2)];
    for (const text of cells) { const td = document.createElement('td'); td.textContent = text; tr.appendChild(td); }
    tr.style.color = a.colour === 'ok' ? '' : '#' + marginColours[a.colour].toString(16).padStart(6, '0');
    rows.appendChild(tr);
  }
}

function sampleIndex(t) {
  const ts = app.run.t;
  let lo = 0, hi = ts.length - 1;
  while (lo < hi) {  // last sample with ts <= t
    const mid = (lo + hi + 1) >> 1;
    if (ts[mid] <= t) lo = mid; else hi = mid - 1;
  }
  return lo;
}

function showTime(t) {
  if (!app.run) return;
  const ts = app.run.t, t0 = ts[0], t1 = ts[ts.length - 1];
  app.time = Math.min(Math.max(t, t0), t1);
  const i = sampleIndex(app.time);
  app.s = Float64Array.from(app.run.frames[i]);
  app.inputs = app.s.slice(0, app.info.inputCount);
  showMessage('');
  placeMachine();
  if (app.forces) placeForces(app.model.forwardKinematics(app.s).positions, i);
  ui('scrub').value = String(Math.round(((app.time - t0) / Math.max(t1 - t0, 1e-12)) * 1000));
  ui('time').textContent = `t = ${app.time.toFixed(3)} s of ${t1.toFixed(3)} s`;
  drawPlot(ui('plot'), app.run, app.time);
}

function play() {
  if (!app.run) return;
  if (app.time >= app.run.t[app.run.t.length - 1]) app.time = app.run.t[0];
  app.playing = true;
  ui('play').textContent = 'pause';
  gizmo.detach();
  app.selected = null;
}

function pause() {
  app.playing = false;
  ui('play').textContent = 'play';
}

ui('play').onclick = () => (app.playing ? pause() : play());
ui('speed').onchange = () => { app.speed = Number(ui('speed').value); };
ui('scrub').oninput = () => {
  if (!app.run) return;
  pause();
  const ts = app.run.t;
  showTime(ts[0] + (Number(ui('scrub').value) / 1000) * (ts[ts.length - 1] - ts[0]));
};
ui('show-com').onchange = () => { comGroup.visible = ui('show-com').checked; placeMachine(); };
ui('show-tracks').onchange = () => { tracks.visible = ui('show-tracks').checked; };
ui('show-forces').onchange = () => { forceGroup.visible = ui('show-forces').checked; };

// --- frame loop -------------------------------------------------------------------------------
let lastFrame = performance.now();
function resize() {
  const w = sceneEl.clientWidth, h = sceneEl.clientHeight;
  if (renderer.domElement.width !== Math.floor(w * renderer.getPixelRatio()) || renderer.domElement.height !== Math.floor(h * renderer.getPixelRatio())) {
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
    if (app.run) drawPlot(ui('plot'), app.run, app.time);
  }
}
function frame(now) {
  const dt = Math.min((now - lastFrame) / 1000, 0.1);
  lastFrame = now;
  resize();
  if (app.playing && app.run) {
    const end = app.run.t[app.run.t.length - 1];
    showTime(app.time + dt * app.speed);
    if (app.time >= end) pause();
  }
  renderer.render(scene, camera);
  requestAnimationFrame(frame);
}

// --- start ------------------------------------------------------------------------------------
const params = new URLSearchParams(window.location.search);
const ready = (async () => {
  const t0 = performance.now();
  try {
    await loadScript('runs/index.js');
  } catch (e) {
    registry.index = [];  // no runs exported: the page still poses the model
  }
  const index = registry.index || [];
  let runId = params.get('run') || (params.get('model') ? null : index[0]?.id ?? null);
  // A '+' left unencoded in a link (?run=ST-A1+) reads back as a space; run ids have no spaces.
  if (runId && !index.some((r) => r.id === runId)) runId = runId.replace(/ /g, '+');
  const entry = runId ? index.find((r) => r.id === runId) : null;
  if (runId && !entry) throw new Error(`run '${runId}' is not in runs/index.js (runs: ${index.map((r) => r.id).join(', ') || 'none'})`);
  const modelName = entry ? entry.model : (params.get('model') || index[0]?.model || window.WLX_VIEWER_MODELS[0]);
  // A built-in model's module comes with the page; a model file's (`wlx viewer --model-file`) is
  // written beside it by wlx: any model whose wasm/wlx_<name>.js is in the folder is drawn.
  app.model = await WasmModel.load(modelName, loadScript).catch((e) => {
    throw new Error(`model '${modelName}': ${e.message} (this folder's page came with ${window.WLX_VIEWER_MODELS.join(', ')}; ` +
                    'wlx viewer --model-file FILE writes a model file\'s own module)');
  });
  app.info = app.model.info;
  // The model's branches (its file's default, else within the joints' ranges), as `wlx ik` takes them.
  app.branches = Int32Array.from(app.info.limbs, (limb) => limb.defaultBranch);
  // The nominal pose first, so that a run that fails to load still leaves a machine on screen, and
  // the view and the drawn parts sized to it.
  const nominal = app.model.solve(Float64Array.from(app.info.nominalInputs), app.branches);
  if (!nominal.ok) throw new Error(`the nominal pose: ${nominal.message}`);
  app.inputs = Float64Array.from(app.info.nominalInputs);
  app.s = nominal.s;
  frameView();
  buildMachine(app.info);
  makeHandles(app.info);
  buildPanel(app.info);
  const select = ui('run-select');
  for (const r of index.filter((r) => r.model === app.info.name)) select.add(new Option(`${r.id}${r.description ? ' — ' + r.description : ''}`, r.id));
  select.add(new Option('(no run: nominal pose)', ''));
  select.value = runId || '';
  select.onchange = () => {
    const url = new URL(window.location.href);
    if (select.value) url.searchParams.set('run', select.value); else { url.searchParams.delete('run'); url.searchParams.set('model', app.info.name); }
    window.location.href = url.toString();
  };
  placeMachine();
  if (runId) {
    app.run = prepareRun(await loadRun(runId));
    showTime(app.run.t[0]);
  } else {
    ui('controls').style.opacity = 0.4;
    drawPlot(ui('plot'), null, 0);
  }
  app.loadMs = performance.now() - t0;
  return true;
})();
ready.catch((e) => showMessage(`viewer: ${e.message}`));
requestAnimationFrame(frame);

// The view scaled to the machine at its nominal pose: the default camera and the drawn joints,
// links and handles suit a machine whose frames span some 7 m (the excavator); a 0.9 m quadruped
// gets the same share of the screen and parts in proportion (app.viewScale).
function frameView() {
  const { positions } = app.model.forwardKinematics(app.s);
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let f = 0; f < positions.length / 3; ++f)
    for (let i = 0; i < 3; ++i) lo[i] = Math.min(lo[i], positions[3 * f + i]), hi[i] = Math.max(hi[i], positions[3 * f + i]);
  const size = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  app.viewScale = Math.min(3, Math.max(0.1, size / 7));
  const c = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, Math.max(0, (lo[2] + hi[2]) / 2)];
  orbit.target.set(c[0], c[1], c[2]);
  camera.position.set(c[0] + 9 * app.viewScale, c[1] - 11 * app.viewScale, c[2] + 6 * app.viewScale);
  axes.scale.setScalar(app.viewScale);
  orbit.update();
  orbit.saveState();
}

// --- the page's API (for tests and scripting) -----------------------------------------------
viewer.ready = ready;
viewer.api = {
  info: () => app.info,
  handles: () => app.handles.map((h) => ({ id: h.id, label: h.label })),
  coordinates: () => Object.fromEntries(app.info.coordinates.map((c, k) => [c.name, app.s[k]])),
  inputs: () => Array.from(app.inputs),
  residual: () => app.residual,
  message: () => app.message,
  // Moves a handle by (dx, dy, dz) in K0 (and, for the base, by (dyaw, dpitch, droll)) in
  // `steps` equal steps, each going through the same path as a mouse drag of the gizmo.
  drag(id, delta, steps = 10) {
    const h = app.handles.find((x) => x.id === id);
    if (!h) throw new Error(`no handle '${id}' (handles: ${app.handles.map((x) => x.id).join(', ')})`);
    selectHandle(id);
    let result = { ok: true, message: '' };
    for (let k = 1; k <= steps; ++k) {
      const proxy = new THREE.Object3D();
      proxy.position.copy(h.object.position);
      proxy.quaternion.copy(h.object.quaternion);
      proxy.position.x += (delta.x || 0) / steps;
      proxy.position.y += (delta.y || 0) / steps;
      proxy.position.z += (delta.z || 0) / steps;
      if (delta.yaw || delta.pitch || delta.roll) {
        const e = new THREE.Euler().setFromQuaternion(proxy.quaternion, 'ZYX');
        proxy.rotation.set(e.x + (delta.roll || 0) / steps, e.y + (delta.pitch || 0) / steps, e.z + (delta.yaw || 0) / steps, 'ZYX');
      }
      result = dragHandleTo(h, proxy);
    }
    return result;
  },
  play, pause,
  seek: (t) => { pause(); showTime(t); },
  time: () => app.time,
  playing: () => app.playing,
  setSpeed: (v) => { app.speed = v; },
  runInfo: () => app.run && { id: app.run.id, samples: app.run.t.length, start: app.run.t[0], end: app.run.t[app.run.t.length - 1], plot: app.run.plot },
  ikTimes: () => app.ikTimes.slice(),
  tracks: () => app.tracks,
  // The contacts' overlay at the time shown: each arrow's contact, drawn length (m), scale (m/N)
  // and colour, the support polygon's vertices, the tip-over margin; null for a run without it.
  forces: () => app.forces && {
    metresPerNewton: app.forces.metresPerNewton,
    arrows: app.forces.arrows.map((a) => ({ name: a.contact.name, length: a.length, visible: a.arrow.visible, colour: a.colour })),
    vertices: app.forces.vertices.map((v) => [v.x, v.y]),
    tip: app.forces.tip,
    tipColour: app.forces.tipColour,
    sampleIndex: sampleIndex(app.time),
    shown: forceGroup.visible,
  },
  // Where a handle is on the page, in CSS pixels (to drag it with the mouse).
  screenPoint(id) {
    const h = app.handles.find((x) => x.id === id);
    const p = h.object.position.clone().project(camera);
    const rect = renderer.domElement.getBoundingClientRect();
    return { x: rect.left + ((p.x + 1) / 2) * rect.width, y: rect.top + ((1 - p.y) / 2) * rect.height };
  },
  // Mean milliseconds of one IK solve of the current inputs through the module, over n solves
  // (one drag step is one solve; a single call is below performance.now()'s resolution).
  timeIk(n = 2000) {
    const t0 = performance.now();
    for (let k = 0; k < n; ++k) app.model.solve(app.inputs, app.branches);
    return (performance.now() - t0) / n;
  },
  // A view from above onto the wheels' tracks (for screenshots).
  lookFromAbove() {
    camera.position.set(orbit.target.x + 0.01, orbit.target.y - 0.01, 16 * (app.viewScale || 1));
    orbit.update();
  },
  resetView() { orbit.reset(); },
  loadMs: () => app.loadMs,
  // Pixels of the 3D view that differ from the background, for a blank-canvas check.
  paintedPixels() {
    renderer.render(scene, camera);
    const c = document.createElement('canvas');
    c.width = renderer.domElement.width; c.height = renderer.domElement.height;
    const g = c.getContext('2d');
    g.drawImage(renderer.domElement, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    const srgb = scene.background.getRGB({}, THREE.SRGBColorSpace);  // what the canvas holds
    const [r0, g0, b0] = [srgb.r, srgb.g, srgb.b].map((v) => Math.round(v * 255));
    let painted = 0;
    for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - r0) + Math.abs(d[i + 1] - g0) + Math.abs(d[i + 2] - b0) > 24) ++painted;
    return { painted, total: c.width * c.height };
  },
};
