"""meshpyr.Viewer (the notebook editor) from Python: its state, validated by the editor; its
positions, the very bits of Pyramid.filter / Pyramid.edit; observers; the page's requests
answered in-process within a notebook message's size; save_html; serve() serving the editor
with meshpyr view's guard; and meshpyr without the notebook extra."""

import json
import os
import subprocess
import sys
import urllib.error
import urllib.request

import numpy as np
import pytest

import meshpyr

from conftest import data

anywidget = pytest.importorskip("anywidget", reason="the notebook extra (anywidget) is not installed")


@pytest.fixture(scope="module")
def bunny():
    v, f = meshpyr.read(data("bunny.ply"))
    return meshpyr.Pyramid(v, f)


@pytest.fixture
def viewer(bunny):
    w = meshpyr.show(bunny, name="bunny.ply", open_browser=False)
    yield w
    w.close()


def test_octaves_are_the_spectrum_bands_and_gains_start_at_one(viewer, bunny):
    assert viewer.comm is not None, "the widget opened no comm"
    assert len(meshpyr.Viewer.__doc__) > 40 and len(meshpyr.show.__doc__) > 40
    spectrum = bunny.spectrum()
    assert viewer.octaves == list(zip(spectrum["lo"].tolist(), spectrum["hi"].tolist()))
    assert viewer.gains == [1.0] * len(viewer.octaves)
    assert viewer.normal_only is False and viewer.moves == []
    with pytest.raises(Exception):
        viewer.octaves = [(1, 2)]


def test_positions_are_the_bits_of_filter(viewer, bunny):
    n = len(viewer.octaves)
    viewer.gains = [1.0] * (n - 4) + [0.0, 2.5, 1.0, 1.0]
    bands = viewer.filter_bands()
    assert [g for _, _, g in bands] == [0.0, 2.5]
    assert np.array_equal(viewer.positions, bunny.filter(gains=bands))
    viewer.normal_only = True
    expected = bunny.filter(gains=bands, normal_only=True)
    assert np.array_equal(viewer.positions, expected)
    assert not np.array_equal(expected, bunny.filter(gains=bands))


def test_positions_of_edits_are_the_bits_of_edit(viewer, bunny):
    v = bunny.vertices
    diagonal = float(np.linalg.norm(v.max(0) - v.min(0)))
    level, radius = 2000, 0.15 * diagonal
    points = [v[100], v[2000]]
    deltas = [[0.0, 0.03 * diagonal, 0.0], [0.02 * diagonal, 0.0, 0.0]]
    viewer.moves = [
        {"level": level, "center": list(map(float, p)), "displacement": d, "radius": radius}
        for p, d in zip(points, deltas)
    ]
    n = len(viewer.octaves)
    viewer.gains = [1.0] * (n - 3) + [1.5, 1.0, 1.0]
    expected = bunny.edit(level, list(zip(points, deltas)), radius, gains=viewer.filter_bands())
    assert np.array_equal(viewer.positions, expected)
    assert not np.allclose(expected, bunny.filter(gains=viewer.filter_bands()))


def test_observers_see_changes_from_python_and_from_the_page(viewer):
    seen = []
    viewer.observe(lambda change: seen.append((change["name"], change["new"])), names=["gains", "normal_only", "moves"])
    n = len(viewer.octaves)
    viewer.gains = [2.0] * n
    assert seen == [("gains", [2.0] * n)]
    # What the front end's sync does with a state the page reports.
    viewer.set_state({"gains": [1] * (n - 1) + [0.5], "normal_only": True})
    assert ("gains", [1.0] * (n - 1) + [0.5]) in seen and ("normal_only", True) in seen
    assert viewer.gains == [1.0] * (n - 1) + [0.5]


