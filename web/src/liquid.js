// Screen-space fluid rendering (after van der Laan, Green and Sainz, "Screen space fluid rendering with curvature
// flow", I3D 2009, with a bilateral filter in place of the curvature flow): the particles become one liquid surface
// without building a mesh.
//   1. the scene without the particles → a colour + depth target (what lies behind the liquid, refracted below)
//   2. the particles as sphere splats → their eye-space depth (the nearest sphere surface per pixel)
//   3. the particles again, additively → thickness, weighted by each target's colour (the liquid's tint)
//   4. the depth smoothed by a separable bilateral filter (twice): the spheres' bumps go, the silhouettes and the
//      depth steps between parts (an ear in front of the body) stay
//   5. the scene into the output as it is, then the liquid over it: normals from the smoothed depth, Fresnel
//      reflection of an environment, refraction of pass 1, Beer–Lambert absorption through the thickness, tinted per
//      target, the rim blended in
// Every pass draws with the viewer's camera: in an XR session three.js makes that the headset's ArrayCamera and draws
// each eye into its own viewport, so the liquid works in both eyes (the full-screen passes are clip-space quads that
// fill whichever viewport they are drawn into, and read the eye's projection from three's per-eye uniforms).
// Everything is allocated at the first frame and on resizes, nothing per frame.
import * as THREE from 'three';
import { FF_POSITION_GLSL } from './particles.js';

const QUAD_VERTEX = /* glsl */ `
  varying vec2 vNdc;
  flat varying vec4 vProj;   // P00, P11, P20, P21: the eye's projection (asymmetric in a headset)
  flat varying vec2 vZ;      // P22, P32
  void main() {
    vNdc = position.xy;
    vProj = vec4(projectionMatrix[0][0], projectionMatrix[1][1], projectionMatrix[2][0], projectionMatrix[2][1]);
    vZ = vec2(projectionMatrix[2][2], projectionMatrix[3][2]);
    gl_Position = vec4(position.xy, 0.0, 1.0);
  }`;

const SPLAT_VERTEX = /* glsl */ `
  ${FF_POSITION_GLSL}
  uniform float uRadius;          // splat radius, world units
  uniform float uViewportHeight;  // pixels of the viewport drawn into
  varying vec3 vCenter;           // view space
  varying float vRadius;          // view space
  varying vec3 vColour;
  flat varying vec2 vZ;
  void main() {
    vec4 mv = modelViewMatrix * vec4(ffPosition(), 1.0);
    vCenter = mv.xyz;
    vRadius = uRadius * length(modelViewMatrix[0].xyz);
    vColour = ffColour();
    vZ = vec2(projectionMatrix[2][2], projectionMatrix[3][2]);
    gl_Position = projectionMatrix * mv;
    gl_PointSize = max(1.0, 2.0 * vRadius * projectionMatrix[1][1] * 0.5 * uViewportHeight / max(1e-4, -mv.z));
  }`;

// Eye-space depth of the sphere's front surface (positive, metres); 0 where there is no liquid.
const DEPTH_FRAGMENT = /* glsl */ `
  varying vec3 vCenter;
  varying float vRadius;
  varying vec3 vColour;
  flat varying vec2 vZ;
  void main() {
    vec2 p = gl_PointCoord * 2.0 - 1.0;
    float r2 = dot(p, p);
    if (r2 > 1.0) discard;
    vec3 pos = vCenter + vec3(p.x, -p.y, sqrt(1.0 - r2)) * vRadius;
    gl_FragDepth = clamp(((vZ.x * pos.z + vZ.y) / -pos.z) * 0.5 + 0.5, 0.0, 1.0);
    gl_FragColor = vec4(-pos.z, 0.0, 0.0, 1.0);
  }`;

// The chord through the sphere, added up: rgb = colour × thickness, a = thickness.
const THICKNESS_FRAGMENT = /* glsl */ `
  varying vec3 vCenter;
  varying float vRadius;
  varying vec3 vColour;
  void main() {
    vec2 p = gl_PointCoord * 2.0 - 1.0;
    float r2 = dot(p, p);
    if (r2 > 1.0) discard;
    float t = 2.0 * vRadius * sqrt(1.0 - r2);
    gl_FragColor = vec4(vColour * t, t);
  }`;

