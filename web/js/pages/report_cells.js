// The report view's building blocks: a figure of report.json looked up by its path, printed
// in a cell that carries data-key (the path, dot-joined) and data-value (the figure as
// report.json has it), so the browser test compares every number shown with report.json.
import {h} from '../dom.js';
import {formatNumber} from '../format.js';

export function get(object, path) {
  let value = object;
  for (const key of path) {
    if (value === null || value === undefined) return undefined;
    value = value[key];
  }
  return value;
}

// The text of a figure: a number with `digits` significant digits, yes/no, a string as it
// is, anything else as JSON.
export function figureText(value, digits = 4) {
  if (typeof value === 'boolean') return value ? 'yes' : 'no';
  if (typeof value === 'number' || typeof value === 'string') return formatNumber(value, digits);
  return JSON.stringify(value);
}

// An element showing the figure at `path` of the report (or '–' without data-key when absent).
export function figure(tag, report, path, digits = 4, props = {}) {
  const value = get(report, path);
  const el = h(tag, props);
  if (value === undefined || value === null) {
    el.textContent = '–';
    return el;
  }
  el.dataset.key = path.join('.');
  el.dataset.value = typeof value === 'object' ? JSON.stringify(value) : String(value);
  el.textContent = figureText(value, digits);
  return el;
}

// A table cell with the figure at `path` of the report (or '–').
export function cell(report, path, digits = 4) {
  return figure('td', report, path, digits, {class: 'num'});
}

export function table(id, head, rows) {
  return h('table', {class: 'figures-table', id},
           h('thead', null, h('tr', null, head.map((c) => h('th', null, c)))), h('tbody', null, rows));
}

// A label-value table: rows [label, path, digits?].
export function factsTable(id, report, rows) {
  return h('table', {class: 'figures-table facts-table', id}, h('tbody', null,
    rows.map(([label, path, digits]) => h('tr', null, h('td', null, label), cell(report, path, digits)))));
}

export function valueWithSigma(report, valuePath, sigmaPath, unit = '') {
  return h('span', null, cell(report, valuePath).textContent, ' ± ',
           h('span', {class: 'sigma'}, cell(report, sigmaPath).textContent), unit);
}
