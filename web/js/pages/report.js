// The report view of a job, drawn from its report.json: every figure the stages measured.
// refine: Table II (MAP poses, refined without and with DVL side by side), ATE over time
// (trajectories.json), RPE, the DVL scale s_d and the DVL-IMU rotation with their sigma;
// map: Table V, the metric distributions as histograms, points per sensor and per filter;
// ba: the lambda=1 fraction per iteration (Fig. 16), cost per iteration (Fig. 17), DVL
// residual histograms after GICP and after the BA (Fig. 18c); inspect: the shapes table and,
// with ground truth, which objects were found or missed; compare: what changed between two
// jobs (report_compare.js).
// Every number printed carries data-key (its path in report.json) and data-value, so the
// browser test compares each one with report.json.
import {ApiError, fetchArtifactJson, jobsApi} from '../api.js';
import {h, message} from '../dom.js';
import {formatNumber, formatSeconds} from '../format.js';
import {drawnPlots, histogramPlot, linePlot} from '../plots.js';
import {jobHash} from '../router.js';
import {compareSection} from './report_compare.js';
import {cell, get, table, valueWithSigma} from './report_cells.js';

// ---- stages ---------------------------------------------------------------------------------

function stageTimes(report) {
  const seconds = report.stage_seconds || {};
  const names = Object.keys(report.stages || {});
  return h('section', {id: 'report-times'}, h('h2', null, 'Stages'),
    table('stage-times', ['stage', 'seconds'], names.map((s) => h('tr', null, h('td', null, s), cell(report, ['stage_seconds', s], 3)))));
}

function ingestSection(report) {
  const sensors = get(report, ['stages', 'ingest', 'sensors']) || {};
  const keys = ['count', 'rate_hz_measured', 'rate_hz_nominal', 'duration_s'];
  const present = keys.filter((k) => Object.values(sensors).some((s) => typeof s?.[k] === 'number'));
  return h('section', {id: 'report-ingest'}, h('h2', null, 'Ingest'),
    table('ingest-sensors', ['sensor', 'type', ...present], Object.entries(sensors).map(([name, s]) => h('tr', null,
      h('td', null, name), h('td', null, String(s?.type ?? '')),
      present.map((k) => cell(report, ['stages', 'ingest', 'sensors', name, k]))))));
}

const TABLE_II_ROWS = [['map', 'MAP poses (recorded)'], ['refined_without_dvl', 'refined, without DVL'],
                       ['refined_with_dvl', 'refined, with DVL']];

