// tugsim instructor station: 3D view, gauges, tension plot and orders for a running simulation or
// a replay. Talks only to the live view node that served it: GET /api/state (a snapshot sampled at
// the node's http_rate), GET /api/scene (hull shapes), GET /api/sea (the run's wave components),
// POST /api/publish?topic=... (orders, checked by the node like any client's). World frame: ENU
// (x east, y north, z up), as the simulation's.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/OrbitControls.js';

const params = new URLSearchParams(location.search);
const KN = 1852 / 3600;
const $ = (id) => document.getElementById(id);
const fmt = (v, d) => (v === null || v === undefined || !Number.isFinite(v)) ? '--' : v.toFixed(d);
// an angle with the page's one sign convention (REP-103: + port, - starboard) and the side named
const signed = (v, d) => {
  const t = fmt(v, d);
  if (t === '--' || Number(t) === 0) return t === '--' ? t : (0).toFixed(d);
  return `${v > 0 ? '+' : ''}${t} ${v > 0 ? 'P' : 'S'}`;
};

const app = {
  snap: null, scene: {}, selected: params.get('vessel') || null, rope: params.get('rope') || null,
  camera: params.get('camera') || 'follow', touched: 0, frames: 0, updates: 0, lastSceneAsk: 0,
  peakSeen: 1, answers: [],
};
// for tests and the curious: app.snap, app.project(name), app.send(...); app.hold = true keeps the
// picture still (snapshots not applied) for a pixel check
window.instructor = app;

