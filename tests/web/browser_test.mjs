// The dashboard in a real headless Chromium against a real keel-server with a worker on
// loopback and keel-sim missions (issue #13, "Tests"): sign-in and a refused token, the job
// list updated live while a job runs, a list of 300 jobs drawn a window at a time and
// reached by scrolling, a failed job's error, the report view's numbers
// against report.json, the viewer's point and vertex counts against Debian's draco_decoder,
// the legend's range against the sidecar and the decoded values, a map from its 3D tiles
// (counts against draco_decoder and the .pnts headers, legends against tileset.json), a shape click moving the
// camera, the camera restored from the URL, a compare job of two surveys of the bridge and of
// the hull (its report's figures against report.json, the figures that differ reached by
// scrolling, its change map's and change hull's counts against draco_decoder and each
// colouring's legend against the sidecar), the queue page against GET /v1/queue, missing
// and corrupt artifacts shown as messages; and no console error or failed request.
//   node tests/web/browser_test.mjs --bin build/bin --web build/share/keel/web --out DIR
// Exits 77 (CTest: skipped) with the reason when Chromium or node_modules are absent.
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import {after, before, test} from 'node:test';
import {Server, distanceToMesh, dracoMesh, dracoVertexCount, poseTransform, launchChromium, missingPrerequisite, parseArgs, readPnts, simulate, simulateAsync,
        sourceDir, tempDir, watchPage} from './harness.mjs';

const args = parseArgs(process.argv.slice(2));
const binDir = path.resolve(args.bin || path.join(sourceDir, 'build/bin'));
const webDir = path.resolve(args.web || path.join(binDir, '../share/keel/web'));
const outDir = path.resolve(args.out || tempDir('keel-web-out-'));
const why = missingPrerequisite(binDir, webDir);
if (why) {
  console.log(`SKIP: browser tests: ${why}`);
  process.exit(77);
}
fs.mkdirSync(outDir, {recursive: true});

// The map stage writes per-point metrics as Draco attributes when asked (docs/stage-options.md).
const stageOptions = fs.readFileSync(path.join(sourceDir, 'docs/stage-options.md'), 'utf8');
const pointMetrics = stageOptions.includes('write_point_metrics');

const BRIDGE_SENSORS = 'imu,dvl,lidar_h,sonar,depth';

let server;
let browser;
// GET /v1/events and /v1/queue (docs/api.md "Live events and the queue"): the tests of the
// live list and of the queue page skip, saying so, on a server without them.
let hasEvents = true;
let hasQueue = true;
let page;
let problems;
const jobs = {};
let secondSurveys;  // the second surveys' mission folders (a promise)
let comparisonsMade;  // the compare tests' jobs (comparisons())
const work = tempDir('keel-web-test-');

// Screenshots of the page when a test fails, named after the test.
async function step(name, fn, shown = () => page) {
  try {
    await fn();
  } catch (e) {
    const p = shown();
    if (p && !p.isClosed()) {
      const file = path.join(outDir, `${name.replace(/[^a-z0-9]+/gi, '_')}.png`);
      await p.screenshot({path: file, fullPage: true}).catch(() => {});
      console.log(`screenshot: ${file}`);
    }
    throw e;
  }
}

async function signIn(p, srv) {
  await p.goto(`${srv.url}/#/signin`);
  await p.fill('#token', srv.token);
  await p.click('form.signin button[type=submit]');
}

before(async () => {
  const bridge = path.join(work, 'bridge');
  const hull = path.join(work, 'hull');
  // The first surveys of both scenes; the compare test adds their second surveys.
  simulate(binDir, bridge, {scenario: 'usv-bridge', survey: 1, duration: 20, sensors: BRIDGE_SENSORS});
  simulate(binDir, hull, {scenario: 'hauv-hull', survey: 1, duration: 60});
  // The second surveys for the compare tests (comparisons()), made while the first tests run.
  secondSurveys = Promise.all([
    simulateAsync(binDir, path.join(work, 'bridge_survey2'), {scenario: 'usv-bridge', survey: 2, duration: 20, sensors: BRIDGE_SENSORS}),
    simulateAsync(binDir, path.join(work, 'hull_survey2'), {scenario: 'hauv-hull', survey: 2, duration: 60})]);
  secondSurveys.catch(() => {});  // the compare tests report it
  jobs.bridgeMission = bridge;
  jobs.hullMission = hull;
  server = await new Server(binDir, webDir, {workers: 1}).start();
  hasEvents = (await server.api('v1/events?job_id=none', {raw: true, method: 'HEAD'}).catch(() => ({status: 0}))).status !== 404;
  hasQueue = (await server.api('v1/queue', {raw: true})).status !== 404;
  browser = await launchChromium();
  page = await browser.context.newPage();
  const missingRoute = (r) => r.status() === 404 &&
      ((!hasEvents && r.url().endsWith('/v1/events')) || (!hasQueue && r.url().endsWith('/v1/queue')));
  problems = watchPage(page, {allowStatus: missingRoute});
});

after(async () => {
  await browser?.close();
  await server?.stop();
  fs.rmSync(work, {recursive: true, force: true});
});

test('a refused token shows the sign-in page with the reason', () => step('refused token', async () => {
  const p = await browser.context.newPage();
  try {
    await p.goto(`${server.url}/#/jobs`);
    await p.waitForSelector('form.signin');  // no token: the sign-in page, not a blank one
    await p.fill('#token', 'not-a-token');
    await p.click('form.signin button[type=submit]');
    const text = await p.textContent('#signin-status .message', {timeout: 10000});
    assert.match(text, /refused this token/);
    assert.match(text, /401 unauthorized/);
    // A token the server stops accepting mid-session sends the user back with the reason.
    await p.evaluate(() => sessionStorage.setItem('keel.token', 'revoked-token'));
    await p.goto(`${server.url}/#/queue`);
    const reason = await p.textContent('#signin-status .message', {timeout: 10000});
    assert.match(reason, /refused your token/);
    assert.equal(await p.evaluate(() => sessionStorage.getItem('keel.token')), null);
  } finally {
    await p.close();
  }
}));