// One direction of the bilateral filter: a Gaussian in screen space whose width is a fixed world size at the pixel's
// depth, times a Gaussian in depth (so depth steps between separate parts are kept); empty pixels neither take part
// nor get filled, so the silhouette stays where the particles are.
const BLUR_FRAGMENT = /* glsl */ `
  uniform sampler2D tInput;
  uniform vec2 uTexel;            // 1 / target size
  uniform vec2 uDir;              // (1, 0) or (0, 1)
  uniform float uWorldRadius;     // filter radius, world units
  uniform float uDepthFalloff;    // depth difference at which a neighbour's weight falls to 1/e, world units
  uniform float uViewportHeight;
  uniform float uMaxPixels;
  varying vec2 vNdc;
  flat varying vec4 vProj;
  void main() {
    vec2 uv = gl_FragCoord.xy * uTexel;
    float d = texture2D(tInput, uv).r;
    if (d <= 0.0) { gl_FragColor = vec4(0.0); return; }
    float rPx = clamp(uWorldRadius * vProj.y * 0.5 * uViewportHeight / d, 1.0, uMaxPixels);
    float stepPx = max(1.0, rPx / 7.0);
    float inv2s2 = 2.0 / (rPx * rPx);     // sigma = r / 2
    float sum = 0.0, wsum = 0.0;
    for (int i = -7; i <= 7; ++i) {
      float x = float(i) * stepPx;
      float s = texture2D(tInput, uv + uDir * (x * uTexel)).r;
      if (s <= 0.0) continue;
      float dz = (s - d) / uDepthFalloff;
      float w = exp(-x * x * inv2s2 - dz * dz);
      sum += s * w;
      wsum += w;
    }
    gl_FragColor = vec4(sum / wsum, 0.0, 0.0, 1.0);
  }`;