// ---------------------------------------------------------------- 3D scene
const canvas = $('scene');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
const scene3 = new THREE.Scene();
scene3.background = new THREE.Color(0x9cc3dd);
scene3.fog = new THREE.Fog(0x9cc3dd, 1500, 6000);
const camera = new THREE.PerspectiveCamera(45, 1, 0.5, 20000);
camera.up.set(0, 0, 1);
camera.position.set(-80, -80, 60);
const orbit = new OrbitControls(camera, canvas);
orbit.enabled = false;
orbit.addEventListener('change', () => { dirty = true; });
orbit.maxPolarAngle = Math.PI * 0.495;
scene3.add(new THREE.HemisphereLight(0xdfefff, 0x1c3a4a, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(-300, -200, 500);
scene3.add(sun);
const water = new THREE.Mesh(new THREE.PlaneGeometry(40000, 40000),
  new THREE.MeshPhongMaterial({ color: 0x1d5b7d, shininess: 60, transparent: true, opacity: 0.93 }));
scene3.add(water);
const grid = new THREE.GridHelper(2000, 40, 0x5b8fb0, 0x3f7494);  // 50 m squares
grid.rotation.x = Math.PI / 2;
grid.position.z = 0.02;
grid.material.transparent = true;
grid.material.opacity = 0.45;
scene3.add(grid);

// ---------------------------------------------------------------- the sea
// GET /api/sea gives the components of the run's WaveField (sea_environment, the same seed the
// vessel nodes use): eta(x, y, t) = r(t) sum a_i cos(kx_i x + ky_i y - omega_i t + phase_i), r the
// half-cosine start-up ramp. The surface is a SEA_CELLS x SEA_CELLS grid of SEA_SIZE metres around
// the followed vessel (snapped to whole cells so it does not swim), its vertex heights the sea at
// the snapshot's simulation time (every component; drawn between the vertices as flat triangles);
// its outer SEA_TAPER fraction eases down to the flat water beyond. A calm sea (no waves, hs 0):
// the flat water as before. The sum costs (cells + 1)^2 x components multiply-adds a snapshot (the
// cosines are taken per grid line: cos(A + B) = cos A cos B - sin A sin B).
const SEA_SIZE = 800, SEA_CELLS = 80, SEA_TAPER = 0.2;
const sea = { waves: null, mesh: null, frame: null, t: null, evaluations: 0, ms: 0 };
app.sea = sea;
function seaRamp(t) {
  const T = sea.waves.ramp_time;
  if (!(T > 0)) return 1;
  if (t <= 0) return 0;
  return t >= T ? 1 : 0.5 * (1 - Math.cos(Math.PI * t / T));
}
// the sea's elevation (m) at one point and time, every component: for tests and the curious
app.seaHeight = (x, y, t) => {
  const w = sea.waves;
  if (!w) return 0;
  let eta = 0;
  for (let i = 0; i < w.amplitude.length; i++) {
    eta += w.amplitude[i] * Math.cos(w.kx[i] * x + w.ky[i] * y - w.omega[i] * t + w.phase[i]);
  }
  return seaRamp(t) * eta;
};
function buildSea(w) {
  sea.waves = w;
  const n = SEA_CELLS + 1, d = SEA_SIZE / SEA_CELLS;
  const pos = new Float32Array(3 * n * n), col = new Float32Array(3 * n * n), idx = [];
  for (let iy = 0; iy < n; iy++) {
    for (let ix = 0; ix < n; ix++) {
      const k = iy * n + ix;
      pos[3 * k] = -SEA_SIZE / 2 + ix * d; pos[3 * k + 1] = -SEA_SIZE / 2 + iy * d;
      if (ix < SEA_CELLS && iy < SEA_CELLS) idx.push(k, k + 1, k + n + 1, k, k + n + 1, k + n);
    }
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.setAttribute('color', new THREE.BufferAttribute(col, 3));
  g.setIndex(idx);
  sea.mesh = new THREE.Mesh(g, new THREE.MeshPhongMaterial({ vertexColors: true, shininess: 40, specular: 0x2a4455,
    transparent: true, opacity: 0.93, side: THREE.DoubleSide }));
  sea.mesh.frustumCulled = false;
  scene3.add(sea.mesh);
  // the flat water beyond the surface: a frame with the surface's square cut out
  const outer = new THREE.Shape();
  outer.moveTo(-20000, -20000); outer.lineTo(20000, -20000); outer.lineTo(20000, 20000); outer.lineTo(-20000, 20000);
  const hole = new THREE.Path(), h = SEA_SIZE / 2 - 0.5 * d;
  hole.moveTo(-h, -h); hole.lineTo(-h, h); hole.lineTo(h, h); hole.lineTo(h, -h);
  outer.holes.push(hole);
  sea.frame = new THREE.Mesh(new THREE.ShapeGeometry(outer), water.material);
  scene3.add(sea.frame);
  water.visible = false;
  grid.visible = false;
  const m = w.amplitude.length;
  sea.cx = new Float64Array(n * m); sea.sx = new Float64Array(n * m);
  sea.cy = new Float64Array(n * m); sea.sy = new Float64Array(n * m);
  sea.lastKey = null;
}
const deepColor = new THREE.Color(0x08304a), crestColor = new THREE.Color(0x5f9ab8), tmpColor = new THREE.Color();
function updateSea(t, px, py) {
  const w = sea.waves;
  if (!w || t === null || t === undefined) return;
  const n = SEA_CELLS + 1, d = SEA_SIZE / SEA_CELLS, m = w.amplitude.length;
  const ox = Math.round(px / d) * d, oy = Math.round(py / d) * d;  // the surface's centre, whole cells
  const key = `${t}|${ox}|${oy}`;
  if (key === sea.lastKey) return;
  sea.lastKey = key;
  const t0 = performance.now();
  const r = seaRamp(t);
  const { cx, sx, cy, sy } = sea;
  for (let i = 0; i < n; i++) {
    const x = ox - SEA_SIZE / 2 + i * d, y = oy - SEA_SIZE / 2 + i * d;
    for (let j = 0; j < m; j++) {
      const a = w.kx[j] * x, b = w.ky[j] * y - w.omega[j] * t + w.phase[j];
      cx[i * m + j] = Math.cos(a); sx[i * m + j] = Math.sin(a);
      cy[i * m + j] = w.amplitude[j] * Math.cos(b); sy[i * m + j] = w.amplitude[j] * Math.sin(b);
    }
  }
  const pos = sea.mesh.geometry.attributes.position.array, col = sea.mesh.geometry.attributes.color.array;
  const half = SEA_SIZE / 2, inner = (1 - SEA_TAPER) * half, hs = Math.max(0.1, w.hs);
  for (let iy = 0; iy < n; iy++) {
    const yo = iy * m, ly = Math.abs(-half + iy * d);
    for (let ix = 0; ix < n; ix++) {
      const xo = ix * m;
      let eta = 0;
      for (let j = 0; j < m; j++) eta += cx[xo + j] * cy[yo + j] - sx[xo + j] * sy[yo + j];  // a cos(A + B)
      const edge = Math.max(Math.abs(-half + ix * d), ly);
      const z = r * eta * (edge <= inner ? 1 : Math.max(0, (half - edge) / (half - inner)));
      const k = iy * n + ix;
      pos[3 * k + 2] = z;
      tmpColor.lerpColors(deepColor, crestColor, Math.max(0, Math.min(1, 0.5 + z / hs)));
      col[3 * k] = tmpColor.r; col[3 * k + 1] = tmpColor.g; col[3 * k + 2] = tmpColor.b;
    }
  }
  sea.mesh.position.set(ox, oy, 0);
  sea.frame.position.set(ox, oy, 0);
  sea.mesh.geometry.attributes.position.needsUpdate = true;
  sea.mesh.geometry.attributes.color.needsUpdate = true;
  sea.mesh.geometry.computeVertexNormals();
  sea.t = t; sea.ox = ox; sea.oy = oy;
  sea.evaluations += 1;
  sea.ms = performance.now() - t0;
}
// the surface as drawn at grid vertex (ix, iy): its world x, y, height and time; for tests
app.seaVertex = (ix, iy) => {
  if (!sea.mesh) return null;
  const n = SEA_CELLS + 1, k = iy * n + ix, p = sea.mesh.geometry.attributes.position.array;
  return { x: sea.ox + p[3 * k], y: sea.oy + p[3 * k + 1], z: p[3 * k + 2], t: sea.t, cells: SEA_CELLS,
    size: SEA_SIZE };
};
async function askSea() {
  try {
    const d = await (await fetch('/api/sea', { cache: 'no-store' })).json();
    sea.note = d.note || null;
    if (d.waves && d.waves.amplitude && d.waves.amplitude.length) {
      buildSea(d.waves);
      if (app.snap) seaFollow(app.snap);
      dirty = true;
    }
    sea.asked = true;
  } catch (e) {
    setTimeout(askSea, 2000);  // asked again
  }
}
function seaFollow(s) {
  if (!sea.waves || s.t === null) return;
  const names = Object.keys(s.vessels).sort();
  const v = (app.selected && s.vessels[app.selected]) || (names.length ? s.vessels[names[0]] : null);
  updateSea(s.t, v ? v.x : 0, v ? v.y : 0);
}

const vessels3 = new Map();  // name -> {group, length, hasGeometry, label}
const ropes3 = new Map();    // name -> {group, meshes: []}
const segGeom = new THREE.CylinderGeometry(1, 1, 1, 10, 1);
const Y = new THREE.Vector3(0, 1, 0);

function textSprite(text) {
  const c = document.createElement('canvas');
  c.width = 256; c.height = 64;
  const g = c.getContext('2d');
  g.font = 'bold 34px sans-serif'; g.fillStyle = '#ffffff'; g.strokeStyle = '#000000'; g.lineWidth = 6;
  g.textAlign = 'center'; g.textBaseline = 'middle';
  g.strokeText(text, 128, 32); g.fillText(text, 128, 32);
  const s = new THREE.Sprite(new THREE.SpriteMaterial({ map: new THREE.CanvasTexture(c), depthTest: false }));
  s.scale.set(16, 4, 1);
  s.renderOrder = 10;  // after the (transparent) water, which would otherwise veil a name beyond its centre
  return s;
}

function meshFrom(flat, color) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(flat, 3));
  g.computeVertexNormals();
  return new THREE.Mesh(g, new THREE.MeshPhongMaterial({ color: new THREE.Color(...color), side: THREE.DoubleSide,
    flatShading: true }));
}

function vessel3(name) {
  let v = vessels3.get(name);
  if (v) return v;
  const group = new THREE.Group();
  const box = new THREE.Mesh(new THREE.BoxGeometry(20, 7, 4), new THREE.MeshPhongMaterial({ color: 0x8c1f1a }));
  box.position.z = 0.5;
  group.add(box);
  const label = textSprite(name);
  label.position.set(0, 0, 10);
  group.add(label);
  scene3.add(group);
  v = { group, length: 20, hasGeometry: false, label, placeholder: box };
  vessels3.set(name, v);
  return v;
}

function applyGeometry(name, d) {
  const v = vessel3(name);
  if (v.hasGeometry || !d.hull) return;
  v.group.remove(v.placeholder);
  const hull = meshFrom(d.hull, d.hull_color || [0.55, 0.12, 0.1]);
  v.group.add(hull);
  if (d.deck) v.group.add(meshFrom(d.deck, d.deck_color || [0.75, 0.75, 0.72]));
  hull.geometry.computeBoundingBox();
  const bb = hull.geometry.boundingBox;
  v.length = Math.max(1, bb.max.x - bb.min.x);
  const size = Math.max(0.3, 0.02 * v.length);
  const att = d.attachments || [];
  for (let i = 0; i + 2 < att.length; i += 3) {
    const s = new THREE.Mesh(new THREE.SphereGeometry(size, 12, 8), new THREE.MeshPhongMaterial({ color: 0xffd900 }));
    s.position.set(att[i], att[i + 1], att[i + 2]);
    v.group.add(s);
  }
  const k = Math.max(0.5, v.length / 30);
  v.label.scale.set(16 * k, 4 * k, 1);
  v.label.position.set(0, 0, bb.max.z + 4 * k);
  v.top = bb.max.z;
  v.hasGeometry = true;
}

function tensionColor(ratio) {
  // green (slack) -> yellow (half the breaking load) -> red (breaking load)
  const r = Math.max(0, Math.min(1, ratio));
  const c = new THREE.Color();
  if (r < 0.5) c.lerpColors(new THREE.Color(0x23d160), new THREE.Color(0xffdd57), r / 0.5);
  else c.lerpColors(new THREE.Color(0xffdd57), new THREE.Color(0xff3860), (r - 0.5) / 0.5);
  return c;
}

function updateRope(name, r) {
  let o = ropes3.get(name);
  if (!o) {
    o = { group: new THREE.Group(), meshes: [] };
    scene3.add(o.group);
    ropes3.set(name, o);
  }
  const pts = r.points || [];
  const n = Math.max(0, pts.length - 1);
  while (o.meshes.length < n) {
    const m = new THREE.Mesh(segGeom, new THREE.MeshPhongMaterial({ color: 0x23d160 }));
    o.group.add(m); o.meshes.push(m);
  }
  const radius = Math.max(0.25, 0.004 * camera.position.distanceTo(orbit.target));
  const scale = r.breaking_load || Math.max(app.peakSeen, 1);
  const a = new THREE.Vector3(), b = new THREE.Vector3(), d = new THREE.Vector3();
  o.meshes.forEach((m, i) => {
    m.visible = i < n;
    if (!m.visible) return;
    a.set(...pts[i]); b.set(...pts[i + 1]);
    d.subVectors(b, a);
    const len = d.length();
    m.position.addVectors(a, b).multiplyScalar(0.5);
    m.scale.set(radius, Math.max(len, 1e-3), radius);
    if (len > 1e-6) m.quaternion.setFromUnitVectors(Y, d.normalize());
    const t = 0.5 * ((r.tensions[i] || 0) + (r.tensions[i + 1] || 0));
    m.material.color.copy(tensionColor(t / scale));
  });
}

function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) ||
      canvas.height !== Math.floor(h * renderer.getPixelRatio())) {
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
    return true;
  }
  return false;
}