test('signed in, the job list follows a job live from queued to succeeded', (t) => step('live job list', async () => {
  await signIn(page, server);
  const set = pointMetrics ? ['--set', 'map.write_point_metrics=true'] : [];
  if (!hasEvents) {
    jobs.bridge = server.submit(jobs.bridgeMission, 'ingest,refine,map', set);
    jobs.hull = server.submit(jobs.hullMission, 'ingest,refine,ba,inspect', ['--set', 'ba.mode=proposed']);
    t.skip('this keel-server has no GET /v1/events yet: the live list is not tested');
    return;
  }
  await page.waitForSelector('#jobs-table');
  // Every state a row shows is recorded in the page, without reloading it.
  await page.evaluate(() => {
    window.seenStates = {};
    window.notReloaded = true;
    new MutationObserver(() => {
      for (const tr of document.querySelectorAll('#jobs-table tr[data-job-id]')) {
        const seen = (window.seenStates[tr.dataset.jobId] ||= []);
        const progress = tr.querySelector('.pct')?.textContent || '';
        const entry = `${tr.dataset.state}${progress ? ` ${progress}` : ''}`;
        if (seen[seen.length - 1] !== entry) seen.push(entry);
      }
    }).observe(document.getElementById('jobs-table'), {childList: true, subtree: true});
  });
  jobs.bridge = server.submit(jobs.bridgeMission, 'ingest,refine,map', set);
  jobs.hull = server.submit(jobs.hullMission, 'ingest,refine,ba,inspect', ['--set', 'ba.mode=proposed']);
  await page.waitForSelector(`tr[data-job-id="${jobs.bridge}"]`, {timeout: 20000});
  await page.waitForSelector(`tr[data-job-id="${jobs.bridge}"][data-state="succeeded"]`, {timeout: 600000});
  const seen = await page.evaluate((id) => window.seenStates[id], jobs.bridge);
  assert.ok(await page.evaluate(() => window.notReloaded), 'the page was reloaded');
  assert.ok(seen.some((s) => s.startsWith('running')), `never shown running: ${seen}`);
  assert.equal(seen[seen.length - 1], 'succeeded');
  const job = await server.api(`v1/jobs/${jobs.bridge}`);
  assert.equal(job.state, 'succeeded', job.error);
  const row = await page.$(`tr[data-job-id="${jobs.bridge}"]`);
  assert.equal(await row.$eval('td.attempts', (td) => td.textContent), String(job.attempts));
}));

test('a failed job shows its error before anything else', () => step('failed job', async () => {
  const id = server.submit(jobs.bridgeMission, 'ingest,refine', ['--set', 'refine.no_such_option=1']);
  const job = await server.waitJob(id);
  assert.equal(job.state, 'failed');
  await page.goto(`${server.url}/#/jobs/${id}`);
  const error = await page.waitForSelector('#job-error .message.error');
  assert.ok((await error.textContent()).includes(job.error), `page shows: ${await error.textContent()}`);
  const first = await page.evaluate(() => {
    const e = document.getElementById('job-error');
    const t = document.getElementById('timeline');
    return Boolean(e.compareDocumentPosition(t) & Node.DOCUMENT_POSITION_FOLLOWING);
  });
  assert.ok(first, 'the error comes after the timeline');
  assert.equal(await page.getAttribute('.stage-row[data-stage="refine"]', 'class'), 'stage-row failed');
  await page.selectOption('#log-level', 'error');
  const visible = await page.$$eval('#log .line:not([hidden])', (lines) => lines.map((l) => l.textContent));
  assert.ok(visible.length >= 1 && visible.every((l) => /failed|error/i.test(l)), `error lines: ${visible}`);
}));

// Every number the report view prints equals report.json's at the same path.
async function checkReportNumbers(id, requiredKeys) {
  const report = await server.artifactJson((await server.artifacts(id))['report.json']);
  await page.goto(`${server.url}/#/jobs/${id}/report`);
  await page.waitForSelector('body[data-report-ready="true"]', {timeout: 30000});
  const cells = await page.$$eval('[data-key]', (els) => els.map((e) => ({key: e.dataset.key, value: e.dataset.value, text: e.textContent})));
  const keys = new Set(cells.map((c) => c.key));
  for (const key of requiredKeys) assert.ok(keys.has(key), `the report view lacks ${key}`);
  assertCellsMatch(report, cells);
  return {report, cells};
}

// Each cell ({key, value, text}) shows the figure report.json has at its key.
function assertCellsMatch(report, cells) {
  for (const c of cells) {
    const expected = c.key.split('.').reduce((o, k) => (o === undefined || o === null ? undefined : o[k]), report);
    assert.notEqual(expected, undefined, `${c.key} is not in report.json`);
    if (typeof expected === 'number') {
      assert.equal(Number(c.value), expected, c.key);
      const shown = Number(c.text.replace(/,/g, ''));
      // Printed with 3-4 significant digits.
      assert.ok(Math.abs(shown - expected) <= 5e-3 * Math.abs(expected) + 1e-12, `${c.key}: shows ${c.text} for ${expected}`);
    } else {
      assert.equal(c.value, typeof expected === 'object' ? JSON.stringify(expected) : String(expected), c.key);
    }
  }
}

test('the report view shows report.json\'s figures for refine and map', () => step('report bridge', async () => {
  assert.equal((await server.waitJob(jobs.bridge)).state, 'succeeded');
  // The compare tests' jobs start now, so the worker runs them while the pages of the first
  // jobs are tested (their own tests report a failure).
  comparisons().catch(() => {});
  const t = 'stages.refine.evaluation.table';
  const required = [`${t}.map.ate.translation_m.rmse`, `${t}.refined_with_dvl.ate.translation_m.rmse`,
                    `${t}.refined_without_dvl.ate.translation_m.rmse`, `${t}.refined_with_dvl.rpe.translation_m.rmse`,
                    'stages.refine.dvl.dvl_scale.value', 'stages.refine.dvl.dvl_scale.sigma',
                    'stages.refine.dvl.dvl_rotation.sigma_deg.0', 'stages.map.metrics.table_v.rows.0.slam_map'];
  const {report, cells} = await checkReportNumbers(jobs.bridge, required);
  assert.ok(cells.length > 40, `${cells.length} figures`);
  // Histograms drawn from the same counts.
  const plots = await page.evaluate(() => Object.fromEntries(window.keelReport.plots));
  for (const [name, metrics] of Object.entries(report.stages.map.metrics.maps)) {
    const plot = plots[`hist-${name}-roughness_m`];
    assert.ok(plot, `no roughness histogram of ${name}`);
    assert.deepEqual(plot.series[0].values, metrics.roughness_m.histogram_counts);
    assert.deepEqual(plot.edges, metrics.roughness_m.histogram_edges);
  }
  const artifacts = await server.artifacts(jobs.bridge);
  if (artifacts['trajectories.json']) {
    const trajectories = await server.artifactJson(artifacts['trajectories.json']);
    const refined = trajectories.trajectories.find((x) => x.name === 'refined');
    if (refined?.ate_m) assert.deepEqual(plots['ate-refined'].series[0].values, refined.ate_m);
  }
}));

async function openViewer(id, query = '') {
  await page.goto(`${server.url}/#/jobs/${id}/viewer${query}`);
  await page.waitForSelector('body[data-viewer-ready="true"]', {timeout: 120000});
}

async function layerShown(name) {
  await page.waitForSelector(`.layer-entry[data-layer="${name}"][data-status="shown"]`, {timeout: 120000});
}

