// The point-to-plane residual of the calibration page: how far candidate points lie from
// the reference sensor's surfaces. The reference window's points, in the world, go into a
// voxel hash once per window; each voxel with enough points gets the plane of its points'
// covariance (centroid and the eigenvector of the smallest eigenvalue, as in point-to-plane
// ICP, Chen & Medioni 1992), kept when its points are flat (smallest eigenvalue well below
// the middle one). A candidate point is matched to the plane whose centroid is nearest among
// the 27 voxels around it; its residual is |n . (p - c)| in metres. Pure (tested in node).
import {transformPoint} from './extrinsic.js';

export const PLANE_DEFAULTS = {
  voxel_m: 0.5,
  min_points: 6,
  // lambda_min / lambda_mid at most this: the voxel's points are a plane, not a blob or a line.
  max_flatness: 0.1,
  // The dense lookup grid's largest size (64 MiB of Int32); beyond, a hash.
  max_grid_cells: 1 << 24,
};

// Candidate points whose residual the page computes on every step.
export const SAMPLE_POINTS = 5000;

const SPAN = 131072;  // voxel indices per axis around the first point: 65 km at 0.5 m
const HALF = SPAN / 2;
const key = (ix, iy, iz) => ((ix + HALF) * SPAN + (iy + HALF)) * SPAN + (iz + HALF);

// Eigenvalues (ascending) and unit eigenvectors of a symmetric 3x3 matrix [a00, a01, a02,
// a11, a12, a22] by cyclic Jacobi rotations (Golub & Van Loan, Algorithm 8.4.3).
export function symmetricEigen3([a00, a01, a02, a11, a12, a22]) {
  const a = [[a00, a01, a02], [a01, a11, a12], [a02, a12, a22]];
  const v = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
  for (let sweep = 0; sweep < 32; sweep += 1) {
    const off = a[0][1] ** 2 + a[0][2] ** 2 + a[1][2] ** 2;
    if (off < 1e-30 * (a[0][0] ** 2 + a[1][1] ** 2 + a[2][2] ** 2) || off === 0) break;
    for (const [p, q] of [[0, 1], [0, 2], [1, 2]]) {
      if (a[p][q] === 0) continue;
      const theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
      const t = Math.sign(theta || 1) / (Math.abs(theta) + Math.sqrt(theta * theta + 1));
      const c = 1 / Math.sqrt(t * t + 1);
      const s = t * c;
      for (let k = 0; k < 3; k += 1) {
        const akp = a[k][p];
        const akq = a[k][q];
        a[k][p] = c * akp - s * akq;
        a[k][q] = s * akp + c * akq;
      }
      for (let k = 0; k < 3; k += 1) {
        const apk = a[p][k];
        const aqk = a[q][k];
        a[p][k] = c * apk - s * aqk;
        a[q][k] = s * apk + c * aqk;
      }
      for (let k = 0; k < 3; k += 1) {
        const vkp = v[k][p];
        const vkq = v[k][q];
        v[k][p] = c * vkp - s * vkq;
        v[k][q] = s * vkp + c * vkq;
      }
    }
  }
  const order = [0, 1, 2].sort((i, j) => a[i][i] - a[j][j]);
  return {values: order.map((i) => a[i][i]), vectors: order.map((i) => [v[0][i], v[1][i], v[2][i]])};
}

// The planes of a window of reference scans: scans = [{points: Float32Array (x, y, z in the
// sensor frame), matrix: T_world_sensor (extrinsic.js layout)}].
export function buildPlaneMap(scans, options = {}) {
  const {voxel_m, min_points, max_flatness, max_grid_cells} = {...PLANE_DEFAULTS, ...options};
  const origin = [0, 0, 0];
  let haveOrigin = false;
  const sums = new Map();  // key -> Float64Array [n, sx, sy, sz, sxx, sxy, sxz, syy, syz, szz]
  const p = new Float64Array(3);
  for (const {points, matrix} of scans) {
    for (let i = 0; i < points.length; i += 3) {
      transformPoint(matrix, points[i], points[i + 1], points[i + 2], p);
      if (!haveOrigin) {
        for (let d = 0; d < 3; d += 1) origin[d] = Math.floor(p[d] / voxel_m) * voxel_m;
        haveOrigin = true;
      }
      // Sums of coordinates relative to the origin: no cancellation with UTM-sized values.
      const x = p[0] - origin[0];
      const y = p[1] - origin[1];
      const z = p[2] - origin[2];
      const ix = Math.floor(x / voxel_m);
      const iy = Math.floor(y / voxel_m);
      const iz = Math.floor(z / voxel_m);
      if (Math.abs(ix) >= HALF || Math.abs(iy) >= HALF || Math.abs(iz) >= HALF) continue;
      const k = key(ix, iy, iz);
      let s = sums.get(k);
      if (!s) sums.set(k, (s = new Float64Array(10)));
      s[0] += 1; s[1] += x; s[2] += y; s[3] += z;
      s[4] += x * x; s[5] += x * y; s[6] += x * z; s[7] += y * y; s[8] += y * z; s[9] += z * z;
    }
  }
  // The planes in one Float64Array (cx, cy, cz, nx, ny, nz relative to the origin, 6 per
  // plane) and a lookup from voxel to plane: a dense grid of plane numbers over the planes'
  // bounding box (one array read per neighbour, what keeps a slider step fast) unless that
  // box is huge, then the hash.
  const found = [];
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (const [k, s] of sums) {
    const n = s[0];
    if (n < min_points) continue;
    const c = [s[1] / n, s[2] / n, s[3] / n];
    const cov = [s[4] / n - c[0] * c[0], s[5] / n - c[0] * c[1], s[6] / n - c[0] * c[2],
                 s[7] / n - c[1] * c[1], s[8] / n - c[1] * c[2], s[9] / n - c[2] * c[2]];
    const {values, vectors} = symmetricEigen3(cov);
    if (!(values[1] > 0) || Math.max(0, values[0]) > max_flatness * values[1]) continue;
    const cell = [Math.floor(k / (SPAN * SPAN)) - HALF, Math.floor(k / SPAN) % SPAN - HALF, (k % SPAN) - HALF];
    for (let d = 0; d < 3; d += 1) {
      lo[d] = Math.min(lo[d], cell[d]);
      hi[d] = Math.max(hi[d], cell[d]);
    }
    found.push([k, cell, c, vectors[0]]);
  }
  const planes = new Float64Array(6 * found.length);
  found.forEach(([, , c, normal], i) => planes.set([...c, ...normal], 6 * i));
  const size = found.length ? hi.map((h, d) => h - lo[d] + 1) : [0, 0, 0];
  let grid = null;
  let hash = null;
  if (size[0] * size[1] * size[2] <= max_grid_cells) {
    grid = new Int32Array(size[0] * size[1] * size[2]).fill(-1);
    found.forEach(([, cell], i) => {
      grid[(cell[0] - lo[0]) + size[0] * ((cell[1] - lo[1]) + size[1] * (cell[2] - lo[2]))] = i;
    });
  } else {
    hash = new Map(found.map(([k], i) => [k, i]));
  }
  return {planes, count: found.length, grid, hash, lo, size, origin, voxel_m,
          referencePoints: scans.reduce((t, s) => t + s.points.length / 3, 0)};
}