// The 3D view is drawn when something changed (a snapshot, the mouse, the camera, the window),
// not at every animation frame: the data changes at the node's http_rate (10 Hz), and a
// software-rendered WebGL canvas at 60 frames a second costs a whole core.
let dirty = true;
app.invalidate = () => { dirty = true; };

// ---------------------------------------------------------------- cameras
// Follow frames the followed vessel's tow (the vessels joined to it by ropes, a rope's ends
// matched to the nearest hull), Bird's-eye every vessel: their hulls and the ropes, fitted into
// the part of the canvas the overlays leave free, refitted as they move. The mouse wheel zooms
// every camera (Follow and Bird's-eye: towards the followed vessel; clicking the camera's button
// again fits the tow once more); Free orbit is OrbitControls' own.
const followPos = new THREE.Vector3(), followLook = new THREE.Vector3(), lastTarget = new THREE.Vector3();
let cameraInit = false;
const zoom = { follow: 1, birdseye: 1 };  // 1: the tow fitted; < 1 closer, > 1 farther
app.zoom = zoom;
// the follow camera looks down this much, from this far round from astern (starboard quarter): the
// tow is not one hull hiding the next
const FOLLOW_ELEVATION = 30 * Math.PI / 180, FOLLOW_QUARTER = 35 * Math.PI / 180;
function targetVessel() {
  const s = app.snap;
  if (!s || !app.selected || !s.vessels[app.selected]) return null;
  return s.vessels[app.selected];
}
function setCamera(mode) {
  if (mode === app.camera && zoom[mode] !== undefined) zoom[mode] = 1;  // the same button again: fit
  app.camera = mode;
  for (const b of document.querySelectorAll('#camera-bar button')) b.classList.toggle('on', b.dataset.camera === mode);
  orbit.enabled = mode === 'orbit';
  camera.up.set(0, mode === 'birdseye' ? 1 : 0, mode === 'birdseye' ? 0 : 1);
  if (mode === 'orbit') {
    // OrbitControls takes its up axis from the camera when made: keep ENU z up
    camera.up.set(0, 0, 1);
    orbit.object.up.set(0, 0, 1);
  }
  cameraInit = false;
  dirty = true;
}
for (const b of document.querySelectorAll('#camera-bar button')) b.onclick = () => setCamera(b.dataset.camera);
canvas.addEventListener('wheel', (e) => {
  if (app.camera === 'orbit') return;  // OrbitControls zooms
  e.preventDefault();
  zoom[app.camera] = Math.min(6, Math.max(0.04, zoom[app.camera] * Math.exp(0.0015 * e.deltaY)));
  dirty = true;
}, { passive: false });