test('the viewer shows every map with its point count and a legend equal to the attribute range', () => step('viewer maps', async () => {
  const artifacts = await server.artifacts(jobs.bridge);
  const maps = Object.keys(artifacts).filter((n) => /^map_.*\.drc$/.test(n) && !n.endsWith('_preview.drc'));
  assert.ok(maps.length >= 2, `maps: ${maps}`);
  await openViewer(jobs.bridge);
  for (const file of maps) {
    const name = file.replace(/\.drc$/, '');
    const box = await page.$(`.layer-entry[data-layer="${name}"] input[type=checkbox]`);
    if (!(await box.isChecked())) await box.check();
    await layerShown(name);
    const decoded = Number(await page.getAttribute(`.layer-entry[data-layer="${name}"]`, 'data-points'));
    const level = await page.getAttribute(`.layer-entry[data-layer="${name}"]`, 'data-level');
    const shownFile = level === 'preview' ? `${name}_preview.drc` : file;
    const oracle = dracoVertexCount(await server.artifactBytes(artifacts[shownFile]));
    if (oracle !== null) assert.equal(decoded, oracle, `${shownFile}: page vs draco_decoder`);
    const sidecar = artifacts[`${name}.json`] ? await server.artifactJson(artifacts[`${name}.json`]) : null;
    if (sidecar && level === 'full') assert.equal(decoded, sidecar.points, `${name}: page vs sidecar`);
    if (!sidecar) continue;
    // Each colouring's legend: the sidecar's min/max, and the decoded values' min/max.
    for (const mode of await page.$$eval('#color-by option', (os) => os.map((o) => o.value))) {
      await page.selectOption('#color-by', mode);
      const legend = await page.$(`.legend-box[data-layer="${name}"][data-mode="${mode}"]`);
      if (!legend) continue;  // this map lacks the attribute (keeps its height colouring)
      const min = Number(await legend.getAttribute('data-min'));
      const max = Number(await legend.getAttribute('data-max'));
      const expected = mode === 'height' ? {min: sidecar.bbox_min[2], max: sidecar.bbox_max[2]} : sidecar.attributes[mode];
      assert.equal(min, expected.min, `${name} ${mode} min`);
      assert.equal(max, expected.max, `${name} ${mode} max`);
      // An attribute with undefined points says how they are drawn.
      assert.equal(Boolean(await legend.$('.no-data')), expected.no_data !== undefined, `${name} ${mode}: no-data entry`);
      if (level === 'full') {
        const decodedRange = await page.evaluate(([l, m]) => window.keelViewer.attributeRange(l, m === 'height' ? 'position' : m), [name, mode]);
        const tolerance = 1e-5 * Math.max(1, Math.abs(expected.max - expected.min));
        assert.ok(Math.abs(decodedRange.min - expected.min) <= tolerance, `${name} ${mode}: decoded min ${decodedRange.min} vs ${expected.min}`);
        assert.ok(Math.abs(decodedRange.max - expected.max) <= tolerance, `${name} ${mode}: decoded max ${decodedRange.max} vs ${expected.max}`);
      }
    }
  }
  if (pointMetrics) {
    const modes = await page.$$eval('#color-by option', (os) => os.map((o) => o.value));
    for (const m of ['density', 'roughness', 'planarity']) assert.ok(modes.includes(m), `no ${m} colouring: ${modes}`);
  }
  // Trajectories: the line has as many vertices as trajectories.json has poses.
  if (artifacts['trajectories.json']) {
    const doc = await server.artifactJson(artifacts['trajectories.json']);
    for (const t of doc.trajectories)
      assert.equal(Number(await page.getAttribute(`.layer-entry[data-layer="trajectory:${t.name}"]`, 'data-poses')), t.xyz.length);
  }
}));

// The same map drawn from its level-of-detail tiles (?lod=tiles; by default only maps over
// the point budget are): the map's point count from tileset.json against draco_decoder's
// count of its Draco file, the points on screen against the .pnts headers of the tiles the
// page shows, and each colouring's legend against tileset.json's ranges.
test('a map drawn from its level-of-detail tiles shows the map\'s count, its tiles\' points and the tileset\'s ranges', (t) => step('viewer tiles', async () => {
  const artifacts = await server.artifacts(jobs.bridge);
  const tar = artifacts['tiles_combined.tar'];
  if (!tar) {
    t.skip('the map stage wrote no tiles_combined.tar');
    return;
  }
  const tileset = JSON.parse((await server.artifactFile(tar, 'tileset.json')).toString('utf8'));
  const keel = tileset.extras.keel;
  await openViewer(jobs.bridge, '?lod=tiles');
  const entry = '.layer-entry[data-layer="map_combined"]';
  await layerShown('map_combined');
  const row = await page.$eval(entry, (e) => ({...e.dataset}));
  assert.equal(row.level, 'tiles');
  assert.equal(Number(row.points), keel.points, 'page vs tileset.json');
  const oracle = dracoVertexCount(await server.artifactBytes(artifacts['map_combined.drc']));
  if (oracle !== null) assert.equal(keel.points, oracle, 'tileset.json vs draco_decoder on map_combined.drc');
  // The tiles on screen, each tile's points read from its own header.
  const shown = await page.evaluate(() => [...window.keelViewer.layers.get('map_combined').tiles.visibleTiles].map((tile) => tile.content.uri));
  assert.ok(shown.length > 0, 'no tile on screen');
  let points = 0;
  let zMin = Infinity;
  let zMax = -Infinity;
  for (const uri of shown) {
    const tile = readPnts(await server.artifactFile(tar, uri));
    points += tile.points;
    zMin = Math.min(zMin, tile.zMin);
    zMax = Math.max(zMax, tile.zMax);
  }
  assert.equal(Number(row.drawn), points, `points on screen in ${shown.join(', ')}`);
  assert.ok(points <= Number(row.points));
  // Height: the legend spans the points on screen, and the colour ramp's ends are the legend's.
  const height = await page.$('.legend-box[data-layer="map_combined"][data-mode="height"]');
  const [min, max] = [Number(await height.getAttribute('data-min')), Number(await height.getAttribute('data-max'))];
  assert.ok(min <= zMin + 1e-3 && max >= zMax - 1e-3, `height legend ${min}..${max} vs tiles on screen ${zMin}..${zMax}`);
  const ramp = await page.evaluate(() => {
    const u = window.keelViewer.layers.get('map_combined').material.uniforms;
    return [u.vmin.value, u.vmax.value];
  });
  assert.deepEqual(ramp, [min, max], 'colour ramp ends vs height legend');
  // Colourings: every attribute tileset.json lists, its legend its min/max.
  const modes = await page.$$eval('#color-by option', (os) => os.map((o) => o.value));
  for (const [mode, range] of Object.entries(keel.attributes)) {
    assert.ok(modes.includes(mode), `no ${mode} colouring: ${modes}`);
    await page.selectOption('#color-by', mode);
    const legend = await page.waitForSelector(`.legend-box[data-layer="map_combined"][data-mode="${mode}"]`);
    assert.equal(Number(await legend.getAttribute('data-min')), range.min, `${mode} min`);
    assert.equal(Number(await legend.getAttribute('data-max')), range.max, `${mode} max`);
  }
  await page.selectOption('#color-by', 'height');
}));

