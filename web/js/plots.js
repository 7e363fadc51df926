// uPlot charts for the report view: lines over a shared x (per iteration, over time) and
// histograms as bars over bin edges. Each chart keeps the data it drew (window.keelReport)
// so tests can compare it with report.json.
import uPlot from 'uplot';
import {h} from './dom.js';

const PALETTE = ['#4e79a7', '#f28e2b', '#e15759', '#76b7b2', '#59a14f', '#edc948', '#b07aa1'];

export const drawnPlots = new Map();

function sizeOf(el) {
  return {width: Math.max(320, Math.min(640, (el.clientWidth || 480) - 8)), height: 220};
}

// series: [{label, values}] over x. `log` = logarithmic y.
export function linePlot(container, {id, title, xLabel, yLabel, x, series, log = false}) {
  const el = h('div', {class: 'plot', id: `plot-${id}`, dataset: {plot: id}}, h('h4', null, title));
  container.append(el);
  const data = [Float64Array.from(x), ...series.map((s) => s.values.map((v) => (v === null || !Number.isFinite(v) ? null : v)))];
  drawnPlots.set(id, {x: [...x], series: series.map((s) => ({label: s.label, values: [...s.values]}))});
  const options = {
    ...sizeOf(container),
    scales: {x: {time: false}, y: log ? {distr: 3} : {}},
    axes: [{label: xLabel}, {label: yLabel}],
    series: [{label: xLabel}, ...series.map((s, i) => ({label: s.label, stroke: PALETTE[i % PALETTE.length], width: 1.5,
                                                        points: {show: x.length < 60}}))],
  };
  return new uPlot(options, data, el);
}

// A histogram from bin edges (n + 1) and counts (n); several series share the edges. The bars
// may hold another quantity than a count (yLabel: an area per bin).
export function histogramPlot(container, {id, title, xLabel, yLabel = 'count', edges, series}) {
  const el = h('div', {class: 'plot', id: `plot-${id}`, dataset: {plot: id}}, h('h4', null, title));
  container.append(el);
  const centers = edges.slice(0, -1).map((e, i) => 0.5 * (e + edges[i + 1]));
  drawnPlots.set(id, {edges: [...edges], series: series.map((s) => ({label: s.label, values: [...s.counts]}))});
  const bars = uPlot.paths.bars({size: [0.9 / Math.max(1, series.length), 100]});
  const options = {
    ...sizeOf(container),
    scales: {x: {time: false}},
    axes: [{label: xLabel}, {label: yLabel}],
    series: [{label: xLabel}, ...series.map((s, i) => ({label: s.label, fill: `${PALETTE[i % PALETTE.length]}99`,
                                                        stroke: PALETTE[i % PALETTE.length], paths: bars, points: {show: false}}))],
  };
  return new uPlot(options, [centers, ...series.map((s) => s.counts)], el);
}