const COMPOSITE_FRAGMENT = /* glsl */ `
  uniform sampler2D tDepth;       // smoothed eye depth, 0: no liquid
  uniform sampler2D tThick;       // rgb: colour × thickness, a: thickness
  uniform sampler2D tScene;       // what lies behind (linear colour)
  uniform sampler2D tSceneDepth;
  uniform vec2 uOutSize;          // pixels of the whole output (both eyes)
  uniform vec2 uFluidTexel;       // 1 / size of the liquid's targets
  uniform vec3 uLight;            // world direction towards the light
  uniform float uAbsorb;          // absorption of the colours a target's tint lacks, per world unit
  uniform float uRefract;         // refraction offset, in eye-viewport units per unit of normal
  uniform float uScatter;        // grey scattering per world unit: how quickly the liquid shows its own colour
  uniform float uEdge;            // thickness over which the rim fades in, world units
  uniform float uTransparentBackground;  // AR: keep the passthrough visible where there is no liquid
  varying vec2 vNdc;
  flat varying vec4 vProj;
  flat varying vec2 vZ;

  vec3 viewPos(vec2 ndc, float d) { return vec3(d * (ndc.x + vProj.z) / vProj.x, d * (ndc.y + vProj.w) / vProj.y, -d); }
  float sceneDepth(vec2 uv) { float z = texture2D(tSceneDepth, uv).r * 2.0 - 1.0; return vZ.y / (z + vZ.x); }
  // A sky over a horizon and a dark floor, with two soft lights: what the liquid reflects.
  vec3 environment(vec3 r) {
    float y = r.y;
    vec3 sky = mix(vec3(0.55, 0.62, 0.70), vec3(0.16, 0.30, 0.62), smoothstep(0.0, 0.8, y));
    vec3 ground = mix(vec3(0.10, 0.11, 0.12), vec3(0.03, 0.035, 0.04), smoothstep(0.0, -0.6, y));
    vec3 c = y > 0.0 ? sky : ground;
    c = mix(ground, c, smoothstep(-0.04, 0.04, y));
    c += vec3(6.0, 5.6, 5.0) * pow(max(dot(r, uLight), 0.0), 180.0);
    c += vec3(0.9, 0.95, 1.0) * pow(max(dot(r, normalize(vec3(-0.6, 0.5, -0.4))), 0.0), 24.0);
    return c;
  }

  void main() {
    vec2 uv = gl_FragCoord.xy / uOutSize;
    float d = texture2D(tDepth, uv).r;
    // Just outside the liquid's (coarser) depth, a neighbour's depth: the silhouette then comes from the (filtered)
    // thickness below, smooth at any resolution of the liquid's targets.
    if (d <= 0.0) {
      float e;
      e = texture2D(tDepth, uv + vec2(uFluidTexel.x, 0.0)).r; if (e > 0.0) d = e;
      e = texture2D(tDepth, uv - vec2(uFluidTexel.x, 0.0)).r; if (e > 0.0 && (d <= 0.0 || e < d)) d = e;
      e = texture2D(tDepth, uv + vec2(0.0, uFluidTexel.y)).r; if (e > 0.0 && (d <= 0.0 || e < d)) d = e;
      e = texture2D(tDepth, uv - vec2(0.0, uFluidTexel.y)).r; if (e > 0.0 && (d <= 0.0 || e < d)) d = e;
      if (d > 0.0 && texture2D(tThick, uv).a <= 0.0) d = 0.0;
    }
    if (d <= 0.0 || d > sceneDepth(uv) + 1e-3) discard;  // the scene, drawn straight into the output, shows
    // ndc per uv (2 on the desktop, 4 across one eye of a side-by-side headset image).
    vec2 k = vec2(dFdx(vNdc.x) / dFdx(uv.x), dFdy(vNdc.y) / dFdy(uv.y));
    vec3 P = viewPos(vNdc, d);
    vec2 tx = vec2(uFluidTexel.x, 0.0), ty = vec2(0.0, uFluidTexel.y);
    float dxp = texture2D(tDepth, uv + tx).r, dxm = texture2D(tDepth, uv - tx).r;
    float dyp = texture2D(tDepth, uv + ty).r, dym = texture2D(tDepth, uv - ty).r;
    vec3 Pxp = viewPos(vNdc + vec2(k.x * tx.x, 0.0), dxp), Pxm = viewPos(vNdc - vec2(k.x * tx.x, 0.0), dxm);
    vec3 Pyp = viewPos(vNdc + vec2(0.0, k.y * ty.y), dyp), Pym = viewPos(vNdc - vec2(0.0, k.y * ty.y), dym);
    // The one-sided difference with the smaller depth change (an edge or a step does not tilt the normal).
    vec3 ddx = dxp <= 0.0 ? P - Pxm : dxm <= 0.0 ? Pxp - P : (abs(dxp - d) < abs(d - dxm) ? Pxp - P : P - Pxm);
    vec3 ddy = dyp <= 0.0 ? P - Pym : dym <= 0.0 ? Pyp - P : (abs(dyp - d) < abs(d - dym) ? Pyp - P : P - Pym);
    if (dxp <= 0.0 && dxm <= 0.0) ddx = vec3(1.0, 0.0, 0.0);
    if (dyp <= 0.0 && dym <= 0.0) ddy = vec3(0.0, 1.0, 0.0);
    vec3 n = normalize(cross(ddx, ddy));
    vec3 V = normalize(-P);
    if (dot(n, V) < 0.0) n = -n;

    // Thickness (a small blur against the splats' graininess) and its tint.
    vec4 th = 0.4 * texture2D(tThick, uv);
    th += 0.15 * (texture2D(tThick, uv + 2.0 * tx) + texture2D(tThick, uv - 2.0 * tx) +
                  texture2D(tThick, uv + 2.0 * ty) + texture2D(tThick, uv - 2.0 * ty));
    float thick = max(th.a, 1e-5);
    vec3 tint = clamp(th.rgb / thick, 0.0, 1.0);
    vec3 transmit = exp(-(uAbsorb * (1.0 - tint) + 0.15 * uAbsorb * 0.1) * thick);

    // World-space normal and reflection (viewMatrix is orthonormal: v * M is M's inverse applied).
    vec3 nw = normalize((vec4(n, 0.0) * viewMatrix).xyz);
    vec3 rw = normalize((vec4(reflect(-V, n), 0.0) * viewMatrix).xyz);
    float cosv = clamp(dot(n, V), 0.0, 1.0);
    float fresnel = 0.02 + 0.98 * pow(1.0 - cosv, 5.0);

    // Refraction: what lies behind, displaced along the normal by an amount that grows with the thickness.
    vec2 off = n.xy * uRefract * min(thick, 0.25) / k;
    vec3 behind = texture2D(tScene, clamp(uv + off, vec2(0.0), vec2(1.0))).rgb;
    // Light scattered in the liquid, in its tint (without it, a dyed liquid over a dark floor would read as black).
    float diffuse = 0.35 + 0.65 * max(dot(nw, uLight), 0.0);
    vec3 scatter = tint * (1.0 - exp(-uScatter * thick)) * diffuse * 0.45;
    vec3 colour = mix(behind * transmit + scatter, environment(rw), fresnel);
    // The light's highlight (the environment's sun lobe is too small a target for a rippled surface alone).
    vec3 lv = normalize((viewMatrix * vec4(uLight, 0.0)).xyz);
    colour += vec3(1.0, 0.97, 0.92) * 0.9 * pow(max(dot(n, normalize(lv + V)), 0.0), 90.0);
    // The rim, where the liquid is thinner than a particle, fades into the background (blended over the output).
    float rim = smoothstep(0.0, uEdge, thick);
    // AR: no background to refract, the passthrough shows through as much as the liquid transmits.
    float a = uTransparentBackground > 0.5 ? rim * clamp(1.0 - dot(transmit, vec3(0.333)) + fresnel, 0.0, 1.0) : rim;
    if (uTransparentBackground > 0.5) colour = scatter + environment(rw) * fresnel;
    gl_FragColor = vec4(colour, a);
    #include <colorspace_fragment>
  }`;

