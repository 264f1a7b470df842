// fluidform's live viewer: frames from `fluidform serve` over a WebSocket (protocol.js), received and decoded in a
// Worker (frame_worker.js), drawn with three.js at the display's rate whatever the simulation's: every display frame
// places the particles between the last two frames received, by their simulation times (interpolate.js; the GPU mixes
// the two, particles.js). Three looks: liquid (screen-space fluid rendering, liquid.js; the default, with a fall back
// to spheres when the measured frame time cannot hold the display rate), spheres, and the mesh. Orbit controls,
// play/pause/restart, the controller switch, target dragging and mesh swaps, a HUD, and VR/AR buttons that enter an
// immersive WebXR session where the browser supports one (asking for the headset's highest frame rate). In playback
// (a finished run) the run's animation.glb plays in step with the particle frames, and a slider seeks (the frame it
// asked for is drawn as it is, not interpolated from the frame before the jump).
//
// URL flags (for the browser test and for comparisons): ?look=liquid|spheres|mesh picks the look and turns the
// automatic fall back off; ?decode=main receives and decodes frames on the main thread (the old path).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { VRButton } from 'three/addons/webxr/VRButton.js';
import { ARButton } from 'three/addons/webxr/ARButton.js';
import * as protocol from './protocol.js';
import { Hud, RateCounter } from './hud.js';
import { ParticleView, FF_POSITION_GLSL } from './particles.js';
import { LiquidRenderer } from './liquid.js';
import { FrameClock } from './interpolate.js';
import { createFrameSource } from './source.js';
import { TargetBoxes } from './targets.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const LOOKS = ['liquid', 'spheres', 'mesh'];
const forcedLook = LOOKS.includes(params.get('look')) ? params.get('look') : null;

// What the page knows, also read by the browser test (web/test/viewer.test.mjs).
const state = {
  connected: false,
  hello: null,
  framesReceived: 0,
  bytesReceived: 0,
  particlesReceived: 0,  // summed over frames: bytes per particle = bytesReceived / particlesReceived
  badFrames: 0,
  frame: null,           // header fields of the newest frame
  previousFrame: -1,     // frame number of the one received before it
  history: [],           // {frame, time, error, continues} of the last frames received (at most 4000)
  poses: [],             // the server's last pose per target
  poseAcks: 0,
  errors: [],
  animation: { loaded: false, duration: 0, clips: 0, meshes: 0, time: 0, clipTime: NaN },  // clipTime: the clip's own
  // Playback seeks: how many sent, the last frame asked for, the one not arrived yet (null: none), frames that cut.
  seek: { sent: 0, last: null, pending: null, cuts: 0 },
  renderedFrames: 0,     // display frames drawn
  decode: 'worker',      // where frames are received and decoded: 'worker' or 'main' (?decode=main)
  // Main-thread time (ms, summed): handling received frames (and decoding them, on the old path) and the render loop.
  main: { ingestMs: 0, decodeMs: 0, renderMs: 0, ingested: 0, workerDecodeMs: 0 },
  interp: { discontinuities: 0, alpha: 1, time: NaN },
  gpu: '',
  look: { mode: forcedLook ?? 'liquid', auto: !forcedLook, fellBack: false, liquidFrameMs: NaN, displayMs: NaN,
          reason: '' },
  // Pointer moves of a dragged target; draws that followed one (checked) and showed the box where the move put it.
  drag: { moves: 0, checked: 0, drawnNext: 0, lagMs: [] },
  xr: { presenting: false, mode: null, sessions: 0, renderedFrames: 0, frameRateRequested: null, frameRate: null,
        supportedFrameRates: null, frameRateError: null },
  surface: { received: 0, vertices: 0, triangles: 0, frame: -1, buildMs: NaN },  // the newest live surface
};
window.__ff = state;
// Desktop only: a display frame in which nothing changed (no new in-between, camera, drag, resize) is not drawn again.
let dirty = true;
const redraw = () => (dirty = true);

