// One Draco point cloud of a job with its sidecar (a map, map_<sensor>.drc or
// map_combined.drc, or a compare job's change map, change_<map>.drc): the preview first when
// the map stage wrote one, the full map on demand, both kept within the point budget by even
// thinning. A coarse copy (at most COARSE_POINTS) gives the first picture fast and is drawn
// while the camera moves; the budgeted copy when it rests.
import * as THREE from 'three';
import {attributeLegend, heightLegend, rampEnds} from './attribute_legend.js';
import {decodeDraco} from './draco.js';
import {NO_NO_DATA, noDataBelow, pointMaterial, rampTexture} from './materials.js';
import {strideFor, thinGeometry} from './thinning.js';

export const COARSE_POINTS = 250000;
// The budgeted copy is drawn in pieces of at most this many points, one more piece per
// frame, so no single frame uploads millions of points to the GPU.
export const PIECE_POINTS = 400000;

// Views (no copies) of consecutive ranges of a geometry's points.
function pieces(geometry, size) {
  const count = geometry.getAttribute('position').count;
  const out = [];
  for (let start = 0; start < count; start += size) {
    const end = Math.min(count, start + size);
    const piece = new THREE.BufferGeometry();
    for (const [name, a] of Object.entries(geometry.attributes))
      piece.setAttribute(name, new THREE.BufferAttribute(a.array.subarray(start * a.itemSize, end * a.itemSize), a.itemSize));
    out.push(piece);
  }
  return out;
}

// What a map can be coloured by: height always; the rest when the sidecar lists them.
export const COLOR_MODES = ['height', 'intensity', 'sensor', 'density', 'roughness', 'planarity'];
// A change map (docs/artifacts.md, compare): the change first, the layer's first colouring.
export const CHANGE_COLOR_MODES = ['m3c2_m', 'significant', 'lod95_m', 'c2c_m', 'height'];

export class PointCloudLayer {
  // source: {name, sidecar (or null), full: artifact, preview: artifact or null,
  //          fetchBytes(artifact, onProgress) -> ArrayBuffer}
  // colorModes: the colourings it offers, in order, those its sidecar lists.
  constructor(source, {budget, onChange, colorModes = COLOR_MODES}) {
    this.name = source.name;
    this.colorModes = colorModes;
    this.source = source;
    this.sidecar = source.sidecar;
    this.budget = budget;
    this.onChange = onChange;
    this.object3d = new THREE.Group();
    this.object3d.name = source.name;
    this.material = pointMaterial();
    this.coarse = null;  // THREE.Points
    this.details = [];   // THREE.Points pieces of the budgeted copy
    this.level = '';     // 'preview' | 'full'
    this.status = 'idle';
    this.message = '';
    this.progress = 0;
    this.decodedPoints = 0;
    this.drawnPoints = 0;
    this.colorMode = 'height';
    this.decoded = null;  // the geometry as decoded, kept for tests' read-back
  }

  modes() {
    const attributes = this.sidecar?.attributes || {};
    return this.colorModes.filter((m) => m === 'height' || attributes[m]);
  }

  hasPreview() {
    return Boolean(this.source.preview);
  }

  // Loads the preview (or the map when there is none), or the full map when `full`.
  async load({full = false} = {}) {
    const artifact = full || !this.source.preview ? this.source.full : this.source.preview;
    this.level = artifact === this.source.full ? 'full' : 'preview';
    this.status = 'loading';
    this.warmed = this.warmed || this.warm?.();
    this.message = `downloading ${artifact.name}`;
    this.onChange?.(this);
    try {
      let shownAt = 0;
      const bytes = await this.source.fetchBytes(artifact, (got, total) => {
        this.progress = total ? got / total : 0;
        const now = performance.now();
        if (now - shownAt < 100) return;  // at most ten progress updates a second
        shownAt = now;
        this.onChange?.(this);
      });
      performance.mark(`keel:${this.name}:downloaded`);
      this.message = `decoding ${artifact.name}`;
      this.onChange?.(this);
      const geometry = await decodeDraco(bytes, this.sidecar, artifact.name);
      performance.mark(`keel:${this.name}:decoded`);
      await this.warmed;  // the shader compiled and drawn once (started with the download)
      await this.show(geometry);
      performance.mark(`keel:${this.name}:thinned`);
      this.status = 'shown';
      this.message = '';
    } catch (e) {
      this.status = 'error';
      this.message = e.message || String(e);
    }
    this.onChange?.(this);
  }

