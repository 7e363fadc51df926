// The compare report's derived tables (docs/artifacts.md, compare): which of the two runs'
// figures differ, most changed first, and the relative ATE as rows. Pure (tested in node).

// The magnitude a figure's change is sorted by: |relative|, or Infinity for a figure that
// was 0 in A and is not in B (no relative change is defined: it appeared from nothing).
function changeMagnitude(row) {
  if (Number.isFinite(row.relative)) return Math.abs(row.relative);
  return row.difference !== 0 ? Infinity : 0;
}

// The rows of `runs.figures` whose values differ, as [{index (in figures), row}], ordered by
// |relative| (largest first); ties by |difference|, then by name, so the order is stable.
export function figuresThatDiffer(figures) {
  const out = [];
  (figures || []).forEach((row, index) => {
    if (row && typeof row.a === 'number' && typeof row.b === 'number' && row.a !== row.b) out.push({index, row});
  });
  return out.sort((x, y) => changeMagnitude(y.row) - changeMagnitude(x.row) ||
                            Math.abs(y.row.difference) - Math.abs(x.row.difference) ||
                            String(x.row.figure).localeCompare(String(y.row.figure)));
}

// `runs.relative_ate` as table rows: one per trajectory and alignment ({trajectory,
// alignment ('none' | 'se3'), key (its path below relative_ate)}), or one with the error
// for a trajectory that could not be compared ({trajectory, error}).
export function relativeAteRows(relativeAte) {
  const rows = [];
  for (const [trajectory, entry] of Object.entries(relativeAte || {})) {
    if (typeof entry?.error === 'string') {
      rows.push({trajectory, error: entry.error});
      continue;
    }
    for (const key of Object.keys(entry || {}).filter((k) => k.startsWith('ate_')).sort())
      rows.push({trajectory, alignment: key.slice(4), key: [trajectory, key]});
  }
  return rows;
}