export class LiquidRenderer {
  constructor(renderer, particles) {
    this.renderer = renderer;
    this.particles = particles;
    this.scale = 1;             // resolution of the liquid's targets relative to the output
    this.radiusFactor = 1.25;   // splat radius over the particle radius: neighbours overlap into one surface
    this.blurFactor = 4.5;      // filter radius over the particle radius
    this.depthFalloffFactor = 4.0;
    this.size = new THREE.Vector2(0, 0);
    this.fluidSize = new THREE.Vector2(0, 0);
    this.floatType = renderer.extensions.has('EXT_color_buffer_float') ? THREE.FloatType : THREE.HalfFloatType;
    this.stats = { frames: 0 };

    const u = particles.uniforms;
    const splatUniforms = { ...u, uRadius: { value: 0.01 } };
    this.splatUniforms = splatUniforms;
    this.depthMaterial = new THREE.ShaderMaterial({ uniforms: splatUniforms, vertexShader: SPLAT_VERTEX,
                                                    fragmentShader: DEPTH_FRAGMENT });
    this.thickMaterial = new THREE.ShaderMaterial({ uniforms: splatUniforms, vertexShader: SPLAT_VERTEX,
                                                    fragmentShader: THICKNESS_FRAGMENT, depthTest: false,
                                                    depthWrite: false, blending: THREE.CustomBlending,
                                                    blendSrc: THREE.OneFactor, blendDst: THREE.OneFactor,
                                                    blendSrcAlpha: THREE.OneFactor, blendDstAlpha: THREE.OneFactor });
    // The particles' own scene: a root that copies the world group's transform (AR placement) every frame.
    this.fluidScene = new THREE.Scene();
    this.root = new THREE.Group();
    this.root.matrixAutoUpdate = false;
    this.points = new THREE.Points(particles.geometry, this.depthMaterial);
    this.points.frustumCulled = false;
    this.root.add(this.points);
    this.fluidScene.add(this.root);

    const quad = new THREE.PlaneGeometry(2, 2);
    const quadScene = (material) => {
      const s = new THREE.Scene();
      const m = new THREE.Mesh(quad, material);
      m.frustumCulled = false;
      s.add(m);
      return s;
    };
    this.blurUniforms = {
      tInput: { value: null }, uTexel: { value: new THREE.Vector2() }, uDir: { value: new THREE.Vector2(1, 0) },
      uWorldRadius: { value: 0.02 }, uDepthFalloff: { value: 0.03 }, uViewportHeight: { value: 500 },
      uMaxPixels: { value: 40 },
    };
    this.blurScene = quadScene(new THREE.ShaderMaterial({ uniforms: this.blurUniforms, vertexShader: QUAD_VERTEX,
                                                          fragmentShader: BLUR_FRAGMENT, depthTest: false,
                                                          depthWrite: false }));
    this.compositeUniforms = {
      tDepth: { value: null }, tThick: { value: null }, tScene: { value: null }, tSceneDepth: { value: null },
      uOutSize: { value: new THREE.Vector2() }, uFluidTexel: { value: new THREE.Vector2() },
      uLight: { value: new THREE.Vector3(0.4, 0.8, 0.45).normalize() }, uAbsorb: { value: 5.0 },
      uRefract: { value: 0.35 }, uScatter: { value: 2.5 }, uEdge: { value: 0.02 }, uTransparentBackground: { value: 0 },
    };
    this.compositeScene = quadScene(new THREE.ShaderMaterial({ uniforms: this.compositeUniforms,
                                                               vertexShader: QUAD_VERTEX,
                                                               fragmentShader: COMPOSITE_FRAGMENT, depthTest: false,
                                                               depthWrite: false, transparent: true }));
    this.targets = null;
    this.savedViewports = [new THREE.Vector4(), new THREE.Vector4()];
    this.clearColour = new THREE.Color();
  }

