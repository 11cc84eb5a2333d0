// meshpyr view: the page. Plain WebGL2, no libraries. It keeps the editor's state (gains,
// normal-only switch, edits) and asks the server for positions; the server holds the pyramid.
// A scan over the display budget is shown as a level of its progressive mesh: each move gets
// a preview at the shown vertices at once, then the exact result from the server's background
// work. `window.meshpyr` exposes the state and timings for scripts and the browser test.
'use strict';

const token = new URLSearchParams(location.search).get('token') || '';
const $ = (id) => document.getElementById(id);

// How requests reach the server: fetch, unless the page's host installed another transport
// before this script (the notebook widget, a saved page): a function like fetch that resolves
// with a Response (docs/view-api.md).
const transport = window.meshpyrTransport || ((path, options) => fetch(path, options));

async function api(path, options = {}) {
  const headers = Object.assign({ 'X-Meshpyr-Token': token }, options.headers || {});
  const response = await transport(path, Object.assign({}, options, { headers }));
  if (!response.ok) {
    let message = response.status + ' ' + response.statusText;
    try { message = (await response.json()).error; } catch (_) { /* not JSON */ }
    throw new Error(message);
  }
  return response;
}

function showError(e) {
  $('error').textContent = e ? String(e.message || e) : '';
}

// ---- small vector helpers -------------------------------------------------------------------
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const normalize = (a) => scale(a, 1 / (Math.hypot(a[0], a[1], a[2]) || 1));

// ---- state ----------------------------------------------------------------------------------
const M = window.meshpyr = {
  info: null,
  gains: [],
  normalOnly: false,
  moves: [],          // committed edits: {level, center, displacement, radius}
  pending: null,      // the edit being dragged
  positions: null,    // Float32Array of the result on screen: the finest in input vertex
                      // order, or over the budget the shown level's vertices in PM order
  faces: null,        // Uint32Array of the triangles on screen (the input's, or the level's)
  shownLevel: null,   // vertex count of the level on screen, null for the finest
  lod: false,         // true when the scan is over the display budget (see info.display)
  version: 0,         // over the budget: number of the state on screen (server's count)
  exact: true,        // whether the result on screen is exact (false: a preview)
  exactLatencies: [], // over the budget: per exact result, {ms: input to drawn, drawMs}
  preview: null,      // over the budget: the last preview's positions (shown vertices)
  updates: 0,         // results received and drawn
  latencies: [],      // per result: {ms: input to drawn, its parts (see requestResult), kind}
  renderer: null,     // {name, software, cullsBackFaces}: the WebGL renderer, whether it
                      // rasterises on the CPU, and whether the result is drawn front faces only
  ready: false,       // the editor's first result is drawn
  opening: null,      // while the scan opens: the server's stage, progress and picture
  firstPictureMs: null, // performance.now() when the first picture (of the opening) was drawn
  pictures: [],       // the opening's pictures drawn: {what, triangles, ms}
  texture: null,      // a textured scan: {images: decoded count, groups} (null: untextured)
  levelTexture: null, // the scrubber's level drawn textured: {groups} (null: plain or none)
};

// ---- camera ---------------------------------------------------------------------------------
const camera = { target: [0, 0, 0], distance: 1, yaw: 0.6, pitch: 0.35, fov: 35 * Math.PI / 180 };

function resetView() {
  const { min, max } = M.info.bbox;
  camera.target = scale(add(min, max), 0.5);
  camera.distance = 1.6 * M.info.diagonal;
  camera.yaw = 0.6;
  camera.pitch = 0.35;
  requestDraw();
}

function cameraBasis() {
  const cp = Math.cos(camera.pitch);
  const back = [Math.sin(camera.yaw) * cp, Math.sin(camera.pitch), Math.cos(camera.yaw) * cp];
  const eye = add(camera.target, scale(back, camera.distance));
  const forward = scale(back, -1);
  const right = normalize(cross(forward, [0, 1, 0]));
  const up = cross(right, forward);
  return { eye, forward, right, up };
}

function matrices(aspect) {
  const { eye, forward, right, up } = cameraBasis();
  const view = [
    right[0], up[0], -forward[0], 0,
    right[1], up[1], -forward[1], 0,
    right[2], up[2], -forward[2], 0,
    -dot(right, eye), -dot(up, eye), dot(forward, eye), 1,
  ];
  const near = camera.distance * 0.01;
  const far = camera.distance * 4 + 4 * M.info.diagonal;
  const f = 1 / Math.tan(camera.fov / 2);
  const proj = [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) / (near - far), -1,
    0, 0, 2 * far * near / (near - far), 0];
  return { view, proj };
}

// The ray through canvas pixel (x, y) in CSS pixels.
function rayAt(x, y) {
  const canvas = $('canvas');
  const { eye, forward, right, up } = cameraBasis();
  const t = Math.tan(camera.fov / 2);
  const aspect = canvas.clientWidth / canvas.clientHeight;
  const nx = (2 * x / canvas.clientWidth - 1) * t * aspect;
  const ny = (1 - 2 * y / canvas.clientHeight) * t;
  return { origin: eye, dir: normalize(add(forward, add(scale(right, nx), scale(up, ny)))) };
}

