"""meshpyr.show in a real JupyterLab started by the test, in headless Chromium: the widget
renders in the cell's output (anywidget's extension, the comm, the page's frame), draws, a
slider on the page reaches the kernel (its observer sees the new gains, and the positions equal
Pyramid.filter's), and gains set in the kernel move the sliders.

MESHPYR_WIDGET_SCREENSHOT=path.png saves the window after the slider moved (the picture of
python/README.md). Needs jupyterlab (.ci/run installs it), chromium and chromedriver; skipped without them unless
MESHPYR_REQUIRE_BROWSER=1.
"""

import json
import os
import pathlib
import subprocess
import sys
import time
import urllib.request

import numpy as np
import pytest

from conftest import data
from webdriver import driver_or_skip, free_port

pytest.importorskip("anywidget", reason="the notebook extra (anywidget) is not installed")
if os.environ.get("MESHPYR_REQUIRE_BROWSER") != "1":
    pytest.importorskip("jupyterlab", reason="jupyterlab is not installed")

# The kernel writes what its observer sees to gains.json: the gains and whether the positions
# are Pyramid.filter's for them.
CELL = f"""
import json, numpy as np, meshpyr
v, f = meshpyr.read({str(data("bunny.ply"))!r})
pyramid = meshpyr.Pyramid(v, f)
viewer = meshpyr.show(pyramid, name="bunny.ply", height=480)
def report(change):
    same = np.array_equal(viewer.positions, pyramid.filter(gains=viewer.filter_bands()))
    with open("gains.json.tmp", "w") as out:
        json.dump({{"gains": viewer.gains, "same_bits": bool(same)}}, out)
    import os; os.replace("gains.json.tmp", "gains.json")
viewer.observe(report, names="gains")
viewer
"""


def notebook(path):
    cell = {"cell_type": "code", "metadata": {}, "execution_count": None, "outputs": [], "id": "c0",
            "source": CELL.strip().splitlines(keepends=True)}
    meta = {"kernelspec": {"name": "python3", "display_name": "Python 3", "language": "python"}}
    path.write_text(json.dumps({"cells": [cell], "metadata": meta, "nbformat": 4, "nbformat_minor": 5}))


@pytest.fixture
def lab(tmp_path):
    """A JupyterLab server on a free port with its own config, data and runtime folders."""
    port, token = free_port(), "meshpyr-test-token"
    env = dict(os.environ)
    for name in ("JUPYTER_CONFIG_DIR", "JUPYTER_RUNTIME_DIR", "IPYTHONDIR"):
        env[name] = str(tmp_path / name.lower())
    root = tmp_path / "root"
    root.mkdir()
    log = open(tmp_path / "lab.log", "w")
    process = subprocess.Popen(
        [sys.executable, "-m", "jupyterlab", "--no-browser", f"--port={port}", "--ip=127.0.0.1",
         "--allow-root", f"--IdentityProvider.token={token}", f"--ServerApp.root_dir={root}", "--expose-app-in-browser",
         "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate"],
        env=env, stdout=log, stderr=subprocess.STDOUT,
    )
    deadline = time.monotonic() + 120
    while True:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/status?token={token}", timeout=5):
                break
        except OSError:
            if process.poll() is not None or time.monotonic() > deadline:
                process.kill()
                raise AssertionError("JupyterLab did not start: " + (tmp_path / "lab.log").read_text()[-2000:])
            time.sleep(0.3)
    yield root, f"http://127.0.0.1:{port}/lab/tree/test.ipynb?token={token}"
    process.terminate()
    try:
        process.wait(timeout=20)
    except subprocess.TimeoutExpired:
        process.kill()
    log.close()


def test_show_works_in_jupyterlab(lab):
    root, url = lab
    notebook(root / "test.ipynb")
    driver = driver_or_skip()
    try:
        driver.navigate(url)
        # The notebook open, its kernel ready; then any dialog dismissed (a build suggestion,
        # say, when other extensions are installed) and the cell run.
        find = (
            "const app = window.jupyterapp;"
            "const w = app && Array.from(app.shell.widgets('main')).find((x) => x.sessionContext && x.content);"
        )
        ready = find + (
            "const k = w && w.sessionContext.session && w.sessionContext.session.kernel;"
            "return !!(k && k.status === 'idle' && w.content.widgets.length);"
        )
        deadline = time.monotonic() + 120
        while not driver.script(ready):
            assert time.monotonic() < deadline, "the notebook's kernel did not start"
            time.sleep(0.2)
        driver.script("document.querySelectorAll('.jp-Dialog .jp-mod-reject').forEach((b) => b.click());")
        driver.script(find + "app.shell.activateById(w.id); app.commands.execute('notebook:run-all-cells');")
        driver.wait_for("document.querySelector('.jp-OutputArea iframe.meshpyr-frame')", "JupyterLab")
        driver.enter_frame(".jp-OutputArea iframe.meshpyr-frame")
        driver.wait_for("window.meshpyr && window.meshpyr.ready && window.meshpyr.idle()", "the widget")
        before = driver.screenshot("#canvas")
        drawn = np.mean(np.any(np.abs(before.astype(int) - (18, 20, 26)) > 30, axis=2))
        assert drawn > 0.03, "the canvas is blank"
        n = driver.script("return window.meshpyr.info.octaves.length;")
        band = n - 3
        driver.script(
            "const s = document.querySelector(arguments[0]); s.value = 2.5;"
            "s.dispatchEvent(new Event('input', {bubbles: true}));",
            f"#bands input[data-band='{band}']",
        )
        driver.wait_for("window.meshpyr.idle()", "the widget")
        after = driver.screenshot("#canvas")
        assert np.mean(np.any(np.abs(after.astype(int) - before.astype(int)) > 8, axis=2)) > 0.003
        driver.leave_frame()
        # The picture in python/README.md: MESHPYR_WIDGET_SCREENSHOT=path.png.
        if os.environ.get("MESHPYR_WIDGET_SCREENSHOT"):
            driver.script(
                "document.querySelectorAll('.Toastify button').forEach((b) => {"
                " if (b.textContent.trim() === 'No' || b.classList.contains('Toastify__close-button')) b.click(); });"
            )
            time.sleep(0.5)
            pathlib.Path(os.environ["MESHPYR_WIDGET_SCREENSHOT"]).write_bytes(driver.window_png())
        expected = [1.0] * n
        expected[band] = 2.5
        deadline = time.monotonic() + 60
        report = root / "gains.json"
        while not (report.exists() and json.loads(report.read_text())["gains"] == expected):
            assert time.monotonic() < deadline, f"the kernel did not see the slider: {report.exists() and report.read_text()}"
            time.sleep(0.1)
        assert json.loads(report.read_text())["same_bits"]

        # Gains set in the kernel move the page's sliders.
        driver.script(find + "w.sessionContext.session.kernel.requestExecute({code: arguments[0]});",
                      f"viewer.gains = [0.5] * {n}")
        driver.enter_frame(".jp-OutputArea iframe.meshpyr-frame")
        driver.wait_for(
            f"Array.from(document.querySelectorAll('#bands input'), (s) => Number(s.value)).join() === '{','.join(['0.5'] * n)}'"
            " && window.meshpyr.idle()",
            "the widget",
        )
        driver.leave_frame()
    finally:
        driver.quit()
