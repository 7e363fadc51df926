// The live event stream GET /v1/events (docs/api.md "Live events and the queue"), read with
// fetch() because EventSource cannot send the bearer header. One stream for the whole
// page; pages subscribe to it. A lost stream is reopened with a growing pause, and every
// (re)open emits `hello`, on which pages re-read what they show (events may have been
// missed while it was down).
import {ApiError, request} from './api.js';
import {SseParser} from './sse.js';

const listeners = new Set();
const statusListeners = new Set();
let controller = null;
let status = {state: 'off', detail: ''};

function setStatus(state, detail = '') {
  status = {state, detail};
  for (const fn of statusListeners) fn(status);
}

function emit(event) {
  let data = null;
  try {
    data = JSON.parse(event.data);
  } catch {
    return;  // not one of the documented events
  }
  for (const fn of [...listeners]) {
    try {
      fn(event.type, data);
    } catch (e) {
      console.warn('event listener failed', e);
    }
  }
}

async function run(signal) {
  let pause = 1000;
  while (!signal.aborted) {
    try {
      setStatus('connecting');
      const response = await request('v1/events', {signal, headers: {Accept: 'text/event-stream'}});
      const parser = new SseParser(emit);
      const reader = response.body.pipeThrough(new TextDecoderStream()).getReader();
      setStatus('live');
      pause = 1000;
      for (;;) {
        const {done, value} = await reader.read();
        if (done) break;
        parser.push(value);
      }
      setStatus('offline', 'the server closed the event stream');
    } catch (e) {
      if (signal.aborted) return;
      if (e instanceof ApiError && e.status === 401) {
        setStatus('off', e.describe());
        return;
      }
      setStatus('offline', e instanceof ApiError ? e.describe() : e.message);
    }
    await new Promise((resolve) => setTimeout(resolve, pause));
    pause = Math.min(pause * 2, 10000);
  }
}

export const liveEvents = {
  start() {
    if (controller) return;
    controller = new AbortController();
    run(controller.signal);
  },
  stop() {
    if (!controller) return;
    controller.abort();
    controller = null;
    setStatus('off');
  },
  // fn(type, data) for `hello`, `job` and `log` events; returns the unsubscribe function.
  subscribe(fn) {
    listeners.add(fn);
    return () => listeners.delete(fn);
  },
  onStatus(fn) {
    statusListeners.add(fn);
    fn(status);
    return () => statusListeners.delete(fn);
  },
  status: () => status,
};
