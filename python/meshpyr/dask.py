"""The hierarchy of a scan built in spatial blocks on a Dask cluster (``dask.distributed``).

:func:`build`, :func:`filter` and :func:`edit` are ``meshpyr build``, ``filter`` and ``edit`` with
``--block-vertices N --block-files DIR``: the same options and the same output bytes, but every
round of block tasks runs on the cluster's workers. This process (the driver) reads the input,
cuts each pass into cells, takes the cost cut from the blocks' histograms and assembles the
hierarchy; the workers decimate the blocks. Tasks read and write files only, in a scratch folder
that every worker must see (a shared file system), and hand back small values (a count, a
histogram), never meshes.

Every task is submitted with ``resources={"MEMORY": bytes}``, the memory it is estimated to
hold at its peak (a Rust heap is invisible to Dask's memory manager), so the workers must be
started with that resource: ``dask worker tcp://HOST:8786 --nworkers 1 --nthreads 1
--memory-limit 3GB --resources MEMORY=3e9``. A worker then never runs more tasks at once than
its memory holds. A task whose worker dies is run again by Dask and writes the same bytes, and
the output does not depend on the number of workers or the order the tasks run in.

From the shell::

    python -m meshpyr.dask filter IN -o OUT --enhance 2000:30000=2 \\
        [--scheduler tcp://HOST:8786 | --workers 2 --memory-limit 3GB] [--block-vertices N]
    python -m meshpyr.dask build IN -o OUT.pyr [...]
    python -m meshpyr.dask edit IN -o OUT --level K --move X,Y,Z:DX,DY,DZ --radius R [...]

with every other option of ``meshpyr build``, ``filter`` and ``edit``. Needs the ``dask`` extra
(``pip install "meshpyr[dask]"``).
"""

import argparse
import os
import shutil
import sys
import tempfile
from pathlib import Path

from . import _meshpyr

#: The Dask resource every task declares: the bytes it is estimated to hold.
RESOURCE = "MEMORY"


def run_task(task):
    """Runs one block task (a dict, as :func:`build` hands them to the workers) in this process
    and returns its small output: None, a count, or a histogram as bytes."""
    return _meshpyr._run_task(task)


def block_vertices_for(memory):
    """The largest block (in vertices) whose decimation is estimated to fit ``memory`` bytes:
    the block size :func:`build` and :func:`filter` take when none is given."""
    return _meshpyr._block_vertices_for(int(memory))


def worker_memory(client):
    """The ``MEMORY`` resource of each worker of ``client``'s cluster, by address. Raises
    ValueError when no worker declares it."""
    try:
        info = client.scheduler_info(n_workers=-1)
    except TypeError:  # distributed before 2025 lists every worker without being asked
        info = client.scheduler_info()
    workers = info["workers"]
    memory = {a: w.get("resources", {}).get(RESOURCE) for a, w in workers.items()}
    memory = {a: m for a, m in memory.items() if m}
    if not memory:
        raise ValueError(
            f"no worker of the cluster declares the resource {RESOURCE}: start the workers "
            f"with --resources {RESOURCE}=BYTES (e.g. dask worker ADDRESS --memory-limit 3GB "
            f"--resources {RESOURCE}=3e9)"
        )
    return memory


class _Rounds:
    """Runs each round of tasks on the cluster: one Dask task per block task, each declaring
    its memory, all gathered before the driver goes on."""

    def __init__(self, client, run):
        self.client = client
        self.run = run

    def __call__(self, tasks):
        largest = max(worker_memory(self.client).values())
        for task in tasks:
            if task["memory"] > largest:
                raise MemoryError(
                    f"a {task['kind']} task is estimated at {task['memory']} bytes, more than "
                    f"the largest worker's {RESOURCE} ({largest:.0f}): use smaller blocks "
                    "(block_vertices) or workers with more memory"
                )
        futures = [
            self.client.submit(
                self.run, task, resources={RESOURCE: task["memory"]}, pure=False
            )
            for task in tasks
        ]
        try:
            return self.client.gather(futures)
        finally:
            self.client.cancel(futures)


def _run(command, input, output, flags, client, block_vertices, scratch, quiet, run):
    """``meshpyr COMMAND INPUT -o OUTPUT FLAGS`` with its block tasks on ``client``."""
    if block_vertices is None:
        block_vertices = block_vertices_for(min(worker_memory(client).values()))
    output = Path(output)
    own_scratch = scratch is None
    if own_scratch:
        folder = output.parent if str(output.parent) else Path(".")
        scratch = tempfile.mkdtemp(prefix=".meshpyr-blocks-", dir=folder)
    args = [command, os.fspath(input), "-o", os.fspath(output), *flags]
    args += ["--block-vertices", str(block_vertices), "--block-files", os.fspath(scratch)]
    if quiet:
        args.insert(0, "--quiet")
    try:
        _meshpyr._run_command(args, _Rounds(client, run))
    finally:
        if own_scratch:
            shutil.rmtree(scratch, ignore_errors=True)


