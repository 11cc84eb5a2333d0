#!/usr/bin/env python3
"""`meshpyr view` on a large scan, server side: time to `serving`, to each picture of the
opening (ready to draw) and to the editor, then to the first preview,
slider-to-positions-ready latency per octave (preview and the old exact path), and how far each
preview lies from the exact result at the shown vertices (worst and 99th percentile, in % of
the bounding-box diagonal), per octave and gain.

    python3 benches/compare/view_scale.py MESHPYR SCAN [--budget N] [--gains 0,2,3] [--exact-path]

Stage times are followed by the server's CPU-seconds so far (all threads), which say more
than the wall clock on a loaded machine.

MESHPYR is the binary (target/release/meshpyr). Latency is measured as a page measures it up to
"positions ready": from sending the request to having the f32 positions (draw excluded; the
browser test measures the draw). The exact comparison waits for the server's background
synthesis of each state.
"""

import argparse
import json
import os
import re
import statistics
import struct
import subprocess
import sys
import time
import urllib.error
import urllib.request


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("meshpyr")
    ap.add_argument("scan")
    ap.add_argument("--budget", type=int, default=None)
    ap.add_argument("--gains", default="0,2,3")
    ap.add_argument("--repeat", type=int, default=3, help="latency samples per octave")
    ap.add_argument("--exact-path", action="store_true", help="also time /api/filter")
    ap.add_argument("--no-distance", action="store_true")
    args = ap.parse_args()

    cmd = [args.meshpyr, "view", args.scan, "--no-browser", "-q"]
    if args.budget:
        cmd += ["--budget", str(args.budget)]
    t0 = time.monotonic()
    server = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
    try:
        line = server.stdout.readline()
        serving = time.monotonic() - t0
        m = re.search(r"http://127\.0\.0\.1:(\d+)/\?token=(\w+)", line)
        if not m:
            sys.exit(f"no address in {line!r}")
        port, token = m.group(1), m.group(2)
        vertices = run(args, port, token, serving, t0, server.pid)
        print_peak_memory(server.pid, vertices)
    finally:
        server.terminate()
        server.wait()


def call(port, token, method, path, body=None):
    req = urllib.request.Request(
        f"http://127.0.0.1:{port}{path}",
        data=None if body is None else json.dumps(body).encode(),
        method=method,
        headers={"X-Meshpyr-Token": token, "Content-Type": "application/json"},
    )
    with urllib.request.urlopen(req, timeout=3600) as r:
        return r.read(), dict(r.headers)


def f32s(data):
    n = len(data) // 4
    v = struct.unpack(f"<{n}f", data)
    return [v[i : i + 3] for i in range(0, n, 3)]


def print_peak_memory(pid, vertices):
    """The server's peak resident size so far (Linux), whole and per input vertex."""
    try:
        with open(f"/proc/{pid}/status") as f:
            kb = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))
    except (OSError, StopIteration):
        return
    print(f"server peak resident size: {kb / 1e6:.2f} GB = {kb * 1e3 / vertices:.0f} B/vertex")


def cpu_seconds(pid):
    """User plus system CPU time of process `pid` so far, all threads (Linux; `None` elsewhere)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return None


def stamp(t0, pid):
    """Seconds since the command started, and the server's CPU-seconds (when known)."""
    cpu = cpu_seconds(pid)
    wall = f"{time.monotonic() - t0:.1f} s"
    return wall if cpu is None else f"{wall} ({cpu:.1f} CPU-s)"


def wait_opening(port, token, t0, pid):
    """Follows the opening: when each picture was ready to draw (fetched), when the editor
    was, and when the whole pyramid was in (a staged `.pyr` file's layout recorded after the
    editor is ready); times from the command's start, with the server's CPU-seconds."""
    shown = 0
    while True:
        status = json.loads(call(port, token, "GET", "/api/status")[0])
        opening = status.get("opening")
        if opening is None:
            print(f"editor ready after {stamp(t0, pid)}; load {os.getloadavg()[0]:.1f}")
            while not status.get("layout", {"whole": True})["whole"]:
                if status["layout"].get("error"):
                    sys.exit(f"the whole pyramid failed: {status['layout']['error']}")
                time.sleep(0.2)
                status = json.loads(call(port, token, "GET", "/api/status")[0])
            print(f"whole pyramid in after {stamp(t0, pid)}; load {os.getloadavg()[0]:.1f}")
            return
        if opening["picture"] != shown:
            try:
                data, headers = call(port, token, "GET", "/api/opening")
            except urllib.error.HTTPError:
                continue  # opened meanwhile
            shown = int(headers["X-Meshpyr-Picture"])
            nt = struct.unpack("<I", data[4:8])[0]
            print(f"picture {shown} ready after {stamp(t0, pid)}: {opening['what']} "
                  f"({nt} triangles, {len(data) / 1e6:.1f} MB); stage {opening['stage']}")
        time.sleep(0.05)