test('the camera in the URL reopens the same view', () => step('camera url', async () => {
  await openViewer(jobs.bridge, '?cam=12.5,-40.25,18,3,4.5,-1');
  assert.equal(await page.evaluate(() => window.keelViewer.camera()), '12.5,-40.25,18,3,4.5,-1');
  // Orbit with the mouse: the URL follows, and a reload restores exactly that.
  const canvas = await page.$('#viewer-canvas');
  const b = await canvas.boundingBox();
  await page.mouse.move(b.x + b.width / 2, b.y + b.height / 2);
  await page.mouse.down();
  await page.mouse.move(b.x + b.width / 2 + 120, b.y + b.height / 2 + 40, {steps: 8});
  await page.mouse.up();
  const moved = await page.evaluate(() => window.keelViewer.camera());
  assert.notEqual(moved, '12.5,-40.25,18,3,4.5,-1');
  await page.waitForFunction((c) => new URLSearchParams(location.hash.split('?')[1] || '').get('cam') === c, moved);
  await page.reload();
  await page.waitForSelector('body[data-viewer-ready="true"]', {timeout: 120000});
  assert.equal(await page.evaluate(() => window.keelViewer.camera()), moved);
}));

test('the hull: ba and inspect figures, mesh vertices, deviation legend, a shape click moves the camera', () => step('hull', async () => {
  const job = await server.waitJob(jobs.hull);
  assert.equal(job.state, 'succeeded', job.error);
  const {report} = await checkReportNumbers(jobs.hull, ['stages.ba.modes.proposed.iterations', 'stages.inspect.tau_m']);
  const plots = await page.evaluate(() => Object.fromEntries(window.keelReport.plots));
  assert.deepEqual(plots.fig17.series[0].values, report.stages.ba.modes.proposed.cost_per_iteration);
  assert.deepEqual(plots.fig16.series[0].values, report.stages.ba.modes.proposed.lambda1_fraction_per_iteration);
  assert.deepEqual(plots['fig18c-proposed'].series[1].values, report.stages.ba.modes.proposed.dvl_residuals_final.histogram.counts);

  const artifacts = await server.artifacts(jobs.hull);
  await openViewer(jobs.hull);
  await layerShown('mesh_remeshed');
  const vertices = Number(await page.getAttribute('.layer-entry[data-layer="mesh_remeshed"]', 'data-vertices'));
  const oracle = dracoVertexCount(await server.artifactBytes(artifacts['mesh_remeshed.drc']));
  if (oracle !== null) assert.equal(vertices, oracle, 'mesh_remeshed.drc: page vs draco_decoder');
  if (artifacts['mesh_remeshed.json']) {
    const sidecar = await server.artifactJson(artifacts['mesh_remeshed.json']);
    assert.equal(vertices, sidecar.points);
    const legend = await page.$('.legend-box[data-layer="mesh_remeshed"]');
    assert.equal(Number(await legend.getAttribute('data-min')), sidecar.attributes.deviation.min);
    assert.equal(Number(await legend.getAttribute('data-max')), sidecar.attributes.deviation.max);
    const decoded = await page.evaluate(() => window.keelViewer.attributeRange('mesh_remeshed', 'deviation'));
    assert.ok(Math.abs(decoded.max - sidecar.attributes.deviation.max) <= 1e-6 + 1e-5 * Math.abs(sidecar.attributes.deviation.max));
    // The threshold slider greys what is below it and says how much is above.
    await page.$eval('#deviation-threshold', (s) => {
      s.value = String(Number(s.max) / 2);
      s.dispatchEvent(new Event('input'));
    });
    assert.match(await page.textContent('#threshold-share'), /% of vertices at or above/);
  }
  const shapes = artifacts['shapes.json'] ? (await server.artifactJson(artifacts['shapes.json'])).shapes : [];
  if (shapes.length > 0) {
    const before = await page.evaluate(() => window.keelViewer.camera());
    await page.click('#shapes-table tbody tr:first-child');
    await page.waitForFunction((b) => window.keelViewer.camera() !== b && !window.keelViewer.scene.flight, before);
    const target = (await page.evaluate(() => window.keelViewer.camera())).split(',').slice(3).map(Number);
    shapes[0].centroid_world_m.forEach((c, i) => assert.ok(Math.abs(target[i] - c) <= 1e-3, `camera target ${target} vs shape ${shapes[0].centroid_world_m}`));
  } else {
    console.log('# note: the hull mission gave no shape; the shape click was not exercised');
  }
}));

