// A parser of the server-sent events stream format (HTML Living Standard, "Parsing an event
// stream"), fed with text chunks as fetch() delivers them. EventSource cannot send the
// bearer header the API needs, so the dashboard reads /v1/events with fetch() and this.
// Pure (tested in node).
export class SseParser {
  // onEvent({type, data, id}) for each dispatched event.
  constructor(onEvent) {
    this.onEvent = onEvent;
    this.buffer = '';
    this.type = '';
    this.data = [];
    this.lastId = '';
    this.sawCr = false;
  }

  push(chunk) {
    let text = chunk;
    // A "\r\n" split across two chunks: the '\n' was already counted with the '\r'.
    if (this.sawCr && text.startsWith('\n')) text = text.slice(1);
    this.sawCr = false;
    this.buffer += text;
    let start = 0;
    for (let i = 0; i < this.buffer.length; i += 1) {
      const c = this.buffer[i];
      if (c !== '\n' && c !== '\r') continue;
      this.line(this.buffer.slice(start, i));
      if (c === '\r') {
        if (i + 1 < this.buffer.length) {
          if (this.buffer[i + 1] === '\n') i += 1;
        } else {
          this.sawCr = true;
        }
      }
      start = i + 1;
    }
    this.buffer = this.buffer.slice(start);
  }

  line(line) {
    if (line === '') return this.dispatch();
    if (line.startsWith(':')) return undefined;  // comment (": ping")
    const colon = line.indexOf(':');
    const field = colon < 0 ? line : line.slice(0, colon);
    let value = colon < 0 ? '' : line.slice(colon + 1);
    if (value.startsWith(' ')) value = value.slice(1);
    if (field === 'event') this.type = value;
    else if (field === 'data') this.data.push(value);
    else if (field === 'id' && !value.includes('\0')) this.lastId = value;
    return undefined;
  }

  dispatch() {
    if (this.data.length === 0) {
      this.type = '';
      return;
    }
    const event = {type: this.type || 'message', data: this.data.join('\n'), id: this.lastId};
    this.type = '';
    this.data = [];
    this.onEvent(event);
  }
}
