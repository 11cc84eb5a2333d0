"""The notebook widget's front end (meshpyr/_widget.js) in headless Chromium, driven through
anywidget's model interface: a test page imports the module and renders it with a model whose
``send`` and ``save_changes`` reach a real ``meshpyr.Viewer`` over a small local HTTP bridge
(what the Jupyter comm does in a notebook). The editor's page draws in its frame, a slider
changes the picture and Python's state and positions, gains and edits set from Python show on
the page, undo and a drag edit on the page reach Python, and a ``save_html`` file draws on its
own.

Needs chromium and chromedriver (.ci/run installs them); skipped without them unless
MESHPYR_REQUIRE_BROWSER=1.
"""

import base64
import http.server
import json
import pathlib
import threading

import numpy as np
import pytest

import meshpyr

from conftest import data
from webdriver import ELEMENT, driver_or_skip

pytest.importorskip("anywidget", reason="the notebook extra (anywidget) is not installed")

# The test page: anywidget's model interface (get, set, save_changes, on, off, send) over the
# bridge. Updates from Python arrive through `window.fromKernel`, as the comm delivers them.
TEST_PAGE = """<!doctype html>
<html><head><meta charset="utf-8"><link rel="stylesheet" href="/widget.css"></head>
<body style="margin:0; width:1200px"><div id="root"></div>
<script type="module">
import widget from '/widget.js';
const state = await (await fetch('/state')).json();
const listeners = {};
let dirty = {};
window.inflight = 0;
const fire = (name, ...args) => (listeners[name] || []).slice().forEach((f) => f(...args));
const post = async (path, body) => {
  window.inflight += 1;
  try { return await fetch(path, { method: 'POST', body }); } finally { window.inflight -= 1; }
};
const apply = (changes, local) => {
  const changed = [];
  for (const [k, v] of Object.entries(changes)) {
    if (JSON.stringify(state[k]) === JSON.stringify(v)) continue;
    state[k] = v;
    if (local) dirty[k] = v;
    changed.push(k);
  }
  changed.forEach((k) => fire('change:' + k, state[k]));
};
const model = {
  get: (k) => state[k],
  set: (k, v) => apply(typeof k === 'object' ? k : { [k]: v }, true),
  save_changes() { const body = JSON.stringify(dirty); dirty = {}; post('/update', body); },
  on(names, f) { for (const n of names.split(' ')) (listeners[n] = listeners[n] || []).push(f); },
  off(names, f) { for (const n of names.split(' ')) listeners[n] = (listeners[n] || []).filter((g) => g !== f); },
  send(content) {
    post('/send', JSON.stringify(content)).then(async (r) => {
      const reply = JSON.parse(r.headers.get('X-Reply'));
      fire('msg:custom', reply, [new DataView(await r.arrayBuffer())]);
    });
  },
};
window.fromKernel = (changes) => apply(changes, false);
window.modelState = () => state;
widget.render({ model, el: document.getElementById('root') });
</script></body></html>"""


class Bridge:
    """Serves the test page and the widget's files, and hands the model's messages and state
    updates to ``viewer`` (one at a time, as a kernel does)."""

    def __init__(self, viewer):
        self.viewer = viewer
        here = pathlib.Path(meshpyr._viewer.__file__).parent
        files = {
            "/": (TEST_PAGE.encode(), "text/html"),
            "/widget.js": ((here / "_widget.js").read_bytes(), "text/javascript"),
            "/widget.css": ((here / "_widget.css").read_bytes(), "text/css"),
        }
        lock = threading.Lock()
        bridge = self

        class Handler(http.server.BaseHTTPRequestHandler):
            def log_message(self, *args):
                pass

            def reply(self, body, kind, headers=()):
                self.send_response(200)
                self.send_header("Content-Type", kind)
                self.send_header("Content-Length", str(len(body)))
                for k, v in headers:
                    self.send_header(k, v)
                self.end_headers()
                self.wfile.write(body)

            def do_GET(self):
                if self.path == "/state":
                    with lock:
                        state = bridge.viewer.get_state()
                    state = {k: v for k, v in state.items() if not k.startswith("_") or k == "_page"}
                    self.reply(json.dumps(state).encode(), "application/json")
                elif self.path in files:
                    self.reply(*files[self.path])
                else:
                    self.send_error(404)

            def do_POST(self):
                body = json.loads(self.rfile.read(int(self.headers["Content-Length"])))
                with lock:
                    if self.path == "/update":
                        bridge.viewer.set_state(body)
                        self.reply(b"{}", "application/json")
                        return
                    sent = []
                    bridge.viewer.send = lambda content, buffers=None: sent.append((content, buffers))
                    bridge.viewer._on_request(bridge.viewer, body, [])
                [(content, buffers)] = sent
                self.reply(bytes(buffers[0]), "application/octet-stream", [("X-Reply", json.dumps(content))])

        self.server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.server.server_address[1]}/"
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def close(self):
        self.server.shutdown()
        self.server.server_close()


def drawn_share(pixels, background=(18, 20, 26)):
    """Share of pixels away from the page's background colour."""
    return float(np.mean(np.any(np.abs(pixels.astype(int) - background) > 30, axis=2)))


def changed_share(a, b):
    return float(np.mean(np.any(np.abs(a.astype(int) - b.astype(int)) > 8, axis=2)))


@pytest.fixture(scope="module")
def driver():
    d = driver_or_skip()
    yield d
    d.quit()


def settle(driver):
    """Waits in the frame until the page answered everything, then for the model's updates."""
    driver.enter_frame("iframe.meshpyr-frame")
    driver.wait_for("window.meshpyr && window.meshpyr.ready && window.meshpyr.idle()", "the frame")
    driver.leave_frame()
    driver.wait_for("window.inflight === 0", "the test page")


