// The 3D scene: one WebGL renderer, a z-up perspective camera with orbit controls, and
// rendering on demand (a frame only when something changed), which keeps software WebGL
// responsive. Layers (maps, hull, trajectories, shapes, residuals; later 3D tiles) are
// objects with `object3d` added here; the scene knows nothing about what they draw.
import * as THREE from 'three';
import {OrbitControls} from 'three/addons/controls/OrbitControls.js';
import {decodeCamera, encodeCamera} from './camera_url.js';

export class Scene3d {
  constructor(canvas, {onCameraChange, onInteraction} = {}) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({canvas, antialias: false, powerPreference: 'high-performance'});
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    this.renderer.setClearColor(0x1b2330);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(55, 1, 0.05, 20000);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(30, -30, 30);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.enableDamping = false;
    this.controls.screenSpacePanning = true;
    this.frameCount = 0;
    this.afterRender = [];
    this.pending = false;
    this.flight = null;
    this.onCameraChange = onCameraChange;
    this.controls.addEventListener('change', () => this.requestRender());
    this.controls.addEventListener('start', () => onInteraction?.(true));
    this.controls.addEventListener('end', () => {
      onInteraction?.(false);
      this.onCameraChange?.(this.cameraText());
    });
    this.resizeObserver = new ResizeObserver(() => this.resize());
    this.resizeObserver.observe(canvas.parentElement);
    this.resize();
  }

  resize() {
    const parent = this.canvas.parentElement;
    const width = Math.max(1, parent.clientWidth);
    const height = Math.max(1, parent.clientHeight);
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  add(object) {
    this.scene.add(object);
    this.requestRender();
  }

  remove(object) {
    this.scene.remove(object);
    this.requestRender();
  }

  // Renders in the next animation frame; `then` runs after that frame was drawn.
  requestRender(then) {
    if (then) this.afterRender.push(then);
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => this.renderNow());
  }

  renderNow() {
    this.pending = false;
    if (this.flight) this.stepFlight();
    this.renderer.render(this.scene, this.camera);
    this.frameCount += 1;
    const callbacks = this.afterRender;
    this.afterRender = [];
    for (const fn of callbacks) fn();
  }

  cameraText() {
    return encodeCamera(this.camera.position, this.controls.target);
  }

  // Applies a camera from the URL; false when the text is not a camera.
  setCameraText(text) {
    const camera = decodeCamera(text);
    if (!camera) return false;
    this.camera.position.set(camera.position.x, camera.position.y, camera.position.z);
    this.controls.target.set(camera.target.x, camera.target.y, camera.target.z);
    this.fitClipping(this.camera.position.distanceTo(this.controls.target) * 4);
    this.controls.update();
    this.requestRender();
    return true;
  }

  fitClipping(size) {
    this.camera.near = Math.max(0.01, size / 5000);
    this.camera.far = Math.max(1000, size * 20);
    this.camera.updateProjectionMatrix();
  }

  // Looks at a box from above and aside, the whole box in view.
  fitBox(box) {
    const center = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3()).length() || 1;
    const direction = new THREE.Vector3(0.6, -1, 0.75).normalize();
    this.camera.position.copy(center).addScaledVector(direction, size * 0.9);
    this.controls.target.copy(center);
    this.fitClipping(size);
    this.controls.update();
    this.requestRender();
    this.onCameraChange?.(this.cameraText());
  }

  // Moves the camera to look at `center` from `distance` metres over `ms` milliseconds.
  flyTo(center, distance, ms = 600) {
    const fromTarget = this.controls.target.clone();
    const fromPosition = this.camera.position.clone();
    const direction = fromPosition.clone().sub(fromTarget).normalize();
    if (!Number.isFinite(direction.x) || direction.lengthSq() === 0) direction.set(0.6, -1, 0.75).normalize();
    const toPosition = center.clone().addScaledVector(direction, distance);
    this.flight = {start: performance.now(), ms, fromTarget, fromPosition, toTarget: center.clone(), toPosition};
    this.requestRender();
  }

  stepFlight() {
    const f = this.flight;
    const t = Math.min(1, (performance.now() - f.start) / f.ms);
    const s = t * t * (3 - 2 * t);
    this.controls.target.lerpVectors(f.fromTarget, f.toTarget, s);
    this.camera.position.lerpVectors(f.fromPosition, f.toPosition, s);
    this.controls.update();
    if (t < 1) {
      this.pending = false;
      this.requestRender();
    } else {
      this.flight = null;
      this.onCameraChange?.(this.cameraText());
    }
  }

  // The first visible object under a canvas point: {point, object} or null.
  pick(clientX, clientY, objects, pointThreshold) {
    const rect = this.canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((clientX - rect.left) / rect.width) * 2 - 1,
                                  -((clientY - rect.top) / rect.height) * 2 + 1);
    const raycaster = new THREE.Raycaster();
    raycaster.params.Points.threshold = pointThreshold;
    raycaster.setFromCamera(ndc, this.camera);
    const hits = raycaster.intersectObjects(objects.filter((o) => o.visible), false);
    return hits.length ? hits[0] : null;
  }

  dispose() {
    this.resizeObserver.disconnect();
    this.controls.dispose();
    this.renderer.dispose();
    this.renderer.forceContextLoss?.();
  }
}
