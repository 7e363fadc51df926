// The viewer's pure parts: colour ramps against matplotlib's viridis and ColorBrewer's RdBu
// ends, legends and ramp ends, histograms and ranges against brute force, the camera in the
// URL, even thinning, the residual CSV.
import assert from 'node:assert/strict';
import {test} from 'node:test';
import {attributeLegend, heightLegend, legendCategories, rampEnds, rampSpan} from '../../../web/js/viewer/attribute_legend.js';
import {categoryColor, finiteRange, histogram, rampColor, rampTexels, symmetricRange} from '../../../web/js/viewer/colormap.js';
import {decodeCamera, encodeCamera} from '../../../web/js/viewer/camera_url.js';
import {strideFor, strided} from '../../../web/js/viewer/thinning.js';
import {parseResiduals} from '../../../web/js/viewer/residual_layer.js';
import {taskConfigFor} from '../../../web/js/viewer/draco.js';
import {NO_NO_DATA, noDataBelow} from '../../../web/js/viewer/materials.js';

test('viridis ends are matplotlib\'s #440154 and #fde725', () => {
  assert.deepEqual(rampColor('viridis', 0), [0x44, 0x01, 0x54]);
  assert.deepEqual(rampColor('viridis', 1), [0xfd, 0xe7, 0x25]);
  assert.deepEqual(rampColor('viridis', -3), rampColor('viridis', 0));
  const texels = rampTexels('viridis', 3);
  // Three categories fill the 256 texels in three flat runs.
  assert.deepEqual([...texels.slice(0, 3)], [...texels.slice(4 * 80, 4 * 80 + 3)]);
  assert.notDeepEqual([...texels.slice(0, 3)], [...texels.slice(4 * 100, 4 * 100 + 3)]);
});

// ColorBrewer's 7-class RdBu (colorbrewer2.org), reversed: blue for negative, red for positive.
test('the diverging ramp is ColorBrewer RdBu: #2166ac, #f7f7f7 in the middle, #b2182b', () => {
  assert.deepEqual(rampColor('diverging', 0), [0x21, 0x66, 0xac]);
  assert.deepEqual(rampColor('diverging', 0.5), [0xf7, 0xf7, 0xf7]);
  assert.deepEqual(rampColor('diverging', 1), [0xb2, 0x18, 0x2b]);
  assert.deepEqual(rampColor('diverging', 2), rampColor('diverging', 1));
});

test('a signed attribute: legend = the sidecar range, ramp symmetric about 0 so 0 is white', () => {
  const legend = attributeLegend('change_combined', 'm3c2_m', {unique_id: 1, min: -0.12, max: 0.5});
  assert.deepEqual([legend.min, legend.max, legend.ramp, legend.mode], [-0.12, 0.5, 'diverging', 'm3c2_m']);
  assert.equal(legend.title, 'change_combined: M3C2 change B − A (m)');
  const {vmin, vmax, categories} = rampEnds(legend);
  assert.deepEqual([vmin, vmax, categories], [-0.5, 0.5, 0]);
  assert.deepEqual(rampColor('diverging', (0 - vmin) / (vmax - vmin)), [0xf7, 0xf7, 0xf7]);
  // The legend bar shows the part of the ramp its values span.
  assert.deepEqual(rampSpan(legend), {from: (0.5 - 0.12) / 1, to: 1});
  assert.deepEqual(symmetricRange(0.2, 0.3), {min: -0.3, max: 0.3});
  // All zero (a job compared with itself): zero still in the white middle.
  const zero = rampEnds(attributeLegend('c', 'deviation_change', {min: 0, max: 0}));
  assert.equal((0 - zero.vmin) / (zero.vmax - zero.vmin), 0.5);
  // Unsigned attributes keep viridis over their range.
  assert.deepEqual(rampEnds(attributeLegend('c', 'c2c_m', {min: 0.001, max: 0.8})), {vmin: 0.001, vmax: 0.8, categories: 0});
  assert.deepEqual(rampEnds(heightLegend('m', {min: {z: -2}, max: {z: 3}})), {vmin: -2, vmax: 3, categories: 0});
});

