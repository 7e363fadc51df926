// The 3D viewer of one job: every Draco map (each toggled on its own; preview first, full
// map on demand, within a point budget), coloured by height, intensity, sensor, density,
// roughness or planarity with a legend; the trajectories as lines (refined coloured by its
// ATE); the remeshed hull coloured by its deviation from the CAD model, with a threshold
// slider and histogram; the shapes as boxes (a click in the table flies there); the DVL
// residuals as coloured points; a compare job's change maps and change hull
// (viewer_changes.js); point-to-point and point-to-CAD measurement; and the camera in the
// URL. An artifact that is missing or does not decode is named in a message.
//
// A big map that has level-of-detail tiles (tiles_<map>.tar) is drawn from them (TilesLayer:
// the coarsest tiles first, then those the camera needs); a small one from its Draco file.
// `?lod=tiles` or `?lod=draco` in the URL chooses for every map. Layers share one shape
// (object3d, status, message, boundingBox(), legend(), dispose()).
import * as THREE from 'three';
import {ApiError, artifactUrl, fetchArtifact, fetchArtifactJson, jobsApi, session} from '../api.js';
import {h, message} from '../dom.js';
import {formatNumber} from '../format.js';
import {jobHash, replaceQuery} from '../router.js';
import {useTiles} from '../viewer/lod_choice.js';
import {finiteRange, histogram} from '../viewer/colormap.js';
import {drawHistogram, legendBox} from '../viewer/legend.js';
import {MeshLayer} from '../viewer/mesh_layer.js';
import {pointMaterial} from '../viewer/materials.js';
import {COLOR_MODES, PointCloudLayer} from '../viewer/point_cloud_layer.js';
import {ResidualLayer, parseResiduals} from '../viewer/residual_layer.js';
import {Scene3d} from '../viewer/scene.js';
import {ShapesLayer, validateShapes} from '../viewer/shapes_layer.js';
import {TrajectoryLayer, validateTrajectories} from '../viewer/trajectory_layer.js';
import {setupChanges} from './viewer_changes.js';
import {layerRow, updateLayerUi} from './viewer_layer_rows.js';
import {setupMeasure} from './viewer_measure.js';

const DEFAULT_BUDGET = 3000000;

// Maps of an artifact list: [{name, full, preview, sidecarArtifact}] (combined first).
export function mapsOf(byName) {
  const maps = [];
  for (const name of Object.keys(byName)) {
    const match = /^map_(.+)\.drc$/.exec(name);
    if (!match || match[1].endsWith('_preview')) continue;
    const base = `map_${match[1]}`;
    maps.push({name: base, full: byName[name], preview: byName[`${base}_preview.drc`] || null,
               sidecarArtifact: byName[`${base}.json`] || null, tiles: byName[`tiles_${match[1]}.tar`] || null});
  }
  return maps.sort((a, b) => (a.name === 'map_combined' ? -1 : b.name === 'map_combined' ? 1 : a.name.localeCompare(b.name)));
}