  setRadius(r) {
    this.splatUniforms.uRadius.value = this.radiusFactor * r;
    this.blurUniforms.uWorldRadius.value = this.blurFactor * r;
    this.blurUniforms.uDepthFalloff.value = this.depthFalloffFactor * r;
    this.compositeUniforms.uEdge.value = 1.5 * r;
  }

  ensureTargets(w, h) {
    const fw = Math.max(1, Math.round(w * this.scale)), fh = Math.max(1, Math.round(h * this.scale));
    if (this.targets && this.size.x === w && this.size.y === h && this.fluidSize.x === fw && this.fluidSize.y === fh) return;
    if (this.targets) for (const t of Object.values(this.targets)) t.dispose();
    this.size.set(w, h);
    this.fluidSize.set(fw, fh);
    const fluid = (type, filter) => new THREE.WebGLRenderTarget(fw, fh, { type, format: THREE.RGBAFormat,
                                                                         minFilter: filter, magFilter: filter,
                                                                         depthBuffer: false });
    const depth = new THREE.WebGLRenderTarget(fw, fh, { type: this.floatType, minFilter: THREE.NearestFilter,
                                                        magFilter: THREE.NearestFilter, depthBuffer: true });
    const scene = new THREE.WebGLRenderTarget(w, h, { type: THREE.HalfFloatType, minFilter: THREE.LinearFilter,
                                                      magFilter: THREE.LinearFilter, depthBuffer: true });
    scene.depthTexture = new THREE.DepthTexture(w, h);
    this.targets = { scene, depth, blurA: fluid(this.floatType, THREE.NearestFilter),
                     blurB: fluid(this.floatType, THREE.NearestFilter), thick: fluid(THREE.HalfFloatType, THREE.LinearFilter) };
  }

  // In a headset, three draws each eye into the viewport the XR layer gives it, in output pixels: the liquid's
  // targets may be smaller (scale < 1), so their passes draw with the viewports scaled.
  scaleEyeViewports(on) {
    if (!this.renderer.xr.isPresenting || this.scale === 1) return;
    const cams = this.renderer.xr.getCamera().cameras;
    for (let i = 0; i < cams.length && i < 2; ++i) {
      if (on) {
        this.savedViewports[i].copy(cams[i].viewport);
        cams[i].viewport.multiplyScalar(this.scale).round();
      } else cams[i].viewport.copy(this.savedViewports[i]);
    }
  }