// ---- WebGL ----------------------------------------------------------------------------------
// A software rasteriser (no GPU, or a blocked one) spends most of a slider move drawing: there
// the view gives up multisampling and high-DPI pixels, which cost it several times the draw,
// and the back faces of closed surfaces (see frontWinding).
function probeRenderer() {
  const probe = document.createElement('canvas').getContext('webgl2');
  if (!probe) return { name: '', software: false };
  const debug = probe.getExtension('WEBGL_debug_renderer_info');
  const name = String(probe.getParameter(debug ? debug.UNMASKED_RENDERER_WEBGL : probe.RENDERER));
  const lose = probe.getExtension('WEBGL_lose_context');
  if (lose) lose.loseContext();
  return { name, software: /swiftshader|llvmpipe|softpipe|software|basic render/i.test(name) };
}
M.renderer = probeRenderer();
// Each result is drawn and waited for in one task, so the drawing buffer need not be kept.
const gl = $('canvas').getContext('webgl2', { antialias: !M.renderer.software, preserveDrawingBuffer: false });

// The shaders of the clay and, with `uv`, of a textured scan's image in the clay's place (v runs
// upwards in texture coordinates and downwards in the image's rows). Two programs, so that an
// untextured scan draws with exactly the clay's shader: a software rasteriser pays for a
// texture fetch behind a branch even when the branch is not taken.
const vertexSource = (uv) => `#version 300 es
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;${uv ? '\nlayout(location = 2) in vec2 uv;' : ''}
uniform mat4 view, proj;
out vec3 vPos; out vec3 vNormal;${uv ? ' out vec2 vUv;' : ''}
void main() {
  vec4 p = view * vec4(position, 1.0);
  vPos = p.xyz; vNormal = mat3(view) * normal;${uv ? ' vUv = uv;' : ''}
  gl_Position = proj * p;
}`;
const shadeSource = (uv) => `#version 300 es
precision highp float;
in vec3 vPos; in vec3 vNormal;${uv ? ' in vec2 vUv;\nuniform sampler2D image;' : ''}
uniform bool flatShading;
out vec4 color;
void main() {
  vec3 n = flatShading ? normalize(cross(dFdx(vPos), dFdy(vPos))) : normalize(vNormal);
  vec3 v = normalize(-vPos);
  if (dot(n, v) < 0.0) n = -n;
  vec3 key = normalize(vec3(0.4, 0.7, 0.6));
  float d = max(dot(n, key), 0.0) * 0.75 + max(dot(n, v), 0.0) * 0.25;
  float s = pow(max(dot(n, normalize(key + v)), 0.0), 40.0) * 0.25;
  vec3 base = ${uv ? 'texture(image, vec2(vUv.x, 1.0 - vUv.y)).rgb' : 'vec3(0.80, 0.76, 0.70)'};
  color = vec4(base * (0.18 + 0.82 * d) + s, 1.0);
}`;
const VERTEX = vertexSource(false);
const SHADE = shadeSource(false);
const LINE = `#version 300 es
precision highp float;
in vec3 vPos; in vec3 vNormal;
out vec4 color;
void main() { color = vec4(0.12, 0.14, 0.18, 1.0); }`;

function compile(vertex, fragment) {
  const program = gl.createProgram();
  for (const [type, source] of [[gl.VERTEX_SHADER, vertex], [gl.FRAGMENT_SHADER, fragment]]) {
    const shader = gl.createShader(type);
    gl.shaderSource(shader, source);
    gl.compileShader(shader);
    if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(shader));
    gl.attachShader(program, shader);
  }
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
  return program;
}

// One drawable mesh: positions and normals on the GPU, triangles, and edges built on demand.
// A `cullable` mesh skips its back faces when it is a closed, consistently oriented surface.
class GpuMesh {
  constructor(cullable) {
    this.cullable = cullable;
    this.front = null;
    this.vao = gl.createVertexArray();
    this.position = gl.createBuffer();
    this.normal = gl.createBuffer();
    this.triangles = gl.createBuffer();
    this.edges = null;
    this.nTriangleIndices = 0;
    this.nEdgeIndices = 0;
    this.vertexCount = 0;
    this.indices = null;
    gl.bindVertexArray(this.vao);
    for (const [loc, buf] of [[0, this.position], [1, this.normal]]) {
      gl.bindBuffer(gl.ARRAY_BUFFER, buf);
      gl.enableVertexAttribArray(loc);
      gl.vertexAttribPointer(loc, 3, gl.FLOAT, false, 0, 0);
    }
    gl.bindVertexArray(null);
  }