def build(
    input,
    output,
    *,
    client,
    block_vertices=None,
    scratch=None,
    relax=None,
    no_details=False,
    uv_weight=None,
    quiet=True,
    run=run_task,
):
    """``meshpyr build INPUT -o OUTPUT --block-vertices N --block-files SCRATCH`` with every
    block task run on the Dask cluster of ``client``: the same ``.pyr`` bytes.

    ``block_vertices``: the largest block (default: what the smallest worker's ``MEMORY`` holds,
    :func:`block_vertices_for`; give it to get the same bytes on any cluster). ``scratch``: a
    folder every worker sees (default: a temporary folder next to ``output``, removed
    afterwards). ``relax``, ``no_details`` and ``uv_weight`` are ``--relax``, ``--no-details``
    and ``--uv-weight``. ``quiet=False`` prints what the command prints. ``run``: the function the
    workers call with each task dict (default :func:`run_task`; a wrapper may time or log them).

    Raises OSError when a file cannot be read or written, ValueError for bad options,
    MemoryError when a task is estimated above the largest worker's ``MEMORY`` (no worker would
    ever take it), and whatever Dask raises when a task fails for good (its message names the
    file).
    """
    flags = []
    if relax is not None:
        flags += ["--relax", str(relax)]
    if no_details:
        flags.append("--no-details")
    if uv_weight is not None:
        flags += ["--uv-weight", repr(float(uv_weight))]
    _run("build", input, output, flags, client, block_vertices, scratch, quiet, run)


def _level(value, what):
    if isinstance(value, bool) or not isinstance(value, (int, str)):
        raise ValueError(
            f"{what}: a level is an int vertex count or a feature size such as \"0.02u\", got "
            f"{value!r}"
        )
    return str(value)


def _bands(bands, name, arity):
    out = []
    for i, band in enumerate(bands or ()):
        band = tuple(band)
        if len(band) != arity:
            form = "(a, b)" if arity == 2 else "(a, b, gain)"
            raise ValueError(f"{name}[{i}] must be a tuple {form}, got {len(band)} values")
        a, b = (_level(x, f"{name}[{i}]") for x in band[:2])
        out.append(f"{a}:{b}" if arity == 2 else f"{a}:{b}={float(band[2])!r}")
    return out


def filter(
    input,
    output,
    *,
    client,
    lowpass=None,
    stopband=None,
    enhance=None,
    gains=None,
    normal_only=False,
    relax=None,
    block_vertices=None,
    scratch=None,
    quiet=True,
    run=run_task,
):
    """``meshpyr filter INPUT -o OUTPUT --block-vertices N --block-files SCRATCH`` with every
    block task run on the Dask cluster of ``client``: the same output bytes.

    The filter keywords are those of :meth:`meshpyr.Pyramid.filter` (``lowpass=N``,
    ``stopband=[(a, b)]``, ``enhance=[(a, b, g)]``, ``gains=[(a, b, g)]``, ``normal_only``),
    given to the command as ``--lowpass``, ``--stopband``, ``--enhance``, ``--gain`` and
    ``--normal-only``; ``relax`` is ``--relax``. The other keywords are :func:`build`'s.
    """
    flags = _filter_flags(lowpass, stopband, enhance, gains, normal_only, relax)
    _run("filter", input, output, flags, client, block_vertices, scratch, quiet, run)


def _filter_flags(lowpass, stopband, enhance, gains, normal_only, relax):
    """The command's flags for the filter keywords shared by :func:`filter` and :func:`edit`."""
    flags = []
    if lowpass is not None:
        flags += ["--lowpass", _level(lowpass, "lowpass")]
    for flag, values in [
        ("--stopband", _bands(stopband, "stopband", 2)),
        ("--enhance", _bands(enhance, "enhance", 3)),
        ("--gain", _bands(gains, "gains", 3)),
    ]:
        for v in values:
            flags += [flag, v]
    if normal_only:
        flags.append("--normal-only")
    if relax is not None:
        flags += ["--relax", str(relax)]
    return flags


def _vector(value, what):
    values = tuple(value)
    if len(values) != 3 or any(isinstance(x, bool) for x in values):
        raise ValueError(f"{what} must be three numbers (x, y, z), got {value!r}")
    return ",".join(repr(float(x)) for x in values)