// Software WebGL (SwiftShader on headless test machines, llvmpipe) fills pixels slowly: no multisampling there, and
// the liquid's passes at half resolution (?liquid-scale= overrides). Asked of a throwaway context first, since
// multisampling is chosen when the renderer's context is made.
const gpuName = (() => {
  const gl = document.createElement('canvas').getContext('webgl2');
  if (!gl) return '';
  const ext = gl.getExtension('WEBGL_debug_renderer_info');
  const name = String(ext ? gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER));
  gl.getExtension('WEBGL_lose_context')?.loseContext();
  return name;
})();
const softwareGl = /swiftshader|llvmpipe|software/i.test(gpuName);

// Renderer, scene, camera.
const renderer = new THREE.WebGLRenderer({ antialias: !softwareGl });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.xr.enabled = true;
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
const BACKGROUND = 0x111418;
scene.background = new THREE.Color(BACKGROUND);
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
const liquid = new LiquidRenderer(renderer, particles);
liquid.scale = Number(params.get('liquid-scale')) || (softwareGl ? 0.5 : 1);
const clock = new FrameClock();
const boxes = new TargetBoxes(world, (t, tr, rot, s) => send(protocol.setPose(t, tr, rot, s)));
let meshRoot = null, mixer = null, firstAction = null;

const drawingSize = new THREE.Vector2();
function resize() {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
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

// Connection: the frame source (the Worker, or the main thread with ?decode=main).
state.decode = params.get('decode') === 'main' ? 'main' : 'worker';
const source = createFrameSource({
  worker: state.decode === 'worker',
  url: `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`,
  onOpen: () => { state.connected = true; hud.status('connected'); },
  onClose: () => { state.connected = false; hud.status('disconnected; retrying…'); },
  onText,
  onFrame,
  onSurface,
  onBad: () => (state.badFrames += 1),
});
function send(text) {
  source.send(text);
}

let holding = false;  // the browser test's hold: frames are counted and dropped, the drawing stays where it is
function onFrame(f, decodeMs) {
  const t0 = performance.now();
  state.framesReceived += 1;
  state.bytesReceived += f.bytes;
  state.particlesReceived += f.count;
  if (state.decode === 'main') state.main.decodeMs += decodeMs;
  else state.main.workerDecodeMs += decodeMs;
  recvRate.tick(t0);
  if (holding) {
    source.recycle(f);
    return;
  }
  const { frame, count, time, stepMs, errorRate, simFps, controlled, centroid } = f;
  state.previousFrame = state.frame ? state.frame.frame : -1;
  state.frame = { frame, count, time, stepMs, errorRate, simFps, controlled, centroid };
  // The frame a seek asked for starts a new pair, however near the one before it; so does, while a seek is pending,
  // a frame that does not follow the one before (an earlier seek's). Frames still on their way from before the seek
  // continue the old pair.
  const cut = seek.pending !== null && (frame === seek.pending || frame !== state.previousFrame + 1);
  if (cut) state.seek.cuts += 1;
  // (A seek whose frame never comes, e.g. a restart sent after it, stops holding the slider after 2 s of frames.)
  if (frame === seek.pending || (seek.pending !== null && t0 - seek.lastSent > 2000)) seek.pending = null;
  state.seek.pending = seek.pending;
  const continues = clock.push({ frame, time, count }, t0, cut);
  state.history.push({ frame, time, error: errorRate, centroid, wall: t0, received: state.framesReceived, continues });
  if (state.history.length > 4000) state.history.splice(0, 1000);
  seek.follow(frame);
  particles.push(f.positions, f.targets, count, continues);
  source.recycle(f);  // the buffers go back to the decoder: the data now lives in the GPU attributes
  state.interp.discontinuities = clock.discontinuities;
  const v = hud.values;  // the text is written on the HUD's own tick (4 per second), not per frame
  v.stepMs = stepMs, v.simFps = simFps, v.count = count, v.errorRate = errorRate, v.time = time;
  redraw();
  state.main.ingestMs += performance.now() - t0;
  state.main.ingested += 1;
}

// The live surface: one mesh, its geometry replaced by each new surface.
const surfaceMaterial = new THREE.MeshStandardMaterial({ color: 0x9ecbff, roughness: 0.35, metalness: 0.0, transparent: true, opacity: 0.85 });
let liveSurface = null;
function onSurface(s) {
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
  seek.setup(h);
  // A finished run's report page (report.html in its folder), one click from its playback.
  $('lnk-report').hidden = !h.report;
  if (h.report) $('lnk-report').href = h.report;
  // The device when it is not the CPU (serve --device gpu|auto): "live: adaptive on NVIDIA … (driver)".
  const on = h.device && h.device !== 'cpu' ? ` on ${h.device}` : '';
  hud.status(h.mode === 'playback' ? 'playback' : `live: ${h.controller}${on}`);
  $('btn-play').textContent = h.paused ? 'play' : 'pause';
  if (h.radius) {
    particles.setRadius(h.radius);
    liquid.setRadius(h.radius);
  }
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
        // A liquid that wears its target's look (appearance tint or target) has vertex colours: the mesh shows them.
        const painted = !!o.geometry.getAttribute('color');
        o.material = new THREE.MeshStandardMaterial({ color: painted ? 0xffffff : 0x9ecbff, vertexColors: painted,
                                                      roughness: painted ? 0.3 : 0.35, metalness: 0.0 });
      }
    });
    world.add(meshRoot);
    mixer = new THREE.AnimationMixer(meshRoot);
    for (const clip of gltf.animations) mixer.clipAction(clip).play();
    firstAction = gltf.animations.length ? mixer.clipAction(gltf.animations[0]) : null;
    state.animation = { loaded: true, duration: gltf.animations[0]?.duration ?? 0, clips: gltf.animations.length, meshes, time: 0,
                        clipTime: NaN };
    meshRoot.visible = $('chk-mesh').checked;
    redraw();
  }, undefined, (e) => state.errors.push(`animation: ${e.message ?? e}`));
}

