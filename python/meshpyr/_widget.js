// meshpyr.Viewer's front end (an anywidget module): the editor of `meshpyr view` in a
// sandboxed frame, its /api requests carried to the kernel as widget messages and the answers'
// bodies back as binary buffers. The page's state (gains, normal-only switch, edits) is the
// model's: the page's changes are set on the model, the model's changes (from Python) move
// the page's controls.

const STATE_PATHS = ['/api/filter', '/api/edit', '/api/preview', '/api/export'];

function bytesOf(buffer) {
  if (!buffer) return new ArrayBuffer(0);
  const view = ArrayBuffer.isView(buffer)
    ? new Uint8Array(buffer.buffer, buffer.byteOffset, buffer.byteLength)
    : new Uint8Array(buffer);
  return view.slice().buffer;
}

function render({ model, el }) {
  const frame = document.createElement('iframe');
  frame.className = 'meshpyr-frame';
  // Scripts only: the page cannot reach the notebook's document, cookies or storage.
  frame.setAttribute('sandbox', 'allow-scripts allow-downloads');
  frame.style.height = `${model.get('height')}px`;
  const prefix = Math.random().toString(36).slice(2);
  const pending = new Map();
  let next = 0;
  let fromPage = false;

  const pageState = () => ({
    gains: model.get('gains'), normalOnly: model.get('normal_only'), moves: model.get('moves'),
  });
  const push = () => {
    if (!fromPage && frame.contentWindow) {
      frame.contentWindow.postMessage({ meshpyr: 'state', state: pageState() }, '*');
    }
  };
  const takeState = (path, body) => {
    if (!STATE_PATHS.includes(path.split('?')[0]) || !body) return;
    let state;
    try { state = JSON.parse(body); } catch (_) { return; }
    fromPage = true;
    try {
      model.set({ gains: state.gains, normal_only: Boolean(state.normal_only), moves: state.moves || [] });
      model.save_changes();
    } finally {
      fromPage = false;
    }
  };
  const onFrameMessage = (event) => {
    const m = event.data;
    if (event.source !== frame.contentWindow || !m) return;
    if (m.meshpyr === 'ready') { push(); return; }
    if (m.meshpyr !== 'request') return;
    next += 1;
    const id = `${prefix}-${next}`;
    pending.set(id, m.id);
    takeState(m.path, m.body);
    model.send({ kind: 'request', id, method: m.method, path: m.path, body: m.body });
  };
  const onReply = (msg, buffers) => {
    if (!msg || msg.kind !== 'reply' || !pending.has(msg.id)) return;
    const frameId = pending.get(msg.id);
    pending.delete(msg.id);
    const body = bytesOf(buffers && buffers[0]);
    frame.contentWindow.postMessage(
      { meshpyr: 'reply', id: frameId, status: msg.status, headers: msg.headers, body }, '*', [body]);
  };
  const onHeight = () => { frame.style.height = `${model.get('height')}px`; };

  window.addEventListener('message', onFrameMessage);
  model.on('msg:custom', onReply);
  model.on('change:gains change:normal_only change:moves', push);
  model.on('change:height', onHeight);
  frame.srcdoc = model.get('_page');
  el.classList.add('meshpyr-viewer');
  el.appendChild(frame);
  return () => {
    window.removeEventListener('message', onFrameMessage);
    model.off('msg:custom', onReply);
    model.off('change:gains change:normal_only change:moves', push);
    model.off('change:height', onHeight);
  };
}

export default { render };
