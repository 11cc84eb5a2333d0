"""The task graph of a partitioned build, measured task by task: its total work, its critical
path, and what they extrapolate to (docs/partitioned.md, "Task graph and a billion triangles").

    RAYON_NUM_THREADS=1 python python/benches/task_graph.py SCAN --block-vertices N \\
        [--scratch DIR] [--tasks tasks.tsv] [--scale VERTICES --workers W]

Runs ``meshpyr build SCAN --no-details --block-vertices N --block-files DIR`` with its rounds
handed to this process, which runs each round's tasks one after the other and times each (set
``RAYON_NUM_THREADS=1`` so that a task's time is one core's). The driver's time is what passes
between rounds (the cuts, the cost selection's sums, the assembly) and before the first and
after the last round (reading the input, the working mesh, the first pieces, the hierarchy's
assembly and the `.pyr`).

- total work = every task's time + the driver's;
- critical path = per round its slowest task, summed, + the driver's time (with enough workers
  every task of a round runs at once, and the driver waits for the slowest);
- with W workers, a round of tasks t_1 >= t_2 >= ... takes at least max(t_1, sum / W): printed
  as the time on W workers (the driver's time added as it is, on one core).

``--scale V`` extrapolates to a scan of V vertices split into blocks of N * V / (this scan's
vertices): the same ratio of scan to block, so the same passes and the same number of tasks per
round, each task on a block that many times larger and the driver's whole-mesh work that many
times longer (both about linear in their size; what the driver holds is in docs/partitioned.md,
"Running the passes through files"). Measure with the block size that gives the target's ratio
(for 500M vertices in blocks of 1M, a 1.9M-vertex scan in blocks of 3,800).
"""

import argparse
import os
import statistics
import sys
import tempfile
import time
from collections import Counter, defaultdict

from meshpyr import _meshpyr


class TimedRounds:
    """A round runner that runs tasks in this process, in order, and keeps their times."""

    def __init__(self):
        self.rounds = []  # per round: [(kind, seconds, declared memory)]
        self.driver = 0.0
        self.before = None  # the driver's time before the first round
        self.last = time.perf_counter()

    def __call__(self, tasks):
        start = time.perf_counter()
        self.driver += start - self.last
        if self.before is None:
            self.before = self.driver
        done, outputs = [], []
        for task in tasks:
            t = time.perf_counter()
            outputs.append(_meshpyr._run_task(task))
            done.append((task["kind"], time.perf_counter() - t, task["memory"]))
        self.rounds.append(done)
        self.last = time.perf_counter()
        return outputs

    def finish(self):
        self.after = time.perf_counter() - self.last
        self.driver += self.after


def on_workers(tasks, workers):
    """A lower bound of a round's time on `workers` workers: its slowest task, or its work spread."""
    times = [t for _, t, _ in tasks]
    return max(max(times), sum(times) / workers)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("input")
    p.add_argument("--block-vertices", type=int, required=True)
    p.add_argument("--scratch", help="the task files' folder (default: a temporary one)")
    p.add_argument("--tasks", help="write one line per task: round, kind, seconds, declared bytes")
    p.add_argument("--vertices", type=int, help="the scan's vertex count, for --scale")
    p.add_argument("--scale", type=float, help="extrapolate to a scan of this many vertices")
    p.add_argument("--workers", type=int, default=64)
    a = p.parse_args()

    scratch = a.scratch or tempfile.mkdtemp(prefix="meshpyr-task-graph-")
    out = os.path.join(scratch, "out.pyr")
    args = ["--quiet", "build", a.input, "-o", out, "--no-details"]
    args += ["--block-vertices", str(a.block_vertices), "--block-files", scratch]
    rounds = TimedRounds()
    wall = time.perf_counter()
    _meshpyr._run_command(args, rounds)
    rounds.finish()
    wall = time.perf_counter() - wall
    os.remove(out)

    tasks = [t for r in rounds.rounds for t in r]
    work = sum(t for _, t, _ in tasks) + rounds.driver
    critical = sum(max(t for _, t, _ in r) for r in rounds.rounds if r) + rounds.driver
    kinds = Counter(k for k, _, _ in tasks)
    per_kind = defaultdict(float)
    for k, t, _ in tasks:
        per_kind[k] += t
    print(f"{a.input}: blocks of {a.block_vertices}, wall {wall:.1f} s, {len(rounds.rounds)} rounds, "
          f"{len(tasks)} tasks, {kinds['collapse'] + kinds['finish']} decimation tasks")
    between = rounds.driver - rounds.before - rounds.after
    print(f"driver {rounds.driver:.1f} s (before the first round {rounds.before:.1f}, between rounds "
          f"{between:.1f}, after the last {rounds.after:.1f}); tasks {work - rounds.driver:.1f} s; total work {work:.1f} s; "
          f"critical path {critical:.1f} s")
    for k in sorted(per_kind, key=per_kind.get, reverse=True):
        times = [t for kk, t, _ in tasks if kk == k]
        print(f"  {k:16s} {kinds[k]:5d} tasks {per_kind[k]:8.2f} s  median {statistics.median(times):.3f} "
              f"max {max(times):.3f} s  largest declared {max(m for kk, _, m in tasks if kk == k) / 1e6:.0f} MB")
    waves = sum(on_workers(r, a.workers) for r in rounds.rounds if r) + rounds.driver
    print(f"on {a.workers} workers (lower bound): {waves:.1f} s")
    if a.tasks:
        with open(a.tasks, "w") as f:
            for i, r in enumerate(rounds.rounds):
                for k, t, m in r:
                    f.write(f"{i}\t{k}\t{t:.6f}\t{m}\n")
    if a.scale:
        if not a.vertices:
            sys.exit("--scale needs --vertices (this scan's vertex count)")
        s = a.scale / a.vertices
        spread = sum(on_workers([(k, t * s, m) for k, t, m in r], a.workers) for r in rounds.rounds if r)
        print(f"extrapolated to {a.scale:.3g} vertices in blocks of {a.block_vertices * s:.3g}: "
              f"total work {work * s / 3600:.1f} core-hours, critical path {critical * s / 3600:.2f} h; "
              f"on {a.workers} workers at least {(spread + rounds.driver * s) / 3600:.2f} h, of which "
              f"the driver {rounds.driver * s / 3600:.2f} h")

if __name__ == "__main__":
    main()