// Measurements on the hull: a point picked on the remeshed hull lies on it, point to point
// gives the distance between the two picked points, and point to CAD the distance of the
// picked point to the CAD mesh (cad_model.drc moved into the world by ba_solution.json's
// T_world_model), each against a brute-force distance over draco_decoder's triangles.
test('measurements: point to point on the hull and point to CAD against brute-force distances', (t) => step('measure', async () => {
  const artifacts = await server.artifacts(jobs.hull);
  if (!artifacts['cad_model.drc'] || !artifacts['ba_solution.json']) {
    t.skip('the hull job wrote no cad_model.drc or ba_solution.json');
    return;
  }
  const cad = dracoMesh(await server.artifactBytes(artifacts['cad_model.drc']));
  const remeshed = dracoMesh(await server.artifactBytes(artifacts['mesh_remeshed.drc']));
  if (!cad || !remeshed) {
    t.skip('no draco_decoder for the oracle');
    return;
  }
  const toWorld = poseTransform((await server.artifactJson(artifacts['ba_solution.json'])).T_world_model);
  await openViewer(jobs.hull);
  await layerShown('mesh_remeshed');
  const box = await page.$('#viewer-canvas');
  const area = await box.boundingBox();
  // Clicks around the middle of the view until `count` measurements are made; each click is
  // answered on the page (a miss says so, a first point asks for the second).
  const clickOnHull = async (count) => {
    for (let i = 0; i < 25; i += 1) {
      const x = area.x + area.width * (0.3 + 0.1 * (i % 5)), y = area.y + area.height * (0.3 + 0.1 * Math.floor(i / 5));
      await page.evaluate(() => { document.getElementById('readout').textContent = ''; });
      await page.mouse.click(x, y);
      await page.waitForFunction((n) => window.keelViewer.state.measurements.length >= n ||
                                        /No point there|Click the second point/.test(document.getElementById('readout').textContent),
                                 count, {timeout: 60000});
      if (await page.evaluate((n) => window.keelViewer.state.measurements.length >= n, count)) return;
    }
    throw new Error('no click landed on the hull');
  };
  await page.click('button.measure-mode[data-mode="cad"]');
  await clickOnHull(1);
  const toCad = (await page.evaluate(() => window.keelViewer.state.measurements))[0];
  assert.equal(toCad.kind, 'cad');
  const oracle = distanceToMesh(toCad.from, cad, toWorld);
  assert.ok(Math.abs(toCad.metres - oracle) <= 1e-4, `point to CAD: page ${toCad.metres} m, brute force ${oracle} m`);
  assert.ok(distanceToMesh(toCad.to, cad, toWorld) <= 1e-4, 'the closest point lies on the CAD mesh');
  assert.ok(distanceToMesh(toCad.from, remeshed) <= 1e-4, 'the picked point lies on the remeshed hull');

  await page.click('button.measure-mode[data-mode="distance"]');
  await clickOnHull(2);  // clicks until a first and a second point landed on the hull
  const between = (await page.evaluate(() => window.keelViewer.state.measurements))[1];
  assert.equal(between.kind, 'distance');
  for (const p of [between.from, between.to]) assert.ok(distanceToMesh(p, remeshed) <= 1e-4, `picked ${p} lies on the remeshed hull`);
  assert.ok(Math.abs(between.metres - Math.hypot(...between.to.map((v, i) => v - between.from[i]))) <= 1e-9);
  assert.equal(Number(await page.getAttribute('#measurements li[data-kind="cad"]', 'data-metres')), toCad.metres);
}));

// ---- compare jobs (issue 16) ---------------------------------------------------------------
// Two surveys of one scene compared through POST /v1/comparisons (docs/api.md "Comparisons"):
// A is the first survey's job of the tests above, B a job on keel-sim's second survey (the
// same scene with known changes). The bridge's B runs without point metrics, so the options
// that differ have a row; the hull's B with A's options.
function comparisons() {
  comparisonsMade ||= (async () => {
    // Without blocking: the pages of the first jobs are tested meanwhile.
    const [bridgeB, hullB] = await secondSurveys;
    const b = {bridge: await server.submitAsync(bridgeB, 'ingest,refine,map')};
    b.hull = await server.submitAsync(hullB, 'ingest,refine,ba,inspect', ['--set', 'ba.mode=proposed']);
    const compare = async (a, kind) => {
      for (const id of [a, b[kind]]) {
        const job = await server.waitJob(id);
        assert.equal(job.state, 'succeeded', `${kind} job ${id}: ${job.error}`);
      }
      return (await server.api('v1/comparisons', {method: 'POST', json: {job_a: a, job_b: b[kind], options: {}}})).id;
    };
    const ids = {bridge: await compare(jobs.bridge, 'bridge'), hull: await compare(jobs.hull, 'hull')};
    for (const id of Object.values(ids)) {
      const job = await server.waitJob(id);
      assert.equal(job.state, 'succeeded', `compare job ${id}: ${job.error}`);
    }
    return ids;
  })();
  return comparisonsMade;
}

const nextFrame = (p) => p.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));

// Scrolls the figures that differ from top to bottom: [{index, cells}] of every row in the
// order the table shows them, and the most rows the page held at once.
async function scrollFigures() {
  const seen = new Map();
  let most = 0;
  for (let top = 0; ;) {
    await page.$eval('#compare-figures-scroll', (el, y) => { el.scrollTop = y; }, top);
    await nextFrame(page);
    const rows = await page.$$eval('#compare-figures tbody tr[data-index]', (trs) => trs.map((tr) => ({index: Number(tr.dataset.index),
      cells: [...tr.querySelectorAll('[data-key]')].map((e) => ({key: e.dataset.key, value: e.dataset.value, text: e.textContent}))})));
    most = Math.max(most, rows.length);
    for (const row of rows) if (!seen.has(row.index)) seen.set(row.index, row);  // windows overlap, in the list's order
    const box = await page.$eval('#compare-figures-scroll', (el) => ({top: el.scrollTop, height: el.clientHeight, scroll: el.scrollHeight}));
    if (box.top + box.height >= box.scroll - 1) break;
    top = box.top + box.height;
  }
  return {rows: [...seen.values()], most};
}

