"""A minimal WebDriver client for the browser tests (W3C WebDriver is plain HTTP/JSON, as in
cli/tests/view_support/webdriver.rs): chromedriver with a headless Chromium, scripts, frames,
element screenshots decoded to RGB arrays."""

import base64
import json
import os
import shutil
import socket
import struct
import subprocess
import tempfile
import time
import urllib.error
import urllib.request
import zlib

import numpy as np
import pytest

ELEMENT = "element-6066-11e4-a52e-4f735466cecf"
ARGS = [
    "--headless=new",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--window-size=1280,900",
    "--allow-file-access-from-files",
]


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Driver:
    """chromedriver and one Chromium session; ``quit()`` ends both."""

    def __init__(self, chromium, chromedriver):
        self.port = free_port()
        self.process = subprocess.Popen(
            [chromedriver, f"--port={self.port}"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        self.profile = tempfile.TemporaryDirectory(prefix="meshpyr-chromium-")
        self.session = None
        deadline = time.monotonic() + 30
        while True:
            try:
                if self.call("GET", "/status")["ready"]:
                    break
            except (OSError, urllib.error.URLError):
                pass
            if time.monotonic() > deadline:
                self.quit()
                raise RuntimeError("chromedriver did not start")
            time.sleep(0.1)
        options = {"binary": chromium, "args": ARGS + [f"--user-data-dir={self.profile.name}"]}
        caps = {"capabilities": {"alwaysMatch": {"browserName": "chrome", "goog:chromeOptions": options}}}
        self.session = self.call("POST", "/session", caps)["sessionId"]
        self.call_session("POST", "/timeouts", {"script": 120_000})

    def call(self, method, path, body=None):
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(
            f"http://127.0.0.1:{self.port}{path}", data=data, method=method,
            headers={"Content-Type": "application/json"},
        )
        try:
            with urllib.request.urlopen(request, timeout=180) as answer:
                return json.loads(answer.read())["value"]
        except urllib.error.HTTPError as e:
            raise AssertionError(f"WebDriver {method} {path}: {e.read()[:500]!r}") from None

    def call_session(self, method, path, body=None):
        return self.call(method, f"/session/{self.session}{path}", body)

    def navigate(self, url):
        self.call_session("POST", "/url", {"url": url})

    def script(self, body, *args):
        return self.call_session("POST", "/execute/sync", {"script": body, "args": list(args)})

    def wait_for(self, condition, what="the page"):
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if self.script(f"return !!({condition});"):
                return
            time.sleep(0.05)
        error = self.script("const e = document.getElementById('error'); return e ? e.textContent : null;")
        raise AssertionError(f"timed out waiting for {condition} in {what} (page error: {error})")

    def element(self, selector):
        found = self.call_session("POST", "/element", {"using": "css selector", "value": selector})
        return found[ELEMENT]

    def enter_frame(self, selector):
        self.call_session("POST", "/frame", {"id": {ELEMENT: self.element(selector)}})

    def leave_frame(self):
        self.call_session("POST", "/frame/parent", {})

    def screenshot_png(self, selector):
        """The element as Chromium's PNG bytes."""
        shot = self.call_session("GET", f"/element/{self.element(selector)}/screenshot")
        return base64.b64decode(shot)

    def screenshot(self, selector):
        """The element's pixels, uint8 (height, width, 3)."""
        return decode_png(self.screenshot_png(selector))

    def window_png(self):
        return base64.b64decode(self.call_session("GET", "/screenshot"))

    def quit(self):
        if self.session:
            try:
                self.call("DELETE", f"/session/{self.session}")
            except (OSError, AssertionError):
                pass
        self.process.kill()
        self.process.wait()
        self.profile.cleanup()


def decode_png(data):
    """8-bit RGB or RGBA, non-interlaced PNG (what Chromium writes) as RGB uint8 (h, w, 3)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat = 8, b""
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, chunk = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", chunk)
            assert depth == 8 and colour in (2, 6) and interlace == 0
        elif kind == b"IDAT":
            idat += chunk
        pos += 12 + length
    channels = 3 if colour == 2 else 4
    stride = width * channels
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(height, stride + 1)
    out = np.zeros((height, stride), np.int32)
    previous = np.zeros(stride, np.int32)
    for y in range(height):
        kind, line = raw[y, 0], raw[y, 1:].astype(np.int32)
        row = np.zeros(stride, np.int32)
        if kind == 0:
            row = line
        elif kind == 2:
            row = (line + previous) & 255
        else:
            # Sub, Average and Paeth depend on the pixel to the left: one pixel at a time.
            for x in range(stride):
                a = row[x - channels] if x >= channels else 0
                b = previous[x]
                c = previous[x - channels] if x >= channels else 0
                if kind == 1:
                    p = a
                elif kind == 3:
                    p = (a + b) // 2
                else:
                    pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                    p = a if pa <= pb and pa <= pc else b if pb <= pc else c
                row[x] = (line[x] + p) & 255
        out[y] = row
        previous = row
    return out.reshape(height, width, channels)[:, :, :3].astype(np.uint8)


def driver_or_skip():
    """A Driver, or a skip saying why; with MESHPYR_REQUIRE_BROWSER=1 (CI) a failure instead."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    chromedriver = shutil.which("chromedriver")
    required = os.environ.get("MESHPYR_REQUIRE_BROWSER") == "1"
    if not (chromium and chromedriver):
        why = "no chromium and chromedriver on PATH (Debian packages chromium, chromium-driver)"
        if required:
            pytest.fail(f"{why}, and MESHPYR_REQUIRE_BROWSER=1")
        pytest.skip(why)
    return Driver(chromium, chromedriver)
