// The calibration page's pure parts: rigid transforms against closed forms (Rz(90) maps x to
// y; R = Rz(yaw) Ry(pitch) Rx(roll) read back), calibration_scans.bin's header, index and
// window ranges against a file written to docs/calibration.md's layout, the Jacobi
// eigen-solver against a known decomposition, and the point-to-plane residual against
// closed forms (points on a known plane offset by d give d).
import assert from 'node:assert/strict';
import {test} from 'node:test';
import {invertRigid, matrixFromPose, matrixFromXyzRpy, multiply, transformPoint, withExtrinsicOverride,
        xyzRpyFromMatrix} from '../../../web/js/viewer/extrinsic.js';
import {HEADER_BYTES, parseHeader, parseIndex, scanPoints, sensorOf, windowOf} from '../../../web/js/viewer/calibration_scans.js';
import {buildPlaneMap, pointToPlane, residual, samplePoints, symmetricEigen3} from '../../../web/js/viewer/plane_residual.js';
import {FIXTURE, calibrationScans, poseOf} from '../calibration_fixture.mjs';

const close = (a, b, tol, what) => assert.ok(Math.abs(a - b) <= tol, `${what}: ${a} vs ${b}`);

test('R = Rz(yaw) Ry(pitch) Rx(roll): yaw 90 maps x to y, pitch 90 maps x to -z, roll 90 maps y to z', () => {
  const apply = (rpy, v) => [...transformPoint(matrixFromXyzRpy([0, 0, 0], rpy), ...v)];
  const near = (a, b) => a.forEach((v, i) => close(v, b[i], 1e-12, `${a} vs ${b}`));
  near(apply([0, 0, 90], [1, 0, 0]), [0, 1, 0]);
  near(apply([0, 90, 0], [1, 0, 0]), [0, 0, -1]);
  near(apply([90, 0, 0], [0, 1, 0]), [0, 0, 1]);
  // Fixed axes: roll first, then yaw. (1, 0, 0) -roll 90-> (1, 0, 0) -yaw 90-> (0, 1, 0);
  // (0, 1, 0) -roll 90-> (0, 0, 1) -yaw 90-> (0, 0, 1).
  near(apply([90, 0, 90], [0, 1, 0]), [0, 0, 1]);
  const t = matrixFromXyzRpy([1, 2, 3], [0, 0, 0]);
  near([...transformPoint(t, 1, 1, 1)], [2, 3, 4]);
});

test('xyz/rpy read back, inverse and quaternion poses agree', () => {
  const m = matrixFromXyzRpy([0.1, -0.2, 0.3], [12, -34, 56]);
  const {xyz_m, rpy_deg} = xyzRpyFromMatrix(m);
  [0.1, -0.2, 0.3].forEach((v, i) => close(xyz_m[i], v, 1e-12, 'xyz'));
  [12, -34, 56].forEach((v, i) => close(rpy_deg[i], v, 1e-9, 'rpy'));
  const identity = multiply(m, invertRigid(m));
  identity.forEach((v, i) => close(v, [0, 5, 10, 15].includes(i) ? 1 : 0, 1e-12, `m m^-1 [${i}]`));
  // A quaternion of yaw 90 deg: (0, 0, sin 45, cos 45).
  const q = matrixFromPose({translation: [1, 2, 3], rotation_xyzw: [0, 0, Math.SQRT1_2, Math.SQRT1_2]});
  matrixFromXyzRpy([1, 2, 3], [0, 0, 90]).forEach((v, i) => close(q[i], v, 1e-12, `quaternion [${i}]`));
  // The fixture's pose writer round-trips through matrixFromPose.
  matrixFromPose(poseOf(m)).forEach((v, i) => close(v, m[i], 1e-12, `poseOf [${i}]`));
  assert.throws(() => matrixFromPose({translation: [0, 0, 0], rotation_xyzw: [0, 0, 0, 0]}), /zero length/);
});

