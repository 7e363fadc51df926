// A calibration_scans.bin written in node exactly as docs/calibration.md section 2 lays it
// out, for the calibration page's tests before (and independently of) the calibrate stage:
// a scene of known planes, a body moving along a known path, a reference and a candidate
// sensor whose points lie exactly on the planes with the TRUE extrinsic, while the file's
// T_body_candidate carries a known error (what the user corrects by hand).
import {invertRigid, matrixFromXyzRpy, multiply, transformPoint} from '../../web/js/viewer/extrinsic.js';

// A pose {translation, rotation_xyzw} of a rigid matrix (extrinsic.js layout), through
// Shepperd's method.
export function poseOf(m) {
  const [r00, r11, r22] = [m[0], m[5], m[10]];
  const trace = r00 + r11 + r22;
  let q;
  if (trace > 0) {
    const s = 2 * Math.sqrt(trace + 1);
    q = [(m[6] - m[9]) / s, (m[8] - m[2]) / s, (m[1] - m[4]) / s, s / 4];
  } else if (r00 > r11 && r00 > r22) {
    const s = 2 * Math.sqrt(1 + r00 - r11 - r22);
    q = [s / 4, (m[4] + m[1]) / s, (m[8] + m[2]) / s, (m[6] - m[9]) / s];
  } else if (r11 > r22) {
    const s = 2 * Math.sqrt(1 + r11 - r00 - r22);
    q = [(m[4] + m[1]) / s, s / 4, (m[9] + m[6]) / s, (m[8] - m[2]) / s];
  } else {
    const s = 2 * Math.sqrt(1 + r22 - r00 - r11);
    q = [(m[8] + m[2]) / s, (m[9] + m[6]) / s, s / 4, (m[1] - m[4]) / s];
  }
  return {translation: [m[12], m[13], m[14]], rotation_xyzw: q};
}

// Deterministic pseudo-random numbers in [0, 1) (mulberry32).
function random(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

// A world point on one of the scene's three planes: the floor z = 0, the wall y = 6 and the
// wall x = 30 (a corner, so all six directions of the extrinsic show in the residual).
function scenePoint(rand, bodyX) {
  const pick = rand();
  const u = rand();
  const v = rand();
  if (pick < 0.4) return [bodyX - 6 + 12 * u, -4 + 10 * v, 0];
  if (pick < 0.8) return [bodyX - 6 + 12 * u, 6, 4 * v];
  return [30, -4 + 10 * u, 4 * v];
}

export const FIXTURE = {
  reference: 'lidar_h',
  candidate: 'lidar_v',
  T_body_reference: {xyz_m: [0.2, 0, 0.5], rpy_deg: [0, 0, 0]},
  // The truth, and the mission's wrong value the file carries (2 deg, 5 cm off, issue 31).
  T_reference_candidate_true: {xyz_m: [0.1, 0.05, 0.3], rpy_deg: [0, 85, 10]},
  T_reference_candidate_file: {xyz_m: [0.15, 0.05, 0.3], rpy_deg: [2, 85, 10]},
};

// The body at keyframe j: moving along +x, slightly turning.
export function bodyMatrix(j) {
  return matrixFromXyzRpy([1.5 * j, 0.02 * j, 1.0], [0, 0, 0.5 * j]);
}

// {bytes: Uint8Array, index, points: {sensor: [Float32Array per scan]}} with `keyframes`
// keyframes, per keyframe `referencePoints` and `candidatePoints` points.
export function calibrationScans({keyframes = 12, referencePoints = 2000, candidatePoints = 2000, seed = 7} = {}) {
  const fixture = FIXTURE;
  const T_body_ref = matrixFromXyzRpy(fixture.T_body_reference.xyz_m, fixture.T_body_reference.rpy_deg);
  const T_ref_cand_true = matrixFromXyzRpy(fixture.T_reference_candidate_true.xyz_m, fixture.T_reference_candidate_true.rpy_deg);
  const T_ref_cand_file = matrixFromXyzRpy(fixture.T_reference_candidate_file.xyz_m, fixture.T_reference_candidate_file.rpy_deg);
  const rand = random(seed);
  const sensors = [
    {name: fixture.reference, T_body_sensor: T_body_ref, T_body_true: T_body_ref, count: referencePoints},
    {name: fixture.candidate, T_body_sensor: multiply(T_body_ref, T_ref_cand_file),
     T_body_true: multiply(T_body_ref, T_ref_cand_true), count: candidatePoints},
  ];
  const points = {};
  const entries = [];
  for (const sensor of sensors) {
    points[sensor.name] = [];
    const scans = [];
    for (let j = 0; j < keyframes; j += 1) {
      // The candidate has no scan at keyframe 3 (a gap the page must handle).
      if (sensor.name === fixture.candidate && j === 3) continue;
      const T_world_body = bodyMatrix(j);
      const T_sensor_world = invertRigid(multiply(T_world_body, sensor.T_body_true));
      const block = new Float32Array(3 * sensor.count);
      const p = new Float64Array(3);
      for (let i = 0; i < sensor.count; i += 1) {
        const [x, y, z] = scenePoint(rand, 1.5 * j);
        transformPoint(T_sensor_world, x, y, z, p);
        block.set(p, 3 * i);
      }
      points[sensor.name].push(block);
      scans.push({keyframe: j, t_s: 0.1 * j + 0.01, T_world_body: poseOf(T_world_body), count: sensor.count});
    }
    entries.push({name: sensor.name, type: 'lidar', T_body_sensor: poseOf(sensor.T_body_sensor), source: 'mission.yaml', scans});
  }
  const index = {format: 'keel-calibration-scans', version: 1, reference: fixture.reference, t0_s: 1700000000.0,
                 keyframes: Array.from({length: keyframes}, (_, j) => ({t_s: 0.1 * j})), sensors: entries};
  // Offsets depend on the index's length, which depends on the offsets' digits: write the
  // index with placeholders as wide as the largest offset, then pad.
  const blocks = Object.values(points).flat();
  const total = blocks.reduce((t, b) => t + b.byteLength, 0);
  let length = 0;
  for (let pass = 0; pass < 3; pass += 1) {
    let offset = 16 + length;
    for (const entry of entries)
      for (const scan of entry.scans) {
        scan.offset = offset;
        offset += 12 * scan.count;
      }
    const text = JSON.stringify(index);
    length = Math.ceil((16 + Buffer.byteLength(text) + 64) / 4) * 4 - 16;
  }
  let offset = 16 + length;
  for (const entry of entries)
    for (const scan of entry.scans) {
      scan.offset = offset;
      offset += 12 * scan.count;
    }
  const text = JSON.stringify(index);
  if (Buffer.byteLength(text) > length) throw new Error('fixture index outgrew its padding');
  const bytes = Buffer.alloc(16 + length + total, 0x20);
  bytes.write('KEELCAL1', 0, 'latin1');
  bytes.writeBigUInt64LE(BigInt(length), 8);
  bytes.write(text, 16, 'utf8');
  let at = 16 + length;
  for (const block of blocks) {
    Buffer.from(block.buffer, block.byteOffset, block.byteLength).copy(bytes, at);
    at += block.byteLength;
  }
  return {bytes, index, points};
}
