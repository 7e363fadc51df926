// The job list: state, stage, progress, ETA, worker and attempts of every job, kept live by
// the event stream (a `job` event replaces one row; `hello` re-reads the list), filtered
// by state and mission name (both kept in the URL), with cancel/retry/reprocess. Only the
// rows in view are in the DOM (virtual_rows.js), so a thousand jobs render as fast as forty.
import {ApiError, getJson, jobsApi} from '../api.js';
import {actionButtons, handleActionClick} from '../actions.js';
import {afterPaint, h, message} from '../dom.js';
import {liveEvents} from '../events.js';
import {formatSeconds, formatTime} from '../format.js';
import {STATES, estimatedStageStart, etaSeconds, jobMatches, missionName,
        typicalStageSeconds} from '../job_model.js';
import {jobHash, replaceQuery} from '../router.js';
import {VirtualRows} from '../virtual_rows.js';

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
  let shown = [];               // the jobs that match the filters, newest first
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
  const columns = ['job', 'mission', 'state', 'stage', 'progress', 'ETA', 'worker', 'attempts', 'created', ''];
  const table = h('table', {class: 'jobs', id: 'jobs-table'},
    h('thead', null, h('tr', null, columns.map((c) => h('th', null, c)))),
    tbody);
  const scroller = h('div', {class: 'jobs-scroll', id: 'jobs-scroll'}, table);
  const emptyNote = h('p', {class: 'muted empty-note', id: 'jobs-empty', hidden: true});
  container.append(
    h('div', {class: 'toolbar'}, h('h1', null, 'Jobs'), h('label', null, 'State ', stateSelect),
      h('label', null, 'Mission ', missionInput), count),
    notice, scroller, emptyNote);
  const rowsView = new VirtualRows({scroller, tbody, renderRow, keyOf: (job) => job.id, columns: columns.length});
  let firstRender = true;

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

  const newestFirst = (a, b) => b.created_at_ms - a.created_at_ms || (a.id < b.id ? 1 : -1);

  function showCount() {
    count.textContent = `${shown.length} of ${jobs.size} jobs`;
    emptyNote.hidden = shown.length > 0;
    emptyNote.textContent = jobs.size ? 'No job matches the filters.' : 'No jobs yet.';
    document.body.dataset.jobsRendered = String(shown.length);
  }

  function renderAll() {
    shown = [...jobs.values()].filter((job) => jobMatches(job, filters, missionNames)).sort(newestFirst);
    rowsView.setItems(shown);
    showCount();
    if (firstRender) {
      firstRender = false;
      afterPaint(() => {
        performance.mark('keel:jobs-rendered');
        settle();
      });
    }
  }

  // Structural changes (a job added, or one entering or leaving the filter) are drawn once
  // per frame however many events arrive in it.
  let renderPending = false;
  function scheduleRenderAll() {
    if (renderPending) return;
    renderPending = true;
    requestAnimationFrame(() => {
      renderPending = false;
      if (!disposed) renderAll();
    });
  }

  function upsert(job) {
    const old = jobs.get(job.id);
    document.body.dataset.lastJobEvent = `${job.id} ${job.state}`;  // for tests: a change applied
    if (job.state === 'running' && (!old || old.stage !== job.stage || old.state !== 'running'))
      stageSeen.set(job.id, {stage: job.stage, ms: Date.now()});
    if (filters.state && job.state !== filters.state && !old) return;
    jobs.set(job.id, job);
    if (job.state === 'succeeded' && old?.state !== 'succeeded') typical = typicalStageSeconds(jobs.values());
    const matches = jobMatches(job, filters, missionNames);
    const wasShown = Boolean(old) && jobMatches(old, filters, missionNames);
    if (matches && wasShown) {
      rowsView.refresh(job);  // same place in the order (creation time does not change)
      const i = shown.findIndex((x) => x.id === job.id);
      if (i >= 0) shown[i] = job;
      return;
    }
    if (!old && job.mission_name === undefined && !missionNames.has(job.mission_id)) loadMissionNames();
    if (matches || wasShown) scheduleRenderAll();
    else showCount();
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

  let started = 0;  // list reads started
  let applied = 0;  // the newest one whose answer is shown
  let inFlight = 0;
  let rereadAfter = false;
  let settled = false;  // the first list is on screen (or could not be read)
  // The event stream's `hello`: read the list again, after the read under way (which may
  // have begun before the stream, so missed changes), not beside it, and not before the
  // first list is on screen (events that arrive meanwhile are applied as they come).
  function reread() {
    if (inFlight || !settled) rereadAfter = true;
    else load();
  }
  function settle() {
    settled = true;
    if (!inFlight && rereadAfter && !disposed) {
      rereadAfter = false;
      load();
    }
  }
  async function load() {
    const serial = ++started;
    const state = filters.state;
    inFlight += 1;
    try {
      const {jobs: list} = await getJson(jobsApi.listPath(state));
      // An older answer is shown until a newer one arrives (the re-read when the event
      // stream connects must not hold back the first list), never after it, nor one read for
      // another state filter.
      if (disposed || serial < applied || state !== filters.state) return;
      applied = serial;
      if (serial === 1) performance.mark('keel:jobs-listed');
      jobs.clear();
      for (const job of list) jobs.set(job.id, job);
      typical = typicalStageSeconds(list);
      notice.replaceChildren();
      if (list.some((job) => job.mission_name === undefined)) await loadMissionNames();
      renderAll();
    } catch (e) {
      if (!disposed && !(e instanceof ApiError && e.status === 401))
        showError(`The job list could not be read: ${e instanceof ApiError ? e.describe() : e.message}`);
      settled = true;
    } finally {
      inFlight -= 1;
      if (!inFlight && rereadAfter && settled && !disposed) {
        rereadAfter = false;
        load();
      }
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
    if (type === 'hello') reread();
    else if (type === 'job' && data && data.id) upsert(data);
  });
  // ETAs count down between events.
  const timer = setInterval(() => {
    for (const [id, tr] of rowsView.rows()) {
      const job = jobs.get(id);
      if (job && job.state === 'running') tr.querySelector('td.eta').textContent = etaText(job);
    }
  }, 1000);

  load();
  return () => {
    disposed = true;
    unsubscribe();
    clearInterval(timer);
    rowsView.dispose();
  };
}