test('a compare job\'s report: registration, change per map and its histogram, every figure that differs, relative ATE', () => step('compare report', async () => {
  const {bridge: id} = await comparisons();
  const expected = await server.artifactJson((await server.artifacts(id))['report.json']);
  const compare = expected.stages.compare;
  assert.ok(compare.maps, `the bridge surveys were compared as ${compare.kind}, not maps`);
  const c = 'stages.compare';
  const r = `${c}.maps.registration`;
  const names = Object.keys(compare.maps.maps);
  assert.ok(names.length >= 1, 'no map compared');
  const required = [`${c}.job_a`, `${c}.job_b`, `${c}.kind`, `${r}.T_a_b.translation_norm_m`, `${r}.T_a_b.rotation_deg`, `${r}.rms_stable_m`,
                    `${r}.stable_fraction`, `${r}.converged`, `${r}.iterations`, `${c}.runs.figures_that_differ`];
  for (const name of names)
    for (const k of ['points_a', 'points_b', 'core_points', 'compared_area_m2', 'significant_area_m2', 'significant_fraction',
                     'significant_added_area_m2', 'significant_removed_area_m2', 'registration_error_m', 'points_per_second',
                     'm3c2_m.mean', 'change_histogram.below', 'change_histogram.above'])
      required.push(`${c}.maps.maps.${name}.${k}`);
  compare.runs.options_differ.forEach((o, i) => { if (typeof o.a === 'number') required.push(`${c}.runs.options_differ.${i}.a`); });
  for (const [trajectory, entry] of Object.entries(compare.runs.relative_ate))
    if (!entry.error) required.push(`${c}.runs.relative_ate.${trajectory}.ate_none.translation_m.rmse`);
  const {report, cells} = await checkReportNumbers(id, required);
  assert.equal(report.stages.compare.job_a, jobs.bridge);
  assert.ok(cells.filter((x) => x.key.startsWith(`${c}.`)).length >= required.length);
  // Job A's and B's pages are linked.
  assert.equal(await page.getAttribute(`#compare-jobs a[data-key="${c}.job_a"]`, 'href'), `#/jobs/${compare.job_a}`);
  assert.equal(await page.getAttribute(`#compare-jobs a[data-key="${c}.job_b"]`, 'href'), `#/jobs/${compare.job_b}`);
  // The change histograms drawn from report.json's bins.
  const plots = await page.evaluate(() => Object.fromEntries(window.keelReport.plots));
  for (const name of names) {
    const plot = plots[`change-${name}`];
    assert.ok(plot, `no change histogram of ${name}`);
    assert.deepEqual(plot.edges, compare.maps.maps[name].change_histogram.edges_m);
    assert.deepEqual(plot.series[0].values, compare.maps.maps[name].change_histogram.area_m2);
  }
  // The options that differ: B ran without A's point metrics.
  const options = await page.$$eval('#compare-options tbody tr td:first-child', (tds) => tds.map((td) => td.textContent));
  assert.deepEqual(options, compare.runs.options_differ.map((o) => o.option));
  if (pointMetrics) assert.ok(options.includes('map.write_point_metrics'), `options that differ: ${options}`);
  // Every figure that differs is reached by scrolling, most changed first, and only the rows
  // in view are in the page.
  const figures = compare.runs.figures;
  const differ = figures.map((row, i) => (row.a !== row.b ? i : -1)).filter((i) => i >= 0);
  assert.ok(differ.length > 0, 'no figure differs between two surveys');
  const {rows, most} = await scrollFigures();
  assert.deepEqual(rows.map((row) => row.index).sort((x, y) => x - y), differ);
  for (const row of rows) assertCellsMatch(report, row.cells);
  const magnitude = (f) => (f.relative === undefined ? Infinity : Math.abs(f.relative));
  for (let i = 1; i < rows.length; i += 1)
    assert.ok(magnitude(figures[rows[i - 1].index]) >= magnitude(figures[rows[i].index]),
              `${figures[rows[i - 1].index].figure} above the more changed ${figures[rows[i].index].figure}`);
  if (differ.length > 100) assert.ok(most < differ.length / 2, `${most} of ${differ.length} rows in the page at once`);
  // Relative ATE: a row per trajectory and alignment, or the reason it was not compared.
  const ateRows = await page.$$eval('#compare-relative-ate tbody tr', (trs) => trs.map((tr) => tr.textContent));
  const expectedAte = Object.entries(compare.runs.relative_ate).flatMap(([t, entry]) =>
    (entry.error ? [`${t}${entry.error}`] : Object.keys(entry).filter((k) => k.startsWith('ate_')).map(() => t)));
  assert.equal(ateRows.length, expectedAte.length);
  for (const text of expectedAte) assert.ok(ateRows.some((row) => row.startsWith(text)), `no relative ATE row ${text}`);
}));

test('a hull compare job\'s report: x_gM difference, deviation change and the per-shape growth table', () => step('compare hull report', async () => {
  const {hull: id} = await comparisons();
  const expected = await server.artifactJson((await server.artifacts(id))['report.json']);
  const hull = expected.stages.compare.hull;
  assert.ok(hull, `the hull surveys were compared as ${expected.stages.compare.kind}, not hulls`);
  const b = 'stages.compare.hull';
  const required = [`${b}.x_gM_difference.translation_norm_m`, `${b}.x_gM_difference.rotation_deg`, `${b}.vertices`,
                    `${b}.shape_registration.translation_norm_m`, `${b}.shape_registration.pairs`,
                    `${b}.shapes_a`, `${b}.shapes_b`, `${b}.kept`, `${b}.new`, `${b}.gone`, `${b}.significantly_grown`,
                    `${b}.deviation_change_m.count`];
  hull.shapes.forEach((shape, i) => {
    for (const k of ['height_a_m', 'height_b_m', 'height_growth_m', 'height_growth_sigma_m', 'footprint_a_m2', 'footprint_b_m2',
                     'footprint_growth_m2', 'footprint_growth_sigma_m2', 'significant_growth'])
      if (shape[k] !== undefined) required.push(`${b}.shapes.${i}.${k}`);
    required.push(`${b}.shapes.${i}.centroid_model_m.0`);
  });
  await checkReportNumbers(id, required);
  assert.deepEqual(await page.$$eval('#compare-shapes tbody tr', (trs) => trs.map((tr) => tr.dataset.status)), hull.shapes.map((s) => s.status));
  const plots = await page.evaluate(() => Object.fromEntries(window.keelReport.plots));
  if (hull.deviation_change_m.histogram_counts)
    assert.deepEqual(plots['hull-deviation-change'].series[0].values, hull.deviation_change_m.histogram_counts);
}));

// The legend of `layer` coloured by `mode` against the sidecar's range (height: its bbox's z),
// and the values the page decoded against the same range.
// `clip`: the ramp's ends expected for a change map's M3C2 colouring (its ± box), else ± the
// attribute's larger magnitude.
async function checkChangeLegend(layer, mode, sidecar, clip = null) {
  const legend = await page.waitForSelector(`.legend-box[data-layer="${layer}"][data-mode="${mode}"]`, {timeout: 10000});
  const expected = mode === 'height' ? {min: sidecar.bbox_min[2], max: sidecar.bbox_max[2]} : sidecar.attributes[mode];
  assert.equal(Number(await legend.getAttribute('data-min')), expected.min, `${layer} ${mode} min`);
  assert.equal(Number(await legend.getAttribute('data-max')), expected.max, `${layer} ${mode} max`);
  const decoded = await page.evaluate(([l, m]) => window.keelViewer.attributeRange(l, m === 'height' ? 'position' : m), [layer, mode]);
  const tolerance = 1e-5 * Math.max(1, Math.abs(expected.max - expected.min));
  assert.ok(Math.abs(decoded.min - expected.min) <= tolerance && Math.abs(decoded.max - expected.max) <= tolerance,
            `${layer} ${mode}: decoded ${decoded.min}..${decoded.max} vs sidecar ${expected.min}..${expected.max}`);
  // A signed change: the ramp centred on zero (its ends ± the larger magnitude).
  if (['m3c2_m', 'deviation_a', 'deviation_b', 'deviation_change'].includes(mode)) {
    const ends = await page.evaluate((l) => {
      const u = window.keelViewer.layers.get(l).material.uniforms;
      return [u.vmin.value, u.vmax.value];
    }, layer);
    const extent = clip ?? Math.max(Math.abs(expected.min), Math.abs(expected.max));
    assert.deepEqual(ends, extent > 0 ? [-extent, extent] : [-1, 1], `${layer} ${mode}: ramp ends`);
    if (clip) assert.equal(Number(await legend.$eval('.clip', (e) => e.dataset.clip)), clip, `${layer}: the legend names the clip`);
  }
  if (mode === 'significant') {
    const entries = await legend.$$eval('[data-value]', (es) => es.map((e) => [Number(e.dataset.value), e.textContent]));
    const names = {'-1': /undefined/, 0: /not significant/, 1: /^significant$/};
    assert.deepEqual(entries.map(([v]) => v), Array.from({length: expected.max - expected.min + 1}, (_, i) => expected.min + i));
    for (const [v, text] of entries) assert.match(text, names[v]);
  }
}

