// Sign-in with an API token: kept in this tab's sessionStorage and sent as a bearer header.
// The token is checked against the server before it is kept; a refusal shows its reason.
import {ApiError, request, session} from '../api.js';
import {h, message} from '../dom.js';
import {navigate} from '../router.js';

export function mount(container, {query, reason}) {
  const input = h('input', {type: 'password', id: 'token', name: 'token', autocomplete: 'off',
                            spellcheck: 'false', required: true, placeholder: 'API token'});
  const status = h('div', {id: 'signin-status'});
  if (reason) status.append(message('error', 'Signed out', reason));
  const button = h('button', {type: 'submit'}, 'Sign in');

  const form = h('form', {class: 'signin', on: {submit: async (event) => {
    event.preventDefault();
    const token = input.value.trim();
    if (!token) return;
    button.disabled = true;
    status.replaceChildren(h('p', {class: 'muted'}, 'Checking the token…'));
    try {
      await request('v1/jobs?limit=1', {token});
      session.signIn(token);
      const next = query.get('next');
      navigate(next && next.startsWith('#/') && !next.startsWith('#/signin') ? next : '#/jobs');
    } catch (e) {
      const why = e instanceof ApiError && e.status === 401
          ? `The server refused this token (${e.describe()}).`
          : `The token could not be checked: ${e instanceof ApiError ? e.describe() : e.message}`;
      status.replaceChildren(message('error', 'Not signed in', why));
    } finally {
      button.disabled = false;
    }
  }}},
  h('h1', null, 'Sign in to Keel'),
  h('p', null, 'Paste an API token. keel-server writes the first one to ',
    h('code', null, '<data-dir>/token'), ' when it starts for the first time (the demo prints where).'),
  h('label', {for: 'token'}, 'API token'), input, button, status);
  container.append(form);
  input.focus();
}