  setTriangles(indices) {
    this.indices = drawOrder(indices);
    this.normals = null;
    this.front = undefined;
    this.split = null;
    gl.bindVertexArray(this.vao);
    if (this.uv) gl.disableVertexAttribArray(2);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.triangles);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, this.indices, gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    this.nTriangleIndices = indices.length;
    this.edges = null;
  }

  // A textured scan: the vertices split by texture coordinates for drawing (`/api/texcoords`),
  // while normals, culling and picking stay on the real vertices; the triangles are grouped by
  // image, one draw each. After setTriangles, before setPositions.
  setSplit(split) {
    this.split = split;
    if (!this.uv) this.uv = gl.createBuffer();
    gl.bindVertexArray(this.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.uv);
    gl.bufferData(gl.ARRAY_BUFFER, split.uvs, gl.STATIC_DRAW);
    gl.enableVertexAttribArray(2);
    gl.vertexAttribPointer(2, 2, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.triangles);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, split.triangles, gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    this.nTriangleIndices = split.triangles.length;
    this.vertexCount = 0;
    this.edges = null;
  }

  // Geometry goes to the GPU only here, when it changed: orbiting redraws what is there.
  // Returns when the normals were done (the rest is the upload).
  setPositions(positions) {
    const grow = positions.length !== this.vertexCount * 3;
    if (!this.normals || this.normals.length !== positions.length) this.normals = new Float32Array(positions.length);
    vertexNormals(positions, this.indices, this.normals);
    if (this.front === undefined) {
      this.front = this.cullable ? frontWinding(positions, this.indices) : null;
      if (this.cullable) M.renderer.cullsBackFaces = this.front !== null;
    }
    const normalsDone = performance.now();
    const [drawn, normals] = this.split ? this.splitCopies(positions) : [positions, this.normals];
    for (const [buf, data] of [[this.position, drawn], [this.normal, normals]]) {
      gl.bindBuffer(gl.ARRAY_BUFFER, buf);
      if (grow) gl.bufferData(gl.ARRAY_BUFFER, data, gl.DYNAMIC_DRAW);
      else gl.bufferSubData(gl.ARRAY_BUFFER, 0, data);
    }
    this.vertexCount = positions.length / 3;
    return normalsDone;
  }

  // The positions and normals of the split vertices: copies of their real vertices'.
  splitCopies(positions) {
    const of = this.split.vertexOf, n = of.length;
    const p = this.split.positions || (this.split.positions = new Float32Array(3 * n));
    const q = this.split.normals || (this.split.normals = new Float32Array(3 * n));
    for (let i = 0; i < n; i++) {
      const v = 3 * of[i];
      p[3 * i] = positions[v]; p[3 * i + 1] = positions[v + 1]; p[3 * i + 2] = positions[v + 2];
      q[3 * i] = this.normals[v]; q[3 * i + 1] = this.normals[v + 1]; q[3 * i + 2] = this.normals[v + 2];
    }
    return [p, q];
  }

  edgeBuffer() {
    if (!this.edges) {
      const t = this.split ? this.split.triangles : this.indices;
      const lines = new Uint32Array(2 * t.length);
      for (let i = 0; i < t.length; i += 3) {
        lines.set([t[i], t[i + 1], t[i + 1], t[i + 2], t[i + 2], t[i]], 2 * i);
      }
      this.edges = gl.createBuffer();
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.edges);
      gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, lines, gl.STATIC_DRAW);
      this.nEdgeIndices = lines.length;
    }
    return this.edges;
  }
}

// Area-weighted vertex normals of positions `p` over triangles `t`, into `n`.
function vertexNormals(p, t, n) {
  n.fill(0);
  for (let i = 0; i < t.length; i += 3) {
    const a = 3 * t[i], b = 3 * t[i + 1], c = 3 * t[i + 2];
    const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
    const vx = p[c] - p[a], vy = p[c + 1] - p[a + 1], vz = p[c + 2] - p[a + 2];
    const x = uy * vz - uz * vy, y = uz * vx - ux * vz, z = ux * vy - uy * vx;
    n[a] += x; n[a + 1] += y; n[a + 2] += z;
    n[b] += x; n[b + 1] += y; n[b + 2] += z;
    n[c] += x; n[c + 1] += y; n[c + 2] += z;
  }
}

// The winding (gl.CCW or gl.CW) of the faces of triangles `t` at positions `p` that face out,
// or null unless they form a closed, consistently oriented surface: then every directed edge
// has exactly one twin running the other way, that is the sorted edge keys equal the sorted
// reversed keys and none repeats. Seen from outside, such a surface hides its back faces
// behind its front faces, so a software rasteriser may skip them (half its triangles); where
// a strong enhancement folds the surface over, the fold then shows what lies behind it.
function frontWinding(p, t) {
  const n = p.length / 3;
  const edges = new Float64Array(t.length), twins = new Float64Array(t.length);
  let volume = 0;
  for (let i = 0; i < t.length; i += 3) {
    for (let k = 0; k < 3; k++) {
      const a = t[i + k], b = t[i + (k + 1) % 3];
      edges[i + k] = a * n + b;
      twins[i + k] = b * n + a;
    }
    const a = 3 * t[i], b = 3 * t[i + 1], c = 3 * t[i + 2];
    volume += p[a] * (p[b + 1] * p[c + 2] - p[b + 2] * p[c + 1])
      + p[a + 1] * (p[b + 2] * p[c] - p[b] * p[c + 2])
      + p[a + 2] * (p[b] * p[c + 1] - p[b + 1] * p[c]);
  }
  edges.sort();
  twins.sort();
  for (let i = 0; i < edges.length; i++) {
    if (edges[i] !== twins[i] || (i > 0 && edges[i] === edges[i - 1])) return null;
  }
  return volume > 0 ? gl.CCW : volume < 0 ? gl.CW : null;
}

// The triangles `t` in the order the page draws them and sums their normals: by their last
// vertex (a stable counting sort). Vertex shading caches vertices by index, and files often
// list triangles in an order (by corner type after a subdivision, say) that revisits
// far-apart vertices, which also defeats the CPU's caches in the normals; sorted, nearby
// triangles share recent vertices. Same triangles, so the same picture.
function drawOrder(t) {
  const nt = t.length / 3;
  let nv = 0;
  const last = new Uint32Array(nt);
  for (let i = 0; i < nt; i++) {
    last[i] = Math.max(t[3 * i], t[3 * i + 1], t[3 * i + 2]);
    if (last[i] >= nv) nv = last[i] + 1;
  }
  const start = new Uint32Array(nv + 1);
  for (let i = 0; i < nt; i++) start[last[i] + 1] += 1;
  for (let v = 0; v < nv; v++) start[v + 1] += start[v];
  const out = new Uint32Array(t.length);
  for (let i = 0; i < nt; i++) {
    const j = 3 * start[last[i]]++;
    out[j] = t[3 * i]; out[j + 1] = t[3 * i + 1]; out[j + 2] = t[3 * i + 2];
  }
  return out;
}

let shadeProgram, textureProgram, lineProgram, finest, level, queuedFrame = null;

function requestDraw() {
  if (queuedFrame === null) queuedFrame = requestAnimationFrame(draw);
}

