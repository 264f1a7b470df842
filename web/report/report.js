// The run's report page (OUT/report.html, issue 46): the summary, plots over the run's frames, and the formed mesh
// with its target(s) in a three.js view. `fluidform` writes the page as one self-contained file: this script (bundled
// with three.js and uPlot by esbuild at build time, src/pipeline/CMakeLists.txt) and the run's data as JSON in
// <script id="ff-data">, meshes as base64 arrays, so it opens from disk with no network.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import uPlot from 'uplot';

const data = JSON.parse(document.getElementById('ff-data').textContent);
const $ = (id) => document.getElementById(id);
const fmt = (v, digits = 3) => (v === null || v === undefined || Number.isNaN(v) ? '–' : typeof v === 'number' ? Number(v.toPrecision(digits)).toLocaleString('en') : String(v));
const count = (v) => (typeof v === 'number' ? Math.round(v).toLocaleString('en') : '–');
const pct = (f, digits = 2) => (f === null || f === undefined ? '–' : `${(100 * f).toFixed(digits)} %`);

function bytes(b64, Type) {
  const bin = atob(b64);
  const u8 = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; ++i) u8[i] = bin.charCodeAt(i);
  return new Type(u8.buffer);
}

// --- summary -----------------------------------------------------------------------------------------------------
function summaryRows() {
  const r = data.report, t = r.totals ?? {};
  const targets = (r.targets ?? []).map((x) => x.mesh.split('/').pop()).join(', ') || '–';
  const formed = !(r.targets ?? []).length ? '– (no target)' : t.time_to_form_s === null || t.time_to_form_s === undefined ? 'not formed' : `${fmt(t.time_to_form_s)} s`;
  return [
    ['status', r.status ?? '–'],
    ['target(s)', targets],
    ['fluid particles', count(t.particles)],
    ['control particles', count(t.control_particles)],
    ['device', r.device ?? 'cpu'],
    ['controller', t.controller ?? '–'],
    ['error rate E', t.error_rate_pct === undefined ? '–' : `${fmt(t.error_rate_pct)} % (${fmt(t.error_spacings)} spacings)`],
    ['inside the target', pct(t.inside_fraction)],
    ['splash', pct(t.splash_fraction)],
    ['time to form', formed],
    ['frames', `${count(t.frames)} (${fmt(t.simulated_seconds)} s simulated)`],
    ['per-frame time', t.mean_step_time_s === undefined ? '–' : `${fmt(1000 * t.mean_step_time_s)} ms`],
    ['peak memory', t.peak_memory_mb === undefined ? '–' : `${fmt(t.peak_memory_mb)} MiB`],
    ['fluidform', r.fluidform_version ?? '–'],
  ];
}

function table(el, head, rows) {
  const t = document.createElement('table');
  if (head) t.createTHead().insertRow().append(...head.map((h) => Object.assign(document.createElement('th'), { textContent: h })));
  const body = t.createTBody();
  for (const row of rows) body.insertRow().append(...row.map((c) => Object.assign(document.createElement('td'), { textContent: c })));
  el.append(t);
}

function summary() {
  table($('summary'), null, summaryRows());
  const per = data.report.totals?.per_target ?? [];
  if (per.length > 1 || (data.report.targets ?? []).length > 1) {
    const names = (data.report.targets ?? []).map((x) => x.mesh.split('/').pop());
    table($('per-target'), ['target', 'fluid', 'E (%)', 'inside', 'splash', 'time to form'],
          per.map((p) => [names[p.target] ?? p.target, count(p.fluid), fmt(p.error_rate_pct), pct(p.inside_fraction), pct(p.splash_fraction),
                           p.time_to_form_s === null ? 'not formed' : `${fmt(p.time_to_form_s)} s`]));
  }
  // Still pictures of target and formed shape (drawn by fluidform, io/picture.h, from one view at one scale).
  for (const st of data.stills ?? []) {
    const fig = document.createElement('figure');
    fig.append(Object.assign(document.createElement('img'), { src: st.png, alt: st.label }),
               Object.assign(document.createElement('figcaption'), { textContent: st.label }));
    $('stills').append(fig);
  }
  const warn = $('warnings');
  for (const w of data.warnings ?? []) warn.append(Object.assign(document.createElement('li'), { textContent: w }));
  warn.hidden = !(data.warnings ?? []).length;
}

// --- plots -------------------------------------------------------------------------------------------------------
const COLOURS = ['#2a7ab0', '#d0632b', '#3a9b52', '#8a55b5'];

function plot(el, title, series, yLabel) {
  const m = data.metrics;
  const width = Math.max(320, Math.min(560, el.clientWidth || 560));
  const opts = {
    title, width, height: 220,
    scales: { x: { time: false } },
    axes: [{ label: 'simulated time (s)' }, { label: yLabel }],
    series: [{}, ...series.map(([label], k) => ({ label, stroke: COLOURS[k], width: 1.5 }))],
  };
  const chart = new uPlot(opts, [m.time_s, ...series.map(([, col]) => col)], el);
  chart.root.dataset.drawn = '1';
  return chart;
}

