// What each per-point (or per-vertex) attribute of Keel's Draco files (docs/artifacts.md) is
// coloured with, and the legend a layer shows for it. The legend's min/max are always the
// sidecar's (the values stored in the file); the ramp's ends can differ from them: a signed
// attribute's ramp is centred on zero, so its colour says the sign whatever the range's
// asymmetry, and a categorical one spans its fixed categories, so a category keeps its colour
// when a file happens to hold none of another. Pure (tested in node).
import {isCategorical, symmetricRange} from './colormap.js';

export const ATTRIBUTES = {
  intensity: {label: 'intensity'},
  sensor: {label: 'sensor', ramp: 'categorical'},
  density: {label: 'density', unit: 'points/m²'},
  roughness: {label: 'roughness', unit: 'm'},
  planarity: {label: 'planarity'},
  deviation: {label: 'deviation from CAD', unit: 'm', ramp: 'diverging'},
  // A compare job's change maps and change hull.
  m3c2_m: {label: 'M3C2 change B − A', unit: 'm', ramp: 'diverging'},
  lod95_m: {label: 'level of detection (95 %)', unit: 'm'},
  significant: {label: 'significance of the change', ramp: 'significance', categories: [-1, 1],
                labels: {'-1': 'undefined (too few points)', 0: 'not significant', 1: 'significant'}},
  c2c_m: {label: 'distance to A (C2C)', unit: 'm'},
  deviation_a: {label: 'deviation from CAD in A', unit: 'm', ramp: 'diverging'},
  deviation_b: {label: 'deviation from CAD in B', unit: 'm', ramp: 'diverging'},
  deviation_change: {label: 'deviation change B − A', unit: 'm', ramp: 'diverging'},
};

// The legend of a layer coloured by its height (z extent of `box`, a THREE.Box3 or null).
export function heightLegend(layerName, box) {
  return {title: `${layerName}: height (z, m)`, min: box ? box.min.z : NaN, max: box ? box.max.z : NaN, ramp: 'viridis', mode: 'height'};
}

// The legend of attribute `mode` whose sidecar (or tileset) entry is `info` ({min, max,
// no_data, labels}); `labels` overrides the category names (a tileset's sensors).
export function attributeLegend(layerName, mode, info, {labels} = {}) {
  const spec = ATTRIBUTES[mode] || {label: mode};
  const ramp = spec.ramp || 'viridis';
  const legend = {title: `${layerName}: ${spec.label}${spec.unit ? ` (${spec.unit})` : ''}`, min: info.min, max: info.max, ramp, mode};
  if (isCategorical(ramp)) {
    const [first, last] = spec.categories || [Math.round(info.min), Math.round(info.max)];
    Object.assign(legend, {labels: labels || info.labels || spec.labels || [], first, last});
  } else if (info.no_data !== undefined) {
    legend.noData = info.no_data;
  }
  return legend;
}

// The values at the ramp's two ends (a shader maps vmin..vmax onto it) and, for a categorical
// legend, how many flat colours it holds (each category centred on its integer value).
export function rampEnds(legend) {
  if (isCategorical(legend.ramp)) {
    const first = legend.first ?? Math.round(legend.min);
    const last = legend.last ?? Math.round(legend.max);
    return {vmin: first - 0.5, vmax: last + 0.5, categories: Math.max(1, last - first + 1)};
  }
  if (legend.ramp === 'diverging') {
    // A clip (a change map's ± box) puts the ramp's ends there; beyond, the colours saturate.
    if (legend.clip > 0) return {vmin: -legend.clip, vmax: legend.clip, categories: 0};
    const {min, max} = symmetricRange(legend.min, legend.max);
    return {vmin: min, vmax: max, categories: 0};
  }
  return {vmin: legend.min, vmax: legend.max, categories: 0};
}

// The default clip of a change map's M3C2 colouring: four times the median 95 % level of
// detection (the compare report's lod95_m), so a change at the level of detection shows at a
// quarter of the ramp and the noise of unchanged structure stays pale, however far the few
// largest changes reach; null when the report has no such figure.
export function changeClip(report) {
  const lod = report?.lod95_m?.median;
  return Number.isFinite(lod) && lod > 0 ? 4 * lod : null;
}

// The part of the ramp a legend's values span, as fractions [from, to] of it.
export function rampSpan(legend) {
  const {vmin, vmax} = rampEnds(legend);
  if (!(vmax > vmin)) return {from: 0, to: 1};
  const at = (v) => Math.min(1, Math.max(0, (v - vmin) / (vmax - vmin)));
  return {from: at(legend.min), to: at(legend.max)};
}

// The category names of a categorical legend, value by value from its min to its max:
// [{value, index (its colour in the palette), label}].
export function legendCategories(legend) {
  const out = [];
  const first = legend.first ?? Math.round(legend.min);
  for (let v = Math.round(legend.min); v <= Math.round(legend.max); v += 1)
    out.push({value: v, index: v - first, label: legend.labels?.[v] ?? `${legend.mode} ${v}`});
  return out;
}