// The plane number of voxel (ix, iy, iz), or -1.
function planeAt(map, ix, iy, iz) {
  if (map.hash) {
    const found = map.hash.get(key(ix, iy, iz));
    return found === undefined ? -1 : found;
  }
  const x = ix - map.lo[0];
  const y = iy - map.lo[1];
  const z = iz - map.lo[2];
  const [nx, ny, nz] = map.size;
  if (x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz) return -1;
  return map.grid[x + nx * (y + ny * z)];
}

// Point-to-plane distance (m) of a world point to the plane whose centroid is nearest among
// the 27 voxels around it; NaN when none of them holds a plane.
export function pointToPlane(map, x, y, z) {
  const {planes, origin, voxel_m} = map;
  const px = x - origin[0];
  const py = y - origin[1];
  const pz = z - origin[2];
  const ix = Math.floor(px / voxel_m);
  const iy = Math.floor(py / voxel_m);
  const iz = Math.floor(pz / voxel_m);
  let best = -1;
  let bestSq = Infinity;
  for (let dx = -1; dx <= 1; dx += 1)
    for (let dy = -1; dy <= 1; dy += 1)
      for (let dz = -1; dz <= 1; dz += 1) {
        const i = planeAt(map, ix + dx, iy + dy, iz + dz);
        if (i < 0) continue;
        const o = 6 * i;
        const sq = (px - planes[o]) ** 2 + (py - planes[o + 1]) ** 2 + (pz - planes[o + 2]) ** 2;
        if (sq < bestSq) {
          bestSq = sq;
          best = o;
        }
      }
  if (best < 0) return NaN;
  return Math.abs(planes[best + 3] * (px - planes[best]) + planes[best + 4] * (py - planes[best + 1]) +
                  planes[best + 5] * (pz - planes[best + 2]));
}

// Up to `size` candidate points spread evenly over a window's scans (the same picks for
// every step of the sliders): {scan: Int32Array, x, y, z: Float32Array} in the sensor frames.
export function samplePoints(scanPointArrays, size = SAMPLE_POINTS) {
  const total = scanPointArrays.reduce((t, points) => t + points.length / 3, 0);
  const count = Math.min(size, total);
  const sample = {scan: new Int32Array(count), x: new Float32Array(count), y: new Float32Array(count), z: new Float32Array(count)};
  if (count === 0) return sample;
  const stride = total / count;
  let scan = 0;
  let before = 0;  // points in the scans before `scan`
  for (let i = 0; i < count; i += 1) {
    const global = Math.floor(i * stride);
    while (global >= before + scanPointArrays[scan].length / 3) {
      before += scanPointArrays[scan].length / 3;
      scan += 1;
    }
    const j = 3 * (global - before);
    const points = scanPointArrays[scan];
    sample.scan[i] = scan;
    sample.x[i] = points[j];
    sample.y[i] = points[j + 1];
    sample.z[i] = points[j + 2];
  }
  return sample;
}

// The residual of the sample placed with one matrix per scan (T_world_candidate):
// {median_m, within (fraction of matched points within threshold_m), matched, count}.
export function residual(map, sample, matrices, threshold_m = 0.05) {
  const n = sample.scan.length;
  const distances = new Float64Array(n);
  const p = new Float64Array(3);
  let matched = 0;
  for (let i = 0; i < n; i += 1) {
    transformPoint(matrices[sample.scan[i]], sample.x[i], sample.y[i], sample.z[i], p);
    const d = pointToPlane(map, p[0], p[1], p[2]);
    if (!Number.isNaN(d)) distances[matched++] = d;
  }
  const used = distances.subarray(0, matched).sort();
  let within = 0;
  for (const d of used) if (d <= threshold_m) within += 1;
  const median = matched === 0 ? NaN
      : matched % 2 ? used[(matched - 1) / 2] : 0.5 * (used[matched / 2 - 1] + used[matched / 2]);
  return {median_m: median, within: matched ? within / matched : NaN, matched, count: n, threshold_m};
}