// Draws now; a frame already queued would draw the same again, so it is dropped.
function draw() {
  if (queuedFrame !== null) { cancelAnimationFrame(queuedFrame); queuedFrame = null; }
  const canvas = $('canvas');
  const dpr = M.renderer.software ? 1 : window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
  gl.viewport(0, 0, w, h);
  gl.clearColor(0.07, 0.08, 0.1, 1);
  gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
  const mesh = M.showingResult ? finest : level;
  if (!M.info || !mesh.vertexCount) return;
  const { view, proj } = matrices(w / h);
  gl.enable(gl.DEPTH_TEST);
  if (mesh.front) { gl.enable(gl.CULL_FACE); gl.frontFace(mesh.front); } else gl.disable(gl.CULL_FACE);
  gl.enable(gl.POLYGON_OFFSET_FILL);
  gl.polygonOffset(1, 1);
  const flat = $('smooth').checked ? 0 : 1;
  const use = (program) => {
    gl.useProgram(program);
    gl.uniformMatrix4fv(gl.getUniformLocation(program, 'view'), false, view);
    gl.uniformMatrix4fv(gl.getUniformLocation(program, 'proj'), false, proj);
    gl.uniform1i(gl.getUniformLocation(program, 'flatShading'), flat);
  };
  use(shadeProgram);
  gl.bindVertexArray(mesh.vao);
  gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, mesh.triangles);
  if (mesh.split) {
    const show = $('texture').checked;
    let current = shadeProgram;
    for (const [image, first, count] of mesh.split.groups) {
      const t = show ? mesh.split.textures[image] : undefined;
      const program = t ? textureProgram : shadeProgram;
      if (program !== current) { use(program); current = program; }
      if (t) gl.bindTexture(gl.TEXTURE_2D, t);
      gl.drawElements(gl.TRIANGLES, 3 * count, gl.UNSIGNED_INT, 12 * first);
    }
  } else {
    gl.drawElements(gl.TRIANGLES, mesh.nTriangleIndices, gl.UNSIGNED_INT, 0);
  }
  if ($('wireframe').checked) {
    gl.useProgram(lineProgram);
    gl.uniformMatrix4fv(gl.getUniformLocation(lineProgram, 'view'), false, view);
    gl.uniformMatrix4fv(gl.getUniformLocation(lineProgram, 'proj'), false, proj);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, mesh.edgeBuffer());
    gl.drawElements(gl.LINES, mesh.nEdgeIndices, gl.UNSIGNED_INT, 0);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, mesh.triangles);
  }
  gl.bindVertexArray(null);
}

// ---- results from the server ------------------------------------------------------------------
const request = { busy: false, dirty: false, since: null };
// Over the budget: the exact result awaited, {version, since} (null: none).
let awaited = null;

function stateBody() {
  const moves = M.pending ? M.moves.concat([M.pending]) : M.moves;
  return JSON.stringify({ gains: M.gains, normal_only: M.normalOnly, moves });
}

// The server's parts of an answer, from its `Server-Timing` header: {synthesis: ms, ...}.
function serverTiming(response) {
  const parts = {};
  for (const entry of (response.headers.get('Server-Timing') || '').split(',')) {
    const m = entry.trim().match(/^([\w-]+);dur=([\d.]+)$/);
    if (m) parts[m[1]] = Number(m[2]);
  }
  return parts;
}

// Asks for the result of the current state; while one request runs, later changes wait and
// go out together, so the view never falls behind the sliders. Each result's latency is kept
// with its parts: the server's (synthesis, reordering to the input's order, encoding), the
// transfer (request, answer and the rest of the round trip), the normals, the upload and the
// draw, which the page waits for with a one-pixel read.
function requestResult() {
  if (request.since === null) request.since = performance.now();
  if (request.busy) { request.dirty = true; return; }
  request.busy = true;
  request.dirty = false;
  const since = request.since;
  request.since = null;
  const editing = M.moves.length > 0 || M.pending !== null;
  const kind = M.lod ? 'preview' : editing ? 'edit' : 'filter';
  api('/api/' + kind, { method: 'POST', body: stateBody(), headers: { 'Content-Type': 'application/json' } })
    .then(async (response) => {
      const positions = new Float32Array(await response.arrayBuffer());
      const received = performance.now();
      M.positions = positions;
      M.exact = !M.lod;
      if (M.lod) {
        M.preview = positions;
        M.version = Number(response.headers.get('X-Meshpyr-Version'));
        M.complete = response.headers.get('X-Meshpyr-Preview') === 'complete';
        awaited = { version: M.version, since };
        pollExact();
      }
      const normalsDone = finest.setPositions(positions);
      const uploaded = performance.now();
      showFinest();
      draw();
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4)); // wait until drawn
      const drawn = performance.now();
      const ms = drawn - since;
      const server = serverTiming(response);
      const serverMs = (server.synthesis || 0) + (server.reorder || 0) + (server.combine || 0)
        + (server.encode || 0);
      const answered = Math.min(since + serverMs, received);
      const parts = [['server', since, answered], ['transfer', answered, received],
        ['normals', received, normalsDone], ['upload', normalsDone, uploaded], ['draw', uploaded, drawn]];
      for (const [name, from, to] of parts) {
        performance.clearMeasures('meshpyr ' + name);
        performance.measure('meshpyr ' + name, { start: from, end: to });
      }
      M.latencies.push({
        ms, kind, synthesisMs: server.synthesis ?? Number(response.headers.get('X-Meshpyr-Synthesis-Ms')),
        reorderMs: server.reorder || 0, combineMs: server.combine || 0, encodeMs: server.encode || 0,
        receivedMs: received - since,
        transferMs: received - since - serverMs, normalsMs: normalsDone - received,
        uploadMs: uploaded - normalsDone, drawMs: drawn - uploaded,
      });
      M.updates += 1;
      setStatus(M.lod
        ? `preview: ${ms.toFixed(0)} ms (server ${serverMs.toFixed(0)} ms)${M.complete ? '' : ', fine octaves pending'}`
        : `${kind}: ${ms.toFixed(0)} ms (synthesis ${response.headers.get('X-Meshpyr-Synthesis-Ms')} ms)`);
      showError(null);
    })
    .catch(showError)
    .finally(() => {
      request.busy = false;
      if (request.dirty) requestResult();
    });
}