def test_the_widget_draws_and_syncs_with_python(driver, tmp_path):
    v, f = meshpyr.read(data("bunny.ply"))
    pyramid = meshpyr.Pyramid(v, f)
    viewer = meshpyr.show(pyramid, name="bunny.ply", open_browser=False, height=500)
    bridge = Bridge(viewer)
    try:
        driver.navigate(bridge.url)
        driver.wait_for("document.querySelector('iframe.meshpyr-frame')")
        settle(driver)
        driver.enter_frame("iframe.meshpyr-frame")
        before = driver.screenshot("#canvas")
        assert drawn_share(before) > 0.03, "the canvas is blank"

        # A slider on the page: the picture, Python's gains and positions follow.
        seen = []
        viewer.observe(lambda change: seen.append(change["new"]), names="gains")
        band = len(viewer.octaves) - 3
        driver.script(
            "const s = document.querySelector(arguments[0]); s.value = 3;"
            "s.dispatchEvent(new Event('input', {bubbles: true}));",
            f"#bands input[data-band='{band}']",
        )
        driver.leave_frame()
        settle(driver)
        expected_gains = [1.0] * len(viewer.octaves)
        expected_gains[band] = 3.0
        assert viewer.gains == expected_gains and seen[-1] == expected_gains
        lo, hi = viewer.octaves[band]
        assert np.array_equal(viewer.positions, pyramid.filter(gains=[(lo, hi, 3.0)]))
        driver.enter_frame("iframe.meshpyr-frame")
        page = np.array(driver.script("return Array.from(window.meshpyr.positions);"), np.float32)
        assert page.tobytes() == viewer.positions.astype(np.float32).ravel().tobytes()
        after = driver.screenshot("#canvas")
        assert changed_share(before, after) > 0.003, "the picture hardly changed"
        driver.leave_frame()

        # Gains set from Python move the page's sliders and its result.
        viewer.gains = [1.0] * (len(viewer.octaves) - 2) + [0.0, 0.0]
        driver.script("window.fromKernel(arguments[0]);", {"gains": viewer.gains})
        settle(driver)
        driver.enter_frame("iframe.meshpyr-frame")
        sliders = driver.script("return Array.from(document.querySelectorAll('#bands input'), (s) => Number(s.value));")
        assert sliders == viewer.gains
        page = np.array(driver.script("return Array.from(window.meshpyr.positions);"), np.float32)
        assert page.tobytes() == viewer.positions.astype(np.float32).ravel().tobytes()
        driver.leave_frame()
        assert driver.script("return window.modelState().gains;") == viewer.gains

        # An edit set from Python shows on the page; undo on the page reaches Python.
        v = pyramid.vertices
        diagonal = float(np.linalg.norm(v.max(0) - v.min(0)))
        move = {"level": 2000, "center": v[100].tolist(), "displacement": [0.0, 0.05 * diagonal, 0.0],
                "radius": 0.2 * diagonal}
        viewer.moves = [move]
        driver.script("window.fromKernel(arguments[0]);", {"moves": viewer.moves})
        settle(driver)
        driver.enter_frame("iframe.meshpyr-frame")
        assert driver.script("return window.meshpyr.moves;") == [move]
        page = np.array(driver.script("return Array.from(window.meshpyr.positions);"), np.float32)
        edited = pyramid.edit(2000, [(move["center"], move["displacement"])], move["radius"],
                              gains=viewer.filter_bands())
        assert page.tobytes() == edited.astype(np.float32).ravel().tobytes()
        driver.script("document.getElementById('undo').click();")
        driver.leave_frame()
        settle(driver)
        assert viewer.moves == []
        assert np.array_equal(viewer.positions, pyramid.filter(gains=viewer.filter_bands()))

        # A drag edit on the page reaches Python: its moves, and positions with the bits of
        # Pyramid.edit for that move.
        driver.enter_frame("iframe.meshpyr-frame")
        driver.script("document.getElementById('edit-mode').click();")
        canvas = driver.element("#canvas")
        mouse = [
            {"type": "pointerMove", "duration": 0, "origin": {ELEMENT: canvas}, "x": 0, "y": 0},
            {"type": "pointerDown", "button": 0},
            {"type": "pointerMove", "duration": 300, "origin": "pointer", "x": 0, "y": -50},
            {"type": "pointerUp", "button": 0},
        ]
        driver.call_session("POST", "/actions", {"actions": [
            {"type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"}, "actions": mouse}]})
        driver.wait_for("window.meshpyr.moves.length === 1 && window.meshpyr.idle()", "the frame")
        dragged = driver.script("return window.meshpyr.moves[0];")
        driver.leave_frame()
        settle(driver)
        assert viewer.moves == [dragged] and np.linalg.norm(dragged["displacement"]) > 0
        edited = pyramid.edit(dragged["level"], [(dragged["center"], dragged["displacement"])],
                              dragged["radius"], gains=viewer.filter_bands())
        assert np.array_equal(viewer.positions, edited)

        # The saved page draws the same result on its own, from a file.
        path = tmp_path / "bunny.html"
        viewer.save_html(path)
        driver.navigate(path.as_uri())
        driver.wait_for("window.meshpyr && window.meshpyr.ready", "the saved page")
        shot = driver.screenshot("#canvas")
        assert drawn_share(shot) > 0.03, "the saved page is blank"
        page = np.array(driver.script("return Array.from(window.meshpyr.positions);"), np.float32)
        assert page.tobytes() == viewer.positions.astype(np.float32).ravel().tobytes()
        assert driver.script("return getComputedStyle(document.getElementById('panel')).display;") == "none"
    finally:
        bridge.close()
        viewer.close()
