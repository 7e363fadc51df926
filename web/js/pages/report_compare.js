// The report view's section of a compare job (stages.compare, docs/artifacts.md "compare"):
// the two jobs; the maps' registration, per-map change figures, distributions and change
// histograms; the hull's model-frame difference, deviation change and per-shape growth; the
// runs' options and figures that differ and the relative ATE. Every number carries data-key
// and data-value (report_cells.js).
import {h} from '../dom.js';
import {figuresThatDiffer, relativeAteRows} from '../compare_model.js';
import {histogramPlot} from '../plots.js';
import {jobHash} from '../router.js';
import {VirtualRows} from '../virtual_rows.js';
import {cell, factsTable, figure, get, table} from './report_cells.js';

const BASE = ['stages', 'compare'];
const DISTRIBUTION_KEYS = ['count', 'mean', 'std', 'min', 'p05', 'median', 'p95', 'max'];
const DISTRIBUTION_HEAD = ['count', 'mean', 'std', 'min', 'p05', 'median', 'p95', 'max'];

function jobsTable(report) {
  const link = (key) => {
    const id = get(report, [...BASE, key]);
    return h('td', null, figure('a', report, [...BASE, key], 4, {href: typeof id === 'string' ? jobHash(id) : undefined}),
             typeof id === 'string' ? [' (', h('a', {href: jobHash(id, 'report')}, 'report'), ')'] : null);
  };
  return h('table', {class: 'figures-table facts-table', id: 'compare-jobs'}, h('tbody', null,
    h('tr', null, h('td', null, 'job A (earlier)'), link('job_a')),
    h('tr', null, h('td', null, 'job B (later)'), link('job_b')),
    h('tr', null, h('td', null, 'compared'), h('td', null, figure('span', report, [...BASE, 'kind'])))));
}

// ---- maps -------------------------------------------------------------------------------------

function registrationTable(report) {
  const r = [...BASE, 'maps', 'registration'];
  return factsTable('compare-registration', report, [
    ['translation ‖t‖ (m)', [...r, 'T_a_b', 'translation_norm_m']],
    ['translation x (m)', [...r, 'T_a_b', 'translation_m', 0]],
    ['translation y (m)', [...r, 'T_a_b', 'translation_m', 1]],
    ['translation z (m)', [...r, 'T_a_b', 'translation_m', 2]],
    ['rotation (°)', [...r, 'T_a_b', 'rotation_deg']],
    ['RMS on stable structure (m)', [...r, 'rms_stable_m']],
    ['stable fraction', [...r, 'stable_fraction']],
    ['stable pairs', [...r, 'stable_pairs']],
    ['converged', [...r, 'converged']],
    ['iterations', [...r, 'iterations']],
    ['conditioning', [...r, 'conditioning']],
    ['time (s)', [...r, 'seconds'], 3]]);
}

function perMapTable(report, names) {
  const m = (name, ...path) => [...BASE, 'maps', 'maps', name, ...path];
  return table('compare-maps', ['map', 'points A', 'points B', 'core points', 'defined', 'significant', 'compared area (m²)',
                                'significant area (m²)', 'significant fraction', 'added (m²)', 'removed (m²)',
                                'registration error (m)', 'locally adjusted tiles', 'points/s'],
    names.map((name) => h('tr', {dataset: {map: name}}, h('td', null, name),
      cell(report, m(name, 'points_a')), cell(report, m(name, 'points_b')), cell(report, m(name, 'core_points')),
      cell(report, m(name, 'defined_core_points')), cell(report, m(name, 'significant_core_points')),
      cell(report, m(name, 'compared_area_m2')), cell(report, m(name, 'significant_area_m2')),
      cell(report, m(name, 'significant_fraction')), cell(report, m(name, 'significant_added_area_m2')),
      cell(report, m(name, 'significant_removed_area_m2')), cell(report, m(name, 'registration_error_m')),
      cell(report, m(name, 'local_registration', 'adjusted_tiles')), cell(report, m(name, 'points_per_second'), 3))));
}