export function mount(container, {id, query}) {
  let disposed = false;
  const layers = new Map();  // name -> layer
  const notices = h('div', {class: 'overlay', id: 'viewer-messages'});
  const legends = h('div', {class: 'legend', id: 'legend', hidden: true});
  const readout = h('div', {class: 'readout', id: 'readout', hidden: true});
  const canvas = h('canvas', {id: 'viewer-canvas'});
  const stage = h('div', {class: 'stage'}, canvas, notices, legends, readout);
  const aside = h('aside', {id: 'viewer-panel'}, h('p', null, h('a', {href: jobHash(id)}, `← job ${id}`)),
                  h('p', {class: 'muted', id: 'viewer-status'}, 'Reading the artifact list…'));
  container.append(h('div', {class: 'viewer'}, aside, stage));

  const state = {budget: Number(query.get('budget')) || DEFAULT_BUDGET, color: query.get('color') || 'height',
                 lod: query.get('lod') || 'auto',
                 firstPictureMs: null, ready: false, cameraFromUrl: false, fitted: false, measure: null,
                 measurements: [], interacting: false};
  // The artifact list is requested first: creating the WebGL context below can take a while.
  const artifactList = jobsApi.artifacts(id);
  artifactList.catch(() => {});  // handled in start()
  const scene = new Scene3d(canvas, {
    onCameraChange: (text) => saveUrl({cam: text}),
    onInteraction: (moving) => {
      state.interacting = moving;
      state.userMoved = true;
      for (const layer of layers.values()) layer.setInteracting?.(moving);
      if (!moving) scene.requestRender();
    },
  });
  state.cameraFromUrl = scene.setCameraText(query.get('cam') || '');
  // The Draco maps' shader (one program for them all), compiled and drawn once while the
  // first map downloads (Scene3d.warmUp); tiles layers warm their own the same way.
  let dracoWarm = null;
  const warmMaterials = [];
  const warmDraco = () => {
    if (!dracoWarm) {
      warmMaterials.push(pointMaterial());
      dracoWarm = scene.warmUp(warmMaterials[0]);
    }
    return dracoWarm;
  };
  const measureGroup = new THREE.Group();
  scene.add(measureGroup);

  function saveUrl(changes) {
    for (const [k, v] of Object.entries(changes)) {
      if (v === null || v === undefined || v === '') query.delete(k);
      else query.set(k, v);
    }
    replaceQuery(query);
  }

  function notice(kind, title, detail) {
    const box = message(kind, title, detail);
    box.prepend(h('button', {type: 'button', class: 'dismiss', title: 'dismiss', on: {click: () => box.remove()}}, '×'));
    notices.append(box);
  }

  const fetchBytes = (artifact, onProgress) => fetchArtifact(artifact, {onProgress});

  // ---- the panel ------------------------------------------------------------------------
  const sections = {};
  function section(key, title) {
    sections[key] = h('div', {class: 'panel-section', id: `panel-${key}`}, h('h3', null, title));
    aside.append(sections[key]);
    return sections[key];
  }

  // Redrawn only when a legend changed (tiles report every tile they load; a repaint of the
  // page costs the GPU process time that the 3D view waits for under software WebGL).
  let legendsShown = '';
  function updateLegend() {
    const shown = [];
    for (const layer of layers.values()) {
      if (!layer.object3d.visible || layer.status !== 'shown' || !layer.legend) continue;
      const legend = layer.legend();
      if (legend) shown.push([legend, layer.name]);
    }
    const key = JSON.stringify(shown);
    if (key === legendsShown) return;
    legendsShown = key;
    legends.replaceChildren(...shown.map(([legend, name]) => legendBox(legend, name)));
    legends.hidden = shown.length === 0;
  }

  function firstPicture() {
    if (state.firstPictureMs !== null) return;
    state.firstPictureMs = performance.now();
    performance.mark('keel:first-picture');
  }

  // A tiles layer reports 'tileset' (its extent and attributes are known), 'first-tile' (the
  // root tile can be drawn), 'settled' (the tiles of the first view have loaded), or nothing
  // (more tiles, a new count).
  function onTilesChange(layer, event) {
    // The view is fitted to the tileset's cube first (the tiles to load depend on the camera),
    // then to the extent of the points of the first tile (the whole map, thinned).
    if ((event === 'tileset' || event === 'first-tile') && !state.cameraFromUrl && !state.userMoved) fitView();
    if (event === 'tileset') {
      addColorModes(layer.modes());
      layer.setColorMode(state.color) || layer.setColorMode('height');
    }
    // The first picture is the first frame that drew some of the map's points.
    const drawn = () => {
      if (disposed || !layer.object3d.visible) return;
      if (layer.drawnPoints > 0) firstPicture();
      else scene.requestRender(drawn);
    };
    if (event === 'first-tile') scene.requestRender(drawn);
    if (event === 'settled' || layer.status === 'error') scene.requestRender(() => settle());
    if (layer.status === 'shown') updateLegend();  // the height range grows as tiles load
  }

  function onLayerChange(layer, event) {
    if (disposed) return;
    updateLayerUi(layer);
    if (layer.isTiles) {
      if (layer.status === 'error' && event === 'error') notice('error', `${layer.name} cannot be shown`, layer.message);
      onTilesChange(layer, event);
      return;
    }
    if (layer.status === 'error') notice('error', `${layer.name} cannot be shown`, layer.message);
    if (layer.status === 'shown') {
      // Until the user moves the camera, each layer that arrives widens the view to it.
      if (!state.cameraFromUrl && !state.userMoved) fitView();
      updateLegend();
      if (layer instanceof PointCloudLayer) {
        layer.setInteracting(true);
        scene.requestRender(() => {
          firstPicture();
          // Then the budgeted copy, one piece per frame.
          const more = () => {
            if (!layer.revealMore()) {
              layer.setInteracting(state.interacting);
              scene.requestRender(() => settle());
              return;
            }
            layer.setInteracting(state.interacting);
            scene.requestRender(more);
          };
          more();
        });
      } else {
        scene.requestRender(() => settle());
      }
      if (layer instanceof MeshLayer && layer.kind === 'deviation') setupDeviationControls(layer);
    }
    if (layer.status === 'error') settle();
  }

  function addLayer(layer, visible) {
    layers.set(layer.name, layer);
    layer.object3d.visible = visible;
    scene.add(layer.object3d);
  }

  function fitView() {
    const box = new THREE.Box3();
    for (const layer of layers.values()) {
      if (!layer.object3d.visible) continue;
      const b = layer.status !== 'shown' && !layer.sidecar?.bbox_min && !layer.isTiles ? null : layer.boundingBox?.();
      if (b && !b.isEmpty()) box.union(b);
    }
    if (box.isEmpty()) return;
    scene.fitBox(box);
  }

  // Everything shown by default has loaded (or failed): the page is ready.
  function settle() {
    const pending = [...layers.values()].some((l) => l.object3d.visible && (l.status === 'loading' || l.settling));
    if (!pending && !state.ready && state.started) {
      state.ready = true;
      document.body.dataset.viewerReady = 'true';
      performance.mark('keel:viewer-ready');
    }
    updateLegend();
  }

  // ---- maps -----------------------------------------------------------------------------
  async function setupMaps(byName) {
    const maps = mapsOf(byName);
    if (maps.length === 0) return;
    // The tiles renderer's code loads while the sidecars are read when a map's Draco file
    // already tells it is big; later, if a sidecar tells so; never for small maps.
    const loadTilesModule = () => import('../viewer/tiles_layer.js');
    let tilesModule = maps.some((map) => useTiles(map, null, {lod: state.lod, budget: state.budget})) ? loadTilesModule() : null;
    tilesModule?.catch(() => {});  // reported below
    const el = section('maps', 'Maps');
    const colorSelect = h('select', {id: 'color-by', on: {change: () => {
      state.color = colorSelect.value;
      saveUrl({color: state.color});
      for (const layer of mapLayers()) layer.setColorMode(state.color) || layer.setColorMode('height');
      updateLegend();
      scene.requestRender();
    }}});
    const budgetInput = h('input', {type: 'number', id: 'point-budget', min: 100000, step: 100000, value: state.budget,
                                    on: {change: () => {
      state.budget = Math.max(100000, Number(budgetInput.value) || DEFAULT_BUDGET);
      saveUrl({budget: state.budget === DEFAULT_BUDGET ? '' : state.budget});
      for (const layer of layers.values()) if (layer.isTiles) layer.setBudget(state.budget);
      scene.requestRender();
    }}});
    const sizeInput = h('input', {type: 'range', min: 1, max: 8, step: 1, value: 2, on: {input: () => {
      for (const layer of layers.values()) layer.setPointSize?.(Number(sizeInput.value));
      scene.requestRender();
    }}});
    el.append(h('label', null, 'Colour by ', colorSelect),
              h('label', null, 'Point budget ', budgetInput),
              h('label', null, 'Point size ', sizeInput));

    // A map's sidecar, or the warning to show when it is drawn from its Draco file (tiles
    // carry their attributes and ranges in tileset.json).
    const problems = new Map();
    const sidecars = await Promise.all(maps.map(async (map) => {
      if (!map.sidecarArtifact) {
        problems.set(map.name, [`${map.name}.json is missing`, `${map.name} is drawn by height only: its sidecar names the attributes and their ranges.`]);
        return null;
      }
      try {
        return await fetchArtifactJson(map.sidecarArtifact);
      } catch (e) {
        problems.set(map.name, [`${map.name}.json cannot be read`, `${e.message}; ${map.name} is drawn by height only.`]);
        return null;
      }
    }));
    const modes = new Set(['height']);
    addColorModes = (more) => {
      for (const m of more) {
        if (modes.has(m)) continue;
        modes.add(m);
        colorSelect.append(h('option', {value: m}, m));
        if (m === query.get('color')) state.color = colorSelect.value = m;
      }
    };
    // 3d-tiles-renderer is loaded only for a map drawn from tiles; without it (web/ built
    // before `npm ci` installed it) every map is drawn from its Draco file.
    let TilesLayer = null;
    if (maps.some((map, i) => useTiles(map, sidecars[i], {lod: state.lod, budget: state.budget}))) {
      try {
        ({TilesLayer} = await (tilesModule || (tilesModule = loadTilesModule())));
      } catch (e) {
        notice('warning', 'The level-of-detail tiles cannot be drawn', `${e.message}; the maps are loaded from their Draco files.`);
      }
    }
    maps.forEach((map, i) => {
      const sidecar = sidecars[i];
      const visible = i === 0;
      if (TilesLayer && useTiles(map, sidecar, {lod: state.lod, budget: state.budget})) {
        const url = new URL(`${artifactUrl(map.tiles)}/files/tileset.json`, location.href).href;
        const layer = new TilesLayer({name: map.name, artifact: map.tiles, url, token: session.token()},
                                     {scene, budget: state.budget, onChange: onLayerChange});
        for (const m of COLOR_MODES) if (sidecar?.attributes?.[m]) modes.add(m);
        el.append(layerRow(layer, {checked: visible, onToggle: (on) => {
          layer.object3d.visible = on;
          if (on && layer.status === 'idle') layer.load();
          updateLegend();
          scene.requestRender();
        }}));
        addLayer(layer, visible);
        updateLayerUi(layer);
        return;
      }
      if (problems.has(map.name)) notice('warning', ...problems.get(map.name));
      let preview = map.preview;
      if (sidecar?.preview?.file && !byName[sidecar.preview.file]) {
        notice('warning', `${sidecar.preview.file} is missing`, `${map.name}: its full map is loaded instead.`);
        preview = null;
      }
      const layer = new PointCloudLayer({name: map.name, sidecar, full: map.full, preview, fetchBytes},
                                        {budget: state.budget, onChange: onLayerChange});
      layer.warm = warmDraco;
      for (const m of layer.modes()) modes.add(m);
      const fullButton = h('button', {type: 'button', class: 'load-full', hidden: true, on: {click: () => {
        layer.budget = state.budget;
        layer.load({full: true});
      }}}, `Load full map (${formatNumber(sidecar?.points ?? map.full.size)} ${sidecar?.points ? 'points' : 'bytes'})`);
      el.append(layerRow(layer, {checked: visible, extra: [fullButton], onToggle: (on) => {
        layer.object3d.visible = on;
        if (on && layer.status === 'idle') {
          layer.budget = state.budget;
          layer.load();
        }
        updateLegend();
        scene.requestRender();
      }}));
      layer.ui.fullButton = fullButton;
      addLayer(layer, visible);
      updateLayerUi(layer);
    });
    for (const m of modes) colorSelect.append(h('option', {value: m}, m));
    if (!modes.has(state.color)) state.color = 'height';
    colorSelect.value = state.color;
    for (const layer of mapLayers()) layer.setColorMode(state.color);
  }

  const mapLayers = () => [...layers.values()].filter((l) => l instanceof PointCloudLayer || l.isTiles);
  // Colourings found later (a tileset's attributes); set by setupMaps.
  let addColorModes = () => {};

  // ---- hull -----------------------------------------------------------------------------
  // ba_solution.json's T_world_model: dvl_residuals.csv and cad_model.drc are in the CAD
  // model frame, the maps, trajectories, shapes and the remeshed hull in the world frame.
  async function worldFromModel(byName) {
    const artifact = byName['ba_solution.json'];
    if (!artifact) return null;
    try {
      const t = (await fetchArtifactJson(artifact)).T_world_model;
      if (!Array.isArray(t?.rotation_xyzw) || !Array.isArray(t?.translation)) throw new Error('no T_world_model');
      return new THREE.Matrix4().compose(new THREE.Vector3(...t.translation),
                                         new THREE.Quaternion(...t.rotation_xyzw).normalize(), new THREE.Vector3(1, 1, 1));
    } catch (e) {
      notice('warning', 'ba_solution.json cannot be read', `${e.message}: model-frame layers are drawn unmoved.`);
      return null;
    }
  }

  async function setupHull(byName) {
    const remeshed = byName['mesh_remeshed.drc'];
    const cad = byName['cad_model.drc'];
    if (!remeshed && !cad) return;
    const el = section('hull', 'Hull');
    if (remeshed) {
      let sidecar = null;
      if (!byName['mesh_remeshed.json']) {
        notice('warning', 'mesh_remeshed.json is missing', 'the hull cannot be coloured by its deviation without it.');
      } else {
        try {
          sidecar = await fetchArtifactJson(byName['mesh_remeshed.json']);
        } catch (e) {
          notice('warning', 'mesh_remeshed.json cannot be read', e.message);
        }
      }
      const layer = new MeshLayer({name: 'mesh_remeshed', sidecar, artifact: remeshed, fetchBytes},
                                  {kind: sidecar ? 'deviation' : 'cad', onChange: onLayerChange});
      layer.deviationControls = h('div', {class: 'deviation-controls'});
      el.append(layerRow(layer, {checked: true, extra: [layer.deviationControls], onToggle: (on) => {
        layer.object3d.visible = on;
        updateLegend();
        scene.requestRender();
      }}));
      addLayer(layer, true);
    }
    if (cad) {
      const layer = new MeshLayer({name: 'cad_model', sidecar: null, artifact: cad, fetchBytes},
                                  {kind: 'cad', onChange: onLayerChange, transform: state.T_world_model});
      el.append(layerRow(layer, {checked: false, onToggle: (on) => {
        layer.object3d.visible = on;
        if (on && layer.status === 'idle') layer.load();
        scene.requestRender();
      }}));
      addLayer(layer, false);
    }
  }

  function setupDeviationControls(layer) {
    const values = layer.deviations();
    const {min, max} = layer.range();
    const maxAbs = Math.max(Math.abs(min), Math.abs(max)) || 1;
    const counts = histogram(values, 40, min, max);
    const canvasEl = h('canvas', {class: 'hist', id: 'deviation-histogram'});
    const label = h('span', {id: 'threshold-value'}, '0 m');
    // One deviation mesh per job (a pipeline job's remeshed hull or a compare job's change
    // hull), so these ids are unique in the page.
    const slider = h('input', {type: 'range', id: 'deviation-threshold', min: 0, max: maxAbs, step: maxAbs / 200, value: 0,
                               on: {input: () => {
      const t = Number(slider.value);
      layer.setThreshold(t);
      label.textContent = `${formatNumber(t, 3)} m`;
      let above = 0;
      for (let i = 0; i < values.length; i += 1) if (Math.abs(values[i]) >= t) above += 1;
      share.textContent = `${formatNumber((100 * above) / Math.max(1, values.length), 3)} % of vertices at or above`;
      drawHistogram(canvasEl, counts, {min, max, threshold: t});
      scene.requestRender();
    }}});
    const share = h('div', {class: 'muted', id: 'threshold-share'});
    layer.deviationControls.replaceChildren(
      h('label', null, layer.thresholdLabel || 'Deviation threshold ', label), slider, share, canvasEl);
    requestAnimationFrame(() => drawHistogram(canvasEl, counts, {min, max, threshold: 0}));
  }

  // ---- trajectories, shapes, residuals --------------------------------------------------
  async function setupTrajectories(byName) {
    const artifact = byName['trajectories.json'];
    if (!artifact) return;
    const el = section('trajectories', 'Trajectories');
    try {
      const doc = validateTrajectories(await fetchArtifactJson(artifact), artifact.name);
      doc.trajectories.forEach((t, i) => {
        const layer = new TrajectoryLayer(t, i);
        layer.name = `trajectory:${t.name}`;
        const swatch = layer.swatch();
        const row = layerRow(layer, {checked: true, onToggle: (on) => {
          layer.object3d.visible = on;
          updateLegend();
          scene.requestRender();
        }});
        row.querySelector('span').replaceChildren(row.querySelector('input'), ' ',
          swatch ? h('span', {class: 'swatch', style: {background: swatch}}) : '', t.name, t.ate_m ? ' (by ATE)' : '');
        layer.ui.count.textContent = `${formatNumber(layer.poses)} poses`;
        row.dataset.poses = String(layer.poses);
        el.append(row);
        addLayer(layer, true);
      });
    } catch (e) {
      el.append(message('error', `${artifact.name} cannot be shown`, e.message));
      notice('error', `${artifact.name} cannot be shown`, e.message);
    }
  }

  async function setupShapes(byName) {
    const artifact = byName['shapes.json'];
    if (!artifact) return;
    const el = section('shapes', 'Shapes');
    try {
      const doc = validateShapes(await fetchArtifactJson(artifact), artifact.name);
      const layer = new ShapesLayer(doc);
      el.append(layerRow(layer, {checked: true, onToggle: (on) => {
        layer.object3d.visible = on;
        scene.requestRender();
      }}));
      layer.ui.count.textContent = `${doc.shapes.length} found`;
      addLayer(layer, true);
      if (doc.shapes.length === 0) {
        el.append(h('p', {class: 'muted'}, 'The inspect stage found no shape off the CAD model.'));
        return;
      }
      el.append(h('table', {id: 'shapes-table'},
        h('thead', null, h('tr', null, ['id', 'centroid (m)', 'extent (m)', 'height (m)', 'views'].map((c) => h('th', null, c)))),
        h('tbody', null, doc.shapes.map((s, i) => h('tr', {class: 'clickable', dataset: {shape: String(s.id)},
                                                       on: {click: () => flyToShape(i)}},
          h('td', null, String(s.id)),
          h('td', null, s.centroid_world_m.map((v) => formatNumber(v, 4)).join(', ')),
          h('td', null, (s.extent_m || []).map((v) => formatNumber(v, 3)).join(' × ')),
          h('td', {class: 'num'}, formatNumber(s.max_deviation_m, 3)),
          h('td', {class: 'num'}, String(Array.isArray(s.views) ? s.views.length : s.views ?? ''))))))); 
    } catch (e) {
      el.append(message('error', `${artifact.name} cannot be shown`, e.message));
      notice('error', `${artifact.name} cannot be shown`, e.message);
    }
  }

  function flyToShape(i) {
    const layer = layers.get('shapes');
    if (!layer) return;
    const {center, distance} = layer.viewOf(i);
    layer.highlight(i);
    layer.object3d.visible = true;
    scene.flyTo(center, distance);
  }

  async function setupResiduals(byName) {
    const artifact = byName['dvl_residuals.csv'];
    if (!artifact) return;
    const el = section('residuals', 'DVL residuals (Fig. 18)');
    try {
      const text = new TextDecoder().decode(await fetchArtifact(artifact));
      const residuals = parseResiduals(text, artifact.name);
      const layer = new ResidualLayer(residuals, {transform: state.T_world_model});
      const select = h('select', {id: 'residual-state', on: {change: () => {
        layer.setState(select.value);
        layer.ui.count.textContent = `${formatNumber(layer.count)} beams`;
        updateLegend();
        scene.requestRender();
      }}}, layer.states.map((s) => h('option', {value: s}, s === 'ba' ? 'after BA' : s === 'gicp' ? 'after GICP' : s)));
      select.value = layer.state;
      el.append(layerRow(layer, {checked: false, extra: [h('label', null, 'State ', select)], onToggle: (on) => {
        layer.object3d.visible = on;
        updateLegend();
        scene.requestRender();
      }}));
      layer.ui.count.textContent = `${formatNumber(layer.count)} beams`;
      addLayer(layer, false);
    } catch (e) {
      el.append(message('error', `${artifact.name} cannot be shown`, e.message));
    }
  }

  // ---- measurement: viewer_measure.js ----------------------------------------------------

  // ---- start ----------------------------------------------------------------------------
  async function start() {
    let list;
    try {
      ({artifacts: list} = await artifactList);
    } catch (e) {
      if (!disposed && !(e instanceof ApiError && e.status === 401))
        aside.append(message('error', 'The artifacts could not be listed', e instanceof ApiError ? e.describe() : e.message));
      return;
    }
    if (disposed) return;
    performance.mark('keel:viewer-artifacts');
    const byName = Object.fromEntries(list.map((a) => [a.name, a]));
    document.getElementById('viewer-status').textContent = `${list.length} artifacts`;
    state.T_world_model = await worldFromModel(byName);
    await setupTrajectories(byName);
    const shared = {section, layerRow, addLayer, notice, updateLegend, scene, fetchBytes, onLayerChange, state, query, saveUrl,
                    warmDraco, worldFromModel, setupDeviationControls};
    await Promise.all([setupMaps(byName), setupHull(byName), setupShapes(byName), setupResiduals(byName),
                       setupChanges(shared, id, byName)]);
    if (disposed) return;
    if (layers.size === 0) {
      notice('info', 'Nothing to show in 3D', 'This job has no map, mesh, trajectory or shape yet (the map, refine, ba and inspect stages write them; a compare job its change maps and hull).');
    } else {
      setupMeasure({section, layers, state, scene, canvas, readout, measureGroup});
    }
    state.started = true;
    if (!state.cameraFromUrl) fitView();
    // Load what is shown by default; the rest loads when switched on.
    for (const layer of layers.values()) if (layer.object3d.visible && layer.status === 'idle') layer.load?.();
    updateLegend();
    scene.requestRender(() => settle());
  }

  // For tests and benchmarks: what the page shows, read back from the page itself.
  window.keelViewer = {
    state,
    scene,
    layers,
    camera: () => scene.cameraText(),
    flyToShape,
    // The range of the values a layer holds, leaving out the attribute's no_data value.
    attributeRange(layerName, attribute) {
      const layer = layers.get(layerName);
      const geometry = layer?.decoded || layer?.mesh?.geometry;
      const a = geometry?.getAttribute(attribute);
      const noData = layer?.sidecar?.attributes?.[attribute]?.no_data;
      return a ? finiteRange(a.array, a.itemSize, attribute === 'position' ? 2 : 0, noData === undefined ? undefined : Math.fround(noData)) : null;
    },
  };

  start();
  return () => {
    disposed = true;
    for (const layer of layers.values()) layer.dispose();
    for (const material of warmMaterials) material.dispose();
    scene.dispose();
    delete window.keelViewer;
    delete document.body.dataset.viewerReady;
  };
}
