// A long table drawn a window at a time: only the rows in view (and a few either side) are
// in the DOM, between two spacer rows that keep the scroll height of the whole list, so a
// list of thousands of jobs costs the page what a list of forty does. Rows have one fixed
// height (the CSS gives every row one line), measured once from the first row drawn.
import {afterPaint} from './dom.js';

// The rows [first, last) to draw for a scroll position: those that meet the viewport,
// `overscan` more on either side, clamped to [0, count). Pure (tested in node).
export function rowWindow({scrollTop, viewportHeight, rowHeight, count, overscan = 10}) {
  if (count <= 0 || !(rowHeight > 0)) return {first: 0, last: 0};
  const top = Math.max(0, scrollTop);
  const first = Math.max(0, Math.floor(top / rowHeight) - overscan);
  const last = Math.min(count, Math.ceil((top + Math.max(0, viewportHeight)) / rowHeight) + overscan);
  return {first: Math.min(first, last), last};
}

export class VirtualRows {
  // scroller: the element that scrolls; tbody: where rows go; renderRow(item) -> <tr>;
  // keyOf(item) -> a string that names the item; columns: for the spacer and empty rows.
  constructor({scroller, tbody, renderRow, keyOf, columns, rowHeight = 33}) {
    this.scroller = scroller;
    this.tbody = tbody;
    this.renderRow = renderRow;
    this.keyOf = keyOf;
    this.columns = columns;
    this.rowHeight = rowHeight;
    this.measured = false;
    this.items = [];
    this.drawn = new Map();  // key -> <tr> of the rows in the DOM
    this.range = {first: 0, last: 0};
    this.top = this.spacer();
    this.bottom = this.spacer();
    this.framePending = false;
    scroller.addEventListener('scroll', () => this.schedule(), {passive: true});
    this.resizeObserver = new ResizeObserver(() => this.schedule());
    this.resizeObserver.observe(scroller);
  }

  spacer() {
    const tr = document.createElement('tr');
    tr.className = 'spacer';
    tr.setAttribute('aria-hidden', 'true');
    const td = document.createElement('td');
    td.colSpan = this.columns;
    tr.append(td);
    return tr;
  }

  // Replaces the whole list (new order or filter) and draws the window.
  setItems(items) {
    this.items = items;
    this.draw({force: true});
  }

  // Draws one item again if it is in the window (its content changed, not its place).
  refresh(item) {
    const key = this.keyOf(item);
    const old = this.drawn.get(key);
    if (!old) return;
    const index = this.items.findIndex((x) => this.keyOf(x) === key);
    if (index < 0) return;
    this.items[index] = item;
    const fresh = this.renderRow(item);
    old.replaceWith(fresh);
    this.drawn.set(key, fresh);
  }

  rows() {
    return this.drawn;
  }

  schedule() {
    if (this.framePending) return;
    this.framePending = true;
    requestAnimationFrame(() => {
      this.framePending = false;
      this.draw();
    });
  }

  draw({force = false} = {}) {
    const range = rowWindow({scrollTop: this.scroller.scrollTop, viewportHeight: this.scroller.clientHeight || 900,
                             rowHeight: this.rowHeight, count: this.items.length});
    if (!force && range.first === this.range.first && range.last === this.range.last) return;
    this.range = range;
    const keep = new Map();
    const rows = [];
    for (let i = range.first; i < range.last; i += 1) {
      const item = this.items[i];
      const key = this.keyOf(item);
      const tr = (!force && this.drawn.get(key)) || this.renderRow(item);
      keep.set(key, tr);
      rows.push(tr);
    }
    this.drawn = keep;
    this.top.style.height = `${range.first * this.rowHeight}px`;
    this.bottom.style.height = `${(this.items.length - range.last) * this.rowHeight}px`;
    this.tbody.replaceChildren(this.top, ...rows, this.bottom);
    if (!this.measured && rows.length) {
      this.measured = true;
      afterPaint(() => this.measure(rows[0]));
    }
  }

  // The real height of a row, once, after the browser laid it out anyway (reading it before
  // would force a layout): when it differs from the guess, the window is drawn again.
  measure(tr) {
    if (!tr.isConnected) {
      this.measured = false;  // redrawn before it was measured: the next draw measures
      return;
    }
    const height = tr.getBoundingClientRect().height;
    if (height > 0 && Math.abs(height - this.rowHeight) > 0.5) {
      this.rowHeight = height;
      this.draw({force: true});
    }
  }

  dispose() {
    this.resizeObserver.disconnect();
  }
}