const CHANGE_QUANTITIES = [['m3c2_m', 'M3C2 change (m)'], ['lod95_m', 'level of detection, 95 % (m)'], ['c2c_m', 'C2C distance to A (m)']];

function distributionsTable(report, names) {
  const rows = [];
  for (const name of names)
    for (const [key, label] of CHANGE_QUANTITIES) {
      const path = [...BASE, 'maps', 'maps', name, key];
      if (!get(report, path)) continue;
      rows.push(h('tr', null, h('td', null, name), h('td', null, label), DISTRIBUTION_KEYS.map((k) => cell(report, [...path, k]))));
    }
  return table('compare-distributions', ['map', 'quantity', ...DISTRIBUTION_HEAD], rows);
}

function changeHistograms(report, names) {
  const grid = h('div', {class: 'report-grid'});
  for (const name of names) {
    const path = [...BASE, 'maps', 'maps', name, 'change_histogram'];
    const histogram = get(report, path);
    if (!Array.isArray(histogram?.edges_m) || !Array.isArray(histogram?.area_m2)) continue;
    const box = h('div');
    grid.append(box);
    histogramPlot(box, {id: `change-${name}`, title: `${name}: area by M3C2 change`, xLabel: 'M3C2 change B − A (m)', yLabel: 'area (m²)',
                        edges: histogram.edges_m, series: [{label: `${name} (m²)`, counts: histogram.area_m2}]});
    box.append(h('p', {class: 'muted'}, 'core points beyond the range: ', figure('span', report, [...path, 'below']), ' below, ',
                 figure('span', report, [...path, 'above']), ' above'));
  }
  return grid;
}

function mapsPart(report) {
  const names = Object.keys(get(report, [...BASE, 'maps', 'maps']) || {});
  const normals = get(report, [...BASE, 'maps', 'normals_face']);
  return [
    h('h3', null, 'Registration of B onto A'), registrationTable(report),
    h('h3', null, 'Change per map (M3C2)'),
    normals ? h('p', {class: 'muted'}, `Positive change: B lies on the side of the normal, which faces ${normals}.`) : null,
    perMapTable(report, names),
    h('h3', null, 'Distributions'), distributionsTable(report, names),
    h('h3', null, 'Change histograms'), changeHistograms(report, names)];
}

// ---- hull -------------------------------------------------------------------------------------

function hullFacts(report) {
  const b = [...BASE, 'hull'];
  return factsTable('compare-hull', report, [
    ['x_gM difference, translation ‖t‖ (m)', [...b, 'x_gM_difference', 'translation_norm_m']],
    ['x_gM difference, rotation (°)', [...b, 'x_gM_difference', 'rotation_deg']],
    ['shapes registered by ‖t‖ (m)', [...b, 'shape_registration', 'translation_norm_m']],
    ['shapes agreeing on it', [...b, 'shape_registration', 'pairs']],
    ['x_gM of A, ‖t‖ (m)', [...b, 'x_gM_a', 'translation_norm_m']],
    ['x_gM of B, ‖t‖ (m)', [...b, 'x_gM_b', 'translation_norm_m']],
    ['vertices', [...b, 'vertices']],
    ['vertex pairing, median (m)', [...b, 'vertex_pairing_median_m']],
    ['vertex pairing, max (m)', [...b, 'vertex_pairing_max_m']],
    ['shapes in A', [...b, 'shapes_a']],
    ['shapes in B', [...b, 'shapes_b']],
    ['kept', [...b, 'kept']],
    ['new', [...b, 'new']],
    ['gone', [...b, 'gone']],
    ['significantly grown', [...b, 'significantly_grown']]]);
}

