// The viewer's layers of a compare job (docs/artifacts.md, compare): each change map as
// points coloured by the M3C2 change (a ramp centred on zero), its significance, its level of
// detection or the C2C distance; the change hull coloured by the change of its deviation from
// the CAD model. Called by viewer.js with the page's shared parts (`ctx`).
//
// Frames: the change maps are in job A's world frame, the change hull in the CAD model's.
// With both on screen the hull is moved into A's world by A's T_world_model (its
// ba_solution.json); alone it is drawn in the model frame, which nothing else needs to meet.
import {fetchArtifactJson, jobsApi} from '../api.js';
import {h} from '../dom.js';
import {formatNumber} from '../format.js';
import {jobHash} from '../router.js';
import {changeClip} from '../viewer/attribute_legend.js';
import {changesOf} from '../viewer/change_artifacts.js';
import {MeshLayer} from '../viewer/mesh_layer.js';
import {CHANGE_COLOR_MODES, PointCloudLayer} from '../viewer/point_cloud_layer.js';

// A sidecar, or null with a warning naming what is lost without it.
async function readSidecar(ctx, name, artifact, without) {
  if (!artifact) {
    ctx.notice('warning', `${name}.json is missing`, `${name} ${without}: its sidecar names the attributes and their ranges.`);
    return null;
  }
  try {
    return await fetchArtifactJson(artifact);
  } catch (e) {
    ctx.notice('warning', `${name}.json cannot be read`, `${e.message}; ${name} ${without}.`);
    return null;
  }
}

// changes.json (the comparison's figures), or null with a notice: the M3C2 colours then span
// the attribute's whole range.
async function readChanges(ctx, artifact) {
  try {
    if (!artifact) throw new Error('the job has no changes.json');
    return await fetchArtifactJson(artifact);
  } catch (e) {
    ctx.notice('warning', 'changes.json cannot be read', `${e.message || e}; the M3C2 colours span the change's whole range.`);
    return null;
  }
}

// Job A's T_world_model (THREE.Matrix4), read from the job record's compare options and A's
// ba_solution.json; null, said in a message, when it cannot be had.
async function jobAWorldFromModel(ctx, id) {
  try {
    const jobA = (await jobsApi.get(id))?.options?.compare?.job_a;
    if (!jobA) throw new Error('the compare job names no job A in its options');
    const {artifacts} = await jobsApi.artifacts(jobA);
    const byName = Object.fromEntries(artifacts.map((a) => [a.name, a]));
    if (!byName['ba_solution.json']) throw new Error(`job ${jobA} has no ba_solution.json`);
    return await ctx.worldFromModel(byName);
  } catch (e) {
    ctx.notice('warning', 'change_hull is drawn in the CAD model frame', `${e.message || e}; the change maps are in job A's world frame.`);
    return null;
  }
}

// The ± box of the M3C2 colouring: the ramp's ends, by default changeClip() of the map's
// figures in changes.json (the first map's for the box), kept in the URL (?clip=).
function clipControl(ctx, layers, changes) {
  const defaults = layers.map((layer) => changeClip(changes?.maps?.maps?.[layer.name.replace(/^change_/, '')]));
  const wanted = Number(ctx.query.get('clip'));
  const apply = (value) => layers.forEach((layer, i) => layer.setClip('m3c2_m', value > 0 ? value : defaults[i]));
  apply(wanted);
  const input = h('input', {type: 'number', id: 'change-clip', min: 0, step: 0.005,
                            value: String(wanted > 0 ? wanted : defaults[0] ?? ''), on: {change: () => {
    const value = Number(input.value);
    apply(value);
    ctx.saveUrl({clip: value > 0 ? String(value) : ''});
    ctx.updateLegend();
    ctx.scene.requestRender();
  }}});
  return h('label', {title: 'the M3C2 colours saturate beyond this change (m); empty: four times the median level of detection'},
           'M3C2 colours ± ', input, ' m');
}