function setStatus(text) {
  const shown = M.shownLevel === null ? M.info.vertices : M.shownLevel;
  $('status').textContent = `${shown.toLocaleString()} vertices · ${text}`;
}

// Over the budget: asks the server how its background work goes, every 100 ms while an exact
// result is awaited or fine octaves are being measured, and shows the exact result of the
// state on screen when it is ready.
const poll = { timer: null };
M.exactPending = () => awaited !== null;
M.settled = () => M.idle() && !M.exactPending();

function pollExact() {
  if (poll.timer === null) poll.timer = setTimeout(checkStatus, 100);
}

async function checkStatus() {
  poll.timer = null;
  try {
    const status = await (await api('/api/status')).json();
    showProgress(status);
    if (awaited && status.exact === awaited.version && !request.busy && !request.dirty) {
      const { version, since } = awaited;
      const r = await api('/api/exact?version=' + version);
      const positions = new Float32Array(await r.arrayBuffer());
      if (awaited && awaited.version === version && !request.busy && !request.dirty) {
        awaited = null;
        M.positions = positions;
        finest.setPositions(positions);
        const uploaded = performance.now();
        showFinest();
        draw();
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
        const drawn = performance.now();
        M.exact = true;
        M.exactLatencies.push({ ms: drawn - since, drawMs: drawn - uploaded });
        setStatus(`exact: ${(drawn - since).toFixed(0)} ms after the move`);
        showProgress(status);
      }
    }
    if (awaited || status.octaves.measured < status.octaves.total || layoutPending(status)) pollExact();
  } catch (e) {
    showError(e);
  }
}

// A .pyr file opens staged: the editor is ready before the whole pyramid is recorded, and
// exact results, export, the fine octaves and the finer levels wait for it.
function layoutPending(status) {
  return status.layout && !status.layout.whole && !status.layout.error;
}

function layoutText(status) {
  const l = status.layout;
  if (!l || l.whole) return '';
  if (l.error) return ` · the whole pyramid failed: ${l.error}`;
  return ` · recording the whole pyramid ${(100 * l.done).toFixed(0)} % (exact results and export then)`;
}

function showProgress(status) {
  M.status = status;
  const { measured, total, missing } = status.octaves;
  const d = M.info.display;
  $('display-label').textContent = `level ${d.shown.toLocaleString()} of ${M.info.levels.max.toLocaleString()}` +
    ` vertices (${d.triangles.toLocaleString()} triangles) · ${M.exact ? 'exact result' : 'preview'}` +
    (layoutPending(status) ? layoutText(status) : measured < total ? ` · measuring fine octaves ${measured}/${total}` : '') +
    (status.layout && status.layout.error ? layoutText(status) : '');
  document.querySelectorAll('#bands .band').forEach((row, i) =>
    row.classList.toggle('pending', missing.includes(i)));
}

// ---- equalizer ------------------------------------------------------------------------------
function formatSize(x) {
  return x >= 100 ? x.toFixed(0) : x.toPrecision(2);
}

function buildEqualizer() {
  const bands = $('bands');
  const octaves = M.info.octaves;
  const maxEnergy = Math.max(...octaves.map((o) => o.energy), 1e-300);
  octaves.forEach((o, i) => {
    const row = document.createElement('div');
    row.className = 'band';
    row.title = `levels ${o.from + 1}–${o.to}: details of features about ${o.feature_size.toPrecision(3)} units`;
    row.innerHTML = `<span class="size">${formatSize(o.feature_size)} u</span>
      <input type="range" min="0" max="${M.info.max_gain}" step="0.05" value="1" data-band="${i}">
      <span class="gain">1.00</span><span class="energy"></span>`;
    row.querySelector('.energy').style.width = `${100 * Math.sqrt(o.energy / maxEnergy)}%`;
    row.querySelector('input').addEventListener('input', (e) => {
      M.gains[i] = Number(e.target.value);
      row.querySelector('.gain').textContent = M.gains[i].toFixed(2);
      requestResult();
    });
    bands.appendChild(row);
  });
}

function setGains(gains) {
  M.gains = gains.slice();
  document.querySelectorAll('#bands .band').forEach((row, i) => {
    row.querySelector('input').value = gains[i];
    row.querySelector('.gain').textContent = gains[i].toFixed(2);
  });
  requestResult();
}

// For a host that keeps the state elsewhere too (the notebook widget): sets the gains, the
// normal-only switch and the committed edits, moving the controls, and asks for the result;
// a state equal to the page's (with the edit being dragged) changes nothing.
M.setState = function ({ gains = M.gains, normalOnly = M.normalOnly, moves = M.moves }) {
  const current = M.pending ? M.moves.concat([M.pending]) : M.moves;
  const same = JSON.stringify([gains, normalOnly, moves]) === JSON.stringify([M.gains, M.normalOnly, current]);
  if (same || !M.info) return;
  M.pending = null;
  M.normalOnly = normalOnly;
  $('normal-only').checked = normalOnly;
  M.moves = moves.slice();
  updateEditLabels();
  setGains(gains);
};