// The look: liquid, spheres or the mesh. Picking one by hand (or by ?look=) turns the automatic fall back off.
function setLook(mode, auto = false, reason = '') {
  if (!LOOKS.includes(mode) && mode !== 'none') return;  // 'none': no fluid at all (the test's background shot)
  state.look.mode = mode;
  state.look.auto = auto && state.look.auto;
  if (reason) state.look.reason = reason;
  if (mode !== 'none') $('sel-look').value = mode;
  particles.points.visible = mode === 'spheres';
  if (mode === 'mesh' && !$('chk-mesh').checked) {
    $('chk-mesh').checked = true;
    $('chk-mesh').dispatchEvent(new Event('change'));
  }
  perf.reset();
  hud.look(mode + (state.look.fellBack ? ' (fell back)' : ''));
  redraw();
}

// Panel.
$('btn-play').onclick = () => {
  const paused = $('btn-play').textContent === 'pause';
  send(paused ? protocol.pause() : protocol.play());
  $('btn-play').textContent = paused ? 'play' : 'pause';
};
$('btn-restart').onclick = () => send(protocol.restart());

// Seeking (playback only): a slider of the frame index, 0 to the hello's "frames" − 1. Dragging it sends seek (at
// most every 100 ms, and the value it is let go at); otherwise it follows the frame being played.
const seek = {
  el: $('rng-seek'), label: $('seek-label'), dragging: false, pending: null, sentValue: null, lastSent: 0, timer: 0,
  frames: 0,
  setup(h) {
    const on = h.mode === 'playback' && h.frames > 0;
    $('seek').hidden = !on;
    this.frames = on ? h.frames : 0;
    this.el.max = String(Math.max(0, this.frames - 1));
    if (!on) this.pending = null;
  },
  follow(frame) {
    if (!this.frames || this.dragging || this.pending !== null) return;
    this.el.value = String(frame);
    this.label.textContent = `${frame} / ${this.frames - 1}`;
  },
  // Asks for frame k (clamped as the server clamps it); the frame that comes back breaks the interpolation.
  to(k) {
    if (!this.frames) return;
    k = Math.min(Math.max(0, Math.round(k)), this.frames - 1);
    this.pending = k;
    this.sentValue = k;
    this.lastSent = performance.now();
    state.seek.sent += 1;
    state.seek.last = k;
    state.seek.pending = k;
    this.label.textContent = `${k} / ${this.frames - 1}`;
    send(protocol.seek(k));
  },
};
seek.el.addEventListener('input', () => {
  seek.dragging = true;
  seek.label.textContent = `${seek.el.value} / ${seek.frames - 1}`;
  clearTimeout(seek.timer);
  const wait = 100 - (performance.now() - seek.lastSent);
  if (wait <= 0) seek.to(Number(seek.el.value));
  else seek.timer = setTimeout(() => seek.to(Number(seek.el.value)), wait);
});
seek.el.addEventListener('change', () => {  // let go (or a keyboard step): the value it ends at, unless just sent
  clearTimeout(seek.timer);
  seek.dragging = false;
  if (Number(seek.el.value) !== seek.sentValue) seek.to(Number(seek.el.value));
});
$('sel-controller').onchange = (e) => send(protocol.setController(state.hello.controllers[Number(e.target.value)]));
$('sel-mesh').onchange = (e) => send(protocol.setMesh(0, Number(e.target.value)));
$('sel-look').onchange = (e) => setLook(e.target.value, false);
$('chk-mesh').onchange = (e) => {
  if (meshRoot) meshRoot.visible = e.target.checked;
  if (liveSurface) liveSurface.visible = e.target.checked;
  if (state.hello?.mode === 'live') send(protocol.setSurface(e.target.checked));
  redraw();
};

