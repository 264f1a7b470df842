// fluidform's live viewer: frames from `fluidform serve` over a WebSocket (protocol.js), drawn with three.js; orbit
// controls, play/pause/restart, the controller switch, target dragging and mesh swaps, a HUD, and VR/AR buttons that
// enter an immersive WebXR session where the browser supports one. In playback (a finished run) the run's
// animation.glb plays in step with the particle frames.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { VRButton } from 'three/addons/webxr/VRButton.js';
import { ARButton } from 'three/addons/webxr/ARButton.js';
import * as protocol from './protocol.js';
import { Hud, RateCounter } from './hud.js';
import { ParticleView } from './particles.js';
import { TargetBoxes } from './targets.js';

const $ = (id) => document.getElementById(id);

// What the page knows, also read by the browser test (web/test/viewer.test.mjs).
const state = {
  connected: false,
  hello: null,
  framesReceived: 0,
  bytesReceived: 0,
  badFrames: 0,
  frame: null,          // header fields of the newest frame
  history: [],          // {frame, time, error} of the last frames received (at most 4000)
  poses: [],            // the server's last pose per target
  poseAcks: 0,
  errors: [],
  animation: { loaded: false, duration: 0, clips: 0, meshes: 0, time: 0 },
  renderedFrames: 0,
  // Drawing on demand: a new frame, a camera move, a drag or a resize asks for one draw; nothing changing draws
  // nothing, so an idle viewer leaves the CPU (and, on the test machine, the simulation's cores) alone. `continuous`
  // draws every display frame (the browser test sets it to measure the render rate). An XR session always draws.
  continuous: false,
  xr: { presenting: false, mode: null, sessions: 0, renderedFrames: 0 },
  surface: { received: 0, vertices: 0, triangles: 0, frame: -1, buildMs: NaN },  // the newest live surface
};
window.__ff = state;
let dirty = true;
const redraw = () => (dirty = true);