// A sidecar the compare stage writes beside each change file (docs/artifacts.md "compare").
async function changeSidecar(artifacts, name, kind, frame, attributes) {
  assert.ok(artifacts[`${name}.json`], `the compare job has no ${name}.json (its Draco sidecar, docs/artifacts.md "Draco sidecar")`);
  const sidecar = await server.artifactJson(artifacts[`${name}.json`]);
  assert.equal(sidecar.kind, kind, `${name}.json kind`);
  assert.equal(sidecar.frame, frame, `${name}.json frame`);
  for (const a of attributes) assert.equal(sidecar.attributes?.[a]?.data_type, 'float32', `${name}.json: attribute ${a}`);
  return sidecar;
}

test('the viewer shows a compare job\'s change map: its point count and each colouring\'s legend against the sidecar', () => step('compare viewer', async () => {
  const {bridge: id} = await comparisons();
  const artifacts = await server.artifacts(id);
  const maps = Object.keys(artifacts).filter((n) => /^change_.*\.drc$/.test(n) && n !== 'change_hull.drc');
  assert.ok(maps.length >= 1, `change maps: ${maps}`);
  await openViewer(id);
  for (const file of maps) {
    const name = file.replace(/\.drc$/, '');
    const sidecar = await changeSidecar(artifacts, name, 'point_cloud', 'world', ['m3c2_m', 'lod95_m', 'significant', 'c2c_m']);
    const box = await page.$(`.layer-entry[data-layer="${name}"] input[type=checkbox]`);
    if (!(await box.isChecked())) await box.check();
    await layerShown(name);
    const row = await page.$eval(`.layer-entry[data-layer="${name}"]`, (e) => ({...e.dataset}));
    const oracle = dracoVertexCount(await server.artifactBytes(artifacts[file]));
    if (oracle !== null) assert.equal(Number(row.points), oracle, `${file}: page vs draco_decoder`);
    assert.equal(Number(row.points), sidecar.points, `${name}: page vs sidecar`);
    const modes = await page.$$eval('#change-color-by option', (os) => os.map((o) => o.value));
    for (const m of ['m3c2_m', 'significant', 'lod95_m', 'c2c_m', 'height']) assert.ok(modes.includes(m), `no ${m} colouring: ${modes}`);
    assert.equal(modes[0], 'm3c2_m', 'the change is the first colouring');
    // The M3C2 ramp spans ± four times the median level of detection of changes.json.
    const figures = (await server.artifactJson(artifacts['changes.json'])).maps.maps[name.replace(/^change_/, '')];
    const clip = 4 * figures.lod95_m.median;
    for (const mode of modes) {
      await page.selectOption('#change-color-by', mode);
      await checkChangeLegend(name, mode, sidecar, mode === 'm3c2_m' ? clip : null);
    }
    await page.selectOption('#change-color-by', 'm3c2_m');
    // A clip typed in the box moves the ramp's ends and is kept in the URL.
    await page.fill('#change-clip', '0.05');
    await page.dispatchEvent('#change-clip', 'change');
    await checkChangeLegend(name, 'm3c2_m', sidecar, 0.05);
    assert.match(page.url(), /[?&]clip=0\.05/);
    await page.fill('#change-clip', '');  // back to the default, for the next map
    await page.dispatchEvent('#change-clip', 'change');
  }
}));

test('the viewer shows a compare job\'s change hull: its vertex count and the deviation change legends against the sidecar', () => step('compare hull viewer', async () => {
  const {hull: id} = await comparisons();
  const artifacts = await server.artifacts(id);
  assert.ok(artifacts['change_hull.drc'], 'the hull compare job has no change_hull.drc');
  const sidecar = await changeSidecar(artifacts, 'change_hull', 'mesh', 'model', ['deviation_a', 'deviation_b', 'deviation_change']);
  await openViewer(id);
  await layerShown('change_hull');
  const vertices = Number(await page.getAttribute('.layer-entry[data-layer="change_hull"]', 'data-vertices'));
  const oracle = dracoVertexCount(await server.artifactBytes(artifacts['change_hull.drc']));
  if (oracle !== null) assert.equal(vertices, oracle, 'change_hull.drc: page vs draco_decoder');
  assert.equal(vertices, sidecar.points, 'change_hull: page vs sidecar');
  await checkChangeLegend('change_hull', 'deviation_change', sidecar);
  for (const attribute of ['deviation_a', 'deviation_b', 'deviation_change']) {
    await page.selectOption('#change-hull-color-by', attribute);
    await checkChangeLegend('change_hull', attribute, sidecar);
  }
}));

test('the queue page shows the server\'s own figures', (t) => step('queue', async () => {
  if (!hasQueue) {
    t.skip('this keel-server has no GET /v1/queue yet');
    return;
  }
  await page.goto(`${server.url}/#/queue`);
  await page.waitForSelector('#count-succeeded');
  const queue = await server.api('v1/queue');
  for (const state of ['queued', 'running', 'succeeded', 'failed', 'canceled'])
    assert.equal(await page.textContent(`#count-${state} .value`), String(queue.jobs_by_state[state] ?? 0), state);
  assert.equal(await page.textContent('#workers-alive .value'), String(queue.workers_alive));
}));