test('significance: three fixed categories, each value its colour and label whatever the file holds', () => {
  const all = attributeLegend('change_combined', 'significant', {min: -1, max: 1});
  assert.deepEqual(rampEnds(all), {vmin: -1.5, vmax: 1.5, categories: 3});
  assert.deepEqual(legendCategories(all).map((c) => [c.value, c.index, c.label]),
                   [[-1, 0, 'undefined (too few points)'], [0, 1, 'not significant'], [1, 2, 'significant']]);
  // A file without undefined points: 0 and 1 keep their colours (the ramp still spans -1..1).
  const defined = attributeLegend('change_combined', 'significant', {min: 0, max: 1});
  assert.deepEqual(rampEnds(defined), rampEnds(all));
  assert.deepEqual(legendCategories(defined).map((c) => c.index), [1, 2]);
  assert.deepEqual(categoryColor('significance', 2), rampColor('diverging', 1));  // significant: the ramp's red
  const texels = rampTexels('significance', 3);
  assert.deepEqual([...texels.slice(4 * 255, 4 * 255 + 3)], categoryColor('significance', 2));
  // Sensors: names from the sidecar, colours from the first sensor in the file.
  const sensor = attributeLegend('map_combined', 'sensor', {min: 0, max: 1, labels: ['lidar_h', 'sonar']});
  assert.deepEqual(legendCategories(sensor).map((c) => c.label), ['lidar_h', 'sonar']);
  assert.deepEqual(rampEnds(sensor), {vmin: -0.5, vmax: 1.5, categories: 2});
  assert.equal(attributeLegend('m', 'roughness', {min: 0.01, max: 0.5, no_data: 0.0095}).noData, 0.0095);
});

test('range and histogram equal a brute-force count', () => {
  const values = Float32Array.from({length: 10001}, (_, i) => Math.sin(i) * 3 + (i % 7));
  const {min, max} = finiteRange(values);
  assert.equal(min, Math.min(...values));
  assert.equal(max, Math.max(...values));
  const bins = 17;
  const counts = histogram(values, bins, min, max);
  assert.equal(counts.reduce((a, b) => a + b, 0), values.length);
  const width = (max - min) / bins;
  for (let b = 0; b < bins; b += 1) {
    const lo = min + b * width;
    const hi = b === bins - 1 ? Infinity : min + (b + 1) * width;
    const brute = values.filter((v) => v >= lo && v < hi).length;
    assert.ok(Math.abs(brute - counts[b]) <= 2, `bin ${b}: ${brute} vs ${counts[b]}`);  // float edges
  }
  const xyz = Float32Array.from([0, 0, 5, 1, 1, -2, 2, 2, 9]);
  assert.deepEqual(finiteRange(xyz, 3, 2), {min: -2, max: 9});
});

// docs/artifacts.md: where a metric is undefined a point holds the attribute's no_data, just
// below its smallest defined value; the range of the defined values leaves it out, and the
// shader greys every value below the legend's minimum.
test('no_data is left out of the range and greyed below the legend', () => {
  const noData = 0.01 - 0.5 / 1024;
  const values = Float32Array.from([0.01, 0.2, noData, 0.51, noData]);
  assert.deepEqual(finiteRange(values), {min: Math.fround(noData), max: Math.fround(0.51)});
  assert.deepEqual(finiteRange(values, 1, 0, Math.fround(noData)), {min: Math.fround(0.01), max: Math.fround(0.51)});
  assert.equal(noDataBelow({min: 0.01, max: 0.51, ramp: 'viridis', noData}), 0.01);
  assert.equal(noDataBelow({min: 0.01, max: 0.51, ramp: 'viridis'}), NO_NO_DATA);
  assert.equal(noDataBelow({min: 0, max: 2, ramp: 'categorical', noData: -1}), NO_NO_DATA);
});

test('the camera survives the URL to the millimetre and junk is refused', () => {
  const text = encodeCamera({x: 1.23456, y: -2, z: 3e-4}, {x: 10, y: 20.0004, z: -30});
  assert.equal(text, '1.235,-2,0,10,20,-30');
  assert.deepEqual(decodeCamera(text), {position: {x: 1.235, y: -2, z: 0}, target: {x: 10, y: 20, z: -30}});
  for (const bad of ['', '1,2,3', '1,2,3,4,5,x', '1,2,3,1,2,3', '1,,3,4,5,6', null, 'NaN,1,1,1,1,1'])
    assert.equal(decodeCamera(bad), null, String(bad));
});

