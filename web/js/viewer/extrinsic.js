// Rigid transforms of the calibration page as 4x4 matrices, column-major like
// THREE.Matrix4.elements (element [row + 4 * col]), so a result goes into three.js with
// `matrix.fromArray(m)` and the maths stays pure (tested in node). Conventions of
// docs/calibration.md: `T_a_b` maps points of frame b into frame a; a pose for people is
// {xyz_m, rpy_deg} with R = Rz(yaw) * Ry(pitch) * Rx(roll) (ROS/URDF fixed-axis X-Y-Z).

const DEG = Math.PI / 180;

export function identity() {
  const m = new Float64Array(16);
  m[0] = m[5] = m[10] = m[15] = 1;
  return m;
}

// The matrix of a pose as mission.yaml and calibration_scans.bin write it:
// {translation: [x, y, z], rotation_xyzw: [x, y, z, w]} (the quaternion normalised here).
export function matrixFromPose({translation, rotation_xyzw: q}) {
  if (!Array.isArray(translation) || translation.length !== 3 || !Array.isArray(q) || q.length !== 4)
    throw new Error('a pose needs translation [x, y, z] and rotation_xyzw [x, y, z, w]');
  const n = Math.hypot(...q);
  if (!(n > 0)) throw new Error('a pose\'s rotation_xyzw has zero length');
  const [x, y, z, w] = q.map((v) => v / n);
  const m = identity();
  m[0] = 1 - 2 * (y * y + z * z); m[4] = 2 * (x * y - z * w);     m[8] = 2 * (x * z + y * w);
  m[1] = 2 * (x * y + z * w);     m[5] = 1 - 2 * (x * x + z * z); m[9] = 2 * (y * z - x * w);
  m[2] = 2 * (x * z - y * w);     m[6] = 2 * (y * z + x * w);     m[10] = 1 - 2 * (x * x + y * y);
  [m[12], m[13], m[14]] = translation;
  return m;
}

// R = Rz(yaw) * Ry(pitch) * Rx(roll), angles in degrees; translation in metres.
export function matrixFromXyzRpy([x, y, z], [rollDeg, pitchDeg, yawDeg]) {
  const [cr, sr] = [Math.cos(rollDeg * DEG), Math.sin(rollDeg * DEG)];
  const [cp, sp] = [Math.cos(pitchDeg * DEG), Math.sin(pitchDeg * DEG)];
  const [cy, sy] = [Math.cos(yawDeg * DEG), Math.sin(yawDeg * DEG)];
  const m = identity();
  m[0] = cy * cp; m[4] = cy * sp * sr - sy * cr; m[8] = cy * sp * cr + sy * sr;
  m[1] = sy * cp; m[5] = sy * sp * sr + cy * cr; m[9] = sy * sp * cr - cy * sr;
  m[2] = -sp;     m[6] = cp * sr;                m[10] = cp * cr;
  m[12] = x; m[13] = y; m[14] = z;
  return m;
}

// The inverse of matrixFromXyzRpy: {xyz_m, rpy_deg}, pitch in [-90, 90].
export function xyzRpyFromMatrix(m) {
  const pitch = Math.atan2(-m[2], Math.hypot(m[6], m[10]));
  const roll = Math.atan2(m[6], m[10]);
  const yaw = Math.atan2(m[1], m[0]);
  return {xyz_m: [m[12], m[13], m[14]], rpy_deg: [roll / DEG, pitch / DEG, yaw / DEG]};
}

// a * b.
export function multiply(a, b) {
  const out = new Float64Array(16);
  for (let col = 0; col < 4; col += 1)
    for (let row = 0; row < 4; row += 1)
      out[row + 4 * col] = a[row] * b[4 * col] + a[row + 4] * b[4 * col + 1] + a[row + 8] * b[4 * col + 2] + a[row + 12] * b[4 * col + 3];
  return out;
}

// The inverse of a rigid transform: [R^T, -R^T t].
export function invertRigid(m) {
  const out = identity();
  for (let r = 0; r < 3; r += 1)
    for (let c = 0; c < 3; c += 1) out[r + 4 * c] = m[c + 4 * r];
  for (let r = 0; r < 3; r += 1) out[12 + r] = -(out[r] * m[12] + out[r + 4] * m[13] + out[r + 8] * m[14]);
  return out;
}

// m * [x, y, z, 1] written into out[offset .. offset + 2].
export function transformPoint(m, x, y, z, out = new Float64Array(3), offset = 0) {
  out[offset] = m[0] * x + m[4] * y + m[8] * z + m[12];
  out[offset + 1] = m[1] * x + m[5] * y + m[9] * z + m[13];
  out[offset + 2] = m[2] * x + m[6] * y + m[10] * z + m[14];
  return out;
}

// Numbers as typed (no float noise such as 0.30000000000000004 in a job's options).
const tidy = (v) => Number(v.toPrecision(12));

// A job's options with the override of docs/calibration.md section 1:
// calibration.<candidate>.T_<reference>_<candidate> = {xyz_m, rpy_deg}. The candidate's other
// keys are dropped (one key per sensor); every other option is kept.
export function withExtrinsicOverride(options, candidate, reference, {xyz_m, rpy_deg}) {
  const out = structuredClone(options && typeof options === 'object' ? options : {});
  out.calibration = {...(out.calibration || {})};
  out.calibration[candidate] = {[`T_${reference}_${candidate}`]: {xyz_m: xyz_m.map(tidy), rpy_deg: rpy_deg.map(tidy)}};
  return out;
}