@pytest.mark.parametrize(
    "name, value, message",
    [
        ("gains", [1.0], "expected"),
        ("gains", "fifteen", None),
        ("gains", None, None),
        ("gains", "nan", "finite"),
        ("gains", 3.5, "outside"),
        ("gains", -0.1, "outside"),
        ("moves", [{"level": 1, "center": [0, 0, 0], "displacement": [0, 0, 0], "radius": 1}], "level"),
        ("moves", [{"level": 2000, "center": [0, 0, 0], "displacement": [0, 0, 0], "radius": -1}], "radius"),
        ("moves", [{"level": 2000}], "bad JSON"),
        ("moves", [{"level": 2000, "center": [0, 0, 0], "displacement": [0, 0, 0], "radius": 1, "x": 1}], "bad JSON"),
    ],
)
def test_bad_values_raise_value_error_and_change_nothing(viewer, name, value, message):
    n = len(viewer.octaves)
    if name == "gains" and isinstance(value, (float, str)) and value != "fifteen":
        value = [1.0] * (n - 1) + [float(value)]
    before = (viewer.gains, viewer.moves)
    seen = []
    viewer.observe(seen.append)
    with pytest.raises((ValueError, TypeError)) as raised:
        setattr(viewer, name, value)
    if message is not None:
        assert raised.type is ValueError or issubclass(raised.type, ValueError)
        assert message in str(raised.value)
    assert (viewer.gains, viewer.moves) == before and seen == []


def test_the_pages_requests_are_answered_in_process(viewer, bunny):
    status, kind, _, body = viewer.answer("GET", "/api/info", b"")
    info = json.loads(body)
    assert (status, kind) == (200, "application/json")
    assert info["name"] == "bunny.ply" and info["vertices"] == len(bunny.vertices)
    status, _, _, body = viewer.answer("GET", "/api/faces", b"")
    assert np.array_equal(np.frombuffer(body, "<u4").reshape(-1, 3), bunny.faces)
    n = len(viewer.octaves)
    state = json.dumps({"gains": [1.0] * (n - 1) + [2.0]}).encode()
    status, _, headers, body = viewer.answer("POST", "/api/filter", state)
    assert status == 200 and "Server-Timing" in dict(headers)
    expected = bunny.filter(gains=[(*viewer.octaves[-1], 2.0)]).astype("<f4")
    assert np.frombuffer(body, "<f4").tobytes() == expected.tobytes()
    assert viewer.answer("GET", "/api/nothing", b"")[0] == 404
    assert viewer.answer("POST", "/api/filter", b"{")[0] == 400
    assert viewer.answer("POST", "/api/filter", b" " * (256 * 1024 + 1))[0] == 413


def test_answers_over_a_notebook_messages_limit_are_refused(viewer, monkeypatch):
    from meshpyr import _viewer

    monkeypatch.setattr(_viewer, "MAX_REPLY_BYTES", 1000)
    status, kind, _, body = viewer.answer("GET", "/api/faces", b"")
    assert (status, kind) == (413, "application/json")
    assert "Viewer.positions" in json.loads(body)["error"]


def test_widget_messages_carry_answers_as_buffers(viewer):
    sent = []
    viewer.send = lambda content, buffers=None: sent.append((content, buffers))
    viewer._on_request(viewer, {"kind": "request", "id": "a-1", "method": "GET", "path": "/api/faces", "body": ""}, [])
    viewer._on_request(viewer, {"kind": "something else"}, [])
    [(content, buffers)] = sent
    assert content["id"] == "a-1" and content["status"] == 200
    assert content["headers"]["Content-Type"] == "application/octet-stream"
    assert len(buffers) == 1 and len(buffers[0]) == 12 * len(viewer.pyramid.faces)


def test_the_widget_ships_its_code_and_loads_nothing_from_a_network(viewer):
    from meshpyr import _viewer

    here = os.path.dirname(_viewer.__file__)
    for name in ("_widget.js", "_widget.css", "_frame.js"):
        text = open(os.path.join(here, name), encoding="utf-8").read()
        assert "http://" not in text and "https://" not in text, name
    assert "<script src=" not in viewer._page and "meshpyrTransport" in viewer._page
    assert "https://" not in viewer._page and "http://" not in viewer._page


