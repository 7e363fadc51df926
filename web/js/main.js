// The dashboard's entry: a hash router (#/jobs, #/jobs/<id>, #/jobs/<id>/report,
// #/jobs/<id>/viewer, #/jobs/<id>/calibrate, #/queue, #/signin), the sign-in state and the live-event indicator.
// Pages are modules with mount(container, route) -> unmount; the report view and the 3D
// viewer are loaded only when opened, so the job list never waits for uPlot or three.js.
import {jobsApi, prefetchJson, session} from './api.js';
import {clear, message} from './dom.js';
import {liveEvents} from './events.js';
import {navigate, parseRoute} from './router.js';

const app = document.getElementById('app');
let unmount = null;
let signInReason = '';

const pages = {
  signin: () => import('./pages/signin.js'),
  jobs: () => import('./pages/jobs.js'),
  job: () => import('./pages/job.js'),
  report: () => import('./pages/report.js'),
  viewer: () => import('./pages/viewer.js'),
  calibrate: () => import('./pages/calibrate.js'),
  queue: () => import('./pages/queue.js'),
};

let routeSerial = 0;
async function route() {
  const serial = ++routeSerial;
  let current = parseRoute(location.hash);
  if (!session.token() && current.page !== 'signin') current = {page: 'signin', query: new URLSearchParams()};
  document.getElementById('sign-out').hidden = !session.token();
  for (const link of document.querySelectorAll('#nav a'))
    link.classList.toggle('active', link.dataset.nav === (current.page === 'queue' ? 'queue' : 'jobs'));
  if (session.token()) liveEvents.start();

  if (unmount) {
    try {
      unmount();
    } catch (e) {
      console.warn('unmount failed', e);
    }
    unmount = null;
  }
  clear(app);
  // The job list's request (the viewer's artifact list) runs while its page's code loads.
  if (current.page === 'jobs' && session.token()) prefetchJson(jobsApi.listPath(current.query.get('state') || ''));
  if (current.page === 'viewer' && session.token()) prefetchJson(jobsApi.artifactsPath(current.id));
  let module;
  try {
    module = await pages[current.page]();
  } catch (e) {
    if (serial !== routeSerial) return;
    app.append(message('error', `The ${current.page} page could not be loaded`, String(e.message || e)));
    return;
  }
  if (serial !== routeSerial) return;
  unmount = module.mount(app, {...current, reason: signInReason}) || null;
  signInReason = '';
}

window.addEventListener('hashchange', route);
window.addEventListener('keel:unauthorized', (event) => {
  const error = event.detail;
  const hadToken = Boolean(session.token());
  session.signOut();
  liveEvents.stop();
  signInReason = hadToken ? `The server refused your token: ${error.describe()}` : '';
  if (parseRoute(location.hash).page !== 'signin')
    navigate(`#/signin?next=${encodeURIComponent(location.hash)}`);
  else navigate(location.hash, {replace: true});
});

document.getElementById('sign-out').addEventListener('click', () => {
  session.signOut();
  liveEvents.stop();
  navigate('#/signin');
});

const live = document.getElementById('live');
liveEvents.onStatus(({state, detail}) => {
  live.dataset.state = state;
  live.textContent = {live: 'live', connecting: 'connecting…', offline: 'reconnecting…', off: ''}[state];
  live.title = detail || (state === 'live' ? 'updates arrive as they happen (GET /v1/events)' : '');
});

// Uncaught errors are shown, not swallowed: the page never goes blank without a word.
window.addEventListener('unhandledrejection', (event) => {
  console.error('unhandled', event.reason);
});

route();
