// The HTTP API (docs/api.md) as the dashboard uses it: the bearer token of the session,
// JSON answers, and errors as ApiError with the server's {"error": {"code", "message"}}.
// URLs are relative to the page, so the dashboard also works behind a path prefix.

const TOKEN_KEY = 'keel.token';

export const session = {
  token: () => sessionStorage.getItem(TOKEN_KEY),
  signIn: (token) => sessionStorage.setItem(TOKEN_KEY, token),
  signOut: () => sessionStorage.removeItem(TOKEN_KEY),
};

export class ApiError extends Error {
  constructor(status, code, message) {
    super(message);
    this.status = status;
    this.code = code;
  }

  // "403 forbidden: ..." as shown to a user.
  describe() {
    return this.status ? `${this.status} ${this.code}: ${this.message}` : this.message;
  }
}

// A request with the session's token. Throws ApiError for a non-2xx answer (a 401 also
// tells the app, which shows the sign-in page with the server's reason) or when the server
// cannot be reached.
export async function request(path, {method = 'GET', json, headers = {}, signal, token} = {}) {
  const bearer = token ?? session.token();
  if (!bearer) {
    const error = new ApiError(401, 'unauthorized', 'not signed in');
    window.dispatchEvent(new CustomEvent('keel:unauthorized', {detail: error}));
    throw error;
  }
  const init = {method, signal, headers: {...headers, Authorization: `Bearer ${bearer}`}};
  if (json !== undefined) {
    init.body = JSON.stringify(json);
    init.headers['Content-Type'] = 'application/json';
  }
  let response;
  try {
    response = await fetch(path, init);
  } catch (e) {
    if (e.name === 'AbortError') throw e;
    throw new ApiError(0, 'unreachable', `the server cannot be reached (${e.message})`);
  }
  if (!response.ok) {
    let code = `http_${response.status}`;
    let message = response.statusText || 'request failed';
    try {
      const body = await response.json();
      if (body && body.error) ({code, message} = body.error);
    } catch {
      // not a JSON error body: keep the status text
    }
    const error = new ApiError(response.status, code, message);
    if (response.status === 401 && token === undefined)
      window.dispatchEvent(new CustomEvent('keel:unauthorized', {detail: error}));
    throw error;
  }
  return response;
}

// GETs started early by the app for the page whose module is still loading (the job list:
// its request then runs while the page's code arrives). path -> {promise, at}.
const prefetched = new Map();
const PREFETCH_FRESH_MS = 5000;

export function prefetchJson(path) {
  const promise = request(path).then((response) => response.json());
  promise.catch(() => {});  // the page that takes it handles the error
  prefetched.set(path, {promise, at: performance.now()});
}

export async function getJson(path, options) {
  const early = options ? null : prefetched.get(path);
  if (early) {
    prefetched.delete(path);
    if (performance.now() - early.at < PREFETCH_FRESH_MS) return early.promise;
  }
  return (await request(path, options)).json();
}

export async function postJson(path, json, options = {}) {
  const response = await request(path, {...options, method: 'POST', json: json ?? {}});
  return response.status === 204 ? null : response.json();
}

export const jobsApi = {
  list: (query = {}) => getJson(`v1/jobs?${new URLSearchParams(query)}`),
  // Every job of a state ('' = any) for the job list, newest first (the app prefetches it).
  listPath: (state = '') => `v1/jobs?${new URLSearchParams(state ? {limit: 10000, state} : {limit: 10000})}`,
  get: (id) => getJson(`v1/jobs/${encodeURIComponent(id)}`),
  log: (id, from) => getJson(`v1/jobs/${encodeURIComponent(id)}/log?from=${from}`),
  artifactsPath: (id) => `v1/jobs/${encodeURIComponent(id)}/artifacts`,
  artifacts: (id) => getJson(jobsApi.artifactsPath(id)),
  cancel: (id) => postJson(`v1/jobs/${encodeURIComponent(id)}/cancel`),
  retry: (id) => postJson(`v1/jobs/${encodeURIComponent(id)}/retry`),
  // A new job on the same stored mission with the same stages and options: nothing is
  // uploaded again (POST /v1/reprocess).
  reprocess: (job, options = job.options) =>
    postJson('v1/reprocess', {mission_ids: [job.mission_id], stages: job.stages, options}),
};

export const artifactUrl = (artifact) => `v1/artifacts/${encodeURIComponent(artifact.id)}`;

// Downloads an artifact's bytes; `onProgress(received, total)` while they arrive.
export async function fetchArtifact(artifact, {signal, onProgress} = {}) {
  const response = await request(artifactUrl(artifact), {signal});
  const total = Number(response.headers.get('Content-Length')) || artifact.size || 0;
  if (!onProgress || !response.body) return response.arrayBuffer();
  const reader = response.body.getReader();
  const bytes = new Uint8Array(total);
  let received = 0;
  const chunks = [];
  for (;;) {
    const {done, value} = await reader.read();
    if (done) break;
    if (received + value.length <= bytes.length) bytes.set(value, received);
    else chunks.push(value);
    received += value.length;
    onProgress(received, total);
  }
  if (chunks.length === 0 && received === bytes.length) return bytes.buffer;
  // The server sent more than announced: join everything.
  const joined = new Uint8Array(received);
  joined.set(bytes.subarray(0, Math.min(total, received)), 0);
  let offset = Math.min(total, received);
  for (const chunk of chunks) {
    joined.set(chunk, offset);
    offset += chunk.length;
  }
  return joined.buffer;
}

// Bytes start .. end-1 of an artifact (one HTTP Range request, docs/api.md "Ranged
// downloads"). A server that answers the whole file (200) is sliced here.
export async function fetchArtifactRange(artifact, start, end, {signal} = {}) {
  if (end <= start) return new ArrayBuffer(0);
  const response = await request(artifactUrl(artifact), {signal, headers: {Range: `bytes=${start}-${end - 1}`}});
  const bytes = await response.arrayBuffer();
  if (response.status === 206) {
    if (bytes.byteLength !== end - start)
      throw new Error(`${artifact.name}: bytes ${start}-${end - 1} asked, ${bytes.byteLength} received`);
    return bytes;
  }
  if (bytes.byteLength < end) throw new Error(`${artifact.name}: ${bytes.byteLength} bytes, shorter than ${end}`);
  return bytes.slice(start, end);
}

export async function fetchArtifactJson(artifact, options) {
  const bytes = await fetchArtifact(artifact, options);
  const text = new TextDecoder().decode(bytes);
  try {
    return JSON.parse(text);
  } catch (e) {
    throw new Error(`${artifact.name} is not valid JSON (${e.message})`);
  }
}
