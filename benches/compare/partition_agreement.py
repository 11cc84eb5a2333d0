"""Agreement of the partitioned build with the one-process build (issue 47, docs/partitioned.md):
filters a scan once on each path and prints the issue's measures.

    python3 partition_agreement.py SCAN.ply --block-vertices 50000 [--enhance A:B=G]
        [--meshpyr target/release/meshpyr] [--runs 3] [--keep DIR] [--near-borders]

- p99 of per-vertex |partitioned - one process| over p99 of |one process - input| (bound 0.25);
- max |partitioned - input| over max |one process - input| (bound 1.5: no spikes at borders);
- wall time of the partitioned run over the one-process run, medians of --runs runs each,
  alternated, on the same cores (bound 1.5).

- with --near-borders: the same p99 ratio for the vertices at each ring distance from the
  borders of the build's first pass (its k-d cells along the model's axes, as
  src/pm/partition/cells.rs cuts them), to see whether the differences sit at the borders,
  and the p99 and largest displacement |partitioned - input| at each distance against the
  one-process filter's at the same vertices (a seam or spike at the borders shows there).

- with --baseline OTHER_MESHPYR: the partitioned run also with that binary (say main's, before
  a change to the partitioned analysis), once, and the same two ratios for it, with p99 and max
  of |partitioned - baseline partitioned| over p99 |one process - input|.

The default filter is the README's scan enhancement, `--enhance V/32:V/2=2` with V the input's
vertex count. Distances are in model units and also given relative to the bounding-box diagonal.
Needs numpy (and scipy for --near-borders); the runs use GNU time (/usr/bin/time) for wall time and peak resident memory.
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
    ap.add_argument("--near-borders", action="store_true")
    ap.add_argument("--baseline", default=None, help="another meshpyr binary's partitioned run")
    a = ap.parse_args()

    pos, tris = read_ply(a.scan)
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
    base_out = os.path.join(folder, "baseline_partitioned.ply")
    if a.baseline:
        run([a.baseline] + base[1:] + ["-o", base_out, "--block-vertices", str(a.block_vertices)])

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
    if a.baseline:
        other, _ = read_ply(base_out)
        o_apart = np.linalg.norm(other - whole, axis=1)
        o_moved = np.linalg.norm(other - pos, axis=1)
        change = np.linalg.norm(parts - other, axis=1)
        print(
            f"baseline {a.baseline}: p99 ratio {np.percentile(o_apart, 99) / p99_moved:.3f}, "
            f"max ratio {o_moved.max() / max_whole:.3f}; |partitioned - baseline partitioned|: "
            f"p99 {np.percentile(change, 99) / p99_moved:.3f}, max {change.max() / p99_moved:.3f} "
            f"(of p99 |one process - input|)"
        )
    if a.near_borders:
        by_rings(pos, tris, a.block_vertices, apart, p99_moved, parts_moved, moved)


def first_pass_cells(pos, tris, block):
    """Each vertex's cell in the first pass (-1 if it has no face), as cells.rs cuts them."""
    cell = np.full(len(pos), -1)
    vertices = np.unique(tris)
    depth = 0
    while -(-len(vertices) // (1 << depth)) > block:
        depth += 1

    def cut(part, depth, first):
        if depth == 0 or len(part) < 2:
            cell[part] = first
            return
        p = pos[part]
        axis = int(np.argmax(p.max(axis=0) - p.min(axis=0)))
        part = part[np.lexsort((part, p[:, axis]))]
        mid = len(part) // 2
        cut(part[:mid], depth - 1, first)
        cut(part[mid:], depth - 1, first + (1 << (depth - 1)))

    cut(vertices, depth, 0)
    return cell


def by_rings(pos, tris, block, apart, p99_moved, parts_moved, moved):
    """Prints the p99 ratio, and the displacements of both filters, by ring distance to the
    first pass's borders."""
    import scipy.sparse as sparse
    from scipy.sparse.csgraph import dijkstra

    cell = first_pass_cells(pos, tris, block)[tris]
    across = ~((cell[:, 0] == cell[:, 1]) & (cell[:, 1] == cell[:, 2]))
    border = np.unique(tris[across])
    edges = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    n = len(pos)
    graph = sparse.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    graph = graph.tocsr()
    rings = dijkstra(graph + graph.T, unweighted=True, indices=border, min_only=True, limit=64)
    print(f"first pass: {len(border)} border vertices; p99 |partitioned - one process| over")
    print("p99 |one process - input| by ring distance to them, and the displacement")
    print("|filtered - input| there, partitioned / one process (p99 and max, in p99 |one process - input|):")
    for lo, hi in [(0, 1), (1, 3), (3, 8), (8, 16), (16, 32), (32, 64), (64, np.inf)]:
        near = (rings >= lo) & (rings < hi)
        if near.sum() >= 100:
            ratio = np.percentile(apart[near], 99) / p99_moved
            p, w = parts_moved[near] / p99_moved, moved[near] / p99_moved
            print(
                f"  rings {lo}..{hi}: {near.sum()} vertices, ratio {ratio:.3f}; displacement "
                f"p99 {np.percentile(p, 99):.3f} / {np.percentile(w, 99):.3f}, "
                f"max {p.max():.3f} / {w.max():.3f}"
            )


if __name__ == "__main__":
    main()
