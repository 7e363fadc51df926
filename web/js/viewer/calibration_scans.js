// calibration_scans.bin (docs/calibration.md section 2) as the calibration page reads it:
// the 16-byte header, the JSON index, and one byte range per sensor and window (the scans
// of keyframes k .. k+N-1 of one sensor are contiguous). Pure (tested in node); the page
// does the HTTP Range requests.

export const FILE_NAME = 'calibration_scans.bin';
export const HEADER_BYTES = 16;
const MAGIC = 'KEELCAL1';
const POINT_BYTES = 12;  // 3 float32

// The index's length L from the header's 16 bytes.
export function parseHeader(buffer) {
  const bytes = new Uint8Array(buffer);
  if (bytes.length < HEADER_BYTES) throw new Error(`${FILE_NAME}: ${bytes.length} bytes, shorter than its 16-byte header`);
  const magic = String.fromCharCode(...bytes.subarray(0, 8));
  if (magic !== MAGIC) throw new Error(`${FILE_NAME}: magic is '${magic}', expected '${MAGIC}'`);
  const length = new DataView(bytes.buffer, bytes.byteOffset + 8, 8).getBigUint64(0, true);
  if (length > BigInt(Number.MAX_SAFE_INTEGER)) throw new Error(`${FILE_NAME}: index length ${length} is not plausible`);
  return {indexBytes: Number(length)};
}

function check(condition, what) {
  if (!condition) throw new Error(`${FILE_NAME}: ${what}`);
}

// The index from its UTF-8 bytes, checked: every field the page uses exists with its type,
// each sensor's scans are in keyframe order and lie after the index.
export function parseIndex(buffer, indexBytes = buffer.byteLength, fileSize = Infinity) {
  let index;
  try {
    index = JSON.parse(new TextDecoder().decode(buffer));
  } catch (e) {
    throw new Error(`${FILE_NAME}: the index is not JSON (${e.message})`);
  }
  check(index && index.format === 'keel-calibration-scans', `index.format is '${index?.format}', expected 'keel-calibration-scans'`);
  check(index.version === 1, `index.version ${index.version} is not supported (this page reads version 1)`);
  check(typeof index.reference === 'string', 'index.reference is missing');
  check(Array.isArray(index.keyframes), 'index.keyframes is missing');
  check(Array.isArray(index.sensors), 'index.sensors is missing');
  const pointsStart = HEADER_BYTES + indexBytes;
  for (const [i, sensor] of index.sensors.entries()) {
    const where = `index.sensors[${i}]`;
    check(typeof sensor.name === 'string', `${where}.name is missing`);
    check(sensor.T_body_sensor?.translation && sensor.T_body_sensor?.rotation_xyzw, `${where} (${sensor.name}).T_body_sensor is missing`);
    check(Array.isArray(sensor.scans), `${where} (${sensor.name}).scans is missing`);
    let previous = -1;
    for (const [j, scan] of sensor.scans.entries()) {
      const at = `${where} (${sensor.name}).scans[${j}]`;
      check(Number.isInteger(scan.keyframe) && scan.keyframe > previous, `${at}.keyframe ${scan.keyframe} is not after ${previous}`);
      check(Number.isInteger(scan.offset) && scan.offset >= pointsStart && scan.offset % 4 === 0, `${at}.offset ${scan.offset} is not a point block`);
      check(Number.isInteger(scan.count) && scan.count >= 0, `${at}.count ${scan.count} is not a count`);
      check(scan.offset + scan.count * POINT_BYTES <= fileSize, `${at} ends past the file's ${fileSize} bytes`);
      check(scan.T_world_body?.translation && scan.T_world_body?.rotation_xyzw, `${at}.T_world_body is missing`);
      previous = scan.keyframe;
    }
  }
  check(index.sensors.some((s) => s.name === index.reference), `the reference '${index.reference}' is not among the sensors`);
  return index;
}

export function sensorOf(index, name) {
  const sensor = index.sensors.find((s) => s.name === name);
  if (!sensor) throw new Error(`${FILE_NAME}: no sensor '${name}' (sensors: ${index.sensors.map((s) => s.name).join(', ')})`);
  return sensor;
}

// The scans of keyframes k .. k+N-1 of a sensor and the one byte range holding them:
// {scans, start, end} with `end` exclusive (a Range header names end - 1), or start = end
// when the sensor has no scan in the window.
export function windowOf(sensor, k, n) {
  const scans = sensor.scans.filter((s) => s.keyframe >= k && s.keyframe < k + n);
  if (scans.length === 0) return {scans, start: 0, end: 0};
  for (let i = 1; i < scans.length; i += 1)
    check(scans[i].offset === scans[i - 1].offset + scans[i - 1].count * POINT_BYTES,
          `${sensor.name}'s scans of keyframes ${scans[i - 1].keyframe} and ${scans[i].keyframe} are not contiguous`);
  const last = scans[scans.length - 1];
  return {scans, start: scans[0].offset, end: last.offset + last.count * POINT_BYTES};
}

// Each scan's points (x, y, z float32, little-endian) as a Float32Array over `buffer`, the
// bytes of the window's range (which starts at windowStart in the file).
export function scanPoints(buffer, windowStart, scans) {
  const littleEndian = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;
  if (!littleEndian) throw new Error(`${FILE_NAME}: this browser is big-endian; the file is little-endian`);
  return scans.map((scan) => {
    const from = scan.offset - windowStart;
    check(from >= 0 && from + scan.count * POINT_BYTES <= buffer.byteLength,
          `keyframe ${scan.keyframe}'s points lie outside the bytes received`);
    return new Float32Array(buffer, from, scan.count * 3);
  });
}
