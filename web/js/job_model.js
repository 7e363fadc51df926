// What the pages derive from Job objects (docs/api.md): ETA, filters, stage rows, the
// actions a job allows. Pure (tested in node).

export const STATES = ['queued', 'running', 'succeeded', 'failed', 'canceled'];
export const TERMINAL = new Set(['succeeded', 'failed', 'canceled']);

export function missionName(job, missionNames = new Map()) {
  return job.mission_name || missionNames.get(job.mission_id) || '';
}

// Filters of the job list: state (exact, '' = any) and mission name (case-insensitive
// substring, '' = any).
export function jobMatches(job, {state = '', mission = ''}, missionNames) {
  if (state && job.state !== state) return false;
  if (mission && !missionName(job, missionNames).toLowerCase().includes(mission.toLowerCase()))
    return false;
  return true;
}

export function actionsOf(job) {
  return {
    cancel: job.state === 'queued' || job.state === 'running',
    retry: job.state === 'failed' || job.state === 'canceled',
    reprocess: true,
  };
}

function median(values) {
  if (values.length === 0) return NaN;
  const sorted = [...values].sort((a, b) => a - b);
  const mid = Math.floor(sorted.length / 2);
  return sorted.length % 2 ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
}

// Median seconds of each stage over the finished jobs given: what the ETA assumes a stage
// still to run will take.
export function typicalStageSeconds(jobs) {
  const samples = new Map();
  for (const job of jobs) {
    if (job.state !== 'succeeded' || !job.stage_seconds) continue;
    for (const [stage, seconds] of Object.entries(job.stage_seconds)) {
      if (!samples.has(stage)) samples.set(stage, []);
      samples.get(stage).push(seconds);
    }
  }
  const out = new Map();
  for (const [stage, values] of samples) out.set(stage, median(values));
  return out;
}

// Seconds until a running job finishes: the running stage's remainder extrapolated from its
// progress (elapsed * (1 - p) / p), plus the typical time of each stage still to run.
// `stageStartedMs` is when the running stage began (seen by the page, or estimated).
// NaN when nothing can be said yet (no progress, or a stage never seen finished).
export function etaSeconds(job, {nowMs, stageStartedMs, typical = new Map()}) {
  if (job.state !== 'running') return NaN;
  const progress = job.progress || 0;
  let remaining;
  if (progress > 0.02 && stageStartedMs) {
    const elapsed = Math.max(0, (nowMs - stageStartedMs) / 1000);
    remaining = (elapsed * (1 - progress)) / progress;
  } else if (typical.has(job.stage)) {
    remaining = typical.get(job.stage) * (1 - progress);
  } else {
    return NaN;
  }
  const done = new Set(job.completed_stages || []);
  const index = (job.stages || []).indexOf(job.stage);
  for (const stage of (job.stages || []).slice(index + 1)) {
    if (done.has(stage)) continue;
    if (!typical.has(stage)) return NaN;
    remaining += typical.get(stage);
  }
  return remaining;
}

// When the running stage started, as well as the job says it: its start plus the seconds
// of the stages it finished. (A retried job's kept stages ran in an earlier attempt.)
export function estimatedStageStart(job) {
  if (!job.started_at_ms) return 0;
  let ms = job.started_at_ms;
  for (const stage of job.completed_stages || []) ms += 1000 * ((job.stage_seconds || {})[stage] || 0);
  return ms;
}

// One row per stage of the job for the timeline: {stage, status, seconds, progress}.
// status: done | running | failed | canceled | pending.
export function stageRows(job) {
  const done = new Set(job.completed_stages || []);
  const failedStage = job.state === 'failed' ? failedStageOf(job) : '';
  return (job.stages || []).map((stage) => {
    const seconds = (job.stage_seconds || {})[stage];
    if (done.has(stage)) return {stage, status: 'done', seconds, progress: 1};
    if (job.state === 'running' && job.stage === stage)
      return {stage, status: 'running', seconds, progress: job.progress || 0};
    if (failedStage === stage) return {stage, status: 'failed', seconds, progress: 0};
    if (job.state === 'canceled' && job.stage === stage)
      return {stage, status: 'canceled', seconds, progress: job.progress || 0};
    return {stage, status: 'pending', seconds, progress: 0};
  });
}

// The stage a failed job failed in: the pipeline's errors start with "<stage>: ".
export function failedStageOf(job) {
  if (job.stage && !(job.completed_stages || []).includes(job.stage)) return job.stage;
  const prefix = (job.error || '').split(':')[0];
  if ((job.stages || []).includes(prefix)) return prefix;
  return (job.stages || []).find((s) => !(job.completed_stages || []).includes(s)) || '';
}
