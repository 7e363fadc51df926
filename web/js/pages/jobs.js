// The job list: state, stage, progress, ETA, worker and attempts of every job, kept live by
// the event stream (a `job` event replaces one row; `hello` re-reads the list), filtered
// by state and mission name (both kept in the URL), with cancel/retry/reprocess.
import {ApiError, getJson, jobsApi} from '../api.js';
import {actionButtons, handleActionClick} from '../actions.js';
import {clear, h, message} from '../dom.js';
import {liveEvents} from '../events.js';
import {formatSeconds, formatTime} from '../format.js';
import {STATES, estimatedStageStart, etaSeconds, jobMatches, missionName,
        typicalStageSeconds} from '../job_model.js';
import {jobHash, replaceQuery} from '../router.js';

export function progressBar(fraction) {
  const percent = Math.max(0, Math.min(1, fraction || 0)) * 100;
  return h('div', {class: 'bar', title: `${percent.toFixed(0)} %`},
           h('div', {class: 'fill', style: {width: `${percent}%`}}));
}

export function stateBadge(state) {
  return h('span', {class: `badge ${state}`}, state);
}

export function mount(container, {query}) {
  const filters = {state: query.get('state') || '', mission: query.get('mission') || ''};
  const jobs = new Map();       // id -> Job
  const rows = new Map();       // id -> <tr>
  const stageSeen = new Map();  // id -> {stage, ms}: when this page saw the stage begin
  const missionNames = new Map();
  let typical = new Map();
  let disposed = false;

  const notice = h('div', {class: 'notices'});
  const count = h('span', {class: 'muted', id: 'job-count'});
  const stateSelect = h('select', {id: 'filter-state', on: {change: () => {
    filters.state = stateSelect.value;
    saveFilters();
    load();
  }}}, h('option', {value: ''}, 'any state'), STATES.map((s) => h('option', {value: s}, s)));
  stateSelect.value = filters.state;
  const missionInput = h('input', {id: 'filter-mission', type: 'search', placeholder: 'mission name',
                                   value: filters.mission, on: {input: () => {
    filters.mission = missionInput.value.trim();
    saveFilters();
    renderAll();
  }}});
  const tbody = h('tbody', {on: {click: onClick}});
  const table = h('table', {class: 'jobs', id: 'jobs-table'},
    h('thead', null, h('tr', null,
      ['job', 'mission', 'state', 'stage', 'progress', 'ETA', 'worker', 'attempts', 'created', '']
          .map((c) => h('th', null, c)))),
    tbody);
  container.append(
    h('div', {class: 'toolbar'}, h('h1', null, 'Jobs'), h('label', null, 'State ', stateSelect),
      h('label', null, 'Mission ', missionInput), count),
    notice, table);

  function saveFilters() {
    const q = new URLSearchParams();
    if (filters.state) q.set('state', filters.state);
    if (filters.mission) q.set('mission', filters.mission);
    replaceQuery(q);
  }

  function showError(text) {
    notice.replaceChildren(message('error', text));
  }

  function stageStart(job) {
    const seen = stageSeen.get(job.id);
    if (seen && seen.stage === job.stage) return seen.ms;
    return estimatedStageStart(job);
  }

  function etaText(job) {
    const eta = etaSeconds(job, {nowMs: Date.now(), stageStartedMs: stageStart(job), typical});
    return Number.isFinite(eta) ? formatSeconds(eta) : job.state === 'running' ? '…' : '';
  }

  function renderRow(job) {
    const tr = h('tr', {dataset: {jobId: job.id, state: job.state}},
      h('td', {class: 'id'}, h('a', {href: jobHash(job.id)}, job.id)),
      h('td', {class: 'mission'}, missionName(job, missionNames)),
      h('td', {class: 'state'}, stateBadge(job.state)),
      h('td', {class: 'stage'}, job.state === 'running' ? job.stage : ''),
      h('td', {class: 'progress'}, job.state === 'running'
          ? [progressBar(job.progress), h('span', {class: 'pct'}, `${Math.round(100 * (job.progress || 0))} %`)]
          : ''),
      h('td', {class: 'eta'}, etaText(job)),
      h('td', {class: 'worker'}, job.worker || ''),
      h('td', {class: 'attempts num'}, String(job.attempts ?? 0)),
      h('td', {class: 'created'}, formatTime(job.created_at_ms)),
      h('td', {class: 'actions'}, actionButtons(job)));
    return tr;
  }

  function renderAll() {
    const visible = [...jobs.values()]
        .filter((job) => jobMatches(job, filters, missionNames))
        .sort((a, b) => b.created_at_ms - a.created_at_ms || (a.id < b.id ? 1 : -1));
    rows.clear();
    const fragment = document.createDocumentFragment();
    for (const job of visible) {
      const tr = renderRow(job);
      rows.set(job.id, tr);
      fragment.append(tr);
    }
    clear(tbody).append(fragment);
    count.textContent = `${visible.length} of ${jobs.size} jobs`;
    if (visible.length === 0)
      tbody.append(h('tr', {class: 'empty'}, h('td', {colspan: 10}, jobs.size ? 'No job matches the filters.' : 'No jobs yet.')));
    performance.mark('keel:jobs-rendered');
    document.body.dataset.jobsRendered = String(visible.length);
  }

  function upsert(job) {
    const old = jobs.get(job.id);
    if (job.state === 'running' && (!old || old.stage !== job.stage || old.state !== 'running'))
      stageSeen.set(job.id, {stage: job.stage, ms: Date.now()});
    if (filters.state && job.state !== filters.state && !old) return;
    jobs.set(job.id, job);
    if (job.state === 'succeeded' && old?.state !== 'succeeded') typical = typicalStageSeconds(jobs.values());
    const matches = jobMatches(job, filters, missionNames);
    const row = rows.get(job.id);
    if (row && !matches) {
      row.remove();
      rows.delete(job.id);
    } else if (row) {
      const fresh = renderRow(job);
      row.replaceWith(fresh);
      rows.set(job.id, fresh);
    } else if (matches) {
      if (!old && job.mission_name === undefined && !missionNames.has(job.mission_id)) loadMissionNames();
      renderAll();  // a new job: its place in the order
      return;
    }
    count.textContent = `${rows.size} of ${jobs.size} jobs`;
  }

  async function loadMissionNames() {
    try {
      const {missions} = await getJson('v1/missions');
      for (const m of missions) missionNames.set(m.id, m.name);
      if (!disposed) renderAll();
    } catch (e) {
      if (!(e instanceof ApiError && e.status === 401)) showError(`mission names: ${e.message}`);
    }
  }

  let loading = null;
  async function load() {
    const serial = {};
    loading = serial;
    try {
      const q = {limit: 10000};
      if (filters.state) q.state = filters.state;
      const {jobs: list} = await jobsApi.list(q);
      if (disposed || loading !== serial) return;
      jobs.clear();
      for (const job of list) jobs.set(job.id, job);
      typical = typicalStageSeconds(list);
      notice.replaceChildren();
      if (list.some((job) => job.mission_name === undefined)) await loadMissionNames();
      renderAll();
    } catch (e) {
      if (!disposed && !(e instanceof ApiError && e.status === 401))
        showError(`The job list could not be read: ${e instanceof ApiError ? e.describe() : e.message}`);
    }
  }

  function onClick(event) {
    const tr = event.target.closest('tr[data-job-id]');
    if (!tr) return;
    const job = jobs.get(tr.dataset.jobId);
    if (!job) return;
    handleActionClick(event, job, {
      onDone: (action, answer) => {
        notice.replaceChildren();
        for (const updated of answer?.jobs || (answer ? [answer] : [])) upsert(updated);
      },
      onError: showError,
    });
  }

  const unsubscribe = liveEvents.subscribe((type, data) => {
    if (type === 'hello') load();
    else if (type === 'job' && data && data.id) upsert(data);
  });
  // ETAs count down between events.
  const timer = setInterval(() => {
    for (const [id, tr] of rows) {
      const job = jobs.get(id);
      if (job && job.state === 'running') tr.querySelector('td.eta').textContent = etaText(job);
    }
  }, 1000);

  load();
  return () => {
    disposed = true;
    unsubscribe();
    clearInterval(timer);
  };
}