function refineSection(report, trajectories, trajectoriesError) {
  const base = ['stages', 'refine'];
  const el = h('section', {id: 'report-refine'}, h('h2', null, 'Refine'));
  const evaluation = get(report, [...base, 'evaluation']);
  if (evaluation) {
    const t = [...base, 'evaluation', 'table'];
    el.append(h('h3', null, 'Table II: trajectory error against ground truth'),
      table('table-ii', ['trajectory', 'ATE RMSE (m)', 'ATE mean (m)', 'ATE median (m)', 'ATE max (m)', 'ATE rot RMSE (°)',
                         'RPE RMSE (m)', 'RPE rot RMSE (°)'],
        TABLE_II_ROWS.filter(([row]) => get(report, [...t, row])).map(([row, label]) => h('tr', {dataset: {row}},
          h('td', null, label),
          cell(report, [...t, row, 'ate', 'translation_m', 'rmse']),
          cell(report, [...t, row, 'ate', 'translation_m', 'mean']),
          cell(report, [...t, row, 'ate', 'translation_m', 'median']),
          cell(report, [...t, row, 'ate', 'translation_m', 'max']),
          cell(report, [...t, row, 'ate', 'rotation_deg', 'rmse']),
          cell(report, [...t, row, 'rpe', 'translation_m', 'rmse']),
          cell(report, [...t, row, 'rpe', 'rotation_deg', 'rmse'])))),
      h('p', {class: 'muted'}, evaluation.ate_method || '', '. RPE: ', evaluation.rpe_method || ''),
      h('table', {class: 'figures-table', id: 'ate-reduction'}, h('tbody', null,
        h('tr', null, h('td', null, 'ATE reduction with DVL vs MAP poses (%)'), cell(report, [...base, 'evaluation', 'ate_reduction_with_dvl_vs_map_percent'], 3)),
        h('tr', null, h('td', null, 'ATE reduction without DVL vs MAP poses (%)'), cell(report, [...base, 'evaluation', 'ate_reduction_without_dvl_vs_map_percent'], 3)))));
    // RPE statistics side by side.
    el.append(h('h3', null, 'RPE'), table('rpe', ['trajectory', 'RMSE (m)', 'mean (m)', 'median (m)', 'std (m)', 'max (m)', 'pairs'],
      TABLE_II_ROWS.filter(([row]) => get(report, [...t, row, 'rpe', 'translation_m'])).map(([row, label]) => h('tr', null, h('td', null, label),
        ['rmse', 'mean', 'median', 'std', 'max', 'count'].map((k) => cell(report, [...t, row, 'rpe', 'translation_m', k]))))));
  } else {
    el.append(h('p', {class: 'muted'}, 'No ground truth in this mission: no ATE or RPE.'));
  }
  const dvl = get(report, [...base, 'dvl']);
  if (dvl) {
    const d = [...base, 'dvl'];
    el.append(h('h3', null, 'DVL calibration'), table('dvl-calibration', ['figure', 'estimate', 'σ', 'true', 'error vs truth'], [
      h('tr', null, h('td', null, 'scale s_d'), cell(report, [...d, 'dvl_scale', 'value'], 6), cell(report, [...d, 'dvl_scale', 'sigma'], 3),
        cell(report, [...d, 'dvl_scale', 'true'], 6), h('td', null)),
      ...['x', 'y', 'z'].map((axis, i) => h('tr', null, h('td', null, `DVL–IMU rotation, ${axis} (°)`),
        cell(report, [...d, 'dvl_rotation', 'correction_deg', i]), cell(report, [...d, 'dvl_rotation', 'sigma_deg', i], 3),
        h('td', null), cell(report, [...d, 'dvl_rotation', 'error_vs_truth_deg', i])))]),
      h('p', null, 's_d = ', valueWithSigma(report, [...d, 'dvl_scale', 'value'], [...d, 'dvl_scale', 'sigma'])));
  }
  const plots = h('div', {class: 'report-grid'});
  el.append(h('h3', null, 'ATE over time'), plots);
  if (trajectoriesError) {
    plots.append(message('warning', 'ATE over time cannot be drawn', trajectoriesError));
  } else if (trajectories) {
    const withAte = trajectories.trajectories.filter((t) => Array.isArray(t.ate_m) && Array.isArray(t.t));
    if (withAte.length === 0) plots.append(h('p', {class: 'muted'}, 'trajectories.json has no per-pose error (no ground truth).'));
    for (const t of withAte)
      linePlot(plots, {id: `ate-${t.name}`, title: `ATE of ${t.name} over time`, xLabel: 'time (s)', yLabel: 'error (m)',
                       x: t.t.map((s) => s - t.t[0]), series: [{label: `${t.name} (m)`, values: t.ate_m}]});
  }
  return el;
}

const METRICS = [['surface_density_per_m2', 'surface density (points/m²)'], ['roughness_m', 'roughness (m)'], ['planarity', 'planarity']];