test('the override keeps every other option and names T_<reference>_<candidate>', () => {
  const options = {map: {voxel_m: 0.1}, calibration: {sonar: {T_body_sensor: {xyz_m: [0, 0, 0], rpy_deg: [0, 0, 0]}}}};
  const out = withExtrinsicOverride(options, 'lidar_v', 'lidar_h', {xyz_m: [0.1 + 0.2, 0, 0.4], rpy_deg: [0, 90, 0]});
  assert.deepEqual(out, {map: {voxel_m: 0.1}, calibration: {
    sonar: {T_body_sensor: {xyz_m: [0, 0, 0], rpy_deg: [0, 0, 0]}},
    lidar_v: {T_lidar_h_lidar_v: {xyz_m: [0.3, 0, 0.4], rpy_deg: [0, 90, 0]}}}});
  assert.equal(options.calibration.lidar_v, undefined, 'the job\'s own options are not changed');
});

test('calibration_scans.bin: header, index and one contiguous byte range per window', () => {
  const {bytes, points} = calibrationScans({keyframes: 6, referencePoints: 10, candidatePoints: 7});
  const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.length);
  const {indexBytes} = parseHeader(buffer.slice(0, HEADER_BYTES));
  assert.equal((HEADER_BYTES + indexBytes) % 4, 0);
  const index = parseIndex(buffer.slice(HEADER_BYTES, HEADER_BYTES + indexBytes), indexBytes, bytes.length);
  assert.equal(index.reference, FIXTURE.reference);
  const candidate = sensorOf(index, FIXTURE.candidate);
  // Keyframes 2..4: the candidate has none at 3, so scans of 2 and 4.
  const win = windowOf(candidate, 2, 3);
  assert.deepEqual(win.scans.map((s) => s.keyframe), [2, 4]);
  assert.equal(win.end - win.start, 2 * 7 * 12);
  const arrays = scanPoints(buffer.slice(win.start, win.end), win.start, win.scans);
  assert.deepEqual([...arrays[0]], [...points[FIXTURE.candidate][2]]);
  assert.deepEqual([...arrays[1]], [...points[FIXTURE.candidate][3]]);
  assert.deepEqual(windowOf(candidate, 3, 1), {scans: [], start: 0, end: 0});
  assert.throws(() => sensorOf(index, 'sonr'), /no sensor 'sonr' \(sensors: lidar_h, lidar_v\)/);
  assert.throws(() => parseHeader(new TextEncoder().encode('KEELCAL2________').buffer), /magic is 'KEELCAL2'/);
  const broken = JSON.parse(new TextDecoder().decode(buffer.slice(HEADER_BYTES, HEADER_BYTES + indexBytes)));
  broken.sensors[1].scans[1].keyframe = 0;
  assert.throws(() => parseIndex(new TextEncoder().encode(JSON.stringify(broken)).buffer, indexBytes),
                /sensors\[1\] \(lidar_v\)\.scans\[1\]\.keyframe 0 is not after 0/);
});

test('Jacobi eigen-decomposition of a rotated diagonal matrix', () => {
  // A = R diag(1, 4, 9) R^T with R of rpy (20, 30, 40) deg.
  const r = matrixFromXyzRpy([0, 0, 0], [20, 30, 40]);
  const R = (i, j) => r[i + 4 * j];
  const d = [1, 4, 9];
  const A = (i, j) => d.reduce((s, dk, k) => s + R(i, k) * dk * R(j, k), 0);
  const {values, vectors} = symmetricEigen3([A(0, 0), A(0, 1), A(0, 2), A(1, 1), A(1, 2), A(2, 2)]);
  values.forEach((v, i) => close(v, d[i], 1e-10, `eigenvalue ${i}`));
  vectors.forEach((v, k) => close(Math.abs(v[0] * R(0, k) + v[1] * R(1, k) + v[2] * R(2, k)), 1, 1e-10, `eigenvector ${k}`));
});