test('even thinning keeps every k-th point and its attributes together', () => {
  assert.equal(strideFor(14e6, 3e6), 5);
  assert.equal(strideFor(100, 3e6), 1);
  const xyz = Float32Array.from({length: 30}, (_, i) => i);  // 10 points
  assert.deepEqual([...strided(xyz, 3, 4)], [0, 1, 2, 12, 13, 14, 24, 25, 26]);
  const values = Float32Array.from({length: 10}, (_, i) => i * 10);
  assert.deepEqual([...strided(values, 1, 4)], [0, 40, 80]);
});

test('residual CSV: columns by name, errors naming file and line', () => {
  const csv = 'state,t,x_model_m,y_model_m,z_model_m,residual_m\ngicp,1.5,1,2,3,0.25\nba,1.5,1,2,3,-0.01\n';
  const rows = parseResiduals(csv, 'dvl_residuals.csv');
  assert.deepEqual(rows.gicp, [{x: 1, y: 2, z: 3, r: 0.25}]);
  assert.deepEqual(rows.ba, [{x: 1, y: 2, z: 3, r: -0.01}]);
  assert.throws(() => parseResiduals('state,t,x\n', 'f.csv'), /f\.csv: line 1: no column "x_model_m"/);
  assert.throws(() => parseResiduals(`${csv}ba,2,1,2,zz,0\n`, 'f.csv'), /f\.csv: line 4: expected numbers/);
});

test('Draco attribute ids come from the sidecar; position defaults to 0', () => {
  const config = taskConfigFor({attributes: {intensity: {unique_id: 1}, sensor: {unique_id: 2}, bad: {}}});
  assert.deepEqual(config.attributeIDs, {position: 0, intensity: 1, sensor: 2});
  assert.equal(config.useUniqueIDs, true);
  assert.deepEqual(taskConfigFor(null).attributeIDs, {position: 0});
  assert.equal(taskConfigFor({position_unique_id: 3}).attributeIDs.position, 3);
});

test('maps bigger than the point budget are drawn from their tiles, when they have them', async () => {
  const {useTiles, BIG_DRACO_BYTES} = await import('../../../web/js/viewer/lod_choice.js');
  const tiles = {name: 'tiles_combined.tar'};
  const small = {full: {size: 1000}, tiles};
  const big = {full: {size: BIG_DRACO_BYTES + 1}, tiles};
  const budget = 3000000;
  // By the sidecar's point count when there is one, else by the Draco file's size.
  assert.equal(useTiles(small, {points: budget + 1}, {budget}), true);
  assert.equal(useTiles(big, {points: budget}, {budget}), false);
  assert.equal(useTiles(big, null, {budget}), true);
  assert.equal(useTiles(small, null, {budget}), false);
  // The URL's ?lod= overrides; without tiles there is no choice.
  assert.equal(useTiles(small, null, {lod: 'tiles', budget}), true);
  assert.equal(useTiles(big, null, {lod: 'draco', budget}), false);
  assert.equal(useTiles({full: big.full, tiles: null}, null, {lod: 'tiles', budget}), false);
});

test('tileset extras give the legend its ranges and sensor names; a tileset without them, none', async () => {
  const {tilesetInfo} = await import('../../../web/js/viewer/tiles_layer.js');
  const tileset = {asset: {version: '1.0'}, extras: {keel: {map: 'combined', points: 14412345, tiles: 211,
    sensors: ['lidar_h', 'sonar'], attributes: {intensity: {min: 0, max: 255}, sensor: {min: 0, max: 1}}}}};
  assert.deepEqual(tilesetInfo(tileset), {points: 14412345, sensors: ['lidar_h', 'sonar'],
                                          attributes: {intensity: {min: 0, max: 255}, sensor: {min: 0, max: 1}}});
  assert.deepEqual(tilesetInfo({asset: {version: '1.0'}}), {points: NaN, attributes: {}, sensors: []});
});
