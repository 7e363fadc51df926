// Workers and queue, from the server's own figures (GET /v1/queue): jobs by state, workers
// alive and what each holds, jobs finished and failed in the last hour, their mean time.
// Re-read when a job event arrives (at most once a second) and every 10 s for liveness.
import {ApiError, getJson} from '../api.js';
import {h, message} from '../dom.js';
import {liveEvents} from '../events.js';
import {formatNumber, formatSeconds} from '../format.js';
import {STATES} from '../job_model.js';
import {jobHash} from '../router.js';

export function mount(container) {
  let disposed = false;
  const body = h('div', {id: 'queue'}, h('p', {class: 'muted'}, 'Reading the queue…'));
  container.append(h('h1', null, 'Workers & queue'), body);

  function render(q) {
    const now = Date.now();
    const figure = (label, value, id) => h('div', {class: 'figure', id},
                                            h('div', {class: 'value'}, value), h('div', {class: 'label'}, label));
    const throughput = q.finished_last_hour ?? 0;
    body.replaceChildren(
      h('div', {class: 'figures'},
        STATES.map((s) => figure(s, String(q.jobs_by_state?.[s] ?? 0), `count-${s}`)),
        figure('workers alive', String(q.workers_alive ?? 0), 'workers-alive'),
        figure('finished, last hour', String(throughput), 'finished-hour'),
        figure('failed, last hour', String(q.failed_last_hour ?? 0), 'failed-hour'),
        figure('mean job time, last hour', q.mean_job_seconds_last_hour ? formatSeconds(q.mean_job_seconds_last_hour) : '–', 'mean-seconds'),
        figure('throughput', `${formatNumber(throughput)} jobs/h`, 'throughput')),
      h('h2', null, 'Workers'),
      (q.workers || []).length === 0 ? h('p', {class: 'muted'}, 'No worker has called the server yet.')
          : h('table', {class: 'workers', id: 'workers-table'},
              h('thead', null, h('tr', null, ['worker', 'state', 'job', 'last seen'].map((c) => h('th', null, c)))),
              h('tbody', null, q.workers.map((w) => h('tr', {dataset: {worker: w.id}},
                h('td', null, h('code', null, w.id)),
                h('td', null, h('span', {class: `badge ${w.alive ? 'running' : 'canceled'}`}, w.alive ? 'alive' : 'gone')),
                h('td', null, w.job_id ? h('a', {href: jobHash(w.job_id)}, w.job_id) : 'idle'),
                h('td', null, w.last_seen_ms ? `${formatSeconds(Math.max(0, (now - w.last_seen_ms) / 1000))} ago` : '–'))))));
  }

  async function load() {
    try {
      const q = await getJson('v1/queue');
      if (!disposed) render(q);
    } catch (e) {
      if (!disposed && !(e instanceof ApiError && e.status === 401))
        body.replaceChildren(message('error', 'The queue could not be read', e instanceof ApiError ? e.describe() : e.message));
    }
  }

  let pending = null;
  const unsubscribe = liveEvents.subscribe((type) => {
    if (type !== 'job' && type !== 'hello') return;
    if (pending) return;
    pending = setTimeout(() => {
      pending = null;
      load();
    }, 1000);
  });
  const timer = setInterval(load, 10000);
  load();
  return () => {
    disposed = true;
    unsubscribe();
    clearInterval(timer);
    clearTimeout(pending);
  };
}
