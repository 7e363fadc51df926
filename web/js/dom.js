// A small element builder: h('td', {class: 'num', on: {click}}, 'text', child, ...).
// Text is always set as text (never parsed as HTML), so server strings cannot inject markup.
// Styles go through the CSSOM (el.style), which the page's Content-Security-Policy allows.
export function h(tag, props = null, ...children) {
  const el = document.createElement(tag);
  if (props) {
    for (const [key, value] of Object.entries(props)) {
      if (value === undefined || value === null || value === false) continue;
      if (key === 'class') el.className = value;
      else if (key === 'on') for (const [type, fn] of Object.entries(value)) el.addEventListener(type, fn);
      else if (key === 'style') Object.assign(el.style, value);
      else if (key === 'dataset') Object.assign(el.dataset, value);
      else if (key === 'text') el.textContent = value;
      else if (key in el && typeof value !== 'string') el[key] = value;
      else el.setAttribute(key, value === true ? '' : String(value));
    }
  }
  append(el, children);
  return el;
}

export function append(el, children) {
  for (const child of children.flat(Infinity)) {
    if (child === null || child === undefined || child === false) continue;
    el.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return el;
}

export function clear(el) {
  while (el.firstChild) el.removeChild(el.firstChild);
  return el;
}

// A message box in place of content that could not be shown (missing artifact, error).
export function message(kind, title, detail) {
  return h('div', {class: `message ${kind}`, role: kind === 'error' ? 'alert' : 'status'},
           h('strong', null, title), detail ? h('div', {class: 'detail'}, detail) : null);
}

// Runs `fn` once the browser has drawn the next frame (a task queued from the frame's
// animation callback runs after its paint): what a person sees, for the benchmark's marks.
export function afterPaint(fn) {
  requestAnimationFrame(() => setTimeout(fn, 0));
}