function mapSection(report) {
  const base = ['stages', 'map'];
  const el = h('section', {id: 'report-map'}, h('h2', null, 'Map'));
  const tv = get(report, [...base, 'metrics', 'table_v']);
  if (tv) {
    el.append(h('h3', null, 'Table V: mean map metrics'),
      table('table-v', ['metric', ...tv.columns], tv.rows.map((row, i) => h('tr', {dataset: {metric: row.metric}},
        h('td', null, `${row.metric} (${row.unit})`), tv.columns.map((c) => cell(report, [...base, 'metrics', 'table_v', 'rows', i, c]))))));
    if (tv.ratios) {
      const r = [...base, 'metrics', 'table_v', 'ratios'];
      el.append(table('table-v-ratios', ['change of the inspection map vs the SLAM map', 'this job', 'paper (Table V)'],
        ['density_factor', 'roughness_change_percent', 'planarity_change_percent'].map((k) => h('tr', null, h('td', null, k),
          cell(report, [...r, k], 4), cell(report, [...r, 'paper_table_v', k], 4)))));
    }
  }
  const maps = get(report, [...base, 'metrics', 'maps']) || {};
  const grid = h('div', {class: 'report-grid'});
  el.append(h('h3', null, 'Metric distributions'), grid);
  for (const [mapName, metrics] of Object.entries(maps))
    for (const [key, label] of METRICS) {
      const d = metrics?.[key];
      if (!d?.histogram_edges || !d?.histogram_counts) continue;
      histogramPlot(grid, {id: `hist-${mapName}-${key}`, title: `${mapName}: ${label}`, xLabel: label,
                           edges: d.histogram_edges, series: [{label: mapName, counts: d.histogram_counts}]});
    }
  // Points per sensor, and per filter of each stage of its chain.
  const sensors = get(report, [...base, 'sensors']) || {};
  el.append(h('h3', null, 'Points per sensor'), table('points-per-sensor', ['sensor', 'scans', 'points in', 'points in the map'],
    Object.keys(sensors).map((name) => h('tr', {dataset: {sensor: name}}, h('td', null, name),
      cell(report, [...base, 'sensors', name, 'stats', 'scans']), cell(report, [...base, 'sensors', name, 'stats', 'points_in']),
      cell(report, [...base, 'sensors', name, 'map', 'points'])))));
  if (get(report, [...base, 'combined', 'points']) !== undefined)
    el.append(h('p', null, 'Combined map: ', h('span', {dataset: {key: [...base, 'combined', 'points'].join('.'),
      value: String(get(report, [...base, 'combined', 'points']))}}, formatNumber(get(report, [...base, 'combined', 'points']))), ' points'));
  const filterRows = [];
  for (const name of Object.keys(sensors))
    for (const stage of ['scan_stage', 'intermediary_stage', 'final_stage'])
      (get(report, [...base, 'sensors', name, 'stats', stage, 'filters']) || []).forEach((f, i) => filterRows.push(h('tr', null,
        h('td', null, name), h('td', null, stage.replace('_stage', '')), h('td', null, String(f.filter)),
        cell(report, [...base, 'sensors', name, 'stats', stage, 'filters', i, 'points_in']),
        cell(report, [...base, 'sensors', name, 'stats', stage, 'filters', i, 'points_out']))));
  if (filterRows.length) el.append(h('h3', null, 'Points per filter'), table('points-per-filter', ['sensor', 'stage', 'filter', 'points in', 'points out'], filterRows));
  return el;
}

