// The fluid's particles on the GPU: two position slots (the last two frames received) and each particle's target, in
// preallocated attributes (DynamicDrawUsage, grown only when a frame has more particles than ever before). A frame is
// uploaded once, into the slot of the older one; every display frame then only sets `uMix` and the vertex shader
// places each particle between the two (FF_POSITION_GLSL, shared by the spheres here and the liquid's passes in
// liquid.js). Nothing is allocated per display frame.
import * as THREE from 'three';

export const PALETTE = [0x4fa3ff, 0xff8a3d, 0x6bd66b, 0xe95fd0, 0xf2d04b, 0x46d4c8, 0xb48cff, 0xff5f6b];
export const FREE_COLOUR = 0x8fa3b8;

/** GLSL (vertex): the particle's position between the two slots, and its colour from its target. */
export const FF_POSITION_GLSL = /* glsl */ `
  attribute vec3 position1;   // slot 1 ('position' is slot 0)
  attribute float target;     // the particle's target, 255: free fluid
  uniform float uMix;         // weight of slot 1
  uniform vec3 uPalette[8];
  uniform vec3 uFree;
  vec3 ffPosition() { return position * (1.0 - uMix) + position1 * uMix; }
  vec3 ffColour() {
    if (target > 254.5) return uFree;
    int t = int(mod(target + 0.5, 8.0));
    vec3 c = uPalette[0];
    for (int k = 1; k < 8; ++k) if (k == t) c = uPalette[k];
    return c;
  }`;

const vertexShader = /* glsl */ `
  ${FF_POSITION_GLSL}
  uniform float uSize;            // world diameter
  uniform float uViewportHeight;  // pixels of the viewport drawn into (one eye's in XR)
  varying vec3 vColor;
  void main() {
    vColor = ffColour();
    vec4 mv = modelViewMatrix * vec4(ffPosition(), 1.0);
    gl_Position = projectionMatrix * mv;
    gl_PointSize = max(1.5, uSize * projectionMatrix[1][1] * 0.5 * uViewportHeight / -mv.z);
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

/** The uniforms every particle material shares (one object: setting uMix once sets it for all passes). */
export function particleUniforms(radius) {
  const c = new THREE.Color();
  return {
    uMix: { value: 1 },
    uPalette: { value: PALETTE.map((h) => c.setHex(h).toArray()).map((a) => new THREE.Vector3(...a)) },
    uFree: { value: new THREE.Vector3(...c.setHex(FREE_COLOUR).toArray()) },
    uSize: { value: 2 * radius },
    uViewportHeight: { value: 500 },
  };
}

export class ParticleView {
  constructor(radius = 0.01) {
    this.capacity = 0;
    this.count = 0;
    this.newest = 0;   // the slot holding the newest frame
    this.geometry = new THREE.BufferGeometry();
    this.uniforms = particleUniforms(radius);
    this.material = new THREE.ShaderMaterial({ uniforms: this.uniforms, vertexShader, fragmentShader });
    this.points = new THREE.Points(this.geometry, this.material);
    this.points.frustumCulled = false;
    this.ensure(1);
  }
  get radius() { return 0.5 * this.uniforms.uSize.value; }
  setRadius(r) { this.uniforms.uSize.value = 2 * r; }
  setViewportHeight(px) { this.uniforms.uViewportHeight.value = px; }
  /** Room for n particles; true when the attributes were reallocated (their contents are gone). */
  ensure(n) {
    if (n <= this.capacity) return false;
    this.capacity = Math.max(n, Math.ceil(this.capacity * 1.25));
    const attr = (array, size) => new THREE.BufferAttribute(array, size).setUsage(THREE.DynamicDrawUsage);
    this.slots = [attr(new Float32Array(3 * this.capacity), 3), attr(new Float32Array(3 * this.capacity), 3)];
    this.geometry.setAttribute('position', this.slots[0]);
    this.geometry.setAttribute('position1', this.slots[1]);
    this.targets = attr(new Uint8Array(this.capacity), 1);
    this.geometry.setAttribute('target', this.targets);
    return true;
  }
  /**
   * Uploads a frame (positions Float32Array 3n, targets Uint8Array n). `continues`: into the older slot, the pair
   * then being (previous newest, this); otherwise into both (shown as it is).
   */
  push(positions, targets, n, continues) {
    if (this.ensure(n)) continues = false;
    const p = positions.subarray(0, 3 * n);
    const write = (slot) => {
      const a = this.slots[slot];
      a.array.set(p);
      a.clearUpdateRanges();
      a.addUpdateRange(0, 3 * n);
      a.needsUpdate = true;
    };
    if (continues) {
      this.newest = 1 - this.newest;
      write(this.newest);
    } else {
      write(0);
      write(1);
    }
    this.targets.array.set(targets.subarray(0, n));
    this.targets.clearUpdateRanges();
    this.targets.addUpdateRange(0, n);
    this.targets.needsUpdate = true;
    this.count = n;
    this.geometry.setDrawRange(0, n);
  }
  /** alpha: 0 at the older frame, 1 at the newest. */
  setAlpha(alpha) { this.uniforms.uMix.value = this.newest === 1 ? alpha : 1 - alpha; }
  /** Particle i's coordinate k in the older (which = 0) or newest (1) frame, model space. */
  slotValue(which, i, k) { return this.slots[which === 1 ? this.newest : 1 - this.newest].array[3 * i + k]; }
}
