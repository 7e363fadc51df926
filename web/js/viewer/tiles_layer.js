// One map as level-of-detail tiles (tiles_<map>.tar, docs/artifacts.md "Level-of-detail
// tiles"), drawn by 3d-tiles-renderer: tileset.json first, then only the tiles the camera
// needs, the coarsest first, each served on its own by GET /v1/artifacts/{id}/files/{path}.
// The first picture is the root tile (a few tens of thousands of points), and no task is
// bigger than parsing one tile (at most 100,000 points), so a map of any size opens fast
// and never blocks the page. Points are coloured through the same shader as the Draco maps,
// by height or by a batch-table attribute (intensity, sensor, density, roughness, planarity).
import * as THREE from 'three';
import {TilesRenderer} from '3d-tiles-renderer/three';
import {attributeLegend, heightLegend, rampEnds} from './attribute_legend.js';
import {NO_NO_DATA, noDataBelow, pointMaterial, rampTexture} from './materials.js';

// Target screen-space error in pixels: a tile is refined while its points would be more
// than this far apart on screen (its geometricError is its point spacing in metres), so
// points of the default size (2 px) cover the surfaces they sample.
export const ERROR_TARGET_PX = 2;
// Bytes of a loaded point as the renderer's cache counts them (float positions), for the
// point budget.
const BYTES_PER_POINT = 12;

// The tileset extras' attribute ranges and sensor names (extras.keel) as a legend needs them.
export function tilesetInfo(tileset) {
  const keel = tileset?.extras?.keel;
  if (!keel || typeof keel !== 'object') return {points: NaN, attributes: {}, sensors: []};
  return {points: Number(keel.points), attributes: keel.attributes || {}, sensors: keel.sensors || []};
}

export class TilesLayer {
  // source: {name, artifact (tiles_<map>.tar), token, url (of tileset.json)}; scene: Scene3d;
  // onChange(layer, event): event 'tileset' (extent and attributes known), 'first-tile'
  // (something to draw), 'settled' (the first view's tiles have loaded), 'error', or none.
  constructor(source, {scene, budget, onChange}) {
    this.name = source.name;
    this.source = source;
    this.scene = scene;
    this.budget = budget;
    this.onChange = onChange;
    this.object3d = new THREE.Group();
    this.object3d.name = source.name;
    this.isTiles = true;
    this.material = pointMaterial({worldHeight: true});
    this.material.name = 'tiles points';
    this.warmed = null;  // the shader compiled and drawn once, while the tileset loads
    this.status = 'idle';
    this.message = '';
    this.level = 'tiles';
    this.info = {points: NaN, attributes: {}, sensors: []};
    this.decodedPoints = 0;  // points of the whole map (tileset extras)
    this.drawnPoints = 0;    // points of the tiles on screen
    this.colorMode = 'height';
    this.tiles = null;
    this.cube = null;    // the root tile's cube, until points arrive
    this.bounds = null;  // the extent of the points loaded (the first tile spans the map)
    this.firstTile = false;
    this.settling = false;  // loading the first view's tiles
    this.tilesShown = 0;
  }

  modes() {
    return ['height', ...Object.keys(this.info.attributes).filter((m) => m !== 'height')];
  }

  hasPreview() {
    return false;
  }

