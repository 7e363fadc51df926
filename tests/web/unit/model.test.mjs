// The job list's derived figures: ETA in closed form, filters, stage rows, log levels,
// routes and formats.
import assert from 'node:assert/strict';
import {test} from 'node:test';
import {etaSeconds, failedStageOf, jobMatches, stageRows, typicalStageSeconds} from '../../../web/js/job_model.js';
import {formatBytes, formatNumber, formatSeconds, logLevel} from '../../../web/js/format.js';
import {parseRoute} from '../../../web/js/router.js';

const running = {id: 'j_1', state: 'running', stages: ['ingest', 'refine', 'map'], stage: 'refine',
                 progress: 0.25, completed_stages: ['ingest'], stage_seconds: {ingest: 2}};

test('ETA: the running stage extrapolated from its progress plus the median of the stages to come', () => {
  const finished = [
    {state: 'succeeded', stage_seconds: {ingest: 1, refine: 10, map: 30}},
    {state: 'succeeded', stage_seconds: {ingest: 3, refine: 14, map: 50}},
    {state: 'succeeded', stage_seconds: {ingest: 2, refine: 12, map: 40}},
    {state: 'failed', stage_seconds: {map: 1000}},
  ];
  const typical = typicalStageSeconds(finished);
  assert.equal(typical.get('map'), 40);
  // 8 s into refine at 25 %: 8 * 0.75 / 0.25 = 24 s left in refine, then map's 40 s.
  const eta = etaSeconds(running, {nowMs: 108000, stageStartedMs: 100000, typical});
  assert.equal(eta, 24 + 40);
  // Before any progress, the typical refine time scales down: 12 * (1 - 0) + 40.
  assert.equal(etaSeconds({...running, progress: 0}, {nowMs: 1, stageStartedMs: 1, typical}), 52);
  // A stage never seen finished: nothing to say.
  assert.ok(Number.isNaN(etaSeconds(running, {nowMs: 108000, stageStartedMs: 100000, typical: new Map()})));
  assert.ok(Number.isNaN(etaSeconds({...running, state: 'queued'}, {nowMs: 0, typical})));
});

test('filters: state exactly, mission name as a case-insensitive substring', () => {
  const job = {state: 'failed', mission_name: 'USV-Bridge-2024'};
  assert.ok(jobMatches(job, {state: 'failed', mission: 'bridge'}));
  assert.ok(!jobMatches(job, {state: 'running', mission: ''}));
  assert.ok(!jobMatches(job, {state: '', mission: 'hull'}));
  assert.ok(jobMatches({state: 'queued', mission_id: 'm_1'}, {mission: 'hull'}, new Map([['m_1', 'hauv-hull']])));
});

test('stage rows and the stage a job failed in', () => {
  assert.deepEqual(stageRows(running).map((r) => r.status), ['done', 'running', 'pending']);
  const failed = {state: 'failed', stages: ['ingest', 'refine'], completed_stages: ['ingest'], stage: '',
                  error: 'refine: mission.yaml: no imu'};
  assert.equal(failedStageOf(failed), 'refine');
  assert.deepEqual(stageRows(failed).map((r) => r.status), ['done', 'failed']);
});

test('log levels from the text the pipeline writes', () => {
  assert.equal(logLevel('failed: refine: no IMU'), 'error');
  assert.equal(logLevel('map: read error in scan 3'), 'error');
  assert.equal(logLevel('refine: warning: DVL gap of 3 s'), 'warning');
  assert.equal(logLevel('refine: solved with DVL in 1.2 s'), 'info');
  assert.equal(logLevel('terror'), 'info');
});

test('routes', () => {
  assert.deepEqual({...parseRoute('#/jobs/j_1/viewer?cam=1,2,3,4,5,6'), query: undefined},
                   {page: 'viewer', id: 'j_1', query: undefined});
  assert.equal(parseRoute('#/jobs/j_1/viewer?cam=1,2,3,4,5,6').query.get('cam'), '1,2,3,4,5,6');
  assert.equal(parseRoute('#/jobs/j_2').page, 'job');
  assert.equal(parseRoute('#/jobs/j_2/report').page, 'report');
  assert.deepEqual({...parseRoute('#/jobs/j_2/calibrate?candidate=sonar'), query: undefined}, {page: 'calibrate', id: 'j_2', query: undefined});
  assert.equal(parseRoute('').page, 'jobs');
  assert.equal(parseRoute('#/queue').page, 'queue');
  assert.equal(parseRoute('#/jobs/%E0%A4%A').page, 'jobs');  // a bad escape is not an error
});

test('formats', () => {
  assert.equal(formatBytes(512), '512 B');
  assert.equal(formatBytes(1536), '1.50 KiB');
  assert.equal(formatBytes(14 * 1024 * 1024), '14.0 MiB');
  assert.equal(formatSeconds(0.25), '250 ms');
  assert.equal(formatSeconds(75), '1 min 15 s');
  assert.equal(formatNumber(0.123456), '0.1235');
  assert.equal(formatNumber(1234567), '1,234,567');
  assert.equal(formatNumber(2.5e-5), '2.500e-5');
  assert.equal(formatNumber(null), '–');
});

test('virtual list window: the rows meeting the viewport, overscan either side, clamped', async () => {
  const {rowWindow} = await import('../../../web/js/virtual_rows.js');
  // 1,000 rows of 30 px, a 600 px viewport scrolled to 3,000 px: rows 100..119 meet it.
  assert.deepEqual(rowWindow({scrollTop: 3000, viewportHeight: 600, rowHeight: 30, count: 1000, overscan: 0}),
                   {first: 100, last: 120});
  assert.deepEqual(rowWindow({scrollTop: 3000, viewportHeight: 600, rowHeight: 30, count: 1000, overscan: 5}),
                   {first: 95, last: 125});
  // A row cut by the viewport's edges is drawn: 3,010 px starts inside row 100, 3,610 ends inside row 120.
  assert.deepEqual(rowWindow({scrollTop: 3010, viewportHeight: 600, rowHeight: 30, count: 1000, overscan: 0}),
                   {first: 100, last: 121});
  // Top, bottom, short lists, overscrolled and empty.
  assert.deepEqual(rowWindow({scrollTop: 0, viewportHeight: 600, rowHeight: 30, count: 1000, overscan: 10}), {first: 0, last: 30});
  assert.deepEqual(rowWindow({scrollTop: 29400, viewportHeight: 600, rowHeight: 30, count: 1000, overscan: 10}), {first: 970, last: 1000});
  assert.deepEqual(rowWindow({scrollTop: 0, viewportHeight: 600, rowHeight: 30, count: 7, overscan: 10}), {first: 0, last: 7});
  assert.deepEqual(rowWindow({scrollTop: 90000, viewportHeight: 600, rowHeight: 30, count: 1000, overscan: 10}), {first: 1000, last: 1000});
  assert.deepEqual(rowWindow({scrollTop: -50, viewportHeight: 600, rowHeight: 30, count: 1000, overscan: 0}), {first: 0, last: 20});
  assert.deepEqual(rowWindow({scrollTop: 0, viewportHeight: 600, rowHeight: 30, count: 0}), {first: 0, last: 0});
  // Every row of a long list is in some window while scrolling through it in viewport steps.
  const seen = new Set();
  for (let top = 0; top < 1000 * 30; top += 600) {
    const {first, last} = rowWindow({scrollTop: top, viewportHeight: 600, rowHeight: 30, count: 1000, overscan: 0});
    for (let i = first; i < last; i += 1) seen.add(i);
  }
  assert.equal(seen.size, 1000);
});