const hullLength = (name) => (vessels3.get(name) || { length: 30 }).length;
const yawOf = (v) => Math.atan2(2 * (v.q[3] * v.q[2] + v.q[0] * v.q[1]), 1 - 2 * (v.q[1] * v.q[1] + v.q[2] * v.q[2]));
function nearestVessel(p, s) {
  let best = null, gap = Infinity;
  for (const [n, v] of Object.entries(s.vessels)) {
    const d = Math.hypot(v.x - p[0], v.y - p[1]) - 0.5 * hullLength(n);
    if (d < gap) { gap = d; best = n; }
  }
  return gap < 25 ? best : null;
}
// the vessels joined to `name` by ropes (either end), and those ropes
function towOf(name, s) {
  const links = [];
  for (const [r, o] of Object.entries(s.ropes)) {
    const pts = o.points || [];
    if (pts.length) links.push([r, nearestVessel(pts[0], s), nearestVessel(pts[pts.length - 1], s)]);
  }
  const vessels = new Set([name]), ropes = new Set();
  for (let grew = true; grew;) {
    grew = false;
    for (const [r, a, b] of links) {
      if (!vessels.has(a) && !vessels.has(b)) continue;
      ropes.add(r);
      for (const x of [a, b]) if (x && !vessels.has(x)) { vessels.add(x); grew = true; }
    }
  }
  return { vessels: [...vessels], ropes: [...ropes] };
}
app.towOf = (name) => app.snap ? towOf(name, app.snap) : null;
// points to keep in view: each hull's square of its length, at the waterline and above; the ropes
function towPoints(tow, s) {
  const pts = [];
  for (const n of tow.vessels) {
    const v = s.vessels[n], h = 0.5 * hullLength(n);
    for (const [dx, dy] of [[-h, -h], [h, -h], [h, h], [-h, h]]) {
      pts.push(new THREE.Vector3(v.x + dx, v.y + dy, 0), new THREE.Vector3(v.x + dx, v.y + dy, 0.25 * h));
    }
  }
  for (const r of tow.ropes) {
    const p = s.ropes[r].points || [];
    for (let i = 0; i < p.length; i += Math.max(1, Math.floor(p.length / 12))) pts.push(new THREE.Vector3(...p[i]));
  }
  return pts;
}
// The band of the canvas the overlays leave free (CSS px from the top and from the bottom), and
// the view shifted so that the band's middle is the picture's centre.
function freeBand() {
  const H = canvas.clientHeight, top = 40, box = $('plot-box');
  const bottom = box ? Math.min(0.45 * H, H - box.offsetTop + 8) : 0;
  return { top, bottom, H, W: canvas.clientWidth };
}
// The distance from target along -forward at which every point is inside the band (with a margin)
function fitDistance(target, forward, up, pts, band) {
  const right = new THREE.Vector3().crossVectors(forward, up).normalize();
  const tanV = Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2) * (band.H - band.top - band.bottom) / band.H;
  const tanH = Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2) * camera.aspect;
  const d = new THREE.Vector3();
  let need = 30;
  for (const p of pts) {
    d.subVectors(p, target);
    const x = Math.abs(d.dot(right)) * 1.12, y = Math.abs(d.dot(up)) * 1.12, depth = d.dot(forward);
    need = Math.max(need, x / tanH - depth, y / tanV - depth);
  }
  return need;
}
const FOLLOW_LAG = 0.12;  // s: time constant of the follow camera
function placeCamera(dt) {
  const v = targetVessel();
  if (!v) return;
  const s = app.snap, band = freeBand();
  camera.setViewOffset(band.W, band.H, 0, (band.bottom - band.top) / 2, band.W, band.H);
  // Bird's-eye: every vessel and rope; Follow: the followed vessel's tow
  const tow = app.camera === 'birdseye' ? { vessels: Object.keys(s.vessels), ropes: Object.keys(s.ropes) } :
    towOf(app.selected, s);
  const pts = towPoints(tow, s);
  const box = new THREE.Box3().setFromPoints(pts), centre = box.getCenter(new THREE.Vector3());
  const p = new THREE.Vector3(v.x, v.y, 0), yaw = yawOf(v);
  if (app.camera === 'follow' || (app.camera === 'orbit' && !cameraInit)) {
    const z = app.camera === 'follow' ? zoom.follow : 1;
    const target = new THREE.Vector3().lerpVectors(p, centre, Math.min(1, z));
    const look = yaw + FOLLOW_QUARTER;
    const forward = new THREE.Vector3(Math.cos(look) * Math.cos(FOLLOW_ELEVATION),
      Math.sin(look) * Math.cos(FOLLOW_ELEVATION), -Math.sin(FOLLOW_ELEVATION));
    const up = new THREE.Vector3(0, 0, 1).addScaledVector(forward, -forward.z).normalize();
    const dist = z * fitDistance(target, forward, up, pts, band);
    followPos.copy(target).addScaledVector(forward, -Math.max(dist, 0.6 * hullLength(app.selected) + 15));
    if (!cameraInit || app.hold) { camera.position.copy(followPos); followLook.copy(target); } else {
      const k = 1 - Math.exp(-dt / FOLLOW_LAG);
      camera.position.lerp(followPos, k); followLook.lerp(target, k);
    }
    camera.lookAt(followLook);
    orbit.target.copy(followLook);
    lastTarget.copy(p);
    if (app.camera === 'orbit') orbit.update();
  } else if (app.camera === 'birdseye') {
    const target = new THREE.Vector3().lerpVectors(p, centre, Math.min(1, zoom.birdseye));
    const down = new THREE.Vector3(0, 0, -1), north = new THREE.Vector3(0, 1, 0);
    const dist = zoom.birdseye * fitDistance(target, down, north, pts, band);
    camera.position.set(target.x, target.y, Math.max(dist, 40));
    orbit.target.copy(target);
    camera.lookAt(target);
  } else {
    // the orbit centre travels with the vessel
    const dx = p.x - lastTarget.x, dy = p.y - lastTarget.y;
    camera.position.x += dx; camera.position.y += dy;
    orbit.target.x += dx; orbit.target.y += dy;
    lastTarget.copy(p);
    orbit.update();
  }
  cameraInit = true;
  // names readable at any distance: the sprite 15 % of the distance wide, never below the hull's own scale
  for (const [name, o] of vessels3) {
    const w = Math.max(16 * Math.max(0.5, hullLength(name) / 30), 0.15 * camera.position.distanceTo(o.group.position));
    o.label.scale.set(w, w / 4, 1);
    o.label.position.z = (o.top === undefined ? 4 : o.top) + 0.2 * w;
  }
  grid.position.set(Math.round(p.x / 50) * 50, Math.round(p.y / 50) * 50, 0.02);
}

let lastRender = 0;
function render(now) {
  requestAnimationFrame(render);
  if (resize()) dirty = true;
  if (!dirty && now - lastRender < 1000) return;  // and once a second whatever happens
  dirty = false;
  placeCamera(Math.min(0.5, Math.max(0, (now - lastRender) / 1000)));
  lastRender = now;
  renderer.render(scene3, camera);
  app.frames += 1;
}

// screen position (CSS pixels, in the canvas) of a vessel's origin: for tests
app.project = (name) => {
  const v = vessels3.get(name);
  if (!v) return null;
  const p = v.group.position.clone().project(camera);
  const r = canvas.getBoundingClientRect();
  return { x: r.left + (p.x + 1) / 2 * r.width, y: r.top + (1 - p.y) / 2 * r.height, visible: Math.abs(p.z) <= 1 };
};

