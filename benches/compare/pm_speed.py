"""Whole `meshpyr simplify` process against meshoptimizer's simplify call alone, alternated.

usage: python3 pm_speed.py MESHPYR RATIO RUNS MESH.ply [MESH.ply ...]

For each mesh, RUNS times in turn: the whole `MESHPYR -q simplify MESH -o OUT --ratio RATIO`
process (start-up, reading, repair, decimation, writing; wall clock), then
meshoptimizer.simplify on the same mesh already in memory (target_error=1.0, so only the face
target stops it; only the call is timed). Alternating the two in one loop exposes both to the
same machine load. Prints the medians and ranges, the ratio of the medians and the median of the
per-run ratios.
"""
import os
import subprocess
import sys
import tempfile
import time

import meshoptimizer
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plyio import read_ply  # noqa: E402


def main():
    binary, ratio, runs = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
    out_path = os.path.join(tempfile.mkdtemp(prefix="pm_speed"), "out.ply")
    for mesh in sys.argv[4:]:
        pos, tris = read_ply(mesh)
        vp = np.ascontiguousarray(pos, dtype=np.float32)
        idx = np.ascontiguousarray(tris.reshape(-1), dtype=np.uint32)
        ours, mo = [], []
        for _ in range(runs):
            t0 = time.perf_counter()
            subprocess.run([binary, "-q", "simplify", mesh, "-o", out_path, "--ratio", str(ratio)],
                           check=True)
            ours.append(time.perf_counter() - t0)
            out = np.zeros_like(idx)
            t0 = time.perf_counter()
            meshoptimizer.simplify(out, idx, vp, target_index_count=int(len(tris) * ratio) * 3,
                                   target_error=1.0)
            mo.append(time.perf_counter() - t0)
        pairs = [a / b for a, b in zip(ours, mo)]
        print(f"{os.path.basename(mesh)}: {len(tris)} faces; meshpyr process median "
              f"{np.median(ours):.3f} s ({min(ours):.3f}-{max(ours):.3f}), meshoptimizer call "
              f"median {np.median(mo):.3f} s ({min(mo):.3f}-{max(mo):.3f}); ratio of medians "
              f"{np.median(ours) / np.median(mo):.2f}, median per-run ratio {np.median(pairs):.2f}")


if __name__ == "__main__":
    main()