  async show(geometry) {
    const count = geometry.getAttribute('position')?.count || 0;
    if (count === 0) throw new Error(`${this.name}: the map has no points`);
    this.decodedPoints = count;
    this.decoded = count <= this.budget ? geometry : null;  // tests read values back
    const coarse = await thinGeometry(geometry, strideFor(count, COARSE_POINTS));
    const detail = count <= COARSE_POINTS ? null : await thinGeometry(geometry, strideFor(count, this.budget));
    this.disposeObjects();
    this.coarse = new THREE.Points(coarse, this.material);
    this.coarse.frustumCulled = false;
    this.object3d.add(this.coarse);
    this.details = (detail ? pieces(detail, PIECE_POINTS) : []).map((g) => {
      const points = new THREE.Points(g, this.material);
      points.frustumCulled = false;
      points.visible = false;
      this.object3d.add(points);
      return points;
    });
    this.revealed = 0;
    this.drawnPoints = (detail || coarse).getAttribute('position').count;
    this.applyColor();
    this.setInteracting(true);  // the coarse copy first; the caller switches after a frame
  }

  // While the camera moves (or before the first picture), draw the coarse copy only; at
  // rest the budgeted pieces revealed so far (revealMore adds one per frame).
  setInteracting(moving) {
    if (!this.coarse) return;
    const detailed = !moving && this.details.length > 0 && this.revealed === this.details.length;
    this.coarse.visible = !detailed;
    this.details.forEach((points, i) => { points.visible = !moving && i < this.revealed; });
  }

  // Shows one more piece of the budgeted copy; false when all are shown.
  revealMore() {
    if (this.revealed >= this.details.length) return false;
    this.revealed += 1;
    return true;
  }

  get detail() {
    return this.details?.length ? this.details : null;
  }

  boundingBox() {
    const s = this.sidecar;
    if (s?.bbox_min && s?.bbox_max) return new THREE.Box3(new THREE.Vector3(...s.bbox_min), new THREE.Vector3(...s.bbox_max));
    if (!this.coarse) return null;
    this.coarse.geometry.computeBoundingBox();
    return this.coarse.geometry.boundingBox;
  }

  // The legend of the current colouring: range = the attribute's min/max from the sidecar
  // (the values stored in the file), height = the map's z extent.
  legend() {
    if (this.colorMode === 'height') return heightLegend(this.name, this.boundingBox());
    const legend = attributeLegend(this.name, this.colorMode, this.sidecar.attributes[this.colorMode]);
    if (this.clips?.[this.colorMode] > 0) legend.clip = this.clips[this.colorMode];
    return legend;
  }

  // Ramp ends at ±value for a signed attribute (0 or null: the attribute's own extent).
  setClip(mode, value) {
    this.clips = {...this.clips, [mode]: value};
    if (this.colorMode === mode) this.applyColor();
  }

  setColorMode(mode) {
    if (!this.modes().includes(mode)) return false;
    this.colorMode = mode;
    this.applyColor();
    return true;
  }

  applyColor() {
    const uniforms = this.material.uniforms;
    const legend = this.legend();
    const {vmin, vmax, categories} = rampEnds(legend);
    uniforms.useHeight.value = this.colorMode === 'height' ? 1 : 0;
    uniforms.vmin.value = vmin;
    uniforms.vmax.value = vmax;
    uniforms.noDataBelow.value = this.colorMode === 'height' ? NO_NO_DATA : noDataBelow(legend);
    uniforms.ramp.value.dispose();
    uniforms.ramp.value = rampTexture(legend.ramp, categories);
    for (const points of [this.coarse, ...(this.details || [])]) {
      if (!points) continue;
      const geometry = points.geometry;
      if (this.colorMode === 'height') geometry.deleteAttribute('value');
      else geometry.setAttribute('value', geometry.getAttribute(this.colorMode));
    }
  }

  setPointSize(size) {
    this.material.uniforms.pointSize.value = size;
  }

  disposeObjects() {
    for (const points of [this.coarse, ...(this.details || [])]) {
      if (!points) continue;
      this.object3d.remove(points);
      points.geometry.dispose();
    }
    this.coarse = null;
    this.details = [];
  }

  dispose() {
    this.disposeObjects();
    this.material.dispose();
    this.decoded = null;
  }
}
