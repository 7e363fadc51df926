// Legend boxes of the viewer: one per coloured layer on screen, its range printed from the
// numbers the layer colours with (data-min/data-max carry them at full precision).
import {h} from '../dom.js';
import {formatNumber} from '../format.js';
import {legendCategories, rampSpan} from './attribute_legend.js';
import {categoryColor, cssColor, cssGradient, isCategorical} from './colormap.js';

export function legendBox(legend, layerName) {
  const box = h('div', {class: 'legend-box', dataset: {layer: layerName, mode: legend.mode,
                                                     min: String(legend.min), max: String(legend.max)}},
                h('div', {class: 'legend-title'}, legend.title));
  if (isCategorical(legend.ramp)) {
    for (const {value, index, label} of legendCategories(legend))
      box.append(h('div', {dataset: {value: String(value)}},
                   h('span', {class: 'swatch', style: {background: cssColor(categoryColor(legend.ramp, index))}}), label));
    return box;
  }
  // A symmetric ramp shows the part the values span: its colours are those on screen.
  const {from, to} = rampSpan(legend);
  box.append(h('div', {class: 'ramp', style: {background: cssGradient(legend.ramp, from, to)}}),
             h('div', {class: 'ends'}, h('span', {class: 'min'}, formatNumber(legend.min)),
               h('span', {class: 'max'}, formatNumber(legend.max))));
  if (legend.clip > 0)
    box.append(h('div', {class: 'clip', dataset: {clip: String(legend.clip)}},
                 `colours saturate beyond ±${formatNumber(legend.clip)}`));
  if (legend.noData !== undefined)
    box.append(h('div', {class: 'no-data'}, h('span', {class: 'swatch', style: {background: 'rgb(115,115,115)'}}), 'undefined here'));
  return box;
}

// A small histogram (bars over [min, max]) with an optional threshold marker, on a canvas.
export function drawHistogram(canvas, counts, {min, max, threshold = null, color = '#4e79a7'}) {
  const width = canvas.clientWidth || 260;
  const height = canvas.clientHeight || 70;
  canvas.width = width;
  canvas.height = height;
  const g = canvas.getContext('2d');
  g.clearRect(0, 0, width, height);
  const top = Math.max(1, ...counts);
  const bar = width / counts.length;
  g.fillStyle = color;
  counts.forEach((c, i) => {
    const barHeight = (Math.log1p(c) / Math.log1p(top)) * (height - 12);
    g.fillRect(i * bar, height - 12 - barHeight, Math.max(1, bar - 1), barHeight);
  });
  g.fillStyle = '#6b7385';
  g.font = '10px sans-serif';
  g.fillText(formatNumber(min, 3), 0, height - 1);
  const right = formatNumber(max, 3);
  g.fillText(right, width - g.measureText(right).width, height - 1);
  if (threshold !== null && max > min) {
    for (const t of [threshold, -threshold]) {
      if (t < min || t > max) continue;
      const x = ((t - min) / (max - min)) * width;
      g.fillStyle = '#c62828';
      g.fillRect(x - 1, 0, 2, height - 12);
    }
  }
}