app.hasGeometry = (name) => !!(vessels3.get(name) || {}).hasGeometry;
app.setVisible = (name, on) => { const v = vessels3.get(name); if (v) v.group.visible = on; dirty = true; };
app.showLabels = (on) => { for (const v of vessels3.values()) v.label.visible = on; dirty = true; };
app.cameraDistance = () => camera.position.distanceTo(orbit.target);

// ---------------------------------------------------------------- gauges
function gauge(id, name) {
  return `<div class="gauge" id="${id}"><div class="name">${name}</div><div class="value">--</div>` +
         `<div class="bar"><i></i></div></div>`;
}
function setGauge(id, text, value, t, frac, level) {
  const el = $(id);
  if (!el) return;
  el.querySelector('.value').textContent = text;
  el.dataset.value = (value === null || value === undefined) ? '' : String(value);
  el.dataset.t = t === undefined ? '' : String(t);
  const bar = el.querySelector('.bar i');
  bar.style.width = `${Math.round(100 * Math.max(0, Math.min(1, frac || 0)))}%`;
  bar.style.background = level === 'alarm' ? '#ff3860' : level === 'warn' ? '#ffdd57' : '#23d160';
  el.classList.toggle('warn', level === 'warn');
  el.classList.toggle('alarm', level === 'alarm');
}
const safe = (s) => s.replace(/[^A-Za-z0-9_-]/g, '_');

// what a vessel can be ordered (the station reads its ship file): engine, steering; unknown yet: both
const controlsOf = (v) => v.controls || { engine: true, steering: true };
app.controlsOf = (name) => app.snap && app.snap.vessels[name] ? controlsOf(app.snap.vessels[name]) : null;

function buildGauges(s) {
  const vs = Object.keys(s.vessels).sort(), rs = Object.keys(s.ropes).sort();
  const key = vs.map((v) => `${v}:${JSON.stringify(s.vessels[v].controls)}`).join(',') + '|' + rs.join(',');
  if (key === app.gaugeKey || !vs.length) return;
  app.gaugeKey = key;
  $('vessel-gauges').innerHTML = vs.map((v) => {
    const n = safe(v), c = controlsOf(s.vessels[v]);
    const kind = s.vessels[v].controls ? (c.engine ? '' : ' (unpowered)') : '';
    return `<div class="gauge" style="grid-column: 1 / -1; border: none; padding: 0">` +
      `<b>${v}</b>${kind} <span class="muted" id="g-${n}-anchor"></span></div>` +
      gauge(`g-${n}-speed`, 'speed kn') + gauge(`g-${n}-heading`, 'heading deg T') +
      (c.engine ? gauge(`g-${n}-engine`, 'engine order') + gauge(`g-${n}-rpm`, 'shaft rpm') : '') +
      (c.steering ? gauge(`g-${n}-rudder`, 'rudder / bucket deg, + port') : '') + gauge(`g-${n}-heel`, 'heel deg') +
      gauge(`g-${n}-girting`, 'girting ratio') + gauge(`g-${n}-roll`, 'roll deg') +
      gauge(`g-${n}-pitch`, 'pitch deg') + gauge(`g-${n}-hs`, 'sea Hs m') + gauge(`g-${n}-te`, 'encounter s') +
      gauge(`g-${n}-seafrom`, 'sea from deg');
  }).join('');
  $('rope-gauges').innerHTML = rs.map((r) => {
    const n = safe(r);
    return `<div class="gauge" style="grid-column: 1 / -1; border: none; padding: 0"><b>${r}</b> ` +
      `<span class="muted" id="g-${n}-model"></span></div>` +
      gauge(`g-${n}-tension`, 'tension kN') + gauge(`g-${n}-length`, 'deployed m') + gauge(`g-${n}-winch`, 'winch');
  }).join('');
  const sel = $('vessel');
  sel.innerHTML = vs.map((v) => `<option>${v}</option>`).join('');
  const want = params.get('vessel');  // the page's ?vessel=, until the user picks one
  if (!app.userChose && want && s.vessels[want]) app.selected = want;
  else if (!app.selected || !s.vessels[app.selected]) app.selected = vs.includes('tug') ? 'tug' : vs[0];
  sel.value = app.selected;
  const withWinch = rs.filter((r) => s.ropes[r].has_winch);
  $('rope').innerHTML = withWinch.map((r) => `<option>${r}</option>`).join('');
  if (!app.rope || !withWinch.includes(app.rope)) app.rope = withWinch[0] || null;
  if (app.rope) $('rope').value = app.rope;
  selectVessel(app.selected);
}

