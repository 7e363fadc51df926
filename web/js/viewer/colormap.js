// Colour ramps for the viewer and its legends: viridis (sequential, for height, intensity
// and the point metrics), a diverging blue-white-red for signed values (deviations, changes),
// and categorical palettes (sensors; the significance of a change). Pure (tested in node).

// Viridis at 9 evenly spaced stops (matplotlib's values), linearly interpolated.
const VIRIDIS = [
  [68, 1, 84], [71, 44, 122], [59, 81, 139], [44, 113, 142], [33, 144, 141],
  [39, 173, 129], [92, 200, 99], [170, 220, 50], [253, 231, 37]];
// Blue-white-red (ColorBrewer RdBu, reversed) for signed values around zero.
const DIVERGING = [[33, 102, 172], [103, 169, 207], [209, 229, 240], [247, 247, 247],
  [253, 219, 199], [239, 138, 98], [178, 24, 43]];
// Categorical (Tableau 10).
export const CATEGORICAL = [
  [78, 121, 167], [242, 142, 43], [225, 87, 89], [118, 183, 178], [89, 161, 79],
  [237, 201, 72], [176, 122, 161], [255, 157, 167], [156, 117, 95], [186, 176, 172]];
// A change's significance, values -1, 0, 1 (docs/artifacts.md `significant`): undefined in
// mid grey, not significant in a pale blue-grey that recedes, significant in the diverging
// ramp's red, so what changed stands out.
const SIGNIFICANCE = [[150, 150, 150], [196, 210, 226], [178, 24, 43]];

const RAMPS = {viridis: VIRIDIS, diverging: DIVERGING};
const PALETTES = {categorical: CATEGORICAL, significance: SIGNIFICANCE};

// Whether a legend's ramp is a palette of flat colours, one per integer value.
export function isCategorical(ramp) {
  return ramp in PALETTES;
}

// The flat colour of category `index` (0 = the palette's first) of a palette.
export function categoryColor(palette, index) {
  const colors = PALETTES[palette] || CATEGORICAL;
  return colors[((index % colors.length) + colors.length) % colors.length];
}

// [r, g, b] in 0..255 at t in [0, 1] (clamped; NaN gives grey).
export function rampColor(name, t) {
  if (!Number.isFinite(t)) return [128, 128, 128];
  const stops = RAMPS[name] || VIRIDIS;
  const x = Math.min(1, Math.max(0, t)) * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(x));
  const f = x - i;
  return stops[i].map((c, k) => Math.round(c + f * (stops[i + 1][k] - c)));
}

// A 256 x 1 RGBA ramp for a texture, or `count` flat colours of the palette `name`
// (categorical when it names a ramp) stretched over it.
export function rampTexels(name, count = 0) {
  const texels = new Uint8Array(256 * 4);
  for (let i = 0; i < 256; i += 1) {
    const color = count > 0 ? categoryColor(isCategorical(name) ? name : 'categorical', Math.min(count - 1, Math.floor((i / 256) * count)))
        : rampColor(name, i / 255);
    texels.set([...color, 255], i * 4);
  }
  return texels;
}

export function cssColor([r, g, b]) {
  return `rgb(${r}, ${g}, ${b})`;
}

// A CSS linear-gradient of the part [from, to] of a ramp, for the legend bar (a legend of a
// symmetric ramp shows only the part its values span).
export function cssGradient(name, from = 0, to = 1) {
  const stops = [];
  for (let i = 0; i <= 8; i += 1) stops.push(`${cssColor(rampColor(name, from + (to - from) * (i / 8)))} ${(i / 8) * 100}%`);
  return `linear-gradient(to right, ${stops.join(', ')})`;
}

// The ends of a ramp centred on zero that holds [min, max]: a signed value's colour then
// says its sign (white at no change), whatever the range's asymmetry. Values all zero (a job
// compared with itself) get a ramp of width 2, so zero still falls on its white middle.
export function symmetricRange(min, max) {
  const extent = Math.max(Math.abs(min), Math.abs(max));
  if (!Number.isFinite(extent)) return {min: NaN, max: NaN};
  return extent > 0 ? {min: -extent, max: extent} : {min: -1, max: 1};
}

// Min and max of the finite values of an array (strided: every `stride`-th from `offset`),
// leaving out the values equal to `skip` (an attribute's no_data).
export function finiteRange(array, stride = 1, offset = 0, skip = undefined) {
  let min = Infinity;
  let max = -Infinity;
  for (let i = offset; i < array.length; i += stride) {
    const v = array[i];
    if (v === skip) continue;
    if (v < min) min = v;
    if (v > max) max = v;
  }
  return min <= max ? {min, max} : {min: NaN, max: NaN};
}

// Counts of values in `bins` equal bins over [min, max] (values outside are clamped in).
export function histogram(values, bins, min, max) {
  const counts = new Array(bins).fill(0);
  const width = (max - min) / bins;
  for (let i = 0; i < values.length; i += 1) {
    const v = values[i];
    if (!Number.isFinite(v)) continue;
    let b = width > 0 ? Math.floor((v - min) / width) : 0;
    if (b < 0) b = 0;
    if (b >= bins) b = bins - 1;
    counts[b] += 1;
  }
  return counts;
}
