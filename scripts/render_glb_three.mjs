// Renders a fluidform GLB in three.js (headless chromium, off the network) to a PNG: the water material as
// three.js shows it (MeshPhysicalMaterial: transmission, IOR, absorption), at the animation's end, over a checker
// floor and wall so that the refraction shows. usage: node scripts/render_glb_three.mjs IN.glb OUT.png [--time S]
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const [glb, png] = process.argv.slice(2, 4);
const ti = process.argv.indexOf('--time');
const time = ti > 0 ? Number(process.argv[ti + 1]) : -1;
if (!glb || !png) {
  console.error('usage: node scripts/render_glb_three.mjs IN.glb OUT.png [--time S]');
  process.exit(2);
}
const page = `<!doctype html><html><body style="margin:0"><canvas id="c" width="800" height="600"></canvas>
<script type="importmap">{"imports":{"three":"/three/build/three.module.js","three/addons/":"/three/examples/jsm/"}}</script>
<script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { RoomEnvironment } from 'three/addons/environments/RoomEnvironment.js';
const renderer = new THREE.WebGLRenderer({ canvas: document.getElementById('c'), antialias: true });
renderer.toneMapping = THREE.ACESFilmicToneMapping;
const scene = new THREE.Scene();
scene.environment = new THREE.PMREMGenerator(renderer).fromScene(new RoomEnvironment(), 0.04).texture;
const checker = (() => { const c = document.createElement('canvas'); c.width = c.height = 256; const g = c.getContext('2d');
  for (let i = 0; i < 8; i++) for (let j = 0; j < 8; j++) { g.fillStyle = (i + j) % 2 ? '#445' : '#eee'; g.fillRect(32 * i, 32 * j, 32, 32); }
  const t = new THREE.CanvasTexture(c); t.colorSpace = THREE.SRGBColorSpace; return t; })();
const gltf = await new GLTFLoader().loadAsync('/model.glb');
const model = gltf.scene; scene.add(model);
if (gltf.animations.length) {
  const mixer = new THREE.AnimationMixer(model); const a = mixer.clipAction(gltf.animations[0]); a.play();
  mixer.setTime(${time} >= 0 ? ${time} : gltf.animations[0].duration - 1e-3);
}
model.updateMatrixWorld(true);
const box = new THREE.Box3(); model.traverse((o) => { if (o.isMesh && o.visible && o.getWorldScale(new THREE.Vector3()).x > 0) box.expandByObject(o); });
const size = box.getSize(new THREE.Vector3()), centre = box.getCenter(new THREE.Vector3()), s = size.length();
const floor = new THREE.Mesh(new THREE.PlaneGeometry(4 * s, 4 * s), new THREE.MeshStandardMaterial({ map: checker }));
floor.rotation.x = -Math.PI / 2; floor.position.y = box.min.y; scene.add(floor);
const wall = new THREE.Mesh(new THREE.PlaneGeometry(4 * s, 2 * s), new THREE.MeshStandardMaterial({ map: checker }));
wall.position.set(centre.x, box.min.y + s, centre.z - 0.8 * s); scene.add(wall);
scene.add(new THREE.DirectionalLight(0xffffff, 2).translateX(s).translateY(2 * s).translateZ(s));
const camera = new THREE.PerspectiveCamera(40, 800 / 600, s / 100, 100 * s);
camera.position.set(centre.x + 0.6 * s, centre.y + 0.35 * s, centre.z + 1.3 * s); camera.lookAt(centre);
renderer.render(scene, camera);
const mats = []; model.traverse((o) => { if (o.isMesh) mats.push(o.material.type + ' transmission ' + o.material.transmission); });
window.done = [...new Set(mats)].join('; ');
</script></body></html>`;
const types = { '.js': 'text/javascript', '.html': 'text/html' };
const server = http.createServer((req, res) => {
  const url = decodeURIComponent(req.url.split('?')[0]);
  let file = null;
  if (url === '/') { res.writeHead(200, { 'content-type': 'text/html' }); return res.end(page); }
  if (url === '/model.glb') file = path.resolve(glb);
  else if (url.startsWith('/three/')) file = path.join(root, 'node_modules', url.slice(1));
  if (!file || !file.startsWith(path.join(root, 'node_modules')) && file !== path.resolve(glb) || !fs.existsSync(file)) {
    res.writeHead(404); return res.end();
  }
  res.writeHead(200, { 'content-type': types[path.extname(file)] ?? 'application/octet-stream' });
  fs.createReadStream(file).pipe(res);
}).listen(0, '127.0.0.1');
await new Promise((r) => server.on('listening', r));
const browser = await chromium.launch({ executablePath: '/usr/bin/chromium', headless: true,
  args: ['--headless', '--no-sandbox', '--no-first-run', '--disable-background-networking', '--disable-component-update',
         '--disable-sync', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'] });
try {
  const p = await browser.newPage({ viewport: { width: 800, height: 600 } });
  p.on('pageerror', (e) => console.error('page error:', e.message));
  await p.goto(`http://127.0.0.1:${server.address().port}/`);
  await p.waitForFunction(() => window.done !== undefined, null, { timeout: 120000 });
  console.log(await p.evaluate(() => window.done));
  await (await p.$('#c')).screenshot({ path: png });
} finally {
  await browser.close();
  server.close();
}