function updateGauges(s) {
  for (const [name, v] of Object.entries(s.vessels)) {
    const n = safe(name);
    const spd = Number(v.speed_kn.toFixed(2));
    setGauge(`g-${n}-speed`, fmt(v.speed_kn, 2), spd, v.t, v.speed_kn / 15);
    setGauge(`g-${n}-heading`, fmt(v.heading_deg, 1).padStart(5, '0'), Number(v.heading_deg.toFixed(1)), v.t,
      v.heading_deg / 360);
    setGauge(`g-${n}-engine`, v.engine_order === undefined ? '--' : (v.engine_order >= 0 ? '+' : '') +
      fmt(v.engine_order, 2), v.engine_order, v.t, Math.abs(v.engine_order || 0));
    setGauge(`g-${n}-rpm`, fmt(v.rpm, 0), v.rpm, v.t, 0);
    setGauge(`g-${n}-rudder`, `${signed(v.steering_deg, 1)} (${signed(v.steering_ordered_deg, 0)})`, v.steering_deg,
      v.t, Math.abs(v.steering_deg || 0) / 45);
    setGauge(`g-${n}-heel`, fmt(v.heel_deg, 1), v.heel_deg, v.t, Math.abs(v.heel_deg || 0) / 20,
      Math.abs(v.heel_deg || 0) > 10 ? 'warn' : '');
    const gr = v.girting_ratio, thr = v.girting_threshold || 1;
    setGauge(`g-${n}-girting`, gr === null || gr === undefined ? '--' : `${fmt(gr, 2)} / ${fmt(thr, 2)}`, gr, v.t,
      (gr || 0) / thr, v.girting_warning ? 'alarm' : (gr || 0) > 0.7 * thr ? 'warn' : '');
    // roll and pitch: the totals (heel + roll, trim + pitch; REP-103: roll + starboard side down,
    // pitch + bow down), shown with the side down / the way the bow points
    const roll = v.roll_deg, pitch = v.pitch_deg;
    setGauge(`g-${n}-roll`, roll === undefined ? '--' :
      `${fmt(Math.abs(roll), 1)} ${roll > 0.05 ? 'stbd' : roll < -0.05 ? 'port' : ''}`,
    roll, v.t, Math.abs(roll || 0) / 20, Math.abs(roll || 0) > 10 ? 'warn' : '');
    setGauge(`g-${n}-pitch`, pitch === undefined ? '--' :
      `${fmt(Math.abs(pitch), 1)} ${pitch > 0.05 ? 'bow dn' : pitch < -0.05 ? 'bow up' : ''}`,
    pitch, v.t, Math.abs(pitch || 0) / 10, Math.abs(pitch || 0) > 5 ? 'warn' : '');
    // the encountered sea: Hs, encounter period, where it comes from off the bow (+ port)
    const calm = !(v.wave_hs > 0), ang = v.wave_encounter_angle_deg;
    setGauge(`g-${n}-hs`, v.wave_hs === undefined ? '--' : calm ? 'calm' : fmt(v.wave_hs, 1), v.wave_hs, v.t,
      (v.wave_hs || 0) / 6);
    setGauge(`g-${n}-te`, calm ? '--' : fmt(v.wave_encounter_period, 1), calm ? null : v.wave_encounter_period, v.t, 0);
    setGauge(`g-${n}-seafrom`, calm || ang === undefined ? '--' : `${fmt(Math.abs(ang), 0)} ` +
      `${Math.abs(ang) < 0.5 ? 'ahead' : Math.abs(ang) > 179.5 ? 'astern' : ang > 0 ? 'port' : 'stbd'}`,
    calm ? null : ang, v.t, Math.abs(ang || 0) / 180);
    const an = $(`g-${n}-anchor`), manual = (app.manual || {})[name];
    if (an) an.textContent = `anchor ${v.anchor || '-'}; through water ${fmt(v.stw_kn, 2)} kn` +
      (manual && manual.size ? `; manual: ${[...manual].sort().join(', ')}` : '');
  }
  for (const [name, r] of Object.entries(s.ropes)) {
    const n = safe(name);
    const kn = r.tension / 1000;
    const bl = r.breaking_load;
    const ratio = bl ? r.tension / bl : null;
    setGauge(`g-${n}-tension`, r.broken ? 'PARTED' : bl ? `${fmt(kn, 1)} (${fmt(100 * ratio, 0)}% BL)` : fmt(kn, 1),
      Number(kn.toFixed(1)), r.t, ratio === null ? kn / 200 : ratio,
      r.broken || (ratio !== null && ratio > 0.8) ? 'alarm' : ratio !== null && ratio > 0.5 ? 'warn' : '');
    setGauge(`g-${n}-length`, fmt(r.deployed_length, 1), Number(r.deployed_length.toFixed(1)), r.t, 0);
    setGauge(`g-${n}-winch`, r.payout_rate === null || r.payout_rate === undefined ? r.winch :
      `${r.winch} ${fmt(Math.abs(r.payout_rate), 1)}`, r.payout_rate, r.t, 0);
    const m = $(`g-${n}-model`);
    if (m) m.textContent = `${r.model}${bl ? `, breaking load ${fmt(bl / 1000, 0)} kN` : ''}` +
      `${r.broken ? ', PARTED' : ''}`;
  }
}

// ---------------------------------------------------------------- states: alerts, the run, events
// Shown over the 3D view (#alerts, one line each, data-alert = its kind): a parted rope, a vessel
// aground, an anchor dragging (on the bottom, moving over the ground), a vessel whose data stopped
// (no message for run.silent_after s while the run goes on), the end of the run or replay.
const esc = (t) => String(t).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' })[c]);
function alertsOf(s) {
  const out = [], run = s.run || {}, after = run.silent_after || 3;
  const parted = Object.fromEntries((s.events || []).filter((e) => e.kind === 'rope_parted').map((e) => [e.target, e]));
  for (const [name, r] of Object.entries(s.ropes)) {
    if (!r.broken) continue;
    const e = parted[name];
    out.push(['parted', `${name.toUpperCase()} PARTED` + (e ? ` at t = ${fmt(e.t, 1)} s` +
      (Number.isFinite(e.value) ? `, ${fmt(e.value / 1000, 1)} kN` : '') : '')]);
  }
  for (const [name, v] of Object.entries(s.vessels)) {
    if (v.grounded) out.push(['aground', `${name} AGROUND (under-keel clearance ${fmt(v.ukc, 2)} m)`]);
    if (v.anchor_dragging) out.push(['anchor', `${name} ANCHOR DRAGGING (${fmt(v.speed_kn, 1)} kn over the ground)`]);
    if (run.state !== 'ended' && v.silent_s >= after) {
      out.push(['nodata', `${name}: NO DATA for ${v.silent_s} s (its node stopped, or the simulation is held up)`]);
    }
  }
  if (run.state === 'ended') out.push(['ended', `${run.source === 'replay' ? 'REPLAY' : 'RUN'} ENDED: ${run.ended}`]);
  return out;
}
function showStates(s) {
  const alerts = alertsOf(s), html = alerts.map(([k, t]) => `<div data-alert="${k}">${esc(t)}</div>`).join('');
  if ($('alerts').innerHTML !== html) $('alerts').innerHTML = html;
  app.alerts = alerts;
  const run = s.run || {};
  app.ordersClosed = run.orders_closed || null;
  $('orders-closed').textContent = app.ordersClosed ? `Orders refused: ${app.ordersClosed}` : '';
  enableControls();
  showEvents(s.events || []);
}
// /scenario/events, newest first: the script's orders, the nodes' events, who holds the orders
// (manual_order / manual_handed_back), the run's start and end
const EVENT_CLASS = { rope_parted: 'alarm', rope_failed: 'alarm', grounded: 'alarm', contact_failed: 'alarm',
  command_rejected: 'warn', command_clamped: 'warn', hand_back_refused: 'warn', manual_order: 'own',
  manual_handed_back: 'own', scripted_order_yielded: 'own', scenario_finished: 'end', scenario_started: 'end' };