function setupChangeMaps(ctx, maps, sidecars, changes, el) {
  const layers = maps.map((map, i) => {
    const layer = new PointCloudLayer({name: map.name, sidecar: sidecars[i], full: map.full, preview: null, fetchBytes: ctx.fetchBytes},
                                      {budget: ctx.state.budget, onChange: ctx.onLayerChange, colorModes: CHANGE_COLOR_MODES});
    layer.warm = ctx.warmDraco;
    return layer;
  });
  // The colourings any of the maps has, in CHANGE_COLOR_MODES' order (the change first).
  const modes = CHANGE_COLOR_MODES.filter((m) => layers.some((layer) => layer.modes().includes(m)));
  const wanted = ctx.query.get('change');
  const select = h('select', {id: 'change-color-by', on: {change: () => {
    ctx.saveUrl({change: select.value === modes[0] ? '' : select.value});
    for (const layer of layers) layer.setColorMode(select.value) || layer.setColorMode('height');
    ctx.updateLegend();
    ctx.scene.requestRender();
  }}}, modes.map((m) => h('option', {value: m}, m)));
  select.value = modes.includes(wanted) ? wanted : modes[0];
  const size = h('input', {type: 'range', id: 'change-point-size', min: 1, max: 8, step: 1, value: 2, on: {input: () => {
    for (const layer of layers) layer.setPointSize(Number(size.value));
    ctx.scene.requestRender();
  }}});
  el.append(h('label', null, 'Colour by ', select), clipControl(ctx, layers, changes), h('label', null, 'Point size ', size));
  layers.forEach((layer, i) => {
    layer.setColorMode(select.value) || layer.setColorMode('height');
    el.append(ctx.layerRow(layer, {checked: i === 0, onToggle: (on) => {
      layer.object3d.visible = on;
      if (on && layer.status === 'idle') {
        layer.budget = ctx.state.budget;
        layer.load();
      }
      ctx.updateLegend();
      ctx.scene.requestRender();
    }}));
    ctx.addLayer(layer, i === 0);
  });
}

function setupChangeHull(ctx, hull, sidecar, transform, el) {
  const layer = new MeshLayer({name: hull.name, sidecar, artifact: hull.artifact, fetchBytes: ctx.fetchBytes},
                              {kind: sidecar ? 'deviation' : 'cad', onChange: ctx.onLayerChange, transform,
                               attribute: 'deviation_change'});
  layer.thresholdLabel = '|Change| threshold ';
  layer.deviationControls = h('div', {class: 'deviation-controls'});
  const attributes = layer.attributes();
  const select = attributes.length > 1 ? h('select', {id: 'change-hull-color-by', on: {change: () => {
    layer.setAttribute(select.value);
    if (layer.status === 'shown') ctx.setupDeviationControls(layer);
    ctx.updateLegend();
    ctx.scene.requestRender();
  }}}, attributes.map((a) => h('option', {value: a}, a))) : null;
  if (select) select.value = layer.attribute;
  el.append(ctx.layerRow(layer, {checked: true, extra: [select ? h('label', null, 'Colour by ', select) : null, layer.deviationControls],
                                 onToggle: (on) => {
    layer.object3d.visible = on;
    ctx.updateLegend();
    ctx.scene.requestRender();
  }}));
  ctx.addLayer(layer, true);
}

// Adds the section "Changes" when the job has change maps or a change hull.
export async function setupChanges(ctx, id, byName) {
  const {maps, hull} = changesOf(byName);
  if (maps.length === 0 && !hull) return;
  const el = ctx.section('changes', 'Changes (B against A)');
  const [sidecars, hullSidecar, transform, changes] = await Promise.all([
    Promise.all(maps.map((map) => readSidecar(ctx, map.name, map.sidecarArtifact, 'is drawn by height only'))),
    hull ? readSidecar(ctx, hull.name, hull.sidecarArtifact, 'is drawn without its change colours') : null,
    hull && maps.length > 0 ? jobAWorldFromModel(ctx, id) : null,
    maps.length > 0 ? readChanges(ctx, byName['changes.json']) : null,
  ]);
  if (maps.length > 0) setupChangeMaps(ctx, maps, sidecars, changes, el);
  if (hull) setupChangeHull(ctx, hull, hullSidecar, transform, el);
  el.append(h('p', {class: 'muted'}, `${formatNumber(maps.length)} change map${maps.length === 1 ? '' : 's'}`,
              hull ? ' and the change hull' : '', '; their figures are in the ', h('a', {href: jobHash(id, 'report')}, 'report'), '.'));
}
