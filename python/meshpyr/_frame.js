// The notebook widget's end inside its frame: runs before the editor's app.js and installs a
// transport that carries each /api request to the widget (the frame's parent) and resolves
// with its answer, which the kernel computed. It reports the page's state with each request
// that carries one, and applies states the widget sends (set from Python).
'use strict';
(function () {
  const waiting = new Map();
  let next = 0;
  window.meshpyrTransport = function (path, options = {}) {
    return new Promise((resolve) => {
      next += 1;
      waiting.set(next, resolve);
      const body = options.body == null ? '' : String(options.body);
      parent.postMessage({ meshpyr: 'request', id: next, method: options.method || 'GET', path, body }, '*');
    });
  };
  let pushed = null;
  window.addEventListener('message', (event) => {
    const m = event.data;
    if (event.source !== parent || !m) return;
    if (m.meshpyr === 'reply' && waiting.has(m.id)) {
      const resolve = waiting.get(m.id);
      waiting.delete(m.id);
      resolve(new Response(m.body, { status: m.status, headers: m.headers }));
    } else if (m.meshpyr === 'state') {
      pushed = m.state;
      if (window.meshpyr && window.meshpyr.ready) window.meshpyr.setState(pushed);
    }
  });
  // Once the page has drawn its first result, the widget sends the state set from Python
  // before (or while) the page started.
  const announce = () => {
    if (window.meshpyr && window.meshpyr.ready) parent.postMessage({ meshpyr: 'ready' }, '*');
    else setTimeout(announce, 50);
  };
  setTimeout(announce, 50);
})();