def test_save_html_writes_the_result_in_one_file_atomically(viewer, bunny, tmp_path):
    n = len(viewer.octaves)
    viewer.gains = [1.0] * (n - 1) + [3.0]
    path = tmp_path / "bunny.html"
    path.write_text("old")
    viewer.save_html(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bunny.html"]
    html = path.read_text()
    assert "https://" not in html and "http://" not in html and "<script src=" not in html
    start = html.index("const MESHPYR_SNAPSHOT = ") + len("const MESHPYR_SNAPSHOT = ")
    snapshot = html[start : html.index(";\n", start)]
    import base64
    import re

    positions = re.search(r"positions: '([^']*)'", snapshot).group(1)
    expected = bunny.filter(gains=viewer.filter_bands()).astype("<f4")
    assert base64.b64decode(positions) == expected.tobytes()
    with pytest.raises(OSError):
        viewer.save_html(tmp_path / "missing" / "x.html")


def test_show_takes_a_pyramid_a_pair_or_a_path(bunny, tmp_path):
    v, f = bunny.vertices, bunny.faces
    for x in [(v, f), str(data("bunny.ply")), data("bunny.ply")]:
        w = meshpyr.show(x, open_browser=False)
        assert w.octaves == meshpyr.show(bunny, open_browser=False).octaves
    bunny.save(tmp_path / "b.pyr")
    assert meshpyr.show(tmp_path / "b.pyr", open_browser=False).octaves
    with pytest.raises(TypeError):
        meshpyr.show(42)
    with pytest.raises(ValueError):
        meshpyr.show(bunny, budget=10, open_browser=False)


def test_serve_opens_the_editor_with_its_guard(viewer):
    url = viewer.serve(browser=False)
    assert viewer.url == url and url.startswith("http://127.0.0.1:")
    base, token = url.split("/?token=")
    with urllib.request.urlopen(base + "/") as page:
        assert b"app.js" in page.read()
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(base + "/api/info")
    assert refused.value.code == 403
    request = urllib.request.Request(base + "/api/info", headers={"X-Meshpyr-Token": token})
    with urllib.request.urlopen(request) as info:
        assert json.loads(info.read())["name"] == "bunny.ply"
    foreign = urllib.request.Request(base + "/", headers={"Host": "evil.example:80"})
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(foreign)
    assert refused.value.code == 403
    viewer.stop()
    assert viewer.url is None
    # Refused, or reset by the acceptor as it winds down.
    with pytest.raises((urllib.error.URLError, ConnectionError)):
        urllib.request.urlopen(base + "/", timeout=5)


def test_meshpyr_works_without_the_notebook_extra():
    # anywidget hidden: `import meshpyr` and the rest work; show and Viewer say what to install.
    code = """
import sys
sys.modules["anywidget"] = None
import meshpyr
from meshpyr import *
v, f = meshpyr.read(sys.argv[1])
assert meshpyr.Pyramid(v, f).levels
for attempt in (lambda: meshpyr.show((v, f)), lambda: meshpyr.Viewer):
    try:
        attempt()
    except ImportError as e:
        print(e)
    else:
        raise SystemExit("no ImportError")
"""
    done = subprocess.run([sys.executable, "-c", code, str(data("bunny.ply"))], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert len(lines) == 2 and all("meshpyr[notebook]" in line for line in lines)


def test_the_example_notebook_runs(tmp_path, monkeypatch):
    # Its code cells in order, as a kernel would run them (outside one, without a browser).
    notebook = json.loads((data("bunny.ply").parents[2] / "examples" / "notebook.ipynb").read_text())
    source = "\n".join("".join(c["source"]) for c in notebook["cells"] if c["cell_type"] == "code")
    source = source.replace('"../tests/data/bunny.ply"', repr(str(data("bunny.ply"))))
    monkeypatch.setattr("webbrowser.open", lambda url: pytest.fail(f"opened {url}"))
    monkeypatch.chdir(tmp_path)
    opened = []
    monkeypatch.setattr(meshpyr._viewer.Viewer, "serve", lambda self, **_: opened.append(self))
    exec(compile(source, "notebook.ipynb", "exec"), {})
    assert len(opened) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bunny-enhanced.html", "bunny-enhanced.ply"]
