// The calibration page of a job (docs/calibration.md section 3; seed 000's Algorithm 3, the
// manual extrinsic calibration): choose a candidate range sensor and its reference, a window
// of N keyframes from k, and move the candidate by x, y, z, roll, pitch, yaw; the reference's
// scans are drawn red and the candidate's blue, each scan placed as
//   p_world = T_world_body * T_body_reference * T_reference_candidate * p_candidate.
// Each scan is one THREE.Points whose points stay on the GPU: a step of a slider changes the
// candidate scans' matrices only. The point-to-plane residual of a sample of candidate
// points against the reference window follows every step (plane_residual.js). "Reprocess
// with this extrinsic" makes a job of the same mission whose options carry
// calibration.<candidate>.T_<reference>_<candidate>.
//
// calibration_scans.bin is read with HTTP Range requests: its header, its index, then per
// sensor and window the one contiguous range of that window's scans.
import * as THREE from 'three';
import {ApiError, fetchArtifactJson, fetchArtifactRange, jobsApi} from '../api.js';
import {h, message} from '../dom.js';
import {formatNumber} from '../format.js';
import {jobHash} from '../router.js';
import {FILE_NAME, HEADER_BYTES, parseHeader, parseIndex, scanPoints, sensorOf, windowOf} from '../viewer/calibration_scans.js';
import {invertRigid, matrixFromPose, matrixFromXyzRpy, multiply, xyzRpyFromMatrix, withExtrinsicOverride} from '../viewer/extrinsic.js';
import {SAMPLE_POINTS, buildPlaneMap, residual, samplePoints} from '../viewer/plane_residual.js';
import {Scene3d} from '../viewer/scene.js';

const DEFAULT_WINDOW = 10;
const CACHED_WINDOWS = 6;
// The six values: key, label, unit, slider half-width around the starting value, step.
const VALUES = [
  ['x', 'x', 'm', 0.5, 0.001], ['y', 'y', 'm', 0.5, 0.001], ['z', 'z', 'm', 0.5, 0.001],
  ['roll', 'roll', '°', 10, 0.01], ['pitch', 'pitch', '°', 10, 0.01], ['yaw', 'yaw', '°', 10, 0.01],
];
const RED = 0xe03131;
const BLUE = 0x339af0;

const describe = (e) => (e instanceof ApiError ? e.describe() : e.message);