// The paper's three experiments, scaled to this mesh: low-pass above n/50 vertices, and the
// stop-band and ×2 enhancement of the levels from n/50 to 0.3·n.
function preset(name) {
  const n = M.info.levels.max;
  const a = n / 50, b = 0.3 * n;
  const inBand = (o) => o.from >= a && o.to <= b;
  const gains = M.info.octaves.map((o) => {
    if (name === 'lowpass') return o.to <= a ? 1 : 0;
    if (name === 'stopband') return inBand(o) ? 0 : 1;
    if (name === 'enhance') return inBand(o) ? 2 : 1;
    return 1;
  });
  setGains(gains);
}

// ---- level scrubber -------------------------------------------------------------------------
// Sliders run on a log scale of vertex counts: each octave gets the same travel.
function levelOf(slider, top) {
  const { min } = M.info.levels;
  const max = top || M.info.levels.max;
  const t = Number(slider.value) / Number(slider.max);
  return Math.round(Math.exp(Math.log(min) + t * (Math.log(max) - Math.log(min))));
}

const scrub = { busy: false, again: false };

// True when no answer is awaited (scripts and the browser test wait for it).
M.idle = () => !request.busy && !request.dirty && !scrub.busy && !scrub.again;

// The level the result is shown at: the finest, or over the budget the shown level.
const resultLevel = () => (M.lod ? M.info.display.shown : M.info.levels.max);

function resultLabel() {
  return M.lod
    ? `level ${resultLevel().toLocaleString()} of ${M.info.levels.max.toLocaleString()} vertices (the result, within the budget)`
    : `finest: ${M.info.vertices.toLocaleString()} vertices (the result)`;
}

function showLevel() {
  const n = levelOf($('level'), resultLevel());
  $('level-label').textContent = n >= resultLevel()
    ? resultLabel()
    : `${n.toLocaleString()} of ${M.info.levels.max.toLocaleString()} vertices (progressive mesh)`;
  if (n >= resultLevel()) { showFinest(); requestDraw(); return; }
  if (scrub.busy) { scrub.again = true; return; }
  scrub.busy = true;
  Promise.all([api('/api/level?n=' + n).then((r) => r.arrayBuffer()), levelSplit(n)])
    .then(([bytes, split]) => {
      const nv = setLevelMesh(bytes, split);
      M.shownLevel = nv;
      M.showingResult = false;
      setStatus(`level ${nv}`);
      requestDraw();
      showError(null);
    })
    .catch(showError)
    .finally(() => { scrub.busy = false; if (scrub.again) { scrub.again = false; showLevel(); } });
}

// Puts a mesh laid out as `/api/level` answers (u32 vertex and triangle counts, f32
// positions, u32 triangles) into the level's GPU mesh, drawn with `split` (its texture) when
// there is one; returns its vertex count.
function setLevelMesh(bytes, split) {
  const [nv, nt] = new Uint32Array(bytes, 0, 2);
  level.setTriangles(new Uint32Array(bytes, 8 + 12 * nv, 3 * nt).slice());
  if (split) level.setSplit(split);
  M.levelTexture = split ? { groups: split.groups.length } : null;
  level.setPositions(new Float32Array(bytes, 8, 3 * nv).slice());
  return nv;
}

// A textured scan's level `n` for the scrubber: its corners' texture coordinates, which the
// server derives from the finest ones as for the shown level, drawn with the images already
// decoded; null for an untextured scan, and when the level has none (a hierarchy built without
// the seams), which then draws plain.
async function levelSplit(n) {
  if (!finest.split) return null;
  const r = await api('/api/texcoords?n=' + n);
  if (!r.ok) return null;
  return { ...readLayout(await r.arrayBuffer()), textures: finest.split.textures };
}

// `/api/texcoords` decoded: split vertices, their coordinates, triangles and image groups.
function readLayout(bytes) {
  const [nd, nt, ng] = new Uint32Array(bytes, 0, 3);
  let at = 12;
  const take = (Type, n) => { const a = new Type(bytes, at, n).slice(); at += 4 * n; return a; };
  const vertexOf = take(Uint32Array, nd);
  const uvs = take(Float32Array, 2 * nd);
  const triangles = take(Uint32Array, 3 * nt);
  const flat = take(Uint32Array, 3 * ng);
  const groups = [];
  for (let g = 0; g < ng; g++) groups.push([flat[3 * g], flat[3 * g + 1], flat[3 * g + 2]]);
  return { vertexOf, uvs, triangles, groups };
}

function showFinest() {
  const result = M.lod ? M.info.display.shown : null;
  if (M.shownLevel !== result || !M.showingResult) {
    M.shownLevel = result;
    M.showingResult = true;
    $('level').value = $('level').max;
    $('level-label').textContent = resultLabel();
  }
}

// ---- drag to edit ---------------------------------------------------------------------------
function pick(ray) {
  const p = M.positions, t = M.faces;
  let best = Infinity;
  const o = ray.origin, d = ray.dir;
  for (let i = 0; i < t.length; i += 3) {
    const a = 3 * t[i], b = 3 * t[i + 1], c = 3 * t[i + 2];
    const e1 = [p[b] - p[a], p[b + 1] - p[a + 1], p[b + 2] - p[a + 2]];
    const e2 = [p[c] - p[a], p[c + 1] - p[a + 1], p[c + 2] - p[a + 2]];
    const q = cross(d, e2);
    const det = dot(e1, q);
    if (Math.abs(det) < 1e-20) continue;
    const s = [o[0] - p[a], o[1] - p[a + 1], o[2] - p[a + 2]];
    const u = dot(s, q) / det;
    if (u < 0 || u > 1) continue;
    const r = cross(s, e1);
    const v = dot(d, r) / det;
    if (v < 0 || u + v > 1) continue;
    const dist = dot(e2, r) / det;
    if (dist > 0 && dist < best) best = dist;
  }
  return best < Infinity ? add(o, scale(d, best)) : null;
}

