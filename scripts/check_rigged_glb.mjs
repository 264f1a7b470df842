// Checks a rigged GLB (io/write_rigged_glb.h, `rigged.glb`) the way its users open it: the Khronos glTF validator
// (npm gltf-validator) and three.js's GLTFLoader, headless in node. Plays one clip with an AnimationMixer and, at
// each given time, skins every vertex on the CPU (SkinnedMesh.applyBoneTransform, then the mesh's world matrix) and
// reports the bounds. Prints one JSON line:
//   {"errors", "warnings", "messages": [first issues],
//    "three": {"skinned_meshes", "bones", "vertices", "clips": [{"name", "duration", "tracks"}],
//              "clip": the played clip's name, "poses": [{"t", "min": [x, y, z], "max": [x, y, z]}]}}
// and exits non-zero when three.js cannot load it. usage:
//   node scripts/check_rigged_glb.mjs FILE.glb [--clip NAME|INDEX] [--times T1,T2,...]
import { validate_glb } from './glb_report.mjs';
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

const args = process.argv.slice(2);
const file = args[0];
if (!file) {
  console.error('usage: node scripts/check_rigged_glb.mjs FILE.glb [--clip NAME|INDEX] [--times T1,T2,...]');
  process.exit(2);
}
const opt = (name) => {
  const i = args.indexOf(name);
  return i > 0 ? args[i + 1] : undefined;
};
const times = (opt('--times') ?? '').split(',').filter((s) => s.length).map(Number);
const { out, buffer } = await validate_glb(file);
try {
  const gltf = await new GLTFLoader().parseAsync(buffer, '');
  const skinned = [];
  gltf.scene.traverse((o) => {
    if (o.isSkinnedMesh) skinned.push(o);
  });
  const three = {
    skinned_meshes: skinned.length,
    bones: skinned.length ? skinned[0].skeleton.bones.length : 0,
    vertices: skinned.length ? skinned[0].geometry.attributes.position.count : 0,
    clips: gltf.animations.map((c) => ({ name: c.name, duration: c.duration, tracks: c.tracks.length })),
    poses: [],
  };
  const wanted = opt('--clip');
  let clip = gltf.animations.find((c) => c.name === wanted);
  if (!clip && wanted !== undefined && /^\d+$/.test(wanted)) clip = gltf.animations[Number(wanted)];
  if (!clip && wanted === undefined) clip = gltf.animations[0];
  if (wanted !== undefined && !clip) throw new Error(`no clip '${wanted}'`);
  three.clip = clip ? clip.name : null;
  const mixer = new THREE.AnimationMixer(gltf.scene);
  if (clip) {
    // Once, held at the end: setTime(duration) then shows the last pose rather than wrapping to the first.
    const action = mixer.clipAction(clip);
    action.setLoop(THREE.LoopOnce, 1);
    action.clampWhenFinished = true;
    action.play();
  }
  const mesh = skinned[0];
  for (const t of times) {
    mixer.setTime(t);
    gltf.scene.updateMatrixWorld(true);
    if (!mesh) continue;
    mesh.skeleton.update();
    const pos = mesh.geometry.attributes.position;
    const v = new THREE.Vector3();
    const box = new THREE.Box3();
    for (let i = 0; i < pos.count; i++) {
      v.fromBufferAttribute(pos, i);
      mesh.applyBoneTransform(i, v);
      v.applyMatrix4(mesh.matrixWorld);
      box.expandByPoint(v);
    }
    three.poses.push({ t, min: box.min.toArray(), max: box.max.toArray() });
  }
  out.three = three;
} catch (e) {
  out.three = { error: String(e && e.message ? e.message : e) };
}
console.log(JSON.stringify(out));
process.exit(out.three.error ? 1 : 0);
