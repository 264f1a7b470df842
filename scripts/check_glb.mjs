// Checks a GLB the way its users will open it: the Khronos glTF validator (npm gltf-validator) and three.js's
// GLTFLoader (the loader of the WebXR viewer). Prints one JSON line:
//   {"errors", "warnings", "messages": [first issues], "three": {"meshes", "nodes", "clips", "duration",
//    "vertices_last", "box_last": [min, max] of the last frame's world-space positions, "colours_last": the mean of its
//    vertex colours (null: none), "vertex_colours": whether its material shows them, "texture_last": its material's
//    texture {width, height, uvs, uv_mean} (null: none),
//    "material": the last frame's material as three.js made it: type, transmission, ior, thickness, attenuation}}
// and exits non-zero when the file does not parse. Usage: node scripts/check_glb.mjs FILE.glb
import { validate_glb } from './glb_report.mjs';
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

// Node has no image decoder: an embedded texture (the liquid in its target's texture) is handed to three.js as a
// bitmap of the PNG's size with no pixels, so the loader wires the material's map as a browser would.
globalThis.self ??= globalThis;
globalThis.createImageBitmap ??= async (blob) => {
  const b = new DataView(await blob.arrayBuffer());
  const png = b.byteLength > 24 && b.getUint32(0) === 0x89504e47;
  return { width: png ? b.getUint32(16) : 1, height: png ? b.getUint32(20) : 1, close() {} };
};

const file = process.argv[2];
if (!file) {
  console.error('usage: node scripts/check_glb.mjs FILE.glb');
  process.exit(2);
}
const { out, buffer } = await validate_glb(file);
try {
  const gltf = await new GLTFLoader().parseAsync(buffer, '');
  const meshes = [];
  let nodes = 0;
  gltf.scene.traverse((o) => {
    nodes += 1;
    if (o.isMesh) meshes.push(o);
  });
  // Play the animation to just before its end (the last frame's interval): only the last frame's mesh is then
  // visible (world scale 1).
  const mixer = new THREE.AnimationMixer(gltf.scene);
  const clip = gltf.animations[0];
  if (clip) {
    mixer.clipAction(clip).play();
    mixer.setTime(clip.duration * (1 - 1e-3));
  }
  gltf.scene.updateMatrixWorld(true);
  const visible = meshes.filter((m) => Math.abs(m.matrixWorld.determinant()) > 0);
  const last = visible.length ? visible[visible.length - 1] : null;
  const box = last ? new THREE.Box3().setFromObject(last) : null;
  out.three = {
    meshes: meshes.length,
    nodes,
    clips: gltf.animations.length,
    duration: clip ? clip.duration : 0,
    visible_at_end: visible.length,
    vertices_last: last ? last.geometry.attributes.position.count : 0,
    box_last: box ? [box.min.toArray(), box.max.toArray()] : null,
    // The last frame's vertex colours as three.js reads them (COLOR_0, linear): their mean, or null without any.
    colours_last: last && last.geometry.attributes.color
      ? [0, 1, 2].map((c) => {
          const a = last.geometry.attributes.color;
          let sum = 0;
          for (let i = 0; i < a.count; i++) sum += a.getComponent(i, c);
          return sum / a.count;
        })
      : null,
    vertex_colours: last ? !!last.material.vertexColors : false,
    // The last frame's texture (the liquid in its target's texture): the image's size and the UV attribute's count.
    texture_last: last && last.material.map
      ? { width: last.material.map.image.width, height: last.material.map.image.height,
          uvs: last.geometry.attributes.uv ? last.geometry.attributes.uv.count : 0,
          // the mean UV as three.js reads it (glTF's convention: v down from the image's top row)
          uv_mean: last.geometry.attributes.uv
            ? [0, 1].map((c) => {
                const a = last.geometry.attributes.uv;
                let sum = 0;
                for (let i = 0; i < a.count; i++) sum += a.getComponent(i, c);
                return sum / a.count;
              })
            : null }
      : null,
    material: last
      ? {
          type: last.material.type,
          transmission: last.material.transmission ?? 0,
          ior: last.material.ior ?? null,
          thickness: last.material.thickness ?? 0,
          attenuation_distance: last.material.attenuationDistance ?? null,
          attenuation_color: last.material.attenuationColor ? last.material.attenuationColor.toArray() : null,
        }
      : null,
  };
} catch (e) {
  out.three = { error: String(e && e.message ? e.message : e) };
}
console.log(JSON.stringify(out));
process.exit(out.three.error ? 1 : 0);
