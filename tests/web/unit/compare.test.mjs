// The compare job's pure parts: which figures differ and in what order, the relative ATE as
// rows, and which artifacts are change maps or the change hull.
import assert from 'node:assert/strict';
import {test} from 'node:test';
import {figuresThatDiffer, relativeAteRows} from '../../../web/js/compare_model.js';
import {changesOf} from '../../../web/js/viewer/change_artifacts.js';

test('figures that differ: equal ones left out, most changed first, a figure that was 0 in A before all', () => {
  const figures = [
    {figure: 'same', a: 2, b: 2, difference: 0, relative: 0},
    {figure: 'small', a: 10, b: 11, difference: 1, relative: 0.1},
    {figure: 'from.zero', a: 0, b: 3, difference: 3},
    {figure: 'big.drop', a: 4, b: 1, difference: -3, relative: -0.75},
    {figure: 'zero.both', a: 0, b: 0, difference: 0},
    {figure: 'tie.b', a: 100, b: 110, difference: 10, relative: 0.1},
    {figure: 'tie.a', a: -100, b: -110, difference: -10, relative: -0.1},
    {figure: 'from.zero.larger', a: 0, b: -7, difference: -7},
  ];
  const order = figuresThatDiffer(figures);
  assert.deepEqual(order.map((x) => x.row.figure), ['from.zero.larger', 'from.zero', 'big.drop', 'tie.a', 'tie.b', 'small']);
  // Each keeps its index in report.json's list (the data-key of its cells).
  for (const {index, row} of order) assert.equal(figures[index], row);
  assert.deepEqual(figuresThatDiffer(undefined), []);
  assert.deepEqual(figuresThatDiffer([{figure: 'x', a: 'text', b: 1}]), []);
});

test('fifty thousand figures are ordered in well under a second', () => {
  const figures = Array.from({length: 50000}, (_, i) => ({figure: `f.${i}`, a: 1 + (i % 97), b: 1 + (i % 89), difference: (i % 89) - (i % 97),
                                                         relative: ((i % 89) - (i % 97)) / (1 + (i % 97))}));
  const start = performance.now();
  const order = figuresThatDiffer(figures);
  const ms = performance.now() - start;
  assert.ok(ms < 1000, `${ms} ms`);
  for (let i = 1; i < order.length; i += 1)
    assert.ok(Math.abs(order[i - 1].row.relative) >= Math.abs(order[i].row.relative), `row ${i} out of order`);
});

test('relative ATE rows: one per trajectory and alignment, or the reason it was not compared', () => {
  const stats = {rmse: 1, mean: 1, median: 1, std: 0, min: 1, max: 1, count: 3};
  const rows = relativeAteRows({
    'trajectory_refined.tum': {ate_se3: {translation_m: stats, rotation_deg: stats}, ate_none: {translation_m: stats, rotation_deg: stats}},
    'trajectory_ba.tum': {error: 'not comparable: no matching timestamps'},
  });
  assert.deepEqual(rows, [
    {trajectory: 'trajectory_refined.tum', alignment: 'none', key: ['trajectory_refined.tum', 'ate_none']},
    {trajectory: 'trajectory_refined.tum', alignment: 'se3', key: ['trajectory_refined.tum', 'ate_se3']},
    {trajectory: 'trajectory_ba.tum', error: 'not comparable: no matching timestamps'}]);
  assert.deepEqual(relativeAteRows(undefined), []);
});

test('change maps and the change hull are found by name, each with its sidecar or null', () => {
  const a = (name) => ({name, id: `a_${name}`});
  const byName = Object.fromEntries(['change_lidar_h.drc', 'change_combined.drc', 'change_combined.json', 'change_combined.ply',
                                     'change_hull.drc', 'change_hull.json', 'map_combined.drc', 'changes.json'].map((n) => [n, a(n)]));
  const {maps, hull} = changesOf(byName);
  assert.deepEqual(maps.map((m) => [m.name, m.map, m.full.name, m.sidecarArtifact?.name ?? null]),
                   [['change_combined', 'combined', 'change_combined.drc', 'change_combined.json'],
                    ['change_lidar_h', 'lidar_h', 'change_lidar_h.drc', null]]);
  assert.deepEqual(hull, {name: 'change_hull', artifact: byName['change_hull.drc'], sidecarArtifact: byName['change_hull.json']});
  assert.deepEqual(changesOf({'map_combined.drc': a('map_combined.drc')}), {maps: [], hull: null});
});

test('the M3C2 colours saturate at four levels of detection, or at the larger magnitude without one', async () => {
  const {changeClip, rampEnds, rampSpan} = await import('../../../web/js/viewer/attribute_legend.js');
  assert.equal(changeClip({lod95_m: {median: 0.0234}}), 4 * 0.0234);
  for (const bad of [undefined, {}, {lod95_m: {median: 0}}, {lod95_m: {median: NaN}}]) assert.equal(changeClip(bad), null);
  const legend = {min: -1.0, max: 0.76, ramp: 'diverging', mode: 'm3c2_m'};
  assert.deepEqual(rampEnds(legend), {vmin: -1.0, vmax: 1.0, categories: 0});
  assert.deepEqual(rampEnds({...legend, clip: 0.1}), {vmin: -0.1, vmax: 0.1, categories: 0});
  assert.deepEqual(rampSpan({...legend, clip: 0.1}), {from: 0, to: 1}, 'values beyond the clip: the whole ramp shows');
});