function editLevel() { return levelOf($('edit-level')); }
// The chosen radius, but never under two edge lengths of the edited level: a smaller one
// would catch no vertex of a coarse level, and the drag would do nothing.
function editRadius() {
  const edge = Math.sqrt(2 * M.info.area / (Math.sqrt(3) * editLevel()));
  return Math.max(Number($('radius').value) / 200 * M.info.diagonal, 2 * edge);
}

function updateEditLabels() {
  $('edit-level-label').textContent =
    `moves level ${editLevel().toLocaleString()}: coarser levels give broader edits`;
  $('radius-label').textContent = `radius ${editRadius().toPrecision(3)} units`;
  $('edit-count').textContent = M.moves.length ? `${M.moves.length} edit(s)` : '';
  $('undo').disabled = M.moves.length === 0;
}

// Starts a drag edit at canvas pixel (x, y); returns the drag or null when the ray misses.
function beginEdit(x, y) {
  showFinest();
  const center = pick(rayAt(x, y));
  if (!center) return null;
  const { forward } = cameraBasis();
  return { center, normal: forward };
}

function dragEdit(drag, x, y) {
  const ray = rayAt(x, y);
  const denom = dot(ray.dir, drag.normal);
  if (Math.abs(denom) < 1e-9) return;
  const t = dot(sub(drag.center, ray.origin), drag.normal) / denom;
  const displacement = sub(add(ray.origin, scale(ray.dir, t)), drag.center);
  M.pending = { level: editLevel(), center: drag.center, displacement, radius: editRadius() };
  requestResult();
}

function endEdit() {
  if (M.pending) {
    M.moves.push(M.pending);
    M.pending = null;
    updateEditLabels();
    requestResult();
  }
}

function undo() {
  if (M.moves.length) {
    M.moves.pop();
    updateEditLabels();
    requestResult();
  }
}

// ---- mouse ------------------------------------------------------------------------------------
function installMouse() {
  const canvas = $('canvas');
  let drag = null;
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    canvas.setPointerCapture(e.pointerId);
    const r = canvas.getBoundingClientRect();
    const x = e.clientX - r.left, y = e.clientY - r.top;
    if ($('edit-mode').checked && e.button === 0 && !e.shiftKey) {
      const edit = beginEdit(x, y);
      drag = edit ? { mode: 'edit', edit } : null;
    } else {
      drag = { mode: e.button === 2 || e.shiftKey ? 'pan' : 'orbit', x: e.clientX, y: e.clientY };
    }
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    if (drag.mode === 'edit') {
      const r = canvas.getBoundingClientRect();
      dragEdit(drag.edit, e.clientX - r.left, e.clientY - r.top);
      return;
    }
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX; drag.y = e.clientY;
    if (drag.mode === 'orbit') {
      camera.yaw -= dx * 0.008;
      camera.pitch = Math.max(-1.55, Math.min(1.55, camera.pitch + dy * 0.008));
    } else {
      const { right, up } = cameraBasis();
      const k = 2 * camera.distance * Math.tan(camera.fov / 2) / canvas.clientHeight;
      camera.target = add(camera.target, add(scale(right, -dx * k), scale(up, dy * k)));
    }
    requestDraw();
  });
  const release = () => {
    if (drag && drag.mode === 'edit') endEdit();
    drag = null;
  };
  canvas.addEventListener('pointerup', release);
  canvas.addEventListener('pointercancel', release);
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    camera.distance *= Math.exp(e.deltaY * 0.001);
    requestDraw();
  }, { passive: false });
}

// ---- export -----------------------------------------------------------------------------------
M.exportBytes = async function (format) {
  const r = await api('/api/export?format=' + format, {
    method: 'POST', body: stateBody(), headers: { 'Content-Type': 'application/json' },
  });
  const name = (r.headers.get('Content-Disposition') || '').match(/filename="([^"]+)"/);
  return { bytes: new Uint8Array(await r.arrayBuffer()), name: name ? name[1] : 'mesh.' + format };
};

async function download(format) {
  try {
    const { bytes, name } = await M.exportBytes(format);
    const url = URL.createObjectURL(new Blob([bytes]));
    const a = document.createElement('a');
    a.href = url;
    a.download = name;
    a.click();
    setTimeout(() => URL.revokeObjectURL(url), 10000);
  } catch (e) {
    showError(e);
  }
}

// ---- start ------------------------------------------------------------------------------------
function installControls() {
  for (const id of ['smooth', 'wireframe', 'texture']) $(id).addEventListener('change', requestDraw);
  $('reset-view').addEventListener('click', resetView);
  $('normal-only').addEventListener('change', (e) => { M.normalOnly = e.target.checked; requestResult(); });
  document.querySelectorAll('[data-preset]').forEach((b) =>
    b.addEventListener('click', () => preset(b.dataset.preset)));
  $('level').addEventListener('input', showLevel);
  $('budget').addEventListener('change', setBudget);
  for (const id of ['edit-level', 'radius']) $(id).addEventListener('input', updateEditLabels);
  $('edit-mode').addEventListener('change', (e) => $('canvas').classList.toggle('editing', e.target.checked));
  $('undo').addEventListener('click', undo);
  document.addEventListener('keydown', (e) => {
    if ((e.ctrlKey || e.metaKey) && e.key === 'z') { e.preventDefault(); undo(); }
  });
  document.querySelectorAll('[data-export]').forEach((b) =>
    b.addEventListener('click', () => download(b.dataset.export)));
  window.addEventListener('resize', requestDraw);
}