function baSection(report) {
  const base = ['stages', 'ba'];
  const modes = get(report, [...base, 'modes']) || {};
  const names = Object.keys(modes);
  const el = h('section', {id: 'report-ba'}, h('h2', null, 'Model-assisted bundle adjustment'));
  const m = (name, ...path) => [...base, 'modes', name, ...path];
  el.append(table('ba-modes', ['mode', 'iterations', 'rejected steps', 'solve (s)', 'initial cost', 'final cost', 'landmarks', 'λ=1',
                               'DVL σ after GICP (m)', 'DVL σ after BA (m)', 'robust σ after GICP (m)', 'robust σ after BA (m)'],
    names.map((n) => h('tr', {dataset: {mode: n}}, h('td', null, n), cell(report, m(n, 'iterations')), cell(report, m(n, 'unsuccessful_steps')),
      cell(report, m(n, 'solve_time_s'), 3), cell(report, m(n, 'initial_cost')), cell(report, m(n, 'final_cost')),
      cell(report, m(n, 'landmarks')), cell(report, m(n, 'landmarks_lambda1')),
      cell(report, m(n, 'dvl_residuals_gicp', 'sigma_m')), cell(report, m(n, 'dvl_residuals_final', 'sigma_m')),
      cell(report, m(n, 'dvl_residuals_gicp', 'robust_sigma_m')), cell(report, m(n, 'dvl_residuals_final', 'robust_sigma_m'))))));
  const grid = h('div', {class: 'report-grid'});
  el.append(grid);
  const series = (key) => names.filter((n) => Array.isArray(modes[n]?.[key])).map((n) => ({label: n, values: modes[n][key]}));
  for (const [key, id, title, yLabel, log] of [
    ['lambda1_fraction_per_iteration', 'fig16', 'Fig. 16: fraction of landmarks with λ=1 per iteration', 'fraction', false],
    ['cost_per_iteration', 'fig17', 'Fig. 17: cost per iteration', 'cost', true]]) {
    const s = series(key);
    if (s.length === 0) continue;
    const longest = Math.max(...s.map((x) => x.values.length));
    const x = Array.from({length: longest}, (_, i) => i);
    linePlot(grid, {id, title, xLabel: 'iteration', yLabel, x, log,
                    series: s.map((x2) => ({label: x2.label, values: Array.from({length: longest}, (_, i) => x2.values[i] ?? null)}))});
  }
  for (const n of names) {
    const before = modes[n]?.dvl_residuals_gicp?.histogram;
    const after = modes[n]?.dvl_residuals_final?.histogram;
    if (!before?.counts || !after?.counts || before.counts.length !== after.counts.length) continue;
    const edges = Array.from({length: before.counts.length + 1}, (_, i) => before.first_edge_m + i * before.bin_m);
    histogramPlot(grid, {id: `fig18c-${n}`, title: `Fig. 18(c): DVL range residuals, ${n}`, xLabel: 'residual (m)', edges,
                         series: [{label: 'after GICP', counts: before.counts}, {label: 'after BA', counts: after.counts}]});
  }
  return el;
}

function inspectSection(report) {
  const base = ['stages', 'inspect'];
  const el = h('section', {id: 'report-inspect'}, h('h2', null, 'Inspect'));
  el.append(h('table', {class: 'figures-table', id: 'inspect-figures'}, h('tbody', null,
    [['τ (m)', 'tau_m'], ['deviation noise σ (m)', 'deviation_noise_sigma_m'], ['views', 'views'], ['detections', 'detections'],
     ['vertices moved', 'vertices_moved']].map(([label, key]) => h('tr', null, h('td', null, label), cell(report, [...base, key]))))));
  const shapes = get(report, [...base, 'shapes']) || [];
  el.append(h('h3', null, 'Shapes'), shapes.length === 0 ? h('p', {class: 'muted'}, 'No shape off the CAD model.')
    : table('inspect-shapes', ['id', 'centroid x (m)', 'y (m)', 'z (m)', 'height (m)', 'mean deviation (m)', 'landmarks', 'views'],
      shapes.map((s, i) => h('tr', null, cell(report, [...base, 'shapes', i, 'id']),
        cell(report, [...base, 'shapes', i, 'centroid_world', 0]), cell(report, [...base, 'shapes', i, 'centroid_world', 1]),
        cell(report, [...base, 'shapes', i, 'centroid_world', 2]), cell(report, [...base, 'shapes', i, 'height_m']),
        cell(report, [...base, 'shapes', i, 'mean_deviation_m']), cell(report, [...base, 'shapes', i, 'landmarks']),
        cell(report, [...base, 'shapes', i, 'detections'])))));
  const truth = get(report, [...base, 'truth']);
  if (truth) {
    const t = [...base, 'truth'];
    el.append(h('h3', null, 'Against ground truth'),
      h('p', null, 'found ', h('strong', {dataset: {key: [...t, 'found'].join('.'), value: String(truth.found)}}, String(truth.found)),
        ', missed ', h('strong', {dataset: {key: [...t, 'missed'].join('.'), value: String(truth.missed)}}, String(truth.missed)),
        ', false shapes ', h('strong', {dataset: {key: [...t, 'false_shapes'].join('.'), value: String(truth.false_shapes)}}, String(truth.false_shapes))),
      table('inspect-truth', ['object', 'radius (m)', 'true height (m)', 'found', 'shape', 'measured height (m)', 'height error (m)'],
        (truth.objects || []).map((o, i) => h('tr', {class: o.found ? 'found' : 'missed'}, h('td', null, String(o.kind)),
          cell(report, [...t, 'objects', i, 'radius_m']), cell(report, [...t, 'objects', i, 'true_height_m']),
          cell(report, [...t, 'objects', i, 'found']), cell(report, [...t, 'objects', i, 'shape_id']),
          cell(report, [...t, 'objects', i, 'measured_height_m']), cell(report, [...t, 'objects', i, 'height_error_m'])))));
  }
  return el;
}

