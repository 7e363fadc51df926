// Hash routes of the dashboard (#/jobs, #/jobs/<id>, #/jobs/<id>/report,
// #/jobs/<id>/viewer?cam=..., #/jobs/<id>/calibrate, #/queue, #/signin?next=...). Pure parse, tested in node.

// "#/jobs/j_1/viewer?cam=..." -> {page: 'viewer', id: 'j_1', query: URLSearchParams}
export function parseRoute(hash) {
  const text = hash.replace(/^#\/?/, '');
  const question = text.indexOf('?');
  const path = question < 0 ? text : text.slice(0, question);
  const query = new URLSearchParams(question < 0 ? '' : text.slice(question + 1));
  let parts;
  try {
    parts = path.split('/').filter(Boolean).map(decodeURIComponent);
  } catch {
    parts = [];
  }
  if (parts[0] === 'signin') return {page: 'signin', query};
  if (parts[0] === 'queue') return {page: 'queue', query};
  if (parts[0] === 'jobs' && parts[1]) {
    const sub = parts[2];
    if (sub === 'report' || sub === 'viewer' || sub === 'calibrate') return {page: sub, id: parts[1], query};
    return {page: 'job', id: parts[1], query};
  }
  return {page: 'jobs', query};
}

export function jobHash(id, sub = '') {
  return `#/jobs/${encodeURIComponent(id)}${sub ? `/${sub}` : ''}`;
}

export function navigate(hash, {replace = false} = {}) {
  if (replace || location.hash === hash) {
    history.replaceState(null, '', hash);
    window.dispatchEvent(new HashChangeEvent('hashchange'));
  } else {
    location.hash = hash;
  }
}

// Updates the hash's query without reloading the page (the viewer's camera, filters).
export function replaceQuery(query) {
  const base = location.hash.split('?')[0] || '#/jobs';
  const text = query.toString();
  history.replaceState(null, '', text ? `${base}?${text}` : base);
}