function plots() {
  const m = data.metrics;
  if (!m || !m.time_s || m.time_s.length < 2) {
    $('plots').append('The run has fewer than two frames: nothing to plot.');
    return;
  }
  // null (a frame without the value: no target to be inside of) stays a gap in the curve, not a zero.
  const per100 = (a) => a.map((v) => (v === null ? null : 100 * v));
  const ms = (a) => a.map((v) => (v === null ? null : 1000 * v));
  plot($('plot-error'), 'error rate E', [['E (%)', m.error_rate_pct]], '%');
  plot($('plot-inside'), 'fluid inside and splashed', [['inside (%)', per100(m.inside_fraction)], ['splash (%)', per100(m.splash_fraction)]], '%');
  plot($('plot-substeps'), 'sub-steps per frame', [['sub-steps', m.substeps]], 'sub-steps');
  plot($('plot-time'), 'frame time', [['frame (ms)', ms(m.step_time_s)]], 'ms');
}

// --- 3D view -----------------------------------------------------------------------------------------------------
function meshGeometry(mesh) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(bytes(mesh.positions, Float32Array), 3));
  g.setIndex(new THREE.BufferAttribute(bytes(mesh.indices, Uint32Array), 1));
  // The liquid's look (appearance tint or target): linear RGB bytes per vertex.
  if (mesh.colours) g.setAttribute('color', new THREE.BufferAttribute(bytes(mesh.colours, Uint8Array), 3, true));
  g.computeVertexNormals();
  return g;
}

async function view() {
  const host = $('view');
  const final = data.meshes?.final, targets = data.meshes?.targets ?? [];
  if (!final && !data.animation) {
    host.textContent = (data.warnings ?? []).some((w) => w.startsWith('the final mesh is not shown'))
      ? 'No 3D view: the final mesh could not be shown (see above).'
      : 'No mesh: the run was made with --no-mesh, or stopped before meshing.';
    host.classList.add('empty');
    return;
  }
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  const width = host.clientWidth || 800, height = 480;
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width, height);
  renderer.setClearColor(0xf3f5f8);
  host.append(renderer.domElement);
  const scene = new THREE.Scene();
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(2, 4, 3);
  scene.add(sun);
  const camera = new THREE.PerspectiveCamera(35, width / height, 0.001, 1e6);
  const controls = new OrbitControls(camera, renderer.domElement);

  const liquid = new THREE.Group(), overlay = new THREE.Group();
  scene.add(liquid, overlay);
  const water = new THREE.MeshStandardMaterial({ color: 0x2f8fd8, roughness: 0.25, metalness: 0.0 });
  const painted = new THREE.MeshStandardMaterial({ color: 0xffffff, vertexColors: true, roughness: 0.3, metalness: 0.0 });
  if (final) liquid.add(new THREE.Mesh(meshGeometry(final), final.colours ? painted : water));
  const ghost = new THREE.MeshBasicMaterial({ color: 0xd0632b, wireframe: true, transparent: true, opacity: 0.35 });
  for (const t of targets) overlay.add(new THREE.Mesh(meshGeometry(t), ghost));

  const box = new THREE.Box3().setFromObject(final ? liquid : overlay);
  if (box.isEmpty()) box.set(new THREE.Vector3(-1, 0, -1), new THREE.Vector3(1, 2, 1));
  const centre = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3()).length();
  camera.position.copy(centre).add(new THREE.Vector3(0.55, 0.35, 0.9).multiplyScalar(size * 1.3));
  camera.near = size / 1000;
  camera.far = size * 100;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();

  let mixer = null, clipLength = 0;
  const draw = () => renderer.render(scene, camera);
  controls.addEventListener('change', draw);
  $('chk-target').addEventListener('change', (e) => { overlay.visible = e.target.checked; draw(); });
  $('view-controls').hidden = false;
  if (data.animation_note) $('animation-note').textContent = `(${data.animation_note})`;
  const slider = $('rng-time');
  slider.addEventListener('input', () => {
    if (!mixer) return;
    // The sequence replaces the final mesh from the first move of the slider on.
    mixer.getRoot().visible = true;
    liquid.visible = false;
    mixer.setTime((slider.value / 1000) * clipLength);
    $('time-label').textContent = `${((slider.value / 1000) * clipLength).toFixed(2)} s`;
    draw();
  });
  draw();
  host.dataset.drawn = '1';
  if (data.animation) {
    const r = await loadAnimation(scene, draw);
    mixer = r.mixer;
    clipLength = r.length;
  }
}

// The meshed forming (animation.glb, one mesh per meshed frame shown in turn): its timeline on the slider; the final
// mesh stays the shape shown until the slider is moved.
async function loadAnimation(scene, draw) {
  const glb = bytes(data.animation, Uint8Array);
  const gltf = await new GLTFLoader().parseAsync(glb.buffer, '');
  const clip = gltf.animations[0];
  if (!clip) return { mixer: null, length: 0 };
  gltf.scene.visible = false;
  scene.add(gltf.scene);
  const mixer = new THREE.AnimationMixer(gltf.scene);
  mixer.clipAction(clip).play();
  $('timeline').hidden = false;
  draw();
  return { mixer, length: clip.duration };
}

async function main() {
  document.title = `fluidform report: ${(data.report.targets ?? []).map((x) => x.mesh.split('/').pop()).join(', ') || 'run'}`;
  summary();
  plots();
  try {
    await view();
  } catch (e) {
    $('view').textContent = `The 3D view could not start (${e.message}); the summary and the plots stand.`;
    $('view').classList.add('empty');
  }
  document.body.dataset.ready = '1';
}

main();