// Reference points on the plane n . x = c (world), on a grid; candidate points on the plane
// moved by d along n.
function planeScans(normal, c, d, count = 40) {
  const n = Math.hypot(...normal);
  const u = normal.map((v) => v / n);
  // Two directions in the plane.
  const a = Math.abs(u[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
  const e1 = [u[1] * a[2] - u[2] * a[1], u[2] * a[0] - u[0] * a[2], u[0] * a[1] - u[1] * a[0]];
  const l1 = Math.hypot(...e1);
  e1.forEach((v, i) => { e1[i] = v / l1; });
  const e2 = [u[1] * e1[2] - u[2] * e1[1], u[2] * e1[0] - u[0] * e1[2], u[0] * e1[1] - u[1] * e1[0]];
  const grid = (offset, step, shift) => {
    const points = new Float32Array(3 * count * count);
    for (let i = 0; i < count; i += 1)
      for (let j = 0; j < count; j += 1)
        for (let k = 0; k < 3; k += 1)
          points[3 * (i * count + j) + k] = 100 + (c + offset) * u[k] + (i * step + shift) * e1[k] + (j * step + shift) * e2[k];
    return points;
  };
  return {reference: grid(0, 0.1, 0), candidate: grid(d, 0.09, 0.05)};
}

test('the residual of points on a known plane moved by d is d', () => {
  const ident = matrixFromXyzRpy([0, 0, 0], [0, 0, 0]);
  for (const [normal, d] of [[[0, 0, 1], 0.03], [[1, 2, 3], 0.12], [[0, 1, 0], 0], [[-2, 1, 0.5], 0.3]]) {
    const {reference, candidate} = planeScans(normal, 1.5, d);
    const map = buildPlaneMap([{points: reference, matrix: ident}]);
    assert.ok(map.count > 10, `${map.count} planes`);
    const sample = samplePoints([candidate.subarray(0, 900), candidate.subarray(900)], 500);
    assert.equal(sample.scan.length, 500);
    const r = residual(map, sample, [ident, ident], 0.05);
    // float32 coordinates around 100 m: 1e-5 m.
    close(r.median_m, d, 2e-5, `median for normal ${normal}, d ${d}`);
    assert.ok(r.matched >= 0.8 * r.count, `${r.matched} of ${r.count} matched`);
    assert.equal(r.within, d <= 0.05 ? 1 : 0);
    // The hash that replaces the dense grid over a huge extent finds the same planes.
    const hashed = buildPlaneMap([{points: reference, matrix: ident}], {max_grid_cells: 0});
    assert.ok(hashed.hash && !hashed.grid);
    assert.deepEqual(residual(hashed, sample, [ident, ident], 0.05), r);
  }
});

test('the residual follows the scans\' matrices: a scan moved by t along the normal reads |t|', () => {
  const ident = matrixFromXyzRpy([0, 0, 0], [0, 0, 0]);
  const {reference, candidate} = planeScans([0, 0, 1], 0, 0);
  const map = buildPlaneMap([{points: reference, matrix: ident}]);
  const sample = samplePoints([candidate], 2000);
  close(residual(map, sample, [ident]).median_m, 0, 2e-5, 'in place');
  close(residual(map, sample, [matrixFromXyzRpy([0.3, -0.2, 0.07], [0, 0, 0])]).median_m, 0.07, 2e-5, 'moved');
  // Nothing near the reference: no match, NaN rather than a made-up number.
  const far = residual(map, sample, [matrixFromXyzRpy([0, 0, 50], [0, 0, 0])]);
  assert.equal(far.matched, 0);
  assert.ok(Number.isNaN(far.median_m));
  assert.ok(Number.isNaN(pointToPlane(map, 0, 0, 1e3)));
});

test('the fixture\'s candidate lies on the reference\'s planes with the true extrinsic, not with the file\'s', () => {
  const {index, points} = calibrationScans({keyframes: 6, referencePoints: 3000, candidatePoints: 1000});
  const ref = sensorOf(index, FIXTURE.reference);
  const cand = sensorOf(index, FIXTURE.candidate);
  const T_body_ref = matrixFromPose(ref.T_body_sensor);
  const map = buildPlaneMap(ref.scans.map((s, i) => ({points: points[ref.name][i], matrix: multiply(matrixFromPose(s.T_world_body), T_body_ref)})));
  const sample = samplePoints(points[cand.name], 3000);
  const place = (T_ref_cand) => cand.scans.map((s) => multiply(multiply(matrixFromPose(s.T_world_body), T_body_ref), T_ref_cand));
  const truth = FIXTURE.T_reference_candidate_true;
  const good = residual(map, sample, place(matrixFromXyzRpy(truth.xyz_m, truth.rpy_deg)));
  const initial = multiply(invertRigid(T_body_ref), matrixFromPose(cand.T_body_sensor));
  const bad = residual(map, sample, place(initial));
  assert.ok(good.median_m < 1e-4, `median at the truth ${good.median_m}`);
  assert.ok(bad.median_m > 0.01, `median at the file's value ${bad.median_m}`);
});