// who holds the orders: target -> the controls in manual control, from the ownership events
// (their detail starts "<target> <control>:")
function manualControls(events) {
  const manual = {};
  for (const e of events) {
    if (e.kind !== 'manual_order' && e.kind !== 'manual_handed_back') continue;
    const m = (e.detail || '').match(/^\S+ (\S+):/);
    if (!m) continue;
    const set = manual[e.target] || (manual[e.target] = new Set());
    if (e.kind === 'manual_order') set.add(m[1]); else set.delete(m[1]);
  }
  return manual;
}
function showEvents(events) {
  const key = `${events.length}|${events.length ? events[events.length - 1].t + events[events.length - 1].kind : ''}`;
  if (key === app.eventsKey) return;
  app.eventsKey = key;
  $('events').innerHTML = events.slice().reverse().map((e) =>
    `<div class="ev ${EVENT_CLASS[e.kind] || ''}" data-kind="${esc(e.kind)}"><span class="t">${fmt(e.t, 1)} s</span> ` +
    `<b>${esc(e.kind.replace(/_/g, ' '))}</b>${e.target ? ` ${esc(e.target)}` : ''}: ${esc(e.detail)}</div>`
  ).join('') ||
    '<div class="muted">none yet</div>';
}

// ---------------------------------------------------------------- tension plot
const plot = $('plot');
const COLORS = ['#ffb347', '#6ec6ff', '#c792ea', '#a5e075'];
function drawPlot(s) {
  const dpr = window.devicePixelRatio || 1;
  const W = plot.clientWidth, H = plot.clientHeight;
  if (plot.width !== Math.floor(W * dpr)) { plot.width = Math.floor(W * dpr); plot.height = Math.floor(H * dpr); }
  const g = plot.getContext('2d');
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, W, H);
  const span = 120, t1 = s.t || 0, t0 = t1 - span;
  let ymax = 10;
  for (const h of Object.values(s.history)) for (const [t, x] of h) if (t >= t0) ymax = Math.max(ymax, x / 1000 * 1.15);
  const L = 40, B = 18, X = (t) => L + (t - t0) / span * (W - L - 6), Yp = (x) => H - B - x / ymax * (H - B - 6);
  g.strokeStyle = '#26394a'; g.fillStyle = '#8aa3b8'; g.font = '10px sans-serif'; g.lineWidth = 1;
  const step = Math.pow(10, Math.floor(Math.log10(ymax / 2)));
  const ystep = ymax / step > 8 ? 5 * step : ymax / step > 4 ? 2 * step : step;
  for (let y = 0; y <= ymax; y += ystep) {
    g.beginPath(); g.moveTo(L, Yp(y)); g.lineTo(W - 6, Yp(y)); g.stroke();
    g.fillText(y.toFixed(ystep < 1 ? 1 : 0), 4, Yp(y) + 3);
  }
  for (let t = Math.ceil(t0 / 20) * 20; t <= t1; t += 20) {
    g.beginPath(); g.moveTo(X(t), H - B); g.lineTo(X(t), 6); g.stroke();
    if (t >= 0) g.fillText(`${t}s`, X(t) - 8, H - 5);
  }
  Object.keys(s.history).sort().forEach((name, i) => {
    const h = s.history[name];
    g.strokeStyle = COLORS[i % COLORS.length]; g.lineWidth = 1.8;
    g.beginPath();
    let first = true;
    for (const [t, x] of h) {
      if (t < t0) continue;
      if (first) { g.moveTo(X(t), Yp(x / 1000)); first = false; } else g.lineTo(X(t), Yp(x / 1000));
    }
    g.stroke();
    const bl = s.ropes[name] && s.ropes[name].breaking_load;
    if (bl && bl / 1000 <= ymax) {
      g.setLineDash([4, 3]); g.strokeStyle = '#ff3860';
      g.beginPath(); g.moveTo(L, Yp(bl / 1000)); g.lineTo(W - 6, Yp(bl / 1000)); g.stroke(); g.setLineDash([]);
    }
    g.fillStyle = COLORS[i % COLORS.length];
    g.fillText(name, L + 4 + 70 * i, 14);
  });
}

// ---------------------------------------------------------------- orders
async function sendRaw(topic, body) {
  let a;
  try {
    const r = await fetch(`/api/publish?topic=${encodeURIComponent(topic)}`,
      { method: 'POST', headers: { 'Content-Type': 'application/json' }, body });
    try { a = await r.json(); } catch (e) { a = { accepted: false, reason: `HTTP ${r.status}` }; }
    a.status = r.status;
  } catch (e) {
    a = { accepted: false, status: 0, reason: 'no connection to the live view node: the order went nowhere' };
  }
  app.answers.push(a);
  const el = $('answer');
  // forwarded (202): published by a stand-alone live view, which cannot vouch for the run's clock
  const sent = a.accepted || a.forwarded;
  el.className = sent ? (a.clamped && a.clamped.length ? 'warn' : 'muted') : 'bad';
  el.textContent = sent ? `${topic}: ${a.accepted ? 'sent' : 'forwarded'}${a.clamped && a.clamped.length ? ` (${a.clamped.join('; ')})` : ''}`
    : `${topic}: refused (${a.status}): ${a.reason}`;
  return a;
}
const send = (topic, obj) => sendRaw(topic, JSON.stringify(obj));
app.send = send;
app.sendRaw = sendRaw;

