"""Baseline: meshoptimizer's simplify on a PLY mesh, timing only the simplify call.

usage: python3 meshopt_simplify.py IN.ply OUT.ply RATIO [REPEATS=5]
Prints the median wall time of meshoptimizer.simplify (target_error=1.0 so that only the
face target stops it) and writes the result (original vertex positions, unused ones dropped).
"""
import sys
import time
import numpy as np
import meshoptimizer
from plyio import read_ply, write_ply


def simplify(pos, tris, target_index_count, repeats=5, target_error=1.0):
    """meshoptimizer.simplify on (pos, tris), `repeats` times; only the call is timed.
    Returns (positions, triangles) of the result (unused vertices dropped) and the wall and
    process-CPU seconds of each call."""
    vp = np.ascontiguousarray(pos, dtype=np.float32)
    idx = np.ascontiguousarray(np.asarray(tris).reshape(-1), dtype=np.uint32)
    times, cpu = [], []
    for _ in range(repeats):
        out = np.zeros_like(idx)
        t0, c0 = time.perf_counter(), time.process_time()
        n = meshoptimizer.simplify(out, idx, vp, target_index_count=target_index_count,
                                   target_error=target_error)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    res = out[:n].reshape(-1, 3).astype(np.int64)
    used = np.unique(res)
    remap = np.full(len(pos), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return pos[used], remap[res], times, cpu


def main():
    src, dst, ratio = sys.argv[1], sys.argv[2], float(sys.argv[3])
    repeats = int(sys.argv[4]) if len(sys.argv) > 4 else 5
    pos, tris = read_ply(src)
    target = int(len(tris) * ratio) * 3
    out_pos, res, times, cpu = simplify(pos, tris, target, repeats)
    write_ply(dst, out_pos, res)
    print(f"meshoptimizer.simplify: {len(tris)} -> {len(res)} triangles, "
          f"median wall {np.median(times) * 1000:.1f} ms, cpu {np.median(cpu) * 1000:.1f} ms over {repeats} (wall: "
          + ", ".join(f"{t * 1000:.0f}" for t in times) + ")")


if __name__ == "__main__":
    main()
