// The fluid as point sprites shaded like spheres, coloured by target: one draw call for any particle count, which
// matters on a headset and in software WebGL. Positions are rewritten in place when a frame arrives.
import * as THREE from 'three';

export const PALETTE = [0x4fa3ff, 0xff8a3d, 0x6bd66b, 0xe95fd0, 0xf2d04b, 0x46d4c8, 0xb48cff, 0xff5f6b];
const FREE = new THREE.Color(0x8fa3b8);

const vertexShader = /* glsl */ `
  uniform float uSize;    // world diameter
  uniform float uScale;   // pixels per world unit at distance 1
  attribute vec3 color;
  varying vec3 vColor;
  void main() {
    vColor = color;
    vec4 mv = modelViewMatrix * vec4(position, 1.0);
    gl_Position = projectionMatrix * mv;
    gl_PointSize = max(1.5, uSize * uScale / -mv.z);
  }`;
const fragmentShader = /* glsl */ `
  varying vec3 vColor;
  void main() {
    vec2 p = gl_PointCoord * 2.0 - 1.0;
    float r2 = dot(p, p);
    if (r2 > 1.0) discard;
    vec3 n = vec3(p.x, -p.y, sqrt(1.0 - r2));
    float light = 0.35 + 0.65 * max(dot(n, normalize(vec3(0.4, 0.7, 0.6))), 0.0);
    gl_FragColor = vec4(vColor * light, 1.0);
  }`;

export class ParticleView {
  constructor(radius = 0.01) {
    this.capacity = 0;
    this.geometry = new THREE.BufferGeometry();
    this.material = new THREE.ShaderMaterial({
      uniforms: { uSize: { value: 2 * radius }, uScale: { value: 500 } },
      vertexShader,
      fragmentShader,
    });
    this.points = new THREE.Points(this.geometry, this.material);
    this.points.frustumCulled = false;
    this.colors = new THREE.Color();
  }
  setRadius(r) { this.material.uniforms.uSize.value = 2 * r; }
  /** Pixels per world unit at distance 1: the viewport height over the view height at distance 1. */
  setViewport(heightPx, fovDeg) {
    this.material.uniforms.uScale.value = heightPx / (2 * Math.tan((fovDeg * Math.PI) / 360));
  }
  ensure(n) {
    if (n <= this.capacity) return;
    this.capacity = Math.max(n, Math.ceil(this.capacity * 1.5));
    const pos = new THREE.BufferAttribute(new Float32Array(3 * this.capacity), 3).setUsage(THREE.DynamicDrawUsage);
    const col = new THREE.BufferAttribute(new Float32Array(3 * this.capacity), 3).setUsage(THREE.DynamicDrawUsage);
    this.geometry.setAttribute('position', pos);
    this.geometry.setAttribute('color', col);
  }
  /** `frame` from protocol.decodeFrame. */
  update(frame) {
    const n = frame.count;
    this.ensure(n);
    const pos = this.geometry.getAttribute('position');
    const col = this.geometry.getAttribute('color');
    pos.array.set(frame.positions.subarray(0, 3 * n));
    const c = this.colors;
    for (let i = 0; i < n; ++i) {
      const t = frame.targets[i];
      if (t === 255) c.copy(FREE);
      else c.setHex(PALETTE[t % PALETTE.length]);
      col.array[3 * i] = c.r;
      col.array[3 * i + 1] = c.g;
      col.array[3 * i + 2] = c.b;
    }
    pos.needsUpdate = true;
    col.needsUpdate = true;
    this.geometry.setDrawRange(0, n);
  }
}
