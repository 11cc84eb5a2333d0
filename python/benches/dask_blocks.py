"""Times `meshpyr.dask.build` (or `filter`) on a local cluster and reports the peak resident
memory of the driver and of every worker, and each task's time and declared memory.

    python python/benches/dask_blocks.py SCAN OUT.pyr --workers 2 --memory-limit 3GB \\
        --block-vertices 50000 [--filter --enhance A:B=G] [--tasks tasks.tsv]

The driver's peak is this process's (it also hosts the scheduler); a worker's is its own
process's `ru_maxrss`, asked at the end. `--tasks` writes one line per task run: kind, seconds,
declared bytes, the worker's resident bytes before and its peak after.
"""

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import meshpyr.dask
from distributed import Client, LocalCluster


def timed(task, log_dir):
    """Runs `task` and appends its kind, time, declared memory and the worker's memory to the
    worker's own log file."""
    import psutil

    rss = psutil.Process().memory_info().rss
    start = time.perf_counter()
    out = meshpyr.dask.run_task(task)
    took = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    with open(os.path.join(log_dir, f"tasks-{os.getpid()}.tsv"), "a") as f:
        f.write(f"{task['kind']}\t{took:.6f}\t{task['memory']}\t{rss}\t{peak}\n")
    return out


def peak_rss_kb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def main():
    p = argparse.ArgumentParser()
    p.add_argument("input")
    p.add_argument("output")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--memory-limit", default="3GB")
    p.add_argument("--block-vertices", type=int, default=50000)
    p.add_argument("--filter", action="store_true")
    p.add_argument("--enhance", default="2000:30000=2")
    p.add_argument("--tasks", help="where to write the per-task lines")
    a = p.parse_args()
    from dask.utils import parse_bytes

    memory = parse_bytes(a.memory_limit)
    log_dir = tempfile.mkdtemp(prefix="meshpyr-dask-bench-")
    with LocalCluster(
        n_workers=a.workers,
        threads_per_worker=1,
        memory_limit=memory,
        resources={"MEMORY": memory},
        dashboard_address=":0",
    ) as cluster, Client(cluster) as client:
        client.run(lambda: None)  # workers up
        start = time.perf_counter()

        def run(task):
            return timed(task, log_dir)

        if a.filter:
            lo, rest = a.enhance.split(":")
            hi, gain = rest.split("=")
            meshpyr.dask.filter(
                a.input, a.output, client=client, block_vertices=a.block_vertices,
                enhance=[(int(lo), int(hi), float(gain))], run=run,
            )  # fmt: skip
        else:
            meshpyr.dask.build(
                a.input, a.output, client=client, block_vertices=a.block_vertices, run=run
            )
        wall = time.perf_counter() - start
        workers = client.run(peak_rss_kb)
    print(f"wall {wall:.2f} s; driver peak {peak_rss_kb()} KB")
    for address, kb in sorted(workers.items()):
        print(f"worker {address}: peak {kb} KB")
    lines = []
    for f in sorted(Path(log_dir).iterdir()):
        lines += f.read_text().splitlines()
    by_kind = {}
    for line in lines:
        kind, took, declared, _, _ = line.split("\t")
        n, total, longest, most = by_kind.get(kind, (0, 0.0, 0.0, 0))
        by_kind[kind] = (n + 1, total + float(took), max(longest, float(took)), max(most, int(declared)))
    print("kind           tasks   total s  longest s  largest declared MB")
    for kind, (n, total, longest, most) in sorted(by_kind.items()):
        print(f"{kind:<14} {n:>5} {total:>9.2f} {longest:>10.3f} {most / 1e6:>12.1f}")
    if a.tasks:
        Path(a.tasks).write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
