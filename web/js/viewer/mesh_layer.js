// A Draco mesh of a job coloured by a signed per-vertex attribute in metres, vertices under
// the threshold grey: the remeshed hull (mesh_remeshed.drc, `deviation` from the CAD model) or
// a compare job's change hull (change_hull.drc, `deviation_change`, `deviation_a`,
// `deviation_b`); or the CAD model itself (cad_model.drc), flat and translucent, for
// point-to-CAD measurement.
import * as THREE from 'three';
import {attributeLegend, rampEnds} from './attribute_legend.js';
import {decodeDraco} from './draco.js';
import {meshMaterial, rampTexture} from './materials.js';

export class MeshLayer {
  // source: {name, sidecar, artifact, fetchBytes}; kind: 'deviation' | 'cad'
  // attribute: what colours a 'deviation' mesh (one its sidecar lists).
  // transform: a THREE.Matrix4 placing the mesh in the scene (model -> world), or null.
  constructor(source, {kind, onChange, transform = null, attribute = 'deviation'}) {
    this.name = source.name;
    this.source = source;
    this.sidecar = source.sidecar;
    this.kind = kind;
    this.attribute = attribute;
    this.onChange = onChange;
    this.object3d = new THREE.Group();
    this.object3d.name = source.name;
    this.transform = transform;
    if (transform) {
      this.object3d.matrixAutoUpdate = false;
      this.object3d.matrix.copy(transform);
    }
    this.material = meshMaterial(kind === 'cad' ? {flat: true, opacity: 0.35} : {});
    this.mesh = null;
    this.status = 'idle';
    this.message = '';
    this.progress = 0;
    this.vertices = 0;
    this.faces = 0;
    this.threshold = 0;
  }

  async load() {
    const artifact = this.source.artifact;
    this.status = 'loading';
    this.message = `downloading ${artifact.name}`;
    this.onChange?.(this);
    try {
      const bytes = await this.source.fetchBytes(artifact, (got, total) => {
        this.progress = total ? got / total : 0;
        this.onChange?.(this);
      });
      const geometry = await decodeDraco(bytes, this.sidecar, artifact.name);
      if (!geometry.index) throw new Error(`${artifact.name} is a point cloud, not a mesh`);
      if (this.kind === 'deviation' && !geometry.getAttribute(this.attribute))
        throw new Error(`${artifact.name} has no ${this.attribute} attribute (its sidecar lists none)`);
      geometry.computeVertexNormals();
      this.vertices = geometry.getAttribute('position').count;
      this.faces = geometry.index.count / 3;
      if (this.kind === 'deviation') geometry.setAttribute('value', geometry.getAttribute(this.attribute));
      this.mesh = new THREE.Mesh(geometry, this.material);
      this.object3d.add(this.mesh);
      this.applyRange();
      this.status = 'shown';
      this.message = '';
    } catch (e) {
      this.status = 'error';
      this.message = e.message || String(e);
    }
    this.onChange?.(this);
  }

  // The attributes that can colour this mesh: those of its sidecar.
  attributes() {
    return this.kind === 'deviation' ? Object.keys(this.sidecar?.attributes || {}) : [];
  }

  range() {
    const info = this.sidecar?.attributes?.[this.attribute];
    if (info && Number.isFinite(info.min) && Number.isFinite(info.max)) return {min: info.min, max: info.max};
    return {min: NaN, max: NaN};
  }

  deviations() {
    return this.mesh?.geometry.getAttribute(this.attribute)?.array || new Float32Array(0);
  }

  applyRange() {
    if (this.kind !== 'deviation') return;
    const legend = this.legend();
    const {vmin, vmax} = rampEnds(legend);
    const uniforms = this.material.uniforms;
    uniforms.vmin.value = vmin;
    uniforms.vmax.value = vmax;
    uniforms.threshold.value = this.threshold > 0 ? this.threshold : -1;
    if (this.rampName !== legend.ramp) {
      uniforms.ramp.value.dispose();
      uniforms.ramp.value = rampTexture(legend.ramp);
      this.rampName = legend.ramp;
    }
  }

  // Colours the mesh by another of its attributes.
  setAttribute(name) {
    if (!this.attributes().includes(name)) return false;
    this.attribute = name;
    if (this.mesh) this.mesh.geometry.setAttribute('value', this.mesh.geometry.getAttribute(name));
    this.applyRange();
    return true;
  }

  // Vertices whose |value| is below `metres` are drawn grey (on the CAD model).
  setThreshold(metres) {
    this.threshold = metres;
    this.applyRange();
  }

  legend() {
    if (this.kind !== 'deviation') return null;
    return attributeLegend(this.name, this.attribute, {...this.range()});
  }

  boundingBox() {
    const s = this.sidecar;
    let box = null;
    if (s?.bbox_min && s?.bbox_max) box = new THREE.Box3(new THREE.Vector3(...s.bbox_min), new THREE.Vector3(...s.bbox_max));
    else if (this.mesh) {
      this.mesh.geometry.computeBoundingBox();
      box = this.mesh.geometry.boundingBox.clone();
    }
    return box && this.transform ? box.applyMatrix4(this.transform) : box;
  }

  // The closest point of this mesh's surface to a scene point: {point, distance}.
  closestPoint(scenePoint) {
    if (!this.transform) return this.closestPointLocal(scenePoint);
    const local = scenePoint.clone().applyMatrix4(this.transform.clone().invert());
    const best = this.closestPointLocal(local);
    best.point.applyMatrix4(this.transform);
    return best;
  }

  // The closest point of this mesh's surface to `point` in its own frame (brute force over
  // the triangles): {point, distance}.
  closestPointLocal(point) {
    const geometry = this.mesh.geometry;
    const position = geometry.getAttribute('position');
    const index = geometry.index.array;
    const triangle = new THREE.Triangle();
    const candidate = new THREE.Vector3();
    const best = {point: new THREE.Vector3(), distance: Infinity};
    for (let i = 0; i < index.length; i += 3) {
      triangle.a.fromBufferAttribute(position, index[i]);
      triangle.b.fromBufferAttribute(position, index[i + 1]);
      triangle.c.fromBufferAttribute(position, index[i + 2]);
      triangle.closestPointToPoint(point, candidate);
      const d = candidate.distanceToSquared(point);
      if (d < best.distance) {
        best.distance = d;
        best.point.copy(candidate);
      }
    }
    best.distance = Math.sqrt(best.distance);
    return best;
  }

  dispose() {
    if (this.mesh) this.mesh.geometry.dispose();
    this.material.dispose();
  }
}