export function mount(container, {id, query}) {
  let disposed = false;
  const canvas = h('canvas', {id: 'calibrate-canvas'});
  const notices = h('div', {class: 'overlay', id: 'calibrate-messages'});
  const readout = h('div', {class: 'readout', id: 'calib-residual'}, 'residual: –');
  const status = h('p', {class: 'muted', id: 'calib-status'}, 'Reading the artifact list…');
  const aside = h('aside', {id: 'calibrate-panel'}, h('p', null, h('a', {href: jobHash(id)}, `← job ${id}`)),
                  h('h2', null, 'Extrinsic calibration'), status);
  container.append(h('div', {class: 'viewer calibrate'}, aside, h('div', {class: 'stage'}, canvas, notices, readout)));
  const scene = new Scene3d(canvas, {});
  const referenceGroup = new THREE.Group();
  const candidateGroup = new THREE.Group();
  referenceGroup.name = 'reference';
  candidateGroup.name = 'candidate';
  scene.add(referenceGroup);
  scene.add(candidateGroup);
  const materials = {reference: new THREE.PointsMaterial({color: RED, size: 2, sizeAttenuation: false}),
                     candidate: new THREE.PointsMaterial({color: BLUE, size: 2, sizeAttenuation: false})};

  const state = {job: null, artifact: null, index: null, automatic: null, windows: new Map(),
                 reference: '', candidate: '', k: 0, n: DEFAULT_WINDOW, planes: null, sample: null,
                 candidateBases: [], lastStep: null, loading: null};

  function notice(kind, title, detail) {
    const box = message(kind, title, detail);
    box.prepend(h('button', {type: 'button', class: 'dismiss', title: 'dismiss', on: {click: () => box.remove()}}, '×'));
    notices.append(box);
  }

  // ---- the panel ----------------------------------------------------------------------
  const referenceSelect = h('select', {id: 'calib-reference', on: {change: () => chooseSensors(referenceSelect.value, state.candidate)}});
  const candidateSelect = h('select', {id: 'calib-candidate', on: {change: () => chooseSensors(state.reference, candidateSelect.value)}});
  const kInput = h('input', {type: 'number', id: 'calib-k', min: 0, step: 1, value: 0, on: {change: () => setWindow()}});
  const nInput = h('input', {type: 'number', id: 'calib-n', min: 1, step: 1, value: DEFAULT_WINDOW, on: {change: () => setWindow()}});
  const windowButton = h('button', {type: 'button', id: 'calib-window', on: {click: () => setWindow()}}, 'Show window');
  const counts = h('p', {class: 'muted', id: 'calib-counts'});
  const inputs = {};
  const rows = VALUES.map(([key, label, unit, , step]) => {
    const range = h('input', {type: 'range', id: `calib-${key}-range`, step, on: {input: () => {
      inputs[key].number.value = range.value;
      placeCandidate();
    }}});
    const number = h('input', {type: 'number', id: `calib-${key}`, step, class: 'num', on: {input: () => {
      const v = Number(number.value);
      if (number.value === '' || !Number.isFinite(v)) return;
      centreRange(key, v, false);
      placeCandidate();
    }}});
    inputs[key] = {range, number};
    return h('label', {class: 'calib-value'}, h('span', null, `${label} (${unit})`), range, number);
  });
  const startJob = h('button', {type: 'button', id: 'calib-start-job', on: {click: () => startFrom('job')}}, 'Start from the job\'s extrinsic');
  const startAuto = h('button', {type: 'button', id: 'calib-start-auto', hidden: true, on: {click: () => startFrom('automatic')}},
                      'Start from the automatic result');
  const threshold = h('input', {type: 'number', id: 'calib-threshold', min: 0, step: 0.01, value: 0.05, class: 'num',
                                on: {input: () => placeCandidate()}});
  const reprocessButton = h('button', {type: 'button', id: 'calib-reprocess', on: {click: reprocess}}, 'Reprocess with this extrinsic');
  const reprocessStatus = h('div', {id: 'calib-reprocess-status'});
  const controls = h('div', {id: 'calib-controls', hidden: true},
    h('h3', null, 'Sensors'),
    h('label', null, 'reference (red) ', referenceSelect), h('label', null, 'candidate (blue) ', candidateSelect),
    h('h3', null, 'Window of keyframes'),
    h('label', null, 'first k ', kInput), h('label', null, 'count N ', nInput), windowButton, counts,
    h('h3', null, 'T_reference_candidate'), rows, h('div', {class: 'actions'}, startJob, startAuto),
    h('h3', null, 'Residual'), h('label', null, 'within (m) ', threshold),
    h('h3', null, 'Reprocess'), reprocessButton, reprocessStatus);
  aside.append(controls);

  function centreRange(key, value, always) {
    const [, , , half] = VALUES.find((v) => v[0] === key);
    const {range} = inputs[key];
    if (always || value < Number(range.min) || value > Number(range.max)) {
      range.min = String(value - half);
      range.max = String(value + half);
    }
    range.value = String(value);
  }

  function setValues({xyz_m, rpy_deg}) {
    const values = [...xyz_m, ...rpy_deg];
    VALUES.forEach(([key], i) => {
      const v = Number(values[i].toFixed(key.length === 1 ? 4 : 3));
      inputs[key].number.value = String(v);
      centreRange(key, v, true);
    });
  }

  function values() {
    const v = VALUES.map(([key]) => Number(inputs[key].number.value));
    return {xyz_m: v.slice(0, 3), rpy_deg: v.slice(3)};
  }

  // ---- extrinsics -----------------------------------------------------------------------
  const T_body = (name) => matrixFromPose(sensorOf(state.index, name).T_body_sensor);

  // The job's T_reference_candidate: T_body_reference^-1 * T_body_candidate (the index's).
  function jobExtrinsic() {
    return xyzRpyFromMatrix(multiply(invertRigid(T_body(state.reference)), T_body(state.candidate)));
  }

  // calibration.json's refined T_reference_candidate, when it has one for this pair.
  function automaticExtrinsic() {
    const result = state.automatic;
    if (!result || result.reference !== state.reference) return null;
    const entry = (result.candidates || []).find((c) => c.sensor === state.candidate);
    const pose = entry?.status === 'refined' ? entry.refined?.T_reference_candidate : null;
    return pose && Array.isArray(pose.xyz_m) && Array.isArray(pose.rpy_deg) ? pose : null;
  }

  function startFrom(which) {
    setValues(which === 'automatic' ? automaticExtrinsic() : jobExtrinsic());
    placeCandidate();
  }

  // ---- windows of scans ---------------------------------------------------------------
  // A sensor's scans of keyframes k..k+N-1: one Range request, kept while among the last
  // CACHED_WINDOWS read.
  async function windowScans(name, k, n) {
    const cacheKey = `${name}:${k}:${n}`;
    if (!state.windows.has(cacheKey)) {
      const promise = (async () => {
        const win = windowOf(sensorOf(state.index, name), k, n);
        const bytes = await fetchArtifactRange(state.artifact, win.start, win.end);
        const points = scanPoints(bytes, win.start, win.scans);
        return win.scans.map((scan, i) => ({scan, points: points[i], T_world_body: matrixFromPose(scan.T_world_body)}));
      })();
      state.windows.set(cacheKey, promise);
      promise.catch(() => state.windows.delete(cacheKey));
      // The oldest windows go (a 1 M-point window holds 12 MB).
      for (const old of [...state.windows.keys()].slice(0, Math.max(0, state.windows.size - CACHED_WINDOWS)))
        state.windows.delete(old);
    }
    return state.windows.get(cacheKey);
  }

  function pointsObject(points, material) {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(points, 3));
    geometry.computeBoundingSphere();
    const object = new THREE.Points(geometry, material);
    object.matrixAutoUpdate = false;
    return object;
  }

  function clearGroup(group) {
    for (const child of [...group.children]) {
      child.geometry.dispose();
      group.remove(child);
    }
  }

  // Reads and draws the window (Algorithm 3's window reset), then places the candidate.
  async function showWindow() {
    const serial = (state.loading = {});
    const {reference, candidate, k, n} = state;
    status.textContent = `Reading keyframes ${k}..${k + n - 1} of ${reference} and ${candidate}…`;
    const [referenceScans, candidateScans] = await Promise.all([windowScans(reference, k, n), windowScans(candidate, k, n)]);
    if (disposed || state.loading !== serial) return;
    clearGroup(referenceGroup);
    clearGroup(candidateGroup);
    const T_body_reference = T_body(reference);
    const referencePlaced = referenceScans.map(({points, T_world_body}) => ({points, matrix: multiply(T_world_body, T_body_reference)}));
    for (const {points, matrix} of referencePlaced) {
      const object = pointsObject(points, materials.reference);
      object.matrix.fromArray(matrix);
      referenceGroup.add(object);
    }
    state.candidateBases = candidateScans.map(({T_world_body}) => multiply(T_world_body, T_body_reference));
    for (const {points} of candidateScans) candidateGroup.add(pointsObject(points, materials.candidate));
    referenceGroup.updateMatrixWorld(true);
    const t0 = performance.now();
    state.planes = buildPlaneMap(referencePlaced);
    state.sample = samplePoints(candidateScans.map((s) => s.points), SAMPLE_POINTS);
    performance.measure('keel:calibrate planes', {start: t0});
    const total = (scans) => scans.reduce((t, s) => t + s.points.length / 3, 0);
    state.windowPoints = total(referenceScans) + total(candidateScans);
    counts.textContent = `${reference}: ${referenceScans.length} scans, ${formatNumber(total(referenceScans))} points; ` +
        `${candidate}: ${candidateScans.length} scans, ${formatNumber(total(candidateScans))} points`;
    counts.dataset.points = String(state.windowPoints);
    if (referenceScans.length === 0) notice('warning', `${reference} has no scan in keyframes ${k}..${k + n - 1}`);
    if (candidateScans.length === 0) notice('warning', `${candidate} has no scan in keyframes ${k}..${k + n - 1}`);
    placeCandidate();
    const box = new THREE.Box3().setFromObject(referenceGroup.children.length ? referenceGroup : candidateGroup);
    if (!box.isEmpty()) scene.fitBox(box);
    status.textContent = `Keyframes ${k}..${k + n - 1} of ${state.index.keyframes.length}`;
    container.dataset.calibrateReady = `${reference}:${candidate}:${k}:${n}`;
  }

  function setWindow() {
    const last = state.index.keyframes.length - 1;
    state.k = Math.min(last, Math.max(0, Math.round(Number(kInput.value) || 0)));
    state.n = Math.max(1, Math.round(Number(nInput.value) || 1));
    kInput.value = String(state.k);
    nInput.value = String(state.n);
    // The same window again (a change event, then the button): nothing to read or upload.
    if (container.dataset.calibrateReady === `${state.reference}:${state.candidate}:${state.k}:${state.n}`) return;
    run(showWindow());
  }

  // ---- one step: the candidate's matrices and the residual ------------------------------
  function placeCandidate() {
    if (!state.planes) return;
    const t0 = performance.now();
    const {xyz_m, rpy_deg} = values();
    const T_reference_candidate = matrixFromXyzRpy(xyz_m, rpy_deg);
    const matrices = state.candidateBases.map((base) => multiply(base, T_reference_candidate));
    candidateGroup.children.forEach((object, i) => object.matrix.fromArray(matrices[i]));
    candidateGroup.updateMatrixWorld(true);
    scene.requestRender();
    const t1 = performance.now();
    const r = residual(state.planes, state.sample, matrices, Number(threshold.value) || 0);
    const t2 = performance.now();
    state.lastStep = {placeMs: t1 - t0, residualMs: t2 - t1, residual: r, matrices};
    const shown = Number.isNaN(r.median_m)
        ? `no point of ${state.candidate} lies near a plane of ${state.reference} in keyframes ${state.k}..${state.k + state.n - 1}`
        : `median ${formatNumber(r.median_m, 3)} m · ${(100 * r.within).toFixed(1)} % within ${r.threshold_m} m ` +
          `(${formatNumber(r.matched)} of ${formatNumber(r.count)} points near a reference plane)`;
    readout.textContent = `point-to-plane residual: ${shown}`;
    Object.assign(readout.dataset, {medianM: String(r.median_m), within: String(r.within), matched: String(r.matched),
                                    count: String(r.count)});
  }

  // ---- sensors --------------------------------------------------------------------------
  function chooseSensors(reference, candidate) {
    const names = state.index.sensors.filter((s) => s.scans.length > 0).map((s) => s.name);
    state.reference = reference;
    const others = names.filter((n) => n !== reference);
    state.candidate = others.includes(candidate) ? candidate : others[0] || '';
    referenceSelect.replaceChildren(...names.map((n) => h('option', {value: n, selected: n === reference}, n)));
    candidateSelect.replaceChildren(...others.map((n) => h('option', {value: n, selected: n === state.candidate}, n)));
    if (!state.candidate) {
      notice('error', `No candidate: ${FILE_NAME} has scans of ${names.join(', ') || 'no sensor'} only`);
      return;
    }
    startAuto.hidden = !automaticExtrinsic();
    setValues(jobExtrinsic());
    run(showWindow());
  }

  // ---- reprocess ------------------------------------------------------------------------
  async function reprocess() {
    reprocessButton.disabled = true;
    const options = withExtrinsicOverride(state.job.options, state.candidate, state.reference, values());
    reprocessStatus.replaceChildren(h('p', {class: 'muted'}, 'Creating the job…'));
    try {
      const answer = await jobsApi.reprocess(state.job, options);
      const created = answer?.jobs?.[0];
      reprocessStatus.replaceChildren(created ? message('info', 'New job: ', h('a', {href: jobHash(created.id), id: 'calib-new-job'}, created.id))
          : message('info', 'The job was created (see the job list)'));
    } catch (e) {
      reprocessStatus.replaceChildren(message('error', 'The job could not be created', describe(e)));
    } finally {
      reprocessButton.disabled = false;
    }
  }

  function run(promise) {
    promise.catch((e) => {
      if (!disposed) notice('error', 'The calibration scans could not be shown', describe(e));
    });
  }

  async function load() {
    const [job, {artifacts}] = await Promise.all([jobsApi.get(id), jobsApi.artifacts(id)]);
    if (disposed) return;
    state.job = job;
    const byName = Object.fromEntries(artifacts.map((a) => [a.name, a]));
    state.artifact = byName[FILE_NAME];
    if (!state.artifact) {
      status.replaceChildren(message('error', `Job ${id} has no ${FILE_NAME}`, 'The calibrate stage writes it (docs/calibration.md).'));
      return;
    }
    const {indexBytes} = parseHeader(await fetchArtifactRange(state.artifact, 0, HEADER_BYTES));
    const indexBuffer = await fetchArtifactRange(state.artifact, HEADER_BYTES, HEADER_BYTES + indexBytes);
    state.index = parseIndex(indexBuffer, indexBytes, state.artifact.size || Infinity);
    if (byName['calibration.json']) {
      try {
        state.automatic = await fetchArtifactJson(byName['calibration.json']);
      } catch (e) {
        notice('warning', 'calibration.json could not be read: no automatic result to start from', describe(e));
      }
    }
    if (disposed) return;
    state.n = Math.min(DEFAULT_WINDOW, state.index.keyframes.length);
    nInput.value = String(state.n);
    kInput.max = String(state.index.keyframes.length - 1);
    controls.hidden = false;
    const reference = sensorOf(state.index, query.get('reference') || state.index.reference).name;
    chooseSensors(reference, query.get('candidate') || '');
  }

  // For the browser test and the benchmark: the scene and the last step's figures.
  window.keelCalibration = {scene, referenceGroup, candidateGroup, state};
  load().catch((e) => {
    if (!disposed) status.replaceChildren(message('error', `${FILE_NAME} could not be read`, describe(e)));
  });
  return () => {
    disposed = true;
    clearGroup(referenceGroup);
    clearGroup(candidateGroup);
    for (const m of Object.values(materials)) m.dispose();
    scene.dispose();
    if (window.keelCalibration?.scene === scene) delete window.keelCalibration;
  };
}
