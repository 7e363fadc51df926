// A layer's row in the viewer's panel: its toggle and name, its size (points drawn / decoded,
// vertices), and its loading progress or error; the row's data-* attributes carry the same
// figures for tests. layer.ui holds the row's parts.
import {h} from '../dom.js';
import {formatNumber} from '../format.js';
import {MeshLayer} from '../viewer/mesh_layer.js';
import {PointCloudLayer} from '../viewer/point_cloud_layer.js';

export function layerRow(layer, {checked, onToggle, extra = []}) {
  const box = h('input', {type: 'checkbox', checked, dataset: {layer: layer.name}, on: {change: () => onToggle(box.checked)}});
  const count = h('span', {class: 'count'});
  const status = h('div', {class: 'layer-status muted'});
  const row = h('div', {class: 'layer-entry', dataset: {layer: layer.name}},
                h('label', {class: 'layer'}, h('span', null, box, ' ', layer.name), count), status, extra);
  layer.ui = {row, box, count, status};
  return row;
}

export function updateLayerUi(layer) {
  if (!layer.ui) return;
  const {count, status, row} = layer.ui;
  row.dataset.status = layer.status;
  if (layer.isTiles) {
    count.textContent = layer.decodedPoints ? `${formatNumber(layer.drawnPoints)} / ${formatNumber(layer.decodedPoints)} pts` : '';
    row.dataset.points = String(layer.decodedPoints);
    row.dataset.drawn = String(layer.drawnPoints);
    row.dataset.level = layer.level;
    row.dataset.tiles = String(layer.tilesShown);
  } else if (layer instanceof PointCloudLayer) {
    count.textContent = layer.decodedPoints ? `${formatNumber(layer.drawnPoints)} / ${formatNumber(layer.decodedPoints)} pts` : '';
    row.dataset.points = String(layer.decodedPoints);
    row.dataset.drawn = String(layer.drawnPoints);
    row.dataset.level = layer.level;
    const full = layer.ui.fullButton;
    if (full) {
      full.hidden = !layer.hasPreview() || layer.level === 'full' || layer.status === 'idle';
      full.disabled = layer.status === 'loading';
    }
  } else if (layer instanceof MeshLayer) {
    count.textContent = layer.vertices ? `${formatNumber(layer.vertices)} vertices` : '';
    row.dataset.vertices = String(layer.vertices);
    row.dataset.faces = String(layer.faces);
  }
  status.replaceChildren(layer.status === 'loading'
      ? [layer.message, layer.progress ? ` ${Math.round(layer.progress * 100)} %` : '']
      : layer.status === 'error' ? h('span', {class: 'error'}, layer.message) : '');
}