function deviationChange(report) {
  const path = [...BASE, 'hull', 'deviation_change_m'];
  const d = get(report, path);
  const el = [table('compare-deviation-change', DISTRIBUTION_HEAD, [h('tr', null, DISTRIBUTION_KEYS.map((k) => cell(report, [...path, k])))])];
  if (Array.isArray(d?.histogram_edges) && Array.isArray(d?.histogram_counts)) {
    const grid = h('div', {class: 'report-grid'});
    histogramPlot(grid, {id: 'hull-deviation-change', title: 'Deviation change of the vertices moved in A or B', xLabel: 'deviation change B − A (m)',
                         edges: d.histogram_edges, series: [{label: 'vertices', counts: d.histogram_counts}]});
    el.push(grid);
  }
  return el;
}

function shapesTable(report) {
  const shapes = get(report, [...BASE, 'hull', 'shapes']) || [];
  if (shapes.length === 0) return h('p', {class: 'muted'}, 'No shape in either job.');
  const s = (i, ...path) => cell(report, [...BASE, 'hull', 'shapes', i, ...path]);
  return table('compare-shapes', ['status', 'shape A', 'shape B', 'centroid x (m)', 'y (m)', 'z (m)', 'centroid shift (m)',
                                  'height A (m)', 'height B (m)', 'height growth (m)', '± σ (m)',
                                  'footprint A (m²)', 'footprint B (m²)', 'footprint growth (m²)', '± σ (m²)', 'significant growth'],
    shapes.map((shape, i) => h('tr', {class: `shape-${shape?.status}${shape?.significant_growth ? ' significant' : ''}`, dataset: {status: String(shape?.status)}},
      h('td', null, String(shape?.status ?? '')), s(i, 'shape_a'), s(i, 'shape_b'),
      s(i, 'centroid_model_m', 0), s(i, 'centroid_model_m', 1), s(i, 'centroid_model_m', 2), s(i, 'centroid_shift_m'),
      s(i, 'height_a_m'), s(i, 'height_b_m'), s(i, 'height_growth_m'), s(i, 'height_growth_sigma_m'),
      s(i, 'footprint_a_m2'), s(i, 'footprint_b_m2'), s(i, 'footprint_growth_m2'), s(i, 'footprint_growth_sigma_m2'),
      s(i, 'significant_growth'))));
}

function hullPart(report) {
  const note = get(report, [...BASE, 'hull', 'footprint_note']);
  return [h('h3', null, 'Hull (CAD model frame)'), hullFacts(report),
          h('h3', null, 'Deviation change'), ...deviationChange(report),
          h('h3', null, 'Shapes: growth from A to B'), shapesTable(report),
          typeof note === 'string' ? h('p', {class: 'muted'}, note) : null];
}

// ---- runs -------------------------------------------------------------------------------------

function optionsTable(report) {
  const rows = get(report, [...BASE, 'runs', 'options_differ']) || [];
  if (rows.length === 0) return h('p', {class: 'muted', id: 'compare-options-same'}, 'Both jobs ran with the same options.');
  const o = [...BASE, 'runs', 'options_differ'];
  return table('compare-options', ['option', 'A', 'B'],
    rows.map((row, i) => h('tr', null, h('td', null, String(row?.option ?? '')), cell(report, [...o, i, 'a']), cell(report, [...o, i, 'b']))));
}

