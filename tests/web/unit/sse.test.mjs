// The event-stream parser against the examples of the HTML Living Standard ("Server-sent
// events", section 9.2.6) and against itself fed one character at a time.
import assert from 'node:assert/strict';
import {test} from 'node:test';
import {SseParser} from '../../../web/js/sse.js';

function parse(chunks) {
  const events = [];
  const parser = new SseParser((e) => events.push(e));
  for (const chunk of chunks) parser.push(chunk);
  return events;
}

test('the spec example: two data lines make one event joined by a newline', () => {
  const events = parse(['data: YHOO\ndata: +2\ndata: 10\n\n']);
  assert.deepEqual(events.map((e) => e.data), ['YHOO\n+2\n10']);
  assert.equal(events[0].type, 'message');
});

test('the spec example: comments, ids and events without data', () => {
  const text = ': test stream\n\ndata: first event\nid: 1\n\ndata:second event\nid\n\ndata:  third event\n\n';
  const events = parse([text]);
  assert.deepEqual(events.map((e) => e.data), ['first event', 'second event', ' third event']);
  assert.deepEqual(events.map((e) => e.id), ['1', '', '']);
});

test('the spec example: an empty data field and a data field without colon', () => {
  const events = parse(['data\n\ndata\ndata\n\ndata:\n']);
  assert.deepEqual(events.map((e) => e.data), ['', '\n']);  // the last has no blank line yet
});

test('named events as keel-server sends them, with CRLF and CR line ends', () => {
  const events = parse(['event: hello\r\ndata: {"server_time_ms": 5}\r\n\r\n: ping\r\revent: job\rdata: {"id":"j_1"}\r\r']);
  assert.deepEqual(events.map((e) => [e.type, JSON.parse(e.data)]),
                   [['hello', {server_time_ms: 5}], ['job', {id: 'j_1'}]]);
});

test('chunks split anywhere (one character at a time, CRLF split) give the same events', () => {
  const text = 'event: job\r\ndata: {"id":"j_1","state":"running"}\r\n\r\nevent: log\ndata: {"job_id":"j_1","next":4}\n\n: ping\n\n';
  const whole = parse([text]);
  assert.equal(whole.length, 2);
  assert.deepEqual(parse([...text]), whole);
  for (let cut = 1; cut < text.length; cut += 1)
    assert.deepEqual(parse([text.slice(0, cut), text.slice(cut)]), whole, `cut at ${cut}`);
});
