// A saved result (meshpyr's `save_html`): the editor's page without a server. This script runs
// before app.js and answers its requests from MESHPYR_SNAPSHOT, defined just above: the scan's
// description, its triangles and the result's f32 positions (base64). The panel's controls
// need the server, so it is hidden; orbit, zoom and shading stay.
'use strict';
(function () {
  const data = MESHPYR_SNAPSHOT;
  const decode = (text) => Uint8Array.from(atob(text), (c) => c.charCodeAt(0)).buffer;
  const faces = decode(data.faces);
  const positions = decode(data.positions);
  const reply = (body, type) => new Response(body, { status: 200, headers: { 'Content-Type': type } });
  window.meshpyrTransport = async function (path) {
    if (path === '/api/info') return reply(JSON.stringify(data.info), 'application/json');
    if (path === '/api/status') return reply(JSON.stringify({ lod: false }), 'application/json');
    if (path === '/api/faces') return reply(faces.slice(0), 'application/octet-stream');
    if (path === '/api/filter' || path === '/api/edit') return reply(positions.slice(0), 'application/octet-stream');
    return new Response(JSON.stringify({ error: 'a saved page has no server' }),
      { status: 404, headers: { 'Content-Type': 'application/json' } });
  };
  const style = document.createElement('style');
  style.textContent = '#panel { display: none; } #view { right: 0; }';
  document.head.appendChild(style);
})();