// The job list keeps only the rows in view in the page (web/js/virtual_rows.js): a long list
// still counts every job, reaches each one by scrolling, newest first by the server's
// creation times, and shows a change that arrived while its row was out of view.
let longPage;
test('a long job list draws the rows in view and reaches every job by scrolling', (t) => step('long job list', async () => {
  const bare = await new Server(binDir, webDir, {workers: 0}).start();
  longPage = await browser.context.newPage();
  const longListProblems = watchPage(longPage);
  try {
    const first = bare.submit(jobs.bridgeMission, 'ingest');
    const {mission_id: missionId} = await bare.api(`v1/jobs/${first}`);
    const total = 300;
    for (let made = 1; made < total; made += 20)
      await Promise.all(Array.from({length: Math.min(20, total - made)}, () =>
        bare.api('v1/jobs', {method: 'POST', json: {mission_id: missionId, stages: ['ingest']}})));
    const {jobs: records} = await bare.api('v1/jobs?limit=10000');
    assert.equal(records.length, total);
    const createdMs = new Map(records.map((job) => [job.id, job.created_at_ms]));

    await signIn(longPage, bare);
    await longPage.waitForFunction((n) => document.body.dataset.jobsRendered === String(n), total, {timeout: 30000});
    assert.equal(await longPage.textContent('#job-count'), `${total} of ${total} jobs`);
    const drawn = () => longPage.$$eval('#jobs-table tbody tr[data-job-id]', (trs) => trs.map((tr) => ({id: tr.dataset.jobId, state: tr.dataset.state})));
    const frame = () => longPage.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
    const inView = await drawn();
    assert.ok(inView.length > 5 && inView.length < 100, `${inView.length} rows in the page for ${total} jobs`);

    // A change to the oldest job (the last row, out of view) while the page is open.
    if (hasEvents) {
      await longPage.waitForSelector('#live[data-state="live"]', {timeout: 10000});
      assert.ok(!inView.some((row) => row.id === first), 'the oldest job is drawn before scrolling to it');
      await bare.api(`v1/jobs/${first}/cancel`, {method: 'POST', json: {}});
      // The event has reached the page's list (its latency is measured by the benchmark).
      await longPage.waitForFunction((id) => document.body.dataset.lastJobEvent === `${id} canceled`, first, {timeout: 15000});
    } else {
      t.diagnostic('no GET /v1/events: the change out of view is not tested');
    }

    // Scroll through the whole list a viewport at a time.
    const seen = new Map();  // id -> state
    const order = [];
    for (let top = 0; ; ) {
      await longPage.$eval('#jobs-scroll', (el, y) => { el.scrollTop = y; }, top);
      await frame();
      const rows = await drawn();
      for (const row of rows) {
        if (!seen.has(row.id)) order.push(row.id);  // windows overlap; scrolling down keeps the list's order
        seen.set(row.id, row.state);
      }
      const box = await longPage.$eval('#jobs-scroll', (el) => ({top: el.scrollTop, height: el.clientHeight, scroll: el.scrollHeight}));
      assert.ok(rows.length < 100, `${rows.length} rows in the page at scrollTop ${box.top}`);
      if (box.top + box.height >= box.scroll - 1) break;
      top = box.top + box.height;
    }
    assert.equal(seen.size, total, 'jobs reached by scrolling');
    for (let i = 1; i < order.length; i += 1)
      assert.ok(createdMs.get(order[i - 1]) >= createdMs.get(order[i]), `${order[i - 1]} drawn above the older ${order[i]}`);
    assert.equal(order[order.length - 1], first, 'the oldest job is the last row');
    if (hasEvents) assert.equal(seen.get(first), 'canceled', 'the change made while the row was out of view');
    assert.deepEqual(longListProblems, []);
  } finally {
    await longPage.close();
    await bare.stop();
  }
}, () => longPage));

test('no console error and no failed request on the signed-in pages', () => {
  assert.deepEqual(problems, []);
});

// A job made through the worker protocol with artifacts that are missing or corrupt: the
// pages name them in messages instead of drawing nothing.
test('missing and corrupt artifacts are named in messages', () => step('bad artifacts', async () => {
  const bare = await new Server(binDir, webDir, {workers: 0}).start();
  try {
    const upload = async (name, bytes) => {
      const created = await bare.api('v1/uploads', {method: 'POST', json: {name, size: bytes.length}});
      await fetch(`${bare.url}/v1/uploads/${created.id}`, {method: 'PUT', body: bytes, headers: {
        Authorization: `Bearer ${bare.token}`, 'Content-Range': `bytes 0-${bytes.length - 1}/${bytes.length}`}});
      const {createHash} = await import('node:crypto');
      return (await bare.api(`v1/uploads/${created.id}/complete`, {method: 'POST',
        json: {sha256: createHash('sha256').update(bytes).digest('hex')}})).blob;
    };
    const tarDir = tempDir('keel-web-tar-');
    fs.cpSync(jobs.bridgeMission, tarDir, {recursive: true});
    const {execFileSync} = await import('node:child_process');
    const tar = path.join(work, 'bundle.tar');
    execFileSync('tar', ['-C', tarDir, '-cf', tar, '.']);
    const mission = await bare.api('v1/missions', {method: 'POST', json: {name: 'forged', bundle_blob: await upload('bundle.tar', fs.readFileSync(tar))}});
    const job = await bare.api('v1/jobs', {method: 'POST', json: {mission_id: mission.id, stages: ['map']}});
    const lease = await bare.api('v1/worker/lease', {method: 'POST', json: {worker: 'test:forged', lease_seconds: 60}});
    const register = async (name, bytes) => bare.api(`v1/worker/jobs/${job.id}/artifacts`, {method: 'POST',
      json: {lease_id: lease.lease_id, stage: 'map', name, blob: await upload(name, bytes)}});
    await register('map_combined.drc', Buffer.from('DRACO this is not a draco file at all'));
    await register('map_lidar_h.drc', Buffer.from([0x44, 0x52, 0x41, 0x43, 0x4f, 2, 2, 0, 0, 0, 1, 2, 3]));
    await register('report.json', Buffer.from('{"stages": {"map": '));
    await register('trajectories.json', Buffer.from('{"trajectories": [{"name": "refined", "xyz": [[0, 0]]}]}'));
    await register('tiles_combined.tar', Buffer.from('not a tar archive'));
    await bare.api(`v1/worker/jobs/${job.id}/complete`, {method: 'POST', json: {lease_id: lease.lease_id}});

    const p = await browser.context.newPage();
    try {
      await step('bad artifacts page', () => badArtifactPages(p, bare, job), () => p);
    } finally {
      await p.close();
    }
  } finally {
    await bare.stop();
  }
}));

async function badArtifactPages(p, bare, job) {
  {
    {
      await signIn(p, bare);
      await p.waitForSelector('#jobs-table');
      await p.goto(`${bare.url}/#/jobs/${job.id}/viewer`);
      await p.waitForSelector('body[data-viewer-ready="true"]', {timeout: 60000});
      const messages = await p.$$eval('#viewer-messages .message', (ms) => ms.map((m) => m.textContent));
      const all = messages.join('\n');
      assert.match(all, /map_combined\.json is missing/);
      assert.match(all, /map_combined\.drc could not be decoded/);
      assert.match(all, /map_lidar_h\.json is missing/);
      assert.match(all, /trajectories\.json: trajectories\[0\] \(refined\): xyz must be \[x, y, z\] numbers/);
      // The map from its tiles: the tar has no tileset.json (the server answers 404).
      await p.goto(`${bare.url}/#/jobs/${job.id}/viewer?lod=tiles`);
      await p.waitForSelector('body[data-viewer-ready="true"]', {timeout: 60000});
      const tilesMessages = (await p.$$eval('#viewer-messages .message', (ms) => ms.map((m) => m.textContent))).join('\n');
      assert.match(tilesMessages, /map_combined cannot be shown.*tiles_combined\.tar: tileset\.json could not be loaded/s);
      await p.goto(`${bare.url}/#/jobs/${job.id}/report`);
      assert.match(await p.textContent('#report .message.error'), /report\.json cannot be read.*report\.json is not valid JSON/);
    }
  }
}
