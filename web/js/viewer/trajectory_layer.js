// The trajectories of trajectories.json (docs/artifacts.md) as lines: recorded, refined,
// ground truth, ... each in its own colour; the refined one coloured by its per-pose ATE
// error (`ate_m`) when the mission had ground truth.
import * as THREE from 'three';
import {CATEGORICAL, finiteRange, rampColor} from './colormap.js';

const FIXED = {recorded: [242, 142, 43], ground_truth: [255, 255, 255], refined: [78, 121, 167],
               refined_no_dvl: [176, 122, 161], ba: [89, 161, 79]};

export function validateTrajectories(doc, fileName) {
  if (!doc || !Array.isArray(doc.trajectories)) throw new Error(`${fileName}: no "trajectories" list`);
  doc.trajectories.forEach((t, i) => {
    const where = `${fileName}: trajectories[${i}]`;
    if (typeof t.name !== 'string') throw new Error(`${where}: no name`);
    if (!Array.isArray(t.xyz)) throw new Error(`${where} (${t.name}): no xyz list`);
    if (t.xyz.some((p) => !Array.isArray(p) || p.length !== 3 || !p.every(Number.isFinite)))
      throw new Error(`${where} (${t.name}): xyz must be [x, y, z] numbers`);
    if (t.ate_m && t.ate_m.length !== t.xyz.length)
      throw new Error(`${where} (${t.name}): ate_m has ${t.ate_m.length} values for ${t.xyz.length} poses`);
  });
  return doc;
}

function srgb([r, g, b]) {
  return new THREE.Color().setRGB(r / 255, g / 255, b / 255, THREE.SRGBColorSpace);
}

export class TrajectoryLayer {
  constructor(trajectory, index) {
    this.name = trajectory.name;
    this.trajectory = trajectory;
    this.object3d = new THREE.Group();
    this.object3d.name = `trajectory ${trajectory.name}`;
    this.status = 'shown';
    this.message = '';
    this.poses = trajectory.xyz.length;
    const positions = new Float32Array(trajectory.xyz.flat());
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    this.ate = Array.isArray(trajectory.ate_m) ? trajectory.ate_m : null;
    let material;
    if (this.ate) {
      const {min, max} = finiteRange(this.ate);
      this.ateRange = {min, max};
      const colors = new Float32Array(this.poses * 3);
      const color = new THREE.Color();
      this.ate.forEach((e, i) => {
        color.copy(srgb(rampColor('viridis', (e - min) / Math.max(max - min, 1e-12))));
        colors.set([color.r, color.g, color.b], i * 3);
      });
      geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
      material = new THREE.LineBasicMaterial({vertexColors: true});
    } else {
      material = new THREE.LineBasicMaterial({color: srgb(FIXED[this.name] || CATEGORICAL[index % CATEGORICAL.length])});
    }
    this.line = new THREE.Line(geometry, material);
    this.line.frustumCulled = false;
    this.object3d.add(this.line);
  }

  swatch() {
    return this.ate ? null : `#${this.line.material.color.getHexString(THREE.SRGBColorSpace)}`;
  }

  legend() {
    if (!this.ate) return null;
    return {title: `${this.name}: ATE error (m)`, min: this.ateRange.min, max: this.ateRange.max, ramp: 'viridis', mode: 'ate'};
  }

  boundingBox() {
    this.line.geometry.computeBoundingBox();
    return this.line.geometry.boundingBox;
  }

  dispose() {
    this.line.geometry.dispose();
    this.line.material.dispose();
  }
}