def _moves(moves):
    out = []
    for i, move in enumerate(moves):
        move = tuple(move)
        if len(move) != 2:
            raise ValueError(f"moves[{i}] must be a pair (point, offset), got {len(move)} values")
        point, offset = _vector(move[0], f"moves[{i}][0]"), _vector(move[1], f"moves[{i}][1]")
        out += ["--move", f"{point}:{offset}"]
    if not out:
        raise ValueError("moves is empty: an edit needs at least one (point, offset) pair")
    return out


def edit(
    input,
    output,
    level,
    moves,
    radius,
    *,
    client,
    lowpass=None,
    stopband=None,
    enhance=None,
    gains=None,
    normal_only=False,
    relax=None,
    no_details=False,
    block_vertices=None,
    scratch=None,
    quiet=True,
    run=run_task,
):
    """``meshpyr edit INPUT -o OUTPUT --level LEVEL --move ... --radius RADIUS --block-vertices N
    --block-files SCRATCH`` with every block task run on the Dask cluster of ``client``: the same
    output bytes.

    ``level``, ``moves`` (pairs of a point and an offset, each three numbers) and ``radius`` are
    those of :meth:`meshpyr.Pyramid.edit`, given to the command as ``--level``, one ``--move
    X,Y,Z:DX,DY,DZ`` per pair and ``--radius``; the filter keywords are :func:`filter`'s, applied
    with the edit; ``no_details`` is ``--no-details`` (a ``.pyr`` output without details). The
    other keywords are :func:`build`'s.
    """
    if isinstance(level, bool) or not isinstance(level, int):
        raise ValueError(f"level must be an int vertex count, got {level!r}")
    flags = ["--level", str(level), *_moves(moves), "--radius", repr(float(radius))]
    flags += _filter_flags(lowpass, stopband, enhance, gains, normal_only, relax)
    if no_details:
        flags.append("--no-details")
    _run("edit", input, output, flags, client, block_vertices, scratch, quiet, run)


class _OneLineParser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"error: {message} (see python -m meshpyr.dask --help)\n")


def _parser():
    p = _OneLineParser(
        prog="python -m meshpyr.dask",
        description=(
            "meshpyr build, filter and edit with the hierarchy built in blocks on a Dask "
            "cluster: every option of `meshpyr build`, `filter` and `edit` is accepted and "
            "passed on."
        ),
    )
    p.add_argument("command", choices=["build", "filter", "edit"])
    p.add_argument("input", help="input mesh (or .pyr file for filter)")
    p.add_argument("-o", "--output", required=True, help="output file")
    p.add_argument(
        "--scheduler", metavar="ADDRESS", help="a running scheduler, tcp://HOST:8786"
    )
    p.add_argument(
        "--workers", type=int, metavar="N", help="start a local cluster of N worker processes"
    )
    p.add_argument(
        "--memory-limit",
        metavar="SIZE",
        help="with --workers: each worker's memory (3GB; default: the machine's share)",
    )
    p.add_argument(
        "--block-vertices",
        type=int,
        metavar="N",
        help="blocks of at most N vertices (default: what a worker's MEMORY holds)",
    )
    p.add_argument(
        "--block-files",
        metavar="DIR",
        help="scratch folder every worker sees (default: a temporary folder next to the output)",
    )
    return p


def _local_cluster(workers, memory_limit):
    from dask.utils import parse_bytes
    from distributed import LocalCluster
    from distributed.system import MEMORY_LIMIT

    if workers < 1:
        raise ValueError(f"--workers must be at least 1, got {workers}")
    memory = parse_bytes(memory_limit) if memory_limit else MEMORY_LIMIT // workers
    return LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        memory_limit=memory,
        resources={RESOURCE: memory},
        dashboard_address=":0",
    )


def main(argv=None):
    """The command ``python -m meshpyr.dask``; returns the exit code."""
    args, rest = _parser().parse_known_args(argv)
    if (args.scheduler is None) == (args.workers is None):
        print("error: give either --scheduler ADDRESS or --workers N", file=sys.stderr)
        return 2
    cluster = None
    try:
        from distributed import Client

        if args.workers is not None:
            cluster = _local_cluster(args.workers, args.memory_limit)
            client = Client(cluster)
        else:
            client = Client(args.scheduler)
        with client:
            _run(
                args.command,
                args.input,
                args.output,
                rest,
                client,
                args.block_vertices,
                args.block_files,
                False,
                run_task,
            )
    except ImportError as e:
        print(
            f"error: {e}; python -m meshpyr.dask needs the dask extra: "
            "pip install 'meshpyr[dask]'",
            file=sys.stderr,
        )
        return 1
    except (Exception, KeyboardInterrupt) as e:
        message = " ".join(str(e).split()) or type(e).__name__
        print(f"error: {message}", file=sys.stderr)
        return 130 if isinstance(e, KeyboardInterrupt) else 1
    finally:
        if cluster is not None:
            cluster.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
