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
    const t0 = performance.now();
    this.renderer = new THREE.WebGLRenderer({canvas, antialias: false, powerPreference: 'high-performance'});
    performance.measure('keel:webgl-context', {start: t0});
    // three asks the GPU process whether each new program linked, several round trips that
    // each wait for it (a second under software WebGL on a busy machine); warmUp asks once,
    // early, for the maps' shaders.
    this.renderer.debug.checkShaderErrors = false;
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
    this.beforeRender = new Set();  // per-frame updates of layers that stream (3D tiles)
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
    const t0 = performance.now();
    for (const fn of this.beforeRender) fn();
    const t1 = performance.now();
    this.renderer.render(this.scene, this.camera);
    // Slow frames are named in the page's timeline (the benchmark prints them).
    const t2 = performance.now();
    if (t2 - t0 > 50) performance.measure(`keel:frame ${this.frameCount} (update ${(t1 - t0).toFixed(0)} ms)`, {start: t0, end: t2});
    this.frameCount += 1;
    const callbacks = this.afterRender;
    this.afterRender = [];
    for (const fn of callbacks) fn();
  }

  // Compiles a material's shaders early, while the data downloads, then draws a point with
  // it (at the camera, so clipped: nothing shows) in a task of its own: what a first draw waits for the GPU process
  // for (the program's link, the extensions three asks for when it first uploads a texture)
  // is waited for there, not in the first frame that shows a map. Software WebGL here has no
  // KHR_parallel_shader_compile, and each such wait can take a second on a busy machine.
  // Resolves when the material can be drawn without those waits; a shader that does not link
  // is a console error (three's own checks are off, above).
  warmUp(material) {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.Float32BufferAttribute([0, 0, 0], 3));
    const probe = new THREE.Points(geometry, material);
    const t0 = performance.now();
    this.renderer.compile(probe, this.camera, this.scene);
    const gl = this.renderer.getContext();
    gl.flush();  // to the GPU process now, not with the next frame
    return new Promise((resolve) => setTimeout(resolve, 50)).then(() => {
      const t1 = performance.now();
      // Drawn to the canvas, not a render target: three's program depends on the target's
      // colour space, and the maps' program is the one to link.
      const scene = new THREE.Scene();
      probe.frustumCulled = false;
      probe.position.copy(this.camera.position);
      scene.add(probe);
      this.renderer.render(scene, this.camera);
      this.requestRender();  // the page's own picture again
      performance.measure(`keel:first draw ${material.name || material.type}`, {start: t1});
      const program = this.renderer.properties.get(material).currentProgram;
      if (program) {
        if (!gl.getProgramParameter(program.program, gl.LINK_STATUS))
          console.error(`${material.name || material.type}: shader program not linked: ${gl.getProgramInfoLog(program.program)}`);
      }
      performance.measure(`keel:compile ${material.name || material.type}`, {start: t0});
      geometry.dispose();
    });
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