// Mouse dragging of targets (orbit controls are off while a target is held). The box follows the pointer at once,
// locally, and is drawn in the next display frame; the server gets the pose (throttled) and the fluid follows.
const pointer = new THREE.Vector2();
const raycaster = new THREE.Raycaster();
function rayAt(ev) {
  const r = renderer.domElement.getBoundingClientRect();
  pointer.set(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
  raycaster.setFromCamera(pointer, camera);
  return raycaster.ray;
}
let pendingMove = null;  // {index, position, at}: a pointer move not drawn yet (for the test's same-frame check)
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
  const g = boxes.targets[boxes.drag.index].group;
  state.drag.moves += 1;
  pendingMove = { index: boxes.drag.index, position: g.position.clone(), rotation: g.rotation.y, at: performance.now() };
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
// about the vertical axis instead. The controller's pose is read in the render loop, before the draw: the box moves
// in the display frame the controller did.
for (let i = 0; i < 2; ++i) {
  const ctl = renderer.xr.getController(i);
  const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3(0, 0, -1)]),
                              new THREE.LineBasicMaterial({ color: 0xffffff }));
  line.scale.z = 5;
  ctl.add(line);
  scene.add(ctl);
  const m = new THREE.Matrix4(), ray = new THREE.Ray();
  const ctlRay = () => {
    m.extractRotation(ctl.matrixWorld);
    ray.origin.setFromMatrixPosition(ctl.matrixWorld);
    ray.direction.set(0, 0, -1).applyMatrix4(m).normalize();
    return ray;
  };
  ctl.addEventListener('squeezestart', () => (ctl.userData.squeezing = true));
  ctl.addEventListener('squeezeend', () => (ctl.userData.squeezing = false));
  ctl.addEventListener('selectstart', () => {
    if (state.hello?.mode !== 'live') return;
    const r = ctlRay();
    if (boxes.begin(r, r.direction.clone().negate(), Boolean(ctl.userData.squeezing))) ctl.userData.dragging = true;
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
let xrAr = false;
renderer.xr.addEventListener('sessionstart', () => {
  const session = renderer.xr.getSession();
  const ar = Boolean(session && session.environmentBlendMode && session.environmentBlendMode !== 'opaque');
  xrAr = ar;
  state.xr = { ...state.xr, presenting: true, mode: ar ? 'immersive-ar' : 'immersive-vr', sessions: state.xr.sessions + 1 };
  placeForXr(ar);
  if (ar) {
    scene.background = null;
    grid.visible = false;
  }
  // The headset's highest frame rate: the viewer does not wait for the simulation, so it can draw at any of them.
  const rates = session?.supportedFrameRates;
  state.xr.frameRate = session?.frameRate ?? null;
  if (rates && rates.length && typeof session.updateTargetFrameRate === 'function') {
    const best = Math.max(...rates);
    state.xr.supportedFrameRates = [...rates];
    state.xr.frameRateRequested = best;
    session.updateTargetFrameRate(best)
      .then(() => { state.xr.frameRate = session.frameRate ?? best; perf.reset(); })
      .catch((e) => (state.xr.frameRateError = String(e)));
  }
  perf.reset();
});
renderer.xr.addEventListener('sessionend', () => {
  state.xr = { ...state.xr, presenting: false };
  xrAr = false;
  world.scale.setScalar(1);
  world.position.set(0, 0, 0);
  scene.background = new THREE.Color(BACKGROUND);
  grid.visible = true;
  perf.reset();
  redraw();
});

// Frame time, for the automatic fall back from liquid to spheres. The display's frame period: in XR the session's
// frame rate; on the desktop measured at start, over display frames in which nothing is drawn. Then the median
// period between consecutive drawn frames in liquid mode over 30 frames (8 when far too slow), after a second to
// settle (shaders compile, targets are made): more than 1.25 periods (and 2 ms) is a display rate it cannot hold.
const perf = {
  calib: new Float32Array(30), nCalib: 0, displayMs: NaN,
  deltas: new Float32Array(30), n: 0, since: 0, last: -1, lastDrew: false,
  reset() { this.n = 0; this.since = performance.now(); this.lastDrew = false; },
  median(a, n) {
    const s = this.sorted ?? (this.sorted = new Float32Array(64));
    for (let i = 0; i < n; ++i) s[i] = a[i];
    const v = s.subarray(0, n).sort();
    return v[n >> 1];
  },
  display() {
    if (renderer.xr.isPresenting && state.xr.frameRate) return 1000 / state.xr.frameRate;
    return this.displayMs;
  },
};
function frameTiming(now, drew) {
  const delta = perf.last >= 0 ? now - perf.last : NaN;
  perf.last = now;
  if (!renderer.xr.isPresenting && perf.nCalib < perf.calib.length) {
    if (Number.isFinite(delta)) perf.calib[perf.nCalib++] = delta;
    if (perf.nCalib === perf.calib.length) {
      perf.displayMs = Math.max(4, perf.median(perf.calib, perf.nCalib));
      state.look.displayMs = perf.displayMs;
      perf.reset();
    }
    return;
  }
  if (drew && perf.lastDrew && Number.isFinite(delta) && now - perf.since > 1000 && perf.n < perf.deltas.length)
    perf.deltas[perf.n++] = delta;
  perf.lastDrew = drew;
  // 30 frames decide; 8 already do when they are far too slow (over 3 periods: no point watching it crawl longer).
  const display = perf.display();
  if (perf.n < perf.deltas.length && !(perf.n >= 8 && perf.median(perf.deltas, perf.n) > 3 * display)) return;
  const ms = perf.median(perf.deltas, perf.n);
  perf.n = 0;
  perf.since = now;
  if (state.look.mode !== 'liquid') return;
  state.look.liquidFrameMs = ms;
  state.look.displayMs = display;
  if (state.look.auto && Number.isFinite(display) && ms > 1.25 * display + 2) {
    state.look.fellBack = true;
    setLook('spheres', true, `liquid drew a frame every ${ms.toFixed(1)} ms, the display every ${display.toFixed(1)} ms`);
  }
}

// Render loop (the XR loop when a session is on): every display frame.
let lastHud = 0, lastAlpha = -1, lastSeq = -1, held = false, heldAlpha = 1, suspended = false;
const drawnTarget = [NaN, NaN, NaN], tmpV = new THREE.Vector3();
function frameLoop(now) {
  const t0 = performance.now();
  for (let i = 0; i < 2; ++i) {
    const ctl = renderer.xr.getController(i);
    if (ctl.userData.dragging) {
      boxes.move(ctl.userData.ray());
      dirty = true;
    }
  }
  if (!renderer.xr.isPresenting) controls.update();
  const alpha = held ? heldAlpha : clock.update(t0);
  particles.setAlpha(alpha);
  state.interp.alpha = alpha;
  state.interp.time = clock.time;
  if (mixer && state.animation.duration > 0 && Number.isFinite(clock.time)) {
    mixer.setTime(clock.time % state.animation.duration);
    state.animation.time = clock.time;
    state.animation.clipTime = firstAction ? firstAction.time : NaN;
  }
  if (now - lastHud > 250) {
    lastHud = now;
    hud.update({ fps: renderRate.rate(now), recvFps: recvRate.rate(now) });
    state.hud = hud.values;
  }
  const presenting = renderer.xr.isPresenting;
  let draw = presenting || dirty || alpha !== lastAlpha || clock.seq !== lastSeq;
  if (!presenting && perf.nCalib < perf.calib.length) draw = false;  // measuring the display rate first
  if (draw) {
    dirty = false;
    lastAlpha = alpha;
    lastSeq = clock.seq;
    let eyeHeight;
    if (presenting) eyeHeight = renderer.xr.getCamera().cameras[0]?.viewport.w || renderer.getDrawingBufferSize(drawingSize).y;
    else eyeHeight = renderer.getDrawingBufferSize(drawingSize).y;
    particles.setViewportHeight(eyeHeight);
    if (state.look.mode === 'liquid' && particles.count > 0) {
      particles.points.visible = false;
      liquid.render(scene, camera, world, eyeHeight, presenting && xrAr);
    } else {
      particles.points.visible = state.look.mode === 'spheres';
      renderer.render(scene, camera);
    }
    state.renderedFrames += 1;
    if (presenting) state.xr.renderedFrames += 1;
    renderRate.tick(now);
    const g = boxes.targets[0]?.group;
    if (g) g.getWorldPosition(tmpV).toArray(drawnTarget);
    if (pendingMove) {
      const pg = boxes.targets[pendingMove.index]?.group;
      state.drag.checked += 1;
      if (pg && pg.position.equals(pendingMove.position) && pg.rotation.y === pendingMove.rotation) state.drag.drawnNext += 1;
      if (state.drag.lagMs.length < 200) state.drag.lagMs.push(performance.now() - pendingMove.at);
      pendingMove = null;
    }
  }
  frameTiming(now, draw);
  state.main.renderMs += performance.now() - t0;
}
renderer.setAnimationLoop(frameLoop);

// For tests and tools: where target i is on screen, and in the world (metres, after the XR placement).
state.targetWorld = (i) => boxes.targets[i]?.group.getWorldPosition(new THREE.Vector3()).toArray() ?? null;
state.drawnTarget = drawnTarget;
state.worldScale = () => world.scale.x;
state.targetScreen = (i) => boxes.screenPosition(i, camera, renderer.domElement);
state.project = (p) => {
  const v = world.localToWorld(new THREE.Vector3(...p)).project(camera);
  const r = renderer.domElement.getBoundingClientRect();
  return { x: r.left + ((v.x + 1) / 2) * r.width, y: r.top + ((1 - v.y) / 2) * r.height };
};
state.setLook = (mode) => setLook(mode, false);
state.seekTo = (k) => seek.to(k);
// Which of the animation's meshes is shown now (the first whose world matrix is not scaled to nothing; -1: none, or
// no animation). The run's animation.glb shows one mesh at a time by scaling the others' nodes to zero.
state.animationShown = () => {
  if (!meshRoot) return -1;
  meshRoot.updateMatrixWorld(true);
  let k = -1, i = 0;
  meshRoot.traverse((o) => {
    if (!o.isMesh) return;
    if (k < 0 && o.visible && Math.abs(o.matrixWorld.determinant()) > 1e-15) k = i;
    i += 1;
  });
  return k;
};
state.redraw = redraw;
state.setBackground = (hex) => { scene.background = new THREE.Color(hex); redraw(); };
// Hold: frames are counted but not shown, the drawing stays exactly where it is (the test's screenshots of one frame).
state.hold = (on) => {
  holding = Boolean(on);
  held = holding;
  heldAlpha = state.interp.alpha;
  redraw();
};
// Stops (and restarts) the render loop: another page of the test measures alone.
state.suspend = (on) => {
  suspended = Boolean(on);
  renderer.setAnimationLoop(suspended ? null : frameLoop);
};
state.liquidCoverage = () => {
  const cams = renderer.xr.isPresenting ? renderer.xr.getCamera().cameras : null;
  const vps = cams ? cams.map((c) => c.viewport.toArray()) : [[0, 0, liquid.size.x, liquid.size.y]];
  return { viewports: vps, pixels: liquid.coverage(vps), frames: liquid.stats.frames };
};

// The interpolation, checked from the outside: for the sampled particles, their positions in the two frames of the
// pair and where the GPU draws them now (the same vertex code as every look, read back from a float target).
const probe = (() => {
  const N = 32;
  const rt = new THREE.WebGLRenderTarget(N, 1, { type: THREE.FloatType, minFilter: THREE.NearestFilter,
                                                 magFilter: THREE.NearestFilter, depthBuffer: false });
  const uniforms = { ...particles.uniforms, uIdx: { value: new Int32Array(N) }, uN: { value: 0 } };
  const material = new THREE.ShaderMaterial({
    uniforms, depthTest: false, depthWrite: false,
    vertexShader: /* glsl */ `
      ${FF_POSITION_GLSL}
      uniform int uIdx[${N}];
      uniform int uN;
      varying vec3 vPos;
      void main() {
        int slot = -1;
        for (int k = 0; k < ${N}; ++k) if (k < uN && uIdx[k] == gl_VertexID) slot = k;
        vPos = ffPosition();
        gl_PointSize = 1.0;
        gl_Position = slot < 0 ? vec4(2.0, 2.0, 2.0, 1.0) : vec4((float(slot) + 0.5) / ${N}.0 * 2.0 - 1.0, 0.0, 0.0, 1.0);
      }`,
    fragmentShader: /* glsl */ `varying vec3 vPos; void main() { gl_FragColor = vec4(vPos, 1.0); }`,
  });
  const points = new THREE.Points(particles.geometry, material);
  points.frustumCulled = false;
  const s = new THREE.Scene();
  s.add(points);
  const cam = new THREE.OrthographicCamera();
  const out = new Float32Array(4 * N);
  return (indices) => {
    const n = Math.min(N, indices.length);
    for (let k = 0; k < n; ++k) uniforms.uIdx.value[k] = indices[k];
    uniforms.uN.value = n;
    const prev = renderer.getRenderTarget();
    renderer.setRenderTarget(rt);
    renderer.setClearColor(0x000000, 0);
    renderer.clear();
    renderer.render(s, cam);
    renderer.readRenderTargetPixels(rt, 0, 0, N, 1, out);
    renderer.setRenderTarget(prev);
    renderer.setClearColor(0x000000, 1);
    return Array.from({ length: n }, (_, k) => [out[4 * k], out[4 * k + 1], out[4 * k + 2]]);
  };
})();
state.sampleInterpolation = (indices) => {
  if (renderer.xr.isPresenting || !clock.b) return null;
  const now = performance.now();
  const alpha = held ? heldAlpha : clock.update(now);
  particles.setAlpha(alpha);
  const ids = indices.filter((i) => i < particles.count);
  const drawn = probe(ids);
  return {
    alpha, time: clock.time, single: clock.single, a: { ...clock.a }, b: { ...clock.b }, interval: clock.interval,
    newest: state.frame?.frame, previous: state.previousFrame,
    samples: ids.map((i, k) => ({ i, older: [0, 1, 2].map((c) => particles.slotValue(0, i, c)),
                                  newer: [0, 1, 2].map((c) => particles.slotValue(1, i, c)), drawn: drawn[k] })),
  };
};

state.gpu = gpuName;
state.look.liquidScale = liquid.scale;
setLook(state.look.mode, state.look.auto);
