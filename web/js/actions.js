// Cancel, retry and reprocess buttons, shared by the job list and the job page. A 403 (a
// viewer token may only read) disables every action button of the page and says why.
import {ApiError, jobsApi} from './api.js';
import {h} from './dom.js';
import {actionsOf} from './job_model.js';

let readOnlyReason = '';

export function isReadOnly() {
  return Boolean(readOnlyReason);
}

export function actionButtons(job) {
  const allowed = actionsOf(job);
  const button = (action, label, title) =>
      h('button', {type: 'button', class: `action ${action}`, dataset: {action, jobId: job.id},
                   disabled: !allowed[action] || isReadOnly(), title: readOnlyReason || title}, label);
  return [
    button('cancel', 'Cancel', 'stop this job (a running stage is stopped within seconds)'),
    button('retry', 'Retry', 'run it again from the first stage not finished'),
    button('reprocess', 'Reprocess', 'a new job on the same stored mission, same stages and options'),
  ];
}

// Runs the action of a clicked button. onDone(job or jobs) with the server's answer,
// onError(message). Returns false when the click was not on an action button.
export function handleActionClick(event, job, {onDone, onError}) {
  const button = event.target.closest('button.action');
  if (!button || button.disabled) return false;
  const action = button.dataset.action;
  button.disabled = true;
  const call = action === 'cancel' ? jobsApi.cancel(job.id)
      : action === 'retry' ? jobsApi.retry(job.id) : jobsApi.reprocess(job);
  call.then((answer) => onDone(action, answer)).catch((e) => {
    if (e instanceof ApiError && e.status === 403) {
      readOnlyReason = `your token may only read (${e.describe()})`;
      for (const other of document.querySelectorAll('button.action')) {
        other.disabled = true;
        other.title = readOnlyReason;
      }
    } else {
      button.disabled = false;
    }
    onError(`${action} ${job.id}: ${e instanceof ApiError ? e.describe() : e.message}`);
  });
  return true;
}
