// The DVL range residuals of Fig. 18(a)-(b) of seed 001 (dvl_residuals.csv: state, t, hit
// point in the model frame, residual) as points on the hull, coloured blue-white-red over
// +-max |residual|: after the GICP initialisation or after the bundle adjustment.
import * as THREE from 'three';
import {rampColor} from './colormap.js';

const COLUMNS = ['state', 't', 'x_model_m', 'y_model_m', 'z_model_m', 'residual_m'];

// {gicp: [{x,y,z,r}], ba: [...]} from the CSV text; errors name the file and line.
export function parseResiduals(text, fileName) {
  const lines = text.split(/\r?\n/);
  const header = lines[0].split(',').map((s) => s.trim());
  const index = Object.fromEntries(COLUMNS.map((c) => [c, header.indexOf(c)]));
  for (const c of COLUMNS)
    if (index[c] < 0) throw new Error(`${fileName}: line 1: no column "${c}" (header: ${lines[0]})`);
  const out = {};
  for (let n = 1; n < lines.length; n += 1) {
    if (!lines[n].trim()) continue;
    const f = lines[n].split(',');
    const row = {x: Number(f[index.x_model_m]), y: Number(f[index.y_model_m]),
                 z: Number(f[index.z_model_m]), r: Number(f[index.residual_m])};
    if (![row.x, row.y, row.z, row.r].every(Number.isFinite))
      throw new Error(`${fileName}: line ${n + 1}: expected numbers, got "${lines[n]}"`);
    const state = f[index.state].trim();
    (out[state] ||= []).push(row);
  }
  return out;
}

export class ResidualLayer {
  constructor(residuals, {transform} = {}) {
    this.name = 'dvl residuals';
    this.residuals = residuals;
    this.states = Object.keys(residuals);
    this.object3d = new THREE.Group();
    this.object3d.name = 'dvl residuals';
    this.status = 'shown';
    this.message = '';
    this.transform = transform || null;  // model -> world (THREE.Matrix4), when known
    const all = Object.values(residuals).flat();
    this.maxAbs = all.reduce((m, row) => Math.max(m, Math.abs(row.r)), 0) || 1;
    this.material = new THREE.PointsMaterial({size: 6, sizeAttenuation: false, vertexColors: true});
    this.points = null;
    this.state = residuals.ba ? 'ba' : this.states[0];
    this.build();
  }

  setState(state) {
    if (!this.residuals[state]) return;
    this.state = state;
    this.build();
  }

  build() {
    if (this.points) {
      this.object3d.remove(this.points);
      this.points.geometry.dispose();
    }
    const rows = this.residuals[this.state] || [];
    const positions = new Float32Array(rows.length * 3);
    const colors = new Float32Array(rows.length * 3);
    const v = new THREE.Vector3();
    const color = new THREE.Color();
    rows.forEach((row, i) => {
      v.set(row.x, row.y, row.z);
      if (this.transform) v.applyMatrix4(this.transform);
      positions.set([v.x, v.y, v.z], i * 3);
      const [r, g, b] = rampColor('diverging', 0.5 + row.r / (2 * this.maxAbs));
      color.setRGB(r / 255, g / 255, b / 255, THREE.SRGBColorSpace);
      colors.set([color.r, color.g, color.b], i * 3);
    });
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
    this.points = new THREE.Points(geometry, this.material);
    this.points.frustumCulled = false;
    this.object3d.add(this.points);
    this.count = rows.length;
  }

  legend() {
    return {title: `DVL range residual after ${this.state === 'ba' ? 'BA' : 'GICP'} (m)`,
            min: -this.maxAbs, max: this.maxAbs, ramp: 'diverging', mode: 'residual'};
  }

  boundingBox() {
    this.points.geometry.computeBoundingBox();
    return this.points.geometry.boundingBox;
  }

  dispose() {
    this.points?.geometry.dispose();
    this.material.dispose();
  }
}