// ---- the page ---------------------------------------------------------------------------------

export function mount(container, {id}) {
  let disposed = false;
  const disposers = [];  // what a section started that must stop with the page
  const body = h('div', {id: 'report'}, h('p', {class: 'muted'}, 'Reading report.json…'));
  container.append(h('div', {class: 'toolbar'}, h('h1', null, 'Report of job ', h('code', null, id)),
                     h('a', {href: jobHash(id)}, 'job'), h('a', {href: jobHash(id, 'viewer')}, '3D viewer')), body);
  drawnPlots.clear();

  async function load() {
    let list;
    try {
      ({artifacts: list} = await jobsApi.artifacts(id));
    } catch (e) {
      if (!disposed && !(e instanceof ApiError && e.status === 401))
        body.replaceChildren(message('error', 'The artifacts could not be listed', e instanceof ApiError ? e.describe() : e.message));
      return;
    }
    const byName = Object.fromEntries(list.map((a) => [a.name, a]));
    if (!byName['report.json']) {
      body.replaceChildren(message('info', 'report.json is missing', 'The job has not finished a stage yet, or its stages wrote no report.'));
      return;
    }
    let report;
    try {
      report = await fetchArtifactJson(byName['report.json']);
      if (!report || typeof report.stages !== 'object') throw new Error('report.json has no "stages" object');
    } catch (e) {
      if (!disposed) body.replaceChildren(message('error', 'report.json cannot be read', e.message));
      return;
    }
    let trajectories = null;
    let trajectoriesError = '';
    if (report.stages.refine) {
      if (!byName['trajectories.json']) trajectoriesError = 'trajectories.json is missing';
      else {
        try {
          trajectories = await fetchArtifactJson(byName['trajectories.json']);
          if (!Array.isArray(trajectories?.trajectories)) throw new Error('trajectories.json has no "trajectories" list');
        } catch (e) {
          trajectoriesError = e.message;
          trajectories = null;
        }
      }
    }
    if (disposed) return;
    body.replaceChildren();
    if (byName['report.html'])
      body.append(h('p', {class: 'muted'}, 'The same figures as one file to send: report.html among the job\'s artifacts.'));
    body.append(stageTimes(report));
    const sections = [['ingest', ingestSection], ['refine', (r) => refineSection(r, trajectories, trajectoriesError)],
                      ['map', mapSection], ['ba', baSection], ['inspect', inspectSection],
                      ['compare', (r) => compareSection(r, disposers)]];
    for (const [stage, render] of sections) {
      if (!report.stages[stage]) continue;
      try {
        body.append(render(report));
      } catch (e) {
        body.append(message('error', `The ${stage} section cannot be drawn`, e.message));
      }
    }
    window.keelReport = {report, plots: drawnPlots, totalSeconds: Object.values(report.stage_seconds || {}).reduce((a, b) => a + b, 0)};
    document.body.dataset.reportReady = 'true';
    body.append(h('p', {class: 'muted'}, `Total stage time ${formatSeconds(window.keelReport.totalSeconds)}.`));
  }

  load();
  return () => {
    disposed = true;
    for (const dispose of disposers) dispose();
    delete document.body.dataset.reportReady;
    delete window.keelReport;
  };
}