async function start() {
  if (!gl) throw new Error('this browser has no WebGL2');
  shadeProgram = compile(VERTEX, SHADE);
  lineProgram = compile(VERTEX, LINE);
  finest = new GpuMesh(M.renderer.software);
  level = new GpuMesh(false);
  installMouse();
  const framed = await showOpening();
  await openScan();
  buildEqualizer();
  installControls();
  updateEditLabels();
  if (!framed) resetView();
  requestResult();
  const waitFirst = () => {
    if (M.updates === 0) { setTimeout(waitFirst, 20); return; }
    if (M.firstPictureMs === null) M.firstPictureMs = performance.now();
    M.ready = true;
  };
  waitFirst();
}

// While the server opens the scan (builds its hierarchy and details), draws each picture it
// offers (the input clustered to the budget, or a level read from the start of a .pyr file;
// then the hierarchy's level) under the stage and its progress, the panel inert. Returns when
// the editor is ready: true if a picture was drawn (the camera is set, and stays as the user
// left it).
async function showOpening() {
  let shown = 0;
  $('panel').inert = true;
  try {
    for (;;) {
      const o = (await (await api('/api/status')).json()).opening;
      if (!o) return shown > 0;
      M.opening = o;
      if (o.picture !== shown) shown = await drawOpeningPicture(o) || shown;
      $('status').textContent = `opening: ${o.stage} · ${(100 * o.done).toFixed(0)} % · ` +
        `${o.seconds.toFixed(0)} s · showing ${o.what}`;
      await new Promise((resolve) => setTimeout(resolve, 250));
    }
  } finally {
    $('panel').inert = false;
  }
}

// Draws the opening picture described by status `o`; returns its number (0: the scan opened
// meanwhile, so there is none).
async function drawOpeningPicture(o) {
  let r;
  try { r = await api('/api/opening'); } catch (_) { return 0; }
  setLevelMesh(await r.arrayBuffer());
  if (!M.info) {
    M.info = { bbox: o.bbox, diagonal: o.diagonal };
    resetView();
  }
  M.showingResult = false;
  draw();
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4)); // wait until drawn
  const ms = performance.now();
  if (M.firstPictureMs === null) M.firstPictureMs = ms;
  M.pictures.push({ what: o.what, triangles: level.nTriangleIndices / 3, ms });
  return Number(r.headers.get('X-Meshpyr-Picture'));
}

// Reads the scan's description and the triangles of the result: the input's, or over the
// budget those of the shown level.
async function openScan() {
  M.info = await (await api('/api/info')).json();
  const i = M.info;
  document.title = `${i.name} · meshpyr view`;
  $('meta').textContent = `${i.name}: ${i.vertices.toLocaleString()} vertices, ` +
    `${i.triangles.toLocaleString()} triangles, levels ${i.levels.min}–${i.levels.max}`;
  if (M.gains.length !== i.octaves.length) M.gains = i.octaves.map(() => 1);
  M.lod = i.display.lod;
  $('budget').value = i.display.budget;
  if (M.lod) {
    const bytes = await (await api('/api/display')).arrayBuffer();
    const [, nt] = new Uint32Array(bytes, 0, 2);
    M.faces = new Uint32Array(bytes, 8, 3 * nt).slice();
    M.exact = false;
  } else {
    M.faces = new Uint32Array(await (await api('/api/faces')).arrayBuffer());
    $('display-label').textContent = `the whole scan: ${i.triangles.toLocaleString()} triangles`;
  }
  finest.setTriangles(M.faces);
  M.texture = null;
  $('texture-row').hidden = !i.texture;
  // Without its texture the scan is still the scan: a failure here leaves it plain.
  if (i.texture) await loadTexture(i.texture).catch(showError);
  M.showingResult = false;
  showFinest();
}

// A textured scan: the split vertices and grouped triangles of what is on screen (the input,
// or over the budget the shown level, whose corners the server derives from the finest), and
// its images as WebGL textures (repeating, mipmapped). An image the browser cannot decode
// leaves its faces plain.
async function loadTexture(info) {
  const { vertexOf, uvs, triangles, groups } = readLayout(await (await api('/api/texcoords')).arrayBuffer());
  const textures = {};
  let decoded = 0;
  for (let k = 0; k < info.images.length; k++) {
    try {
      const blob = await (await api('/api/texture?image=' + k)).blob();
      const bitmap = await createImageBitmap(blob);
      const t = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, t);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, gl.RGBA, gl.UNSIGNED_BYTE, bitmap);
      gl.generateMipmap(gl.TEXTURE_2D);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR_MIPMAP_LINEAR);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.REPEAT);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.REPEAT);
      textures[k] = t;
      decoded += 1;
    } catch (e) {
      showError(`texture ${info.images[k]}: ${e.message || e}`);
    }
  }
  if (!textureProgram) textureProgram = compile(vertexSource(true), shadeSource(true));
  finest.setSplit({ vertexOf, uvs, triangles, groups, textures });
  M.texture = { images: decoded, groups: groups.length };
}

// A new display budget: the server makes the level of detail again and the page redraws.
async function setBudget() {
  try {
    await api('/api/budget', {
      method: 'POST', body: JSON.stringify({ triangles: Number($('budget').value) }),
      headers: { 'Content-Type': 'application/json' },
    });
    awaited = null;
    await openScan();
    requestResult();
  } catch (e) {
    showError(e);
  }
}

start().catch((e) => { showError(e); $('status').textContent = 'failed to start'; });