// Renderer, scene, camera.
const renderer = new THREE.WebGLRenderer({ antialias: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.xr.enabled = true;
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x111418);
scene.add(new THREE.HemisphereLight(0xdde8ff, 0x303030, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.8);
sun.position.set(2, 4, 3);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(45, window.innerWidth / window.innerHeight, 0.01, 200);
camera.position.set(1.6, 1.2, 2.4);
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = true;
controls.addEventListener('change', redraw);
const grid = new THREE.GridHelper(4, 40, 0x334455, 0x222a33);
scene.add(grid);

// A "world" group: in AR the content is scaled and placed in front of the user, on the desktop it is identity.
const world = new THREE.Group();
scene.add(world);
const particles = new ParticleView();
world.add(particles.points);
const boxes = new TargetBoxes(world, (t, tr, rot, s) => send(protocol.setPose(t, tr, rot, s)));
let meshRoot = null, mixer = null;

function resize() {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  particles.setViewport(window.innerHeight * renderer.getPixelRatio(), camera.fov);
  redraw();
}
window.addEventListener('resize', resize);
resize();

// XR: VR and AR buttons (three's VRButton/ARButton show "not supported" where the browser has no such session).
const xr = $('xr-buttons');
const vr = VRButton.createButton(renderer);
const ar = ARButton.createButton(renderer, { optionalFeatures: ['local-floor'] });
xr.append(vr, ar);

// HUD.
const hud = new Hud();
const renderRate = new RateCounter(), recvRate = new RateCounter();

// Connection.
let ws = null;
function send(text) {
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(text);
}
function connect() {
  const url = `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`;
  ws = new WebSocket(url);
  ws.binaryType = 'arraybuffer';
  ws.onopen = () => { state.connected = true; hud.status('connected'); };
  ws.onclose = () => {
    state.connected = false;
    hud.status('disconnected; retrying…');
    setTimeout(connect, 1000);
  };
  ws.onmessage = (ev) => {
    if (typeof ev.data === 'string') onText(ev.data);
    else if (protocol.isSurface(ev.data)) onSurface(ev.data);
    else onFrame(ev.data);
  };
}

let decoded = null;
function onFrame(buffer) {
  try {
    decoded = protocol.decodeFrame(buffer, decoded);
  } catch (e) {
    state.badFrames += 1;
    return;
  }
  state.framesReceived += 1;
  state.bytesReceived += buffer.byteLength;
  recvRate.tick();
  const { frame, count, time, stepMs, errorRate, simFps, controlled } = decoded;
  // The fluid's centroid: the browser test checks that the formed shape followed a dragged target.
  const c = [0, 0, 0];
  for (let i = 0; i < 3 * count; i += 3) c[0] += decoded.positions[i], c[1] += decoded.positions[i + 1], c[2] += decoded.positions[i + 2];
  const centroid = c.map((v) => v / Math.max(1, count));
  state.frame = { frame, count, time, stepMs, errorRate, simFps, controlled, centroid };
  state.history.push({ frame, time, error: errorRate, centroid, wall: performance.now(), received: state.framesReceived });
  if (state.history.length > 4000) state.history.splice(0, 1000);
  particles.update(decoded);
  if (mixer && state.animation.duration > 0) {
    mixer.setTime(time % state.animation.duration);
    state.animation.time = time;
  }
  hud.update({ stepMs, simFps, count, errorRate, time });
  redraw();
}

// The live surface: one mesh, its geometry replaced by each new surface.
const surfaceMaterial = new THREE.MeshStandardMaterial({ color: 0x9ecbff, roughness: 0.35, metalness: 0.0, transparent: true, opacity: 0.85 });
let liveSurface = null;
function onSurface(buffer) {
  let s;
  try {
    s = protocol.decodeSurface(buffer);
  } catch (e) {
    state.badFrames += 1;
    return;
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(s.positions, 3));
  g.setIndex(new THREE.BufferAttribute(s.indices, 1));
  g.computeVertexNormals();
  if (!liveSurface) {
    liveSurface = new THREE.Mesh(g, surfaceMaterial);
    world.add(liveSurface);
  } else {
    liveSurface.geometry.dispose();
    liveSurface.geometry = g;
  }
  liveSurface.visible = $('chk-mesh').checked;
  state.surface = { received: state.surface.received + 1, vertices: s.vertices, triangles: s.triangles, frame: s.frame, buildMs: s.buildMs };
  redraw();
}

function onText(text) {
  let m;
  try {
    m = JSON.parse(text);
  } catch {
    return;
  }
  if (m.type === 'hello') onHello(m);
  else if (m.type === 'pose') {
    state.poses[m.target] = m;
    state.poseAcks += 1;
    if (!(boxes.drag && boxes.drag.index === m.target)) boxes.applyPose(m.target, m);
    redraw();
  } else if (m.type === 'error') {
    state.errors.push(m.message);
    hud.status(m.message);
  }
}

function fillSelect(sel, items, current) {
  sel.replaceChildren(...items.map((name, i) => new Option(name, String(i), false, i === current)));
  sel.disabled = items.length < 2;
}

let framed = false;
function onHello(h) {
  // Live: the mesh box shows what the server does (off at first: reconstructing costs simulation time); every
  // viewer follows when one of them turns it on or off, and a reconnect to a fresh server starts off again.
  // Playback has the run's animation.glb and keeps the box as it is.
  if (h.mode === 'live') {
    $('chk-mesh').checked = Boolean(h.surface);
    if (liveSurface) liveSurface.visible = Boolean(h.surface);
  }
  state.hello = h;
  hud.status(h.mode === 'playback' ? 'playback' : `live: ${h.controller}`);
  $('btn-play').textContent = h.paused ? 'play' : 'pause';
  if (h.radius) particles.setRadius(h.radius);
  fillSelect($('sel-controller'), h.controllers ?? [], (h.controllers ?? []).indexOf(h.controller));
  fillSelect($('sel-mesh'), h.meshes ?? [], h.targets?.[0]?.mesh ?? 0);
  boxes.set(h.targets ?? []);
  h.targets?.forEach((t, i) => (state.poses[i] = t.pose));
  if (!framed) frameCamera(h);
  if (h.animation && !meshRoot) loadAnimation(h.animation);
  redraw();
}

// What the scene shows, from a hello: the targets' boxes, or the domain when there are none (empty if neither).
function contentBox(h) {
  const box = new THREE.Box3();
  for (const t of h?.targets ?? []) box.expandByPoint(new THREE.Vector3(...t.box.min)).expandByPoint(new THREE.Vector3(...t.box.max));
  if (box.isEmpty() && h?.domain) box.set(new THREE.Vector3(...h.domain.min), new THREE.Vector3(...h.domain.max));
  return box;
}

// Looks at the targets (or the domain) from a distance that fits them.
function frameCamera(h) {
  const box = contentBox(h);
  if (box.isEmpty()) return;
  framed = true;
  const c = box.getCenter(new THREE.Vector3());
  const r = box.getSize(new THREE.Vector3()).length() * 0.5;
  const dist = (1.6 * r) / Math.tan((camera.fov * Math.PI) / 360);
  camera.position.copy(c).add(new THREE.Vector3(0.55, 0.35, 0.75).normalize().multiplyScalar(dist));
  camera.near = Math.max(1e-3, dist / 100);
  camera.far = dist * 100;
  camera.updateProjectionMatrix();
  controls.target.copy(c);
  grid.position.y = (h.domain?.min?.[1] ?? box.min.y);
  controls.update();
}

function loadAnimation(url) {
  new GLTFLoader().load(url, (gltf) => {
    meshRoot = gltf.scene;
    let meshes = 0;
    meshRoot.traverse((o) => {
      if (o.isMesh) {
        meshes += 1;
        o.material = new THREE.MeshStandardMaterial({ color: 0x9ecbff, roughness: 0.35, metalness: 0.0 });
      }
    });
    world.add(meshRoot);
    mixer = new THREE.AnimationMixer(meshRoot);
    for (const clip of gltf.animations) mixer.clipAction(clip).play();
    state.animation = { loaded: true, duration: gltf.animations[0]?.duration ?? 0, clips: gltf.animations.length, meshes, time: 0 };
    meshRoot.visible = $('chk-mesh').checked;
    redraw();
  }, undefined, (e) => state.errors.push(`animation: ${e.message ?? e}`));
}

// Panel.
$('btn-play').onclick = () => {
  const paused = $('btn-play').textContent === 'pause';
  send(paused ? protocol.pause() : protocol.play());
  $('btn-play').textContent = paused ? 'play' : 'pause';
};
$('btn-restart').onclick = () => send(protocol.restart());
$('sel-controller').onchange = (e) => send(protocol.setController(state.hello.controllers[Number(e.target.value)]));
$('sel-mesh').onchange = (e) => send(protocol.setMesh(0, Number(e.target.value)));
$('chk-particles').onchange = (e) => { particles.points.visible = e.target.checked; redraw(); };
$('chk-mesh').onchange = (e) => {
  if (meshRoot) meshRoot.visible = e.target.checked;
  if (liveSurface) liveSurface.visible = e.target.checked;
  if (state.hello?.mode === 'live') send(protocol.setSurface(e.target.checked));
  redraw();
};

// Mouse dragging of targets (orbit controls are off while a target is held).
const pointer = new THREE.Vector2();
function rayAt(ev) {
  const r = renderer.domElement.getBoundingClientRect();
  pointer.set(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
  const rc = new THREE.Raycaster();
  rc.setFromCamera(pointer, camera);
  return rc.ray;
}
renderer.domElement.addEventListener('pointerdown', (ev) => {
  if (ev.button !== 0 || state.hello?.mode !== 'live') return;
  const normal = camera.getWorldDirection(new THREE.Vector3()).negate();
  if (boxes.begin(rayAt(ev), normal, ev.shiftKey)) {
    controls.enabled = false;
    ev.stopImmediatePropagation();  // the orbit controls must not start turning the camera too
    renderer.domElement.setPointerCapture(ev.pointerId);
  }
}, { capture: true });  // capture: runs before the orbit controls' own listener on the canvas
renderer.domElement.addEventListener('pointermove', (ev) => {
  if (!boxes.drag) return;
  boxes.move(rayAt(ev));
  redraw();
});
const release = () => {
  if (!boxes.drag) return;
  boxes.end();
  controls.enabled = true;
};
renderer.domElement.addEventListener('pointerup', release);
renderer.domElement.addEventListener('pointercancel', release);

// XR controllers: point at a target box and hold the trigger to carry it; hold the grip (squeeze) too to turn it
// about the vertical axis instead.
for (let i = 0; i < 2; ++i) {
  const ctl = renderer.xr.getController(i);
  const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3(0, 0, -1)]),
                              new THREE.LineBasicMaterial({ color: 0xffffff }));
  line.scale.z = 5;
  ctl.add(line);
  scene.add(ctl);
  const ctlRay = () => {
    const m = new THREE.Matrix4().extractRotation(ctl.matrixWorld);
    const origin = new THREE.Vector3().setFromMatrixPosition(ctl.matrixWorld);
    return new THREE.Ray(origin, new THREE.Vector3(0, 0, -1).applyMatrix4(m).normalize());
  };
  ctl.addEventListener('squeezestart', () => (ctl.userData.squeezing = true));
  ctl.addEventListener('squeezeend', () => (ctl.userData.squeezing = false));
  ctl.addEventListener('selectstart', () => {
    if (state.hello?.mode !== 'live') return;
    const ray = ctlRay();
    if (boxes.begin(ray, ray.direction.clone().negate(), Boolean(ctl.userData.squeezing))) ctl.userData.dragging = true;
  });
  ctl.addEventListener('selectend', () => {
    if (ctl.userData.dragging) boxes.end();
    ctl.userData.dragging = false;
  });
  ctl.userData.ray = ctlRay;
}

