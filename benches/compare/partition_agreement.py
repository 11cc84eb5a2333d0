"""Agreement of the partitioned build with the one-process build (issue 47, docs/partitioned.md):
filters a scan once on each path and prints the issue's measures.

    python3 partition_agreement.py SCAN.ply --block-vertices 50000 [--enhance A:B=G]
        [--meshpyr target/release/meshpyr] [--runs 3] [--keep DIR]

- p99 of per-vertex |partitioned - one process| over p99 of |one process - input| (bound 0.25);
- max |partitioned - input| over max |one process - input| (bound 1.5: no spikes at borders);
- wall time of the partitioned run over the one-process run, medians of --runs runs each,
  alternated, on the same cores (bound 1.5).

The default filter is the README's scan enhancement, `--enhance V/32:V/2=2` with V the input's
vertex count. Distances are in model units and also given relative to the bounding-box diagonal.
Needs numpy; the runs use GNU time (/usr/bin/time) for wall time and peak resident memory.
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from plyio import read_ply  # noqa: E402

REPO = os.path.dirname(os.path.dirname(HERE))


def run(cmd):
    """Runs `cmd` under GNU time; returns (wall seconds, peak resident KB)."""
    out = subprocess.run(
        ["/usr/bin/time", "-f", "%e %M"] + cmd, capture_output=True, text=True, check=True
    )
    wall, kb = out.stderr.strip().splitlines()[-1].split()
    return float(wall), int(kb)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scan")
    ap.add_argument("--block-vertices", type=int, default=50000)
    ap.add_argument("--enhance", default=None)
    ap.add_argument("--meshpyr", default=os.path.join(REPO, "target", "release", "meshpyr"))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--keep", default=None, help="folder for the filtered meshes")
    a = ap.parse_args()

    pos, _ = read_ply(a.scan)
    n = len(pos)
    enhance = a.enhance or f"{n // 32}:{n // 2}=2"
    folder = a.keep or tempfile.mkdtemp(prefix="partition_agreement_")
    os.makedirs(folder, exist_ok=True)
    whole_out = os.path.join(folder, "one_process.ply")
    parts_out = os.path.join(folder, "partitioned.ply")
    base = [a.meshpyr, "filter", a.scan, "--enhance", enhance, "--quiet"]
    whole_cmd = base + ["-o", whole_out]
    parts_cmd = base + ["-o", parts_out, "--block-vertices", str(a.block_vertices)]
    times = {"one": [], "parts": []}
    for _ in range(a.runs):
        times["one"].append(run(whole_cmd))
        times["parts"].append(run(parts_cmd))

    whole, _ = read_ply(whole_out)
    parts, _ = read_ply(parts_out)
    diag = float(np.linalg.norm(pos.max(axis=0) - pos.min(axis=0)))
    apart = np.linalg.norm(parts - whole, axis=1)
    moved = np.linalg.norm(whole - pos, axis=1)
    parts_moved = np.linalg.norm(parts - pos, axis=1)
    p99_apart, p99_moved = np.percentile(apart, 99), np.percentile(moved, 99)
    max_parts, max_whole = parts_moved.max(), moved.max()
    t_one = statistics.median(t for t, _ in times["one"])
    t_parts = statistics.median(t for t, _ in times["parts"])
    m_one = max(m for _, m in times["one"])
    m_parts = max(m for _, m in times["parts"])

    print(f"scan {a.scan}: {n} vertices, diagonal {diag:.6g}, filter --enhance {enhance}")
    print(f"blocks of at most {a.block_vertices} vertices; {a.runs} runs each, alternated")
    print(
        f"p99 |partitioned - one process| = {p99_apart:.4g} ({p99_apart / diag:.3g} diag); "
        f"p99 |one process - input| = {p99_moved:.4g}; ratio {p99_apart / p99_moved:.3f} (bound 0.25)"
    )
    print(
        f"max |partitioned - input| = {max_parts:.4g}; max |one process - input| = {max_whole:.4g}; "
        f"ratio {max_parts / max_whole:.3f} (bound 1.5)"
    )
    print(
        f"wall: one process {t_one:.2f} s, partitioned {t_parts:.2f} s (medians); "
        f"ratio {t_parts / t_one:.3f} (bound 1.5)"
    )
    print(
        f"peak resident: one process {m_one / 1024:.0f} MB ({m_one * 1024 / n:.0f} B/vertex), "
        f"partitioned {m_parts / 1024:.0f} MB ({m_parts * 1024 / n:.0f} B/vertex)"
    )
    np.save(os.path.join(folder, "apart.npy"), apart)


if __name__ == "__main__":
    main()
