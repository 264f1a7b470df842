// The targets as boxes that can be grabbed: drag with the mouse (a plane facing the camera through the grab point),
// shift-drag to rotate about the vertical axis, or point an XR controller's ray at a box and hold the trigger. Each
// change goes to the server as a pose (protocol.setPose), at most every `throttleMs`, and the last one on release.
import * as THREE from 'three';
import { PALETTE } from './particles.js';
import { rotationFromDegrees } from './rotation.js';

const ZERO = [0, 0, 0];

export class TargetBoxes {
  /**
   * @param {THREE.Scene} scene
   * @param {(target: number, translate: number[], rotate: number[], scale: number) => void} sendPose
   */
  constructor(scene, sendPose, throttleMs = 50) {
    this.scene = scene;
    this.sendPose = sendPose;
    this.throttleMs = throttleMs;
    this.targets = [];  // {group, pick, pivot: Vector3, pose: {translate, rotate, scale}}
    this.raycaster = new THREE.Raycaster();
    this.drag = null;
    this.lastSent = 0;
    this.tmp = new THREE.Vector3();
    this.tmpMatrix = new THREE.Matrix4();
    this.movePose = { translate: [0, 0, 0], rotate: [0, 0, 0], scale: 1 };
  }

  /** From the server's hello: every target's pivot, rest box and pose. */
  set(list) {
    for (const t of this.targets) this.scene.remove(t.group);
    this.targets = [];
    list.forEach((t, i) => {
      const min = new THREE.Vector3(...t.box.min), max = new THREE.Vector3(...t.box.max);
      const size = max.clone().sub(min);
      const centre = min.clone().add(max).multiplyScalar(0.5);
      const pivot = new THREE.Vector3(...t.pivot);
      const geo = new THREE.BoxGeometry(size.x, size.y, size.z);
      geo.translate(centre.x - pivot.x, centre.y - pivot.y, centre.z - pivot.z);
      const colour = PALETTE[i % PALETTE.length];
      const pick = new THREE.Mesh(geo, new THREE.MeshBasicMaterial({ color: colour, transparent: true, opacity: 0.06,
                                                                      depthWrite: false }));
      const edges = new THREE.LineSegments(new THREE.EdgesGeometry(geo), new THREE.LineBasicMaterial({ color: colour }));
      const group = new THREE.Group();
      group.add(pick, edges);
      this.scene.add(group);
      const entry = { group, pick, pivot, pose: { translate: [0, 0, 0], rotate: [0, 0, 0], scale: 1 } };
      this.targets.push(entry);
      this.applyPose(i, t.pose);
    });
  }

  /** A pose from the server (or set locally while dragging); copied into the box's own arrays. */
  applyPose(i, pose) {
    const t = this.targets[i];
    if (!t || !pose) return;
    const r = pose.rotate ?? ZERO;
    for (let k = 0; k < 3; ++k) t.pose.translate[k] = pose.translate[k], t.pose.rotate[k] = r[k];
    t.pose.scale = pose.scale ?? 1;
    t.group.position.set(t.pivot.x + t.pose.translate[0], t.pivot.y + t.pose.translate[1], t.pivot.z + t.pose.translate[2]);
    // The server's rotation, from the one definition it is tested against (rotation.js).
    const m = rotationFromDegrees(t.pose.rotate);
    this.tmpMatrix.set(m[0], m[1], m[2], 0, m[3], m[4], m[5], 0, m[6], m[7], m[8], 0, 0, 0, 0, 1);
    t.group.quaternion.setFromRotationMatrix(this.tmpMatrix);
    t.group.scale.setScalar(t.pose.scale);
  }

  /** The target under a ray, or -1. */
  pick(ray) {
    this.raycaster.ray.copy(ray);
    const hits = this.raycaster.intersectObjects(this.targets.map((t) => t.pick), false);
    if (!hits.length) return { index: -1 };
    return { index: this.targets.findIndex((t) => t.pick === hits[0].object), point: hits[0].point };
  }

  /** Starts a drag of the target under `ray` on a plane with `normal`; false when nothing is under it. */
  begin(ray, normal, rotate = false) {
    const hit = this.pick(ray);
    if (hit.index < 0) return false;
    const t = this.targets[hit.index];
    // The plane is in world space (rays are); positions are in the parent's space (scaled and moved in AR).
    const local = this.scene.worldToLocal(hit.point.clone());
    this.drag = { index: hit.index, plane: new THREE.Plane().setFromNormalAndCoplanarPoint(normal, hit.point),
                  offset: t.group.position.clone().sub(local), start: local, rotate,
                  rotate0: [...t.pose.rotate], distance: ray.origin.distanceTo(hit.point) };
    t.pick.geometry.computeBoundingBox();
    this.drag.width = t.pick.geometry.boundingBox.getSize(new THREE.Vector3()).x;
    return true;
  }

  /** Moves the dragged target to follow `ray` (in place: an XR drag calls this every display frame). */
  move(ray, now = performance.now()) {
    const d = this.drag;
    if (!d) return;
    const p = this.tmp;
    if (!ray.intersectPlane(d.plane, p)) ray.at(d.distance, p);
    this.scene.worldToLocal(p);
    const t = this.targets[d.index];
    const pose = this.movePose;
    for (let k = 0; k < 3; ++k) pose.translate[k] = t.pose.translate[k], pose.rotate[k] = t.pose.rotate[k];
    pose.scale = t.pose.scale;
    if (d.rotate) {
      // Sideways motion turns the target about the vertical axis: one target width ≈ 180°.
      const width = Math.max(1e-3, d.width * t.pose.scale);
      pose.rotate[1] = d.rotate0[1] + (180 * (p.x - d.start.x)) / width;
    } else {
      const c = p.add(d.offset);
      pose.translate[0] = c.x - t.pivot.x, pose.translate[1] = c.y - t.pivot.y, pose.translate[2] = c.z - t.pivot.z;
    }
    this.applyPose(d.index, pose);
    if (now - this.lastSent >= this.throttleMs) this.flush(now);
  }

  flush(now = performance.now()) {
    const d = this.drag;
    if (!d) return;
    const t = this.targets[d.index];
    this.sendPose(d.index, t.pose.translate, t.pose.rotate, t.pose.scale);
    this.lastSent = now;
  }

  end() {
    if (!this.drag) return;
    this.flush();
    this.drag = null;
  }

  /** Where target i's centre is on screen (CSS pixels), for tests and tooltips. */
  screenPosition(i, camera, canvas) {
    const t = this.targets[i];
    if (!t) return null;
    const v = t.group.getWorldPosition(new THREE.Vector3()).project(camera);
    const r = canvas.getBoundingClientRect();
    return { x: r.left + ((v.x + 1) / 2) * r.width, y: r.top + ((1 - v.y) / 2) * r.height };
  }
}