// In an immersive session the viewer stands at the origin of its floor: the content is put in front of them, on
// the floor at full size in VR, and at table-top size (about half a metre across) 1.2 m ahead in AR.
function placeForXr(ar) {
  const box = contentBox(state.hello);
  if (box.isEmpty()) box.set(new THREE.Vector3(-0.5, 0, -0.5), new THREE.Vector3(0.5, 1, 0.5));
  const c = box.getCenter(new THREE.Vector3()), r = Math.max(1e-3, 0.5 * box.getSize(new THREE.Vector3()).length());
  const s = ar ? Math.min(1, 0.25 / r) : 1;
  world.scale.setScalar(s);
  // World point p goes to s·p + position: the box's bottom centre to (0, floor or table, −distance).
  const ahead = ar ? 1.2 : 1.0 + r;
  world.position.set(-s * c.x, (ar ? 0.8 : 0) - s * box.min.y, -ahead - s * c.z);
}
renderer.xr.addEventListener('sessionstart', () => {
  const session = renderer.xr.getSession();
  const ar = Boolean(session && session.environmentBlendMode && session.environmentBlendMode !== 'opaque');
  state.xr = { ...state.xr, presenting: true, mode: ar ? 'immersive-ar' : 'immersive-vr', sessions: state.xr.sessions + 1 };
  placeForXr(ar);
  if (ar) {
    scene.background = null;
    grid.visible = false;
  }
});
renderer.xr.addEventListener('sessionend', () => {
  state.xr = { ...state.xr, presenting: false };
  world.scale.setScalar(1);
  world.position.set(0, 0, 0);
  scene.background = new THREE.Color(0x111418);
  grid.visible = true;
  redraw();
});