  load() {
    if (this.tiles) return;
    this.status = 'loading';
    this.warmed = this.scene.warmUp(this.material);
    this.settling = true;
    this.message = 'reading tileset.json';
    this.onChange?.(this);
    const tiles = new TilesRenderer(this.source.url);
    this.tiles = tiles;
    tiles.fetchOptions = {headers: {Authorization: `Bearer ${this.source.token}`}};
    tiles.errorTarget = ERROR_TARGET_PX;
    this.setBudget(this.budget);
    tiles.setCamera(this.scene.camera);
    tiles.setResolutionFromRenderer(this.scene.camera, this.scene.renderer);
    // Not drawn before its shader is compiled (drawing would wait for the compile).
    tiles.group.visible = false;
    this.warmed.then(() => {
      tiles.group.visible = true;
      this.scene.requestRender();
    });
    this.object3d.add(tiles.group);
    tiles.addEventListener('load-tileset', ({tileset}) => {
      if (tileset !== tiles.rootTileset) return;
      performance.mark(`keel:${this.name}:tileset`);
      this.info = tilesetInfo(tileset);
      this.decodedPoints = this.info.points || 0;
      this.cube = new THREE.Box3();
      if (!tiles.getBoundingBox(this.cube)) this.cube = null;
      this.message = 'loading the coarsest tiles';
      this.applyColor();
      this.onChange?.(this, 'tileset');
    });
    tiles.addEventListener('load-model', ({scene}) => this.prepareTile(scene));
    tiles.addEventListener('needs-update', () => this.scene.requestRender());
    // The next update may queue finer tiles: settled once an update queues none.
    tiles.addEventListener('tiles-load-end', () => this.scene.requestRender());
    tiles.addEventListener('load-error', ({error, url}) => {
      const what = String(url || '').replace(/^.*\/files\//, '');
      const why = error?.message || String(error);
      if (!this.firstTile) {
        this.status = 'error';
        this.settling = false;
        this.message = `${this.source.artifact.name}: ${what || 'tileset.json'} could not be loaded (${why})`;
        this.onChange?.(this, 'error');
      } else {
        console.warn(`${this.name}: ${what}: ${why}`);
      }
    });
    this.scene.beforeRender.add(this.update);
    this.scene.requestRender();
  }

  // Called by the scene before each frame: tiles chosen for the camera, loads queued.
  update = () => {
    if (!this.tiles || !this.object3d.visible) return;
    this.scene.camera.updateMatrixWorld();
    this.tiles.setResolutionFromRenderer(this.scene.camera, this.scene.renderer);
    this.tiles.update();
    const before = this.drawnPoints;
    this.countDrawn();
    if (this.settling && this.status === 'shown' && !this.tiles.isLoading) {
      this.settling = false;
      performance.mark(`keel:${this.name}:settled`);
      queueMicrotask(() => this.onChange?.(this, 'settled'));
    } else if (this.drawnPoints !== before) {
      queueMicrotask(() => this.onChange?.(this));  // the counts shown
    }
  };

  // A tile's Points as loaded by PNTSLoader: our material, and its batch-table attributes
  // as float vertex attributes the shader can colour by.
  prepareTile(points) {
    points.traverse((object) => {
      if (!object.isPoints) return;
      object.material.dispose();
      object.material = this.material;
      const geometry = object.geometry;
      geometry.computeBoundingBox();
      const box = geometry.boundingBox.clone().translate(object.position);  // PNTSLoader's offset
      this.bounds = this.bounds ? this.bounds.union(box) : box;
      if (this.colorMode === 'height') this.applyRange();
      const table = object.batchTable;
      for (const name of Object.keys(this.info.attributes)) {
        const values = table?.getPropertyArray?.(name);
        if (!values || geometry.getAttribute(name)) continue;
        geometry.setAttribute(name, new THREE.BufferAttribute(values instanceof Float32Array ? values : Float32Array.from(values), 1));
      }
      this.setValueAttribute(geometry);
    });
    if (!this.firstTile) {
      performance.mark(`keel:${this.name}:first-tile`);
      this.firstTile = true;
      this.warmed.then(() => {
        this.status = 'shown';
        this.message = '';
        this.countDrawn();
        this.onChange?.(this, 'first-tile');
      });
    }
    this.scene.requestRender();
  }

  // At most `budget` points loaded (the renderer's cache evicts tiles out of view first and
  // refuses finer tiles beyond it: their coarser parents stay on screen).
  setBudget(budget) {
    this.budget = budget;
    if (!this.tiles) return;
    this.tiles.lruCache.minBytesSize = 0.75 * budget * BYTES_PER_POINT;
    this.tiles.lruCache.maxBytesSize = budget * BYTES_PER_POINT;
  }

  countDrawn() {
    let drawn = 0;
    let shown = 0;
    for (const tile of this.tiles?.visibleTiles || []) {
      const scene = tile.engineData?.scene;
      if (!scene) continue;
      shown += 1;
      scene.traverse((o) => { if (o.isPoints) drawn += o.geometry.getAttribute('position').count; });
    }
    this.drawnPoints = drawn;
    this.tilesShown = shown;
  }

  setValueAttribute(geometry) {
    if (this.colorMode === 'height' || !geometry.getAttribute(this.colorMode)) geometry.deleteAttribute('value');
    else geometry.setAttribute('value', geometry.getAttribute(this.colorMode));
  }

  setInteracting() {}

  boundingBox() {
    return this.bounds || this.cube;
  }

  // The legend: the attribute's min/max over the whole map from the tileset's extras;
  // height = the z extent of the points loaded so far (the first tile's is the map's within
  // its point spacing).
  legend() {
    if (this.colorMode === 'height') return heightLegend(this.name, this.boundingBox());
    return attributeLegend(this.name, this.colorMode, this.info.attributes[this.colorMode], {labels: this.info.sensors});
  }

  setColorMode(mode) {
    if (!this.modes().includes(mode)) return false;
    this.colorMode = mode;
    this.applyColor();
    return true;
  }

  applyColor() {
    const uniforms = this.material.uniforms;
    const {ramp, categories} = this.applyRange();
    uniforms.useHeight.value = this.colorMode === 'height' ? 1 : 0;
    uniforms.ramp.value.dispose();
    uniforms.ramp.value = rampTexture(ramp, categories);
    this.tiles?.forEachLoadedModel((scene) => scene.traverse((o) => { if (o.isPoints) this.setValueAttribute(o.geometry); }));
  }

  // The colour ramp's ends from the legend (the height range grows as tiles load); returns
  // the ramp and its number of categories (0 for a continuous ramp).
  applyRange() {
    const uniforms = this.material.uniforms;
    const legend = this.legend();
    const {vmin, vmax, categories} = rampEnds(legend);
    uniforms.vmin.value = vmin;
    uniforms.vmax.value = vmax;
    uniforms.noDataBelow.value = this.colorMode === 'height' ? NO_NO_DATA : noDataBelow(legend);
    return {ramp: legend.ramp, categories};
  }

  setPointSize(size) {
    this.material.uniforms.pointSize.value = size;
  }

  dispose() {
    this.scene.beforeRender.delete(this.update);
    this.tiles?.dispose();
    this.tiles = null;
    this.material.dispose();
  }
}
