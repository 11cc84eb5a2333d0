"""Times the Python calls on a mesh (default: the bundled bunny) against the same work in
the command line, to show what the bindings add: median and minimum of N runs.

    python3 python/benches/timings.py [MESH] [N] [--cli target/release/meshpyr]
"""

import argparse
import pickle
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import meshpyr

REPO = Path(__file__).resolve().parents[2]


def timed(label, call, runs):
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - start)
    print(f"{label:<34} min {min(times) * 1e3:8.1f} ms   median {statistics.median(times) * 1e3:8.1f} ms")
    return result


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("mesh", nargs="?", default=str(REPO / "tests" / "data" / "bunny.ply"))
    parser.add_argument("runs", nargs="?", type=int, default=5)
    parser.add_argument("--cli", default=str(REPO / "target" / "release" / "meshpyr"))
    args = parser.parse_args()
    v, f = timed("read", lambda: meshpyr.read(args.mesh), args.runs)
    print(f"{args.mesh}: {len(v)} vertices, {len(f)} triangles")
    pyramid = timed("Pyramid(V, F)", lambda: meshpyr.Pyramid(v, f), args.runs)
    timed("filter(lowpass=1000)", lambda: pyramid.filter(lowpass=1000), args.runs)
    blob = timed("to_bytes()", pyramid.to_bytes, args.runs)
    timed("from_bytes()", lambda: meshpyr.Pyramid.from_bytes(blob), args.runs)
    timed("pickle round trip", lambda: pickle.loads(pickle.dumps(pyramid)), args.runs)
    timed("simplify(ratio=0.1)", lambda: meshpyr.simplify(v, f, ratio=0.1), args.runs)
    if Path(args.cli).is_file():
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "out.ply"
            command = [args.cli, "--quiet", "filter", args.mesh, "-o", str(out), "--lowpass", "1000"]
            timed("CLI: meshpyr filter --lowpass 1000", lambda: subprocess.run(command, check=True), args.runs)


if __name__ == "__main__":
    main()