// Render loop (the XR loop when a session is on).
let lastHud = 0;
renderer.setAnimationLoop((now) => {
  for (let i = 0; i < 2; ++i) {
    const ctl = renderer.xr.getController(i);
    if (ctl.userData.dragging) boxes.move(ctl.userData.ray());
  }
  if (!renderer.xr.isPresenting) controls.update();
  if (now - lastHud > 250) {
    lastHud = now;
    hud.update({ fps: renderRate.rate(now), recvFps: recvRate.rate(now) });
    state.hud = { ...hud.values };
  }
  if (renderer.xr.isPresenting) state.xr.renderedFrames += 1;
  else if (!dirty && !state.continuous) return;
  dirty = false;
  renderer.render(scene, camera);
  state.renderedFrames += 1;
  renderRate.tick(now);
});

// For tests and tools: where target i is on screen, and in the world (metres, after the XR placement).
state.targetWorld = (i) => boxes.targets[i]?.group.getWorldPosition(new THREE.Vector3()).toArray() ?? null;
state.worldScale = () => world.scale.x;
state.targetScreen = (i) => boxes.screenPosition(i, camera, renderer.domElement);
state.project = (p) => {
  const v = world.localToWorld(new THREE.Vector3(...p)).project(camera);
  const r = renderer.domElement.getBoundingClientRect();
  return { x: r.left + ((v.x + 1) / 2) * r.width, y: r.top + ((1 - v.y) / 2) * r.height };
};
connect();