  /**
   * Draws `scene` (the particles already hidden in it) with the liquid into whatever target is current (the canvas,
   * or the XR layer). `world` is the group the particles' positions are relative to; `eyeHeight` the pixels of one
   * viewport of the output (an eye's in XR), `transparent` for AR passthrough.
   */
  render(scene, camera, world, eyeHeight, transparent = false) {
    const r = this.renderer;
    const out = r.getRenderTarget();
    let w, h;
    if (out) w = out.width, h = out.height;
    else {
      r.getDrawingBufferSize(this.size0 ?? (this.size0 = new THREE.Vector2()));
      w = this.size0.x, h = this.size0.y;
    }
    this.ensureTargets(w, h);
    const t = this.targets;
    world.updateMatrixWorld();
    this.root.matrix.copy(world.matrixWorld);
    this.root.matrixWorldNeedsUpdate = true;
    r.getClearColor(this.clearColour);
    const clearAlpha = r.getClearAlpha();

    // 1. the scene behind
    r.setRenderTarget(t.scene);
    r.render(scene, camera);

    this.scaleEyeViewports(true);
    const fluidEye = eyeHeight * this.scale;
    this.splatUniforms.uViewportHeight.value = fluidEye;
    r.setClearColor(0x000000, 0);
    // 2. depth of the nearest sphere surface
    this.points.material = this.depthMaterial;
    r.setRenderTarget(t.depth);
    r.render(this.fluidScene, camera);
    // 3. thickness
    this.points.material = this.thickMaterial;
    r.setRenderTarget(t.thick);
    r.render(this.fluidScene, camera);
    // 4. smoothing: (horizontal, vertical) twice
    const b = this.blurUniforms;
    b.uTexel.value.set(1 / this.fluidSize.x, 1 / this.fluidSize.y);
    b.uViewportHeight.value = fluidEye;
    let src = t.depth;
    for (let pass = 0; pass < 4; ++pass) {
      const dst = pass % 2 === 0 ? t.blurA : t.blurB;
      b.tInput.value = src.texture;
      b.uDir.value.set(pass % 2 === 0 ? 1 : 0, pass % 2 === 0 ? 0 : 1);
      r.setRenderTarget(dst);
      r.render(this.blurScene, camera);
      src = dst;
    }
    this.smoothed = src;
    this.scaleEyeViewports(false);
    r.setClearColor(this.clearColour, clearAlpha);

    // 5. the scene straight into the output (exactly as without the liquid where there is none), then the liquid over it
    r.setRenderTarget(out);
    r.render(scene, camera);
    const c = this.compositeUniforms;
    c.tDepth.value = src.texture;
    c.tThick.value = t.thick.texture;
    c.tScene.value = t.scene.texture;
    c.tSceneDepth.value = t.scene.depthTexture;
    c.uOutSize.value.set(w, h);
    c.uFluidTexel.value.set(1 / this.fluidSize.x, 1 / this.fluidSize.y);
    c.uTransparentBackground.value = transparent ? 1 : 0;
    const autoClear = r.autoClear;
    r.autoClear = false;
    r.render(this.compositeScene, camera);
    r.autoClear = autoClear;
    this.stats.frames += 1;
  }

  /**
   * For the browser test: how many pixels of the smoothed depth hold liquid in each of the given viewports (output
   * pixels, e.g. both eyes' in XR). Reads the target back: slow, not for the render loop.
   */
  coverage(viewports) {
    if (!this.smoothed) return viewports.map(() => 0);
    const { x: fw, y: fh } = this.fluidSize;
    const buf = new Float32Array(4 * fw * fh);
    this.renderer.readRenderTargetPixels(this.smoothed, 0, 0, fw, fh, buf);
    return viewports.map(([x, y, w, h]) => {
      let n = 0;
      const x0 = Math.round(x * this.scale), y0 = Math.round(y * this.scale);
      const x1 = Math.min(fw, Math.round((x + w) * this.scale)), y1 = Math.min(fh, Math.round((y + h) * this.scale));
      for (let j = y0; j < y1; ++j) for (let i = x0; i < x1; ++i) if (buf[4 * (j * fw + i)] > 0) n += 1;
      return n;
    });
  }
}