// Every figure that differs, most changed first, in a scrolling table that keeps only the
// rows in view in the page (two reports hold thousands of figures).
function figuresTable(report, disposers) {
  const f = [...BASE, 'runs', 'figures'];
  const items = figuresThatDiffer(get(report, f));
  if (items.length === 0) return [h('p', {class: 'muted'}, 'No figure differs.')];
  const columns = ['figure', 'A', 'B', 'B − A', 'relative (B − A) / |A|'];
  const tbody = h('tbody');
  const scroller = h('div', {class: 'figures-scroll', id: 'compare-figures-scroll'},
    h('table', {class: 'figures-table virtual', id: 'compare-figures'}, h('thead', null, h('tr', null, columns.map((c) => h('th', null, c)))), tbody));
  const renderRow = ({index, row}) => h('tr', {dataset: {index: String(index)}},
    h('td', {class: 'figure-name', title: String(row.figure)}, String(row.figure)),
    cell(report, [...f, index, 'a']), cell(report, [...f, index, 'b']), cell(report, [...f, index, 'difference']),
    cell(report, [...f, index, 'relative'], 3));
  const rows = new VirtualRows({scroller, tbody, renderRow, keyOf: (item) => String(item.index), columns: columns.length, rowHeight: 29});
  rows.setItems(items);
  disposers.push(() => rows.dispose());
  // The stage lists at most a set number of figures (figures_listed of figures_in_both).
  const listed = get(report, [...BASE, 'runs', 'figures_listed']);
  const inBoth = get(report, [...BASE, 'runs', 'figures_in_both']);
  const partial = Number.isFinite(listed) && Number.isFinite(inBoth) && listed < inBoth ? ` among the ${listed.toLocaleString('en-US')} listed` : '';
  return [h('p', {class: 'muted', id: 'compare-figures-count', dataset: {rows: String(items.length)}},
            `${items.length.toLocaleString('en-US')} figures differ${partial}, ordered by |relative change| (a figure that was 0 in A first).`),
          scroller];
}

function relativeAteTable(report) {
  const base = [...BASE, 'runs', 'relative_ate'];
  const rows = relativeAteRows(get(report, base));
  if (rows.length === 0) return h('p', {class: 'muted'}, 'Neither job has a trajectory both can be compared on.');
  const columns = ['trajectory', 'alignment', 'RMSE (m)', 'mean (m)', 'median (m)', 'max (m)', 'rot RMSE (°)', 'rot max (°)', 'poses'];
  return table('compare-relative-ate', columns, rows.map((row) => {
    if (row.error !== undefined)
      return h('tr', {class: 'not-comparable'}, h('td', null, row.trajectory), h('td', {colSpan: columns.length - 1, class: 'muted'}, row.error));
    const p = (...path) => cell(report, [...base, ...row.key, ...path]);
    return h('tr', null, h('td', null, row.trajectory), h('td', null, row.alignment),
      p('translation_m', 'rmse'), p('translation_m', 'mean'), p('translation_m', 'median'), p('translation_m', 'max'),
      p('rotation_deg', 'rmse'), p('rotation_deg', 'max'), p('translation_m', 'count'));
  }));
}

function runsPart(report, disposers) {
  const r = [...BASE, 'runs'];
  return [h('h3', null, 'Runs'), factsTable('compare-runs', report, [
            ['same mission', [...r, 'same_mission']], ['figures in both', [...r, 'figures_in_both']],
            ['figures that differ', [...r, 'figures_that_differ']], ['figures only in A', [...r, 'figures_only_in_a']],
            ['figures only in B', [...r, 'figures_only_in_b']], ['figures listed', [...r, 'figures_listed']]]),
          h('h3', null, 'Options that differ'), optionsTable(report),
          h('h3', null, 'Figures that differ'), ...figuresTable(report, disposers),
          h('h3', null, 'Relative ATE (B against A)'), relativeAteTable(report)];
}

// `disposers`: the section adds what the page must stop when it is left.
export function compareSection(report, disposers) {
  const c = get(report, BASE);
  const el = h('section', {id: 'report-compare'}, h('h2', null, 'Compare: what changed from A to B'), jobsTable(report));
  if (c.maps) el.append(h('div', {id: 'compare-maps-part'}, mapsPart(report)));
  if (c.hull) el.append(h('div', {id: 'compare-hull-part'}, hullPart(report)));
  if (c.runs) el.append(h('div', {id: 'compare-runs-part'}, runsPart(report, disposers)));
  return el;
}