// An order sets what the person touched: the other control goes out as the vessel holds it
// (the sliders snap to 0.05 and 1 deg, so their value would change a held 0.075 and make the
// runner count it as taken; docs/scenarios.md, "Who gives the orders").
app.userSet = { engine: false, helm: false };
function vesselOrder(anchor = 0) {
  if (!app.selected) return null;
  const v = targetVessel() || {};
  const engine = app.userSet.engine || v.engine_order === undefined ? Number($('engine').value) : v.engine_order;
  const helmDeg = app.userSet.helm || v.steering_ordered_deg === undefined ? Number($('steering').value)
    : v.steering_ordered_deg;
  return send(`/${app.selected}/command`, { engine_order: engine, steering_angle: helmDeg * Math.PI / 180, anchor });
}
app.vesselOrder = vesselOrder;
let throttle = null;
function touched(id) {
  app.touched = performance.now();
  if (id) app.userSet[id === 'engine' ? 'engine' : 'helm'] = true;
}
function showSliders() {
  $('engine-out').textContent = Number($('engine').value).toFixed(2);
  $('steering-out').textContent = signed(Number($('steering').value), 0);
}
for (const id of ['engine', 'steering']) {
  $(id).addEventListener('input', () => {
    touched(id); showSliders();
    if (!throttle) throttle = setTimeout(() => { throttle = null; vesselOrder(); }, 250);
  });
  $(id).addEventListener('change', () => { touched(id); showSliders(); vesselOrder(); });
}
const setAndSend = (id, value) => () => { touched(id); $(id).value = String(value); showSliders(); vesselOrder(); };
$('engine-stop').onclick = setAndSend('engine', 0);
$('engine-half').onclick = setAndSend('engine', 0.5);
$('engine-full').onclick = setAndSend('engine', 1);
$('engine-astern').onclick = setAndSend('engine', -0.5);
$('steer-port').onclick = setAndSend('steering', 20);
$('midships').onclick = setAndSend('steering', 0);
$('steer-stbd').onclick = setAndSend('steering', -20);
$('anchor-let-go').onclick = () => { touched(); vesselOrder(1); };
$('anchor-heave-up').onclick = () => { touched(); vesselOrder(2); };
const winch = (sign) => () => {
  if (!app.rope) return;
  const rate = Math.abs(Number($('winch-rate').value) || 0);
  send(`/${app.rope}/winch`, { payout_rate: sign * rate });
};
$('winch-payout').onclick = winch(1);
$('winch-hold').onclick = winch(0);
$('winch-heave').onclick = winch(-1);
$('rope').onchange = () => { app.rope = $('rope').value; };

function selectVessel(name) {
  app.selected = name;
  $('ctl-vessel').textContent = name || '-';
  app.touched = 0;  // the sliders take the new vessel's orders
  cameraInit = false;
  dirty = true;
  enableControls();
}
// the controls of what the selected vessel has (no engine, no helm on an unpowered barge), none
// when orders go nowhere (the run or replay ended, a replay, no connection)
function enableControls() {
  const v = app.snap && app.snap.vessels[app.selected];
  const open = !app.ordersClosed && !app.disconnected;
  const has = !!(v && v.has_command) && open, c = v ? controlsOf(v) : { engine: false, steering: false };
  for (const id of ['engine', 'engine-stop', 'engine-half', 'engine-full', 'engine-astern']) {
    $(id).disabled = !has || !c.engine;
  }
  for (const id of ['steering', 'steer-port', 'midships', 'steer-stbd']) $(id).disabled = !has || !c.steering;
  for (const id of ['anchor-let-go', 'anchor-heave-up']) $(id).disabled = !has || !v || v.anchor === 'none';
  for (const id of ['winch-payout', 'winch-hold', 'winch-heave', 'winch-rate']) $(id).disabled = !app.rope || !open;
}
$('vessel').onchange = () => { app.userChose = true; selectVessel($('vessel').value); };

function syncSliders(s) {
  const v = targetVessel();
  if (!v || performance.now() - app.touched < 3000 || v.engine_order === undefined) return;
  $('engine').value = String(v.engine_order);
  $('steering').value = String(Math.round(v.steering_ordered_deg));
  app.userSet = { engine: false, helm: false };   // the sliders show what is held again
  showSliders();
}

// ---------------------------------------------------------------- polling
async function askScene(s) {
  const missing = Object.keys(s.vessels).some((v) => !(vessels3.get(v) || {}).hasGeometry);
  if (!missing || performance.now() - app.lastSceneAsk < 1000) return;
  app.lastSceneAsk = performance.now();
  try {
    const d = await (await fetch('/api/scene', { cache: 'no-store' })).json();
    for (const [name, geom] of Object.entries(d.vessels)) applyGeometry(name, geom);
  } catch (e) { /* asked again */ }
}

function apply(s) {
  app.snap = s;
  buildGauges(s);
  $('clock').textContent = s.t === null ? 't = --' : `t = ${s.t.toFixed(1)} s`;
  $('clock').dataset.t = s.t === null ? '' : String(s.t);
  for (const [name, v] of Object.entries(s.vessels)) {
    const o = vessel3(name);
    o.group.position.set(v.x, v.y, v.z);
    o.group.quaternion.set(v.q[0], v.q[1], v.q[2], v.q[3]);
  }
  seaFollow(s);
  for (const r of Object.values(s.ropes)) app.peakSeen = Math.max(app.peakSeen, r.tension);
  for (const [name, r] of Object.entries(s.ropes)) updateRope(name, r);
  app.manual = manualControls(s.events || []);
  updateGauges(s);
  showStates(s);
  drawPlot(s);
  syncSliders(s);
  askScene(s);
  if (app.firstT === undefined && s.t !== null) app.firstT = s.t;  // the first simulation time shown
  app.updates += 1;
  dirty = true;
}

// the run in a word: live, replay, run ended / replay ended, no data, waiting
function showConnection(s) {
  const run = s.run || {}, el = $('conn');
  let text, good = false;
  if (s.t === null) text = 'waiting for the simulation';
  else if (run.state === 'ended') text = run.source === 'replay' ? 'replay ended' : 'run ended';
  else if (run.silent_s >= (run.silent_after || 3)) text = `no data for ${run.silent_s} s`;
  else { text = run.state === 'replay' ? 'replay' : 'live'; good = true; }
  el.textContent = text;
  el.className = good ? 'good' : 'bad';
  el.dataset.state = run.state || '';
}

async function poll() {
  let period = 0.1;
  try {
    const r = await fetch('/api/state', { cache: 'no-store' });
    const text = await r.text();
    const s = JSON.parse(text);
    period = s.period || period;
    // a snapshot like the last but for its number (the simulation paused, not started yet, or a
    // replay at its end): nothing to update or draw
    const key = text.replace(/"sample": \d+, /, '');
    if (app.disconnected) { app.disconnected = false; enableControls(); }
    if (key !== app.lastKey && !app.hold) apply(s);
    app.lastKey = key;
    showConnection(s);
  } catch (e) {
    // the run's own live view closes with the run: said as the end of the run when it had ended
    const run = (app.snap && app.snap.run) || {};
    $('conn').textContent = run.state === 'ended' ? `${run.source === 'replay' ? 'replay' : 'run'} ended; the live ` +
      'view has closed' : app.snap ? 'no connection to the live view node: the run has ended or stopped' :
      'no connection to the live view node';
    $('conn').className = 'bad';
    $('conn').dataset.state = 'disconnected';
    if (!app.disconnected) { app.disconnected = true; enableControls(); }
    period = 1.0;
  }
  setTimeout(poll, 1000 * period);
}

setCamera(app.camera);
showSliders();
askSea();
poll();
requestAnimationFrame(render);