def run(args, port, token, serving, t0, pid):
    wait_opening(port, token, t0, pid)
    info = json.loads(call(port, token, "GET", "/api/info")[0])
    disp = info["display"]
    octaves = info["octaves"]
    diag = info["diagonal"]
    print(f"{info['vertices']} vertices, {info['triangles']} triangles; serving after {serving:.1f} s")
    print(f"display: {disp}")
    if not disp["lod"]:
        sys.exit("the scan is within the budget: nothing to preview")
    unit = [1.0] * len(octaves)
    t = time.monotonic()
    call(port, token, "GET", "/api/display")
    data, _ = call(port, token, "POST", "/api/preview", {"gains": unit})
    first = time.monotonic() - t0
    print(f"first picture's data (display + preview) {1e3 * (time.monotonic() - t):.0f} ms;"
          f" {first:.1f} s after start")
    wait_octaves(port, token)
    print(f"fine octaves measured {time.monotonic() - t0:.1f} s after start")

    print("\noctave  levels              preview ms (median; server synthesis + combine)   exact /api/filter ms")
    classes = {}
    for b, o in enumerate(octaves):
        ms, parts = [], []
        for k in range(args.repeat):
            gains = unit.copy()
            gains[b] = 1.5 + 0.25 * k
            t = time.monotonic()
            data, headers = call(port, token, "POST", "/api/preview", {"gains": gains})
            ms.append(1e3 * (time.monotonic() - t))
            parts.append(headers.get("Server-Timing", ""))
        exact_ms = ""
        if args.exact_path:
            t = time.monotonic()
            call(port, token, "POST", "/api/filter", {"gains": gains})
            exact_ms = f"{1e3 * (time.monotonic() - t):.0f}"
        med = statistics.median(ms)
        classes.setdefault(octave_class(b, len(octaves)), []).extend(ms)
        print(f"{b:>6}  {o['from']:>8}..{o['to']:<8}  {med:8.1f}   {parts[-1]:<55} {exact_ms}")
    for c, v in classes.items():
        print(f"{c}: median {statistics.median(v):.1f} ms over {len(v)} moves")
    allms = [x for v in classes.values() for x in v]
    print(f"all octaves: median {statistics.median(allms):.1f} ms, max {max(allms):.1f} ms")
    call(port, token, "POST", "/api/preview", {"gains": unit})

    if args.no_distance:
        return info["vertices"]
    print("\npreview to exact at the shown vertices, % of the diagonal (worst, 99th percentile)")
    gain_list = [float(g) for g in args.gains.split(",")]
    print("octave  levels              " + "".join(f"   gain {g:<14}" for g in gain_list))
    for b, o in enumerate(octaves):
        row = []
        for g in gain_list:
            gains = unit.copy()
            gains[b] = g
            data, headers = call(port, token, "POST", "/api/preview", {"gains": gains})
            version = int(headers["X-Meshpyr-Version"])
            preview = f32s(data)
            exact = f32s(wait_exact(port, token, version))
            d = sorted(
                ((p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 + (p[2] - q[2]) ** 2) ** 0.5
                for p, q in zip(preview, exact)
            )
            row.append(f"{100 * d[-1] / diag:8.4f} {100 * d[int(0.99 * (len(d) - 1))] / diag:8.4f}  ")
        print(f"{b:>6}  {o['from']:>8}..{o['to']:<8}  " + "".join(row), flush=True)
    return info["vertices"]


def octave_class(b, n):
    return ["coarse", "middle", "fine"][min(2, 3 * b // n)]


def wait_octaves(port, token):
    while True:
        s = json.loads(call(port, token, "GET", "/api/status")[0])
        if s["octaves"]["measured"] == s["octaves"]["total"]:
            return
        time.sleep(0.2)


def wait_exact(port, token, version):
    while True:
        s = json.loads(call(port, token, "GET", "/api/status")[0])
        if s["exact"] == version:
            return call(port, token, "GET", f"/api/exact?version={version}")[0]
        time.sleep(0.05)


if __name__ == "__main__":
    main()
