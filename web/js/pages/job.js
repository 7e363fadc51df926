// One job: its error first when it failed, the stage timeline with each stage's time, the
// log followed live (a `log` event says new lines exist; they are read from where this page
// stopped) with a level filter, and the artifacts with size, SHA-256 and download; links to
// the report, the 3D viewer and, when the job has calibration scans, the calibration page.
import {ApiError, fetchArtifact, jobsApi} from '../api.js';
import {actionButtons, handleActionClick} from '../actions.js';
import {h, message} from '../dom.js';
import {liveEvents} from '../events.js';
import {LEVEL_RANK, formatBytes, formatSeconds, formatTime, logLevel} from '../format.js';
import {missionName, stageRows} from '../job_model.js';
import {jobHash} from '../router.js';
import {progressBar, stateBadge} from './jobs.js';

export function mount(container, {id}) {
  let job = null;
  let disposed = false;
  let logNext = 0;
  let logReading = null;
  let logWanted = 0;
  let artifactsShownFor = '';

  const header = h('div', {class: 'job-header'});
  const errorBox = h('div', {id: 'job-error'});
  const notice = h('div', {class: 'notices'});
  const timeline = h('div', {class: 'timeline', id: 'timeline'});
  const levelSelect = h('select', {id: 'log-level', on: {change: applyLevel}},
    h('option', {value: 'info'}, 'all lines'), h('option', {value: 'warning'}, 'warnings and errors'),
    h('option', {value: 'error'}, 'errors only'));
  const follow = h('input', {type: 'checkbox', id: 'log-follow', checked: true});
  const logBox = h('pre', {class: 'log', id: 'log'});
  const artifacts = h('div', {id: 'artifacts'});
  // Shown once the artifacts include calibration_scans.bin (docs/calibration.md section 3).
  const calibrateLink = h('a', {href: jobHash(id, 'calibrate'), id: 'open-calibrate', hidden: true}, 'Calibration');

  container.append(header, errorBox, notice,
    h('section', null, h('h2', null, 'Stages'), timeline),
    h('section', null, h('div', {class: 'toolbar'}, h('h2', null, 'Log'),
      h('label', null, 'Show ', levelSelect), h('label', null, follow, ' follow')), logBox),
    h('section', null, h('h2', null, 'Artifacts'), artifacts));

  function showError(text) {
    notice.replaceChildren(message('error', text));
  }

  function renderHeader() {
    const links = h('span', {class: 'links'},
      h('a', {href: jobHash(job.id, 'report'), id: 'open-report'}, 'Report'),
      h('a', {href: jobHash(job.id, 'viewer'), id: 'open-viewer'}, '3D viewer'), calibrateLink);
    header.replaceChildren(
      h('h1', null, 'Job ', h('code', null, job.id), ' ', stateBadge(job.state)),
      h('dl', {class: 'facts'},
        h('dt', null, 'mission'), h('dd', null, missionName(job) || job.mission_id),
        h('dt', null, 'stages'), h('dd', null, (job.stages || []).join(' → ')),
        h('dt', null, 'attempts'), h('dd', {id: 'job-attempts'}, String(job.attempts ?? 0)),
        h('dt', null, 'worker'), h('dd', null, job.worker || '–'),
        job.batch_id ? [h('dt', null, 'batch'), h('dd', null, job.batch_id)] : null,
        h('dt', null, 'created'), h('dd', null, formatTime(job.created_at_ms)),
        h('dt', null, 'started'), h('dd', null, formatTime(job.started_at_ms)),
        h('dt', null, 'finished'), h('dd', null, formatTime(job.finished_at_ms))),
      h('div', {class: 'actions', on: {click: onAction}}, actionButtons(job), links));
    // A failed job's error comes before anything else.
    errorBox.replaceChildren(job.state === 'failed'
        ? message('error', 'This job failed', job.error || '(the server gave no error text)') : '');
  }

  function renderTimeline() {
    const rows = stageRows(job);
    const longest = Math.max(1e-9, ...rows.map((r) => r.seconds || 0));
    timeline.replaceChildren(...rows.map((row) => h('div', {class: `stage-row ${row.status}`, dataset: {stage: row.stage}},
      h('span', {class: 'stage-name'}, row.stage),
      h('span', {class: 'stage-status'}, row.status),
      row.status === 'running' ? progressBar(row.progress)
          : h('div', {class: 'bar time'}, h('div', {class: 'fill', style: {width: `${100 * (row.seconds || 0) / longest}%`}})),
      h('span', {class: 'stage-seconds'}, row.seconds !== undefined ? formatSeconds(row.seconds)
          : row.status === 'running' ? `${Math.round(100 * row.progress)} %` : ''))));
  }

  function render() {
    renderHeader();
    renderTimeline();
    const key = `${job.state}:${(job.completed_stages || []).length}`;
    if (key !== artifactsShownFor) {
      artifactsShownFor = key;
      loadArtifacts();
    }
  }

  function onAction(event) {
    handleActionClick(event, job, {
      onDone: (action, answer) => {
        notice.replaceChildren();
        if (action === 'reprocess' && answer?.jobs?.length) {
          notice.replaceChildren(message('info', 'Reprocessing: ',
            h('a', {href: jobHash(answer.jobs[0].id)}, answer.jobs[0].id)));
        } else if (answer && answer.id === job.id) {
          job = answer;
          render();
        }
      },
      onError: showError,
    });
  }

  function applyLevel() {
    const min = LEVEL_RANK[levelSelect.value];
    for (const line of logBox.children) line.hidden = LEVEL_RANK[line.dataset.level] < min;
  }

  function appendLines(lines) {
    const min = LEVEL_RANK[levelSelect.value];
    const fragment = document.createDocumentFragment();
    for (const line of lines) {
      const level = logLevel(line.text);
      const span = h('span', {class: `line ${level}`, dataset: {level, seq: String(line.seq)},
                              hidden: LEVEL_RANK[level] < min},
                     h('time', null, formatTime(line.t_ms).slice(11)), ' ', line.text, '\n');
      fragment.append(span);
    }
    logBox.append(fragment);
    if (follow.checked) logBox.scrollTop = logBox.scrollHeight;
  }

  // Reads the log from where the page stopped until the server has no more; one reader at
  // a time, and a `log` event during a read asks for one more pass.
  async function readLog(upTo = 0) {
    logWanted = Math.max(logWanted, upTo);
    if (logReading) return;
    logReading = (async () => {
      try {
        for (;;) {
          const page = await jobsApi.log(id, logNext);
          if (disposed) return;
          appendLines(page.lines);
          const advanced = page.next > logNext;
          logNext = page.next;
          if (!advanced || (page.lines.length === 0 && logNext >= logWanted)) break;
        }
      } catch (e) {
        if (!disposed && !(e instanceof ApiError && e.status === 401)) showError(`log: ${e.message}`);
      } finally {
        logReading = null;
      }
      if (!disposed && logWanted > logNext) readLog();
    })();
  }

  async function loadArtifacts() {
    try {
      const {artifacts: list} = await jobsApi.artifacts(id);
      if (disposed) return;
      renderArtifacts(list);
    } catch (e) {
      if (!disposed) artifacts.replaceChildren(message('error', 'The artifacts could not be listed', e.message));
    }
  }

  function renderArtifacts(list) {
    calibrateLink.hidden = !list.some((a) => a.name === 'calibration_scans.bin');
    if (list.length === 0) {
      artifacts.replaceChildren(h('p', {class: 'muted'}, 'No artifacts yet.'));
      return;
    }
    const sorted = [...list].sort((a, b) => a.name.localeCompare(b.name));
    artifacts.replaceChildren(h('table', {class: 'artifacts', id: 'artifacts-table'},
      h('thead', null, h('tr', null, ['name', 'stage', 'size', 'SHA-256', ''].map((c) => h('th', null, c)))),
      h('tbody', null, sorted.map((a) => h('tr', {dataset: {artifact: a.name}},
        h('td', null, a.name), h('td', null, a.stage), h('td', {class: 'num', title: `${a.size} bytes`}, formatBytes(a.size)),
        h('td', null, h('code', {class: 'sha'}, a.sha256)),
        h('td', null, downloadButton(a)))))));
  }

  function downloadButton(artifact) {
    const button = h('button', {type: 'button', class: 'download', on: {click: async () => {
      button.disabled = true;
      try {
        const bytes = await fetchArtifact(artifact, {onProgress: (got, total) => {
          button.textContent = total ? `${Math.round((100 * got) / total)} %` : formatBytes(got);
        }});
        const url = URL.createObjectURL(new Blob([bytes]));
        const link = h('a', {href: url, download: artifact.name});
        document.body.append(link);
        link.click();
        link.remove();
        setTimeout(() => URL.revokeObjectURL(url), 10000);
        button.textContent = 'Download';
      } catch (e) {
        button.textContent = 'Download';
        showError(`${artifact.name}: ${e instanceof ApiError ? e.describe() : e.message}`);
      } finally {
        button.disabled = false;
      }
    }}}, 'Download');
    return button;
  }

  async function load() {
    try {
      job = await jobsApi.get(id);
      if (disposed) return;
      render();
    } catch (e) {
      if (disposed) return;
      if (e instanceof ApiError && e.status === 404)
        container.replaceChildren(message('error', `No job ${id}`, e.describe()));
      else if (!(e instanceof ApiError && e.status === 401))
        showError(`The job could not be read: ${e instanceof ApiError ? e.describe() : e.message}`);
    }
  }

  const unsubscribe = liveEvents.subscribe((type, data) => {
    if (type === 'hello') {
      load();
      readLog();
    } else if (type === 'job' && data?.id === id) {
      job = data;
      render();
    } else if (type === 'log' && data?.job_id === id) {
      readLog(data.next);
    }
  });

  load();
  readLog();
  return () => {
    disposed = true;
    unsubscribe();
  };
}
