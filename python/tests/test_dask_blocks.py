"""meshpyr.dask: the block tasks of a partitioned build, filter and edit on LocalClusters give
the command line's bytes (``--block-vertices N --block-files DIR``), on one worker and on two, and when a worker
dies in the middle of a run."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import data

pytest.importorskip("dask.distributed", reason="meshpyr.dask needs dask[distributed]")

import cloudpickle  # noqa: E402  (a dependency of distributed)
from distributed import Client, LocalCluster  # noqa: E402

import meshpyr.dask  # noqa: E402

SCAN = data("elephant_holes.ply")  # 2798 vertices, holes: 8 cells of 400 and several passes
BLOCK = 400
ENHANCE = (40, 1500, 2.0)
ENHANCE_FLAG = "40:1500=2.0"
# An edit of level 500: the elephant's first vertex (read below) pulled up.
EDIT_LEVEL, EDIT_OFFSET = 500, (0.0, 0.05, 0.0)
MEMORY = 1_000_000_000

# The test's own task function runs on the workers: sent by value, not by module name.
cloudpickle.register_pickle_by_value(sys.modules[__name__])


def cluster(workers):
    return LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        memory_limit=MEMORY,
        resources={"MEMORY": MEMORY},
        dashboard_address=":0",
    )


@pytest.fixture(scope="module", params=[1, 2], ids=["1 worker", "2 workers"])
def client(request):
    with cluster(request.param) as c, Client(c) as client:
        yield client


@pytest.fixture(scope="module")
def expected(tmp_path_factory, cli):
    """The command line's .pyr, filtered and edited meshes, built in blocks through files."""
    folder = tmp_path_factory.mktemp("cli")
    pyr, filtered, edited = folder / "scan.pyr", folder / "filtered.ply", folder / "edited.ply"
    blocks = ["--block-vertices", BLOCK, "--block-files", folder]
    cli("build", SCAN, "-o", pyr, *blocks)
    cli("filter", SCAN, "-o", filtered, "--enhance", ENHANCE_FLAG, "--normal-only", *blocks)
    point, radius = edit_point()
    move = ",".join(map(repr, point)) + ":" + ",".join(map(repr, EDIT_OFFSET))
    cli(
        "edit", SCAN, "-o", edited, "--level", EDIT_LEVEL, "--move", move,
        "--radius", repr(radius), "--enhance", ENHANCE_FLAG, *blocks,
    )  # fmt: skip
    return {"build": pyr.read_bytes(), "filter": filtered.read_bytes(), "edit": edited.read_bytes()}


def edit_point():
    """The point an edit grabs (the scan's first vertex) and its radius (a tenth of the
    bounding box's diagonal)."""
    v, _ = meshpyr.read(SCAN)
    return tuple(float(x) for x in v[0]), 0.1 * float(np.linalg.norm(np.ptp(v, axis=0)))


def test_a_build_on_the_cluster_is_the_command_lines_build(client, expected, tmp_path):
    out = tmp_path / "scan.pyr"
    meshpyr.dask.build(SCAN, out, client=client, block_vertices=BLOCK)
    assert out.read_bytes() == expected["build"]
    # The scratch folder next to the output is gone.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scan.pyr"]


def test_a_filter_on_the_cluster_is_the_command_lines_filter(client, expected, tmp_path):
    out = tmp_path / "filtered.ply"
    scratch = tmp_path / "scratch"
    meshpyr.dask.filter(
        SCAN,
        out,
        client=client,
        enhance=[ENHANCE],
        normal_only=True,
        block_vertices=BLOCK,
        scratch=scratch,
    )
    assert out.read_bytes() == expected["filter"]
    assert list(scratch.iterdir()) == []


def test_an_edit_on_the_cluster_is_the_command_lines_edit(client, expected, tmp_path):
    out = tmp_path / "edited.ply"
    point, radius = edit_point()
    meshpyr.dask.edit(
        SCAN,
        out,
        EDIT_LEVEL,
        [(point, EDIT_OFFSET)],
        radius,
        client=client,
        enhance=[ENHANCE],
        block_vertices=BLOCK,
    )
    assert out.read_bytes() == expected["edit"]
    assert out.read_bytes() != expected["filter"]


@pytest.mark.parametrize(
    "moves, message",
    [([], "moves is empty"), ([((0, 0), (0, 0, 1))], r"moves\[0\]\[0\] must be three numbers")],
)
def test_an_edit_without_well_formed_moves_is_refused_before_any_work(tmp_path, moves, message):
    with pytest.raises(ValueError, match=message):
        meshpyr.dask.edit(SCAN, tmp_path / "out.ply", EDIT_LEVEL, moves, 1.0, client=None)
    assert list(tmp_path.iterdir()) == []


def kill_own_worker_once(task, marker):
    """Runs `task`, except that the first collapse task ends its worker's process, as a crash
    would, before it writes anything."""
    if task["kind"] == "collapse" and not os.path.exists(marker):
        open(marker, "w").close()
        os._exit(1)
    return meshpyr.dask.run_task(task)


def test_a_worker_that_dies_in_the_middle_of_a_run_changes_no_byte(expected, tmp_path):
    marker = tmp_path / "killed"

    def run(task):
        return kill_own_worker_once(task, str(marker))

    with cluster(2) as c, Client(c) as client:
        out = tmp_path / "scan.pyr"
        meshpyr.dask.build(SCAN, out, client=client, block_vertices=BLOCK, run=run)
    assert marker.exists()
    assert out.read_bytes() == expected["build"]


def command(*args):
    return subprocess.run(
        [sys.executable, "-m", "meshpyr.dask", *map(str, args)],
        capture_output=True,
        text=True,
        check=False,
    )


def test_the_command_filters_on_a_local_cluster(expected, tmp_path):
    out = tmp_path / "filtered.ply"
    done = command(
        "filter", SCAN, "-o", out, "--enhance", ENHANCE_FLAG, "--normal-only",
        "--workers", 2, "--memory-limit", "1GB", "--block-vertices", BLOCK, "--quiet",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert out.read_bytes() == expected["filter"]


def test_the_command_edits_on_a_local_cluster(expected, tmp_path):
    out = tmp_path / "edited.ply"
    point, radius = edit_point()
    move = ",".join(map(repr, point)) + ":" + ",".join(map(repr, EDIT_OFFSET))
    done = command(
        "edit", SCAN, "-o", out, "--level", EDIT_LEVEL, "--move", move, "--radius", repr(radius),
        "--enhance", ENHANCE_FLAG, "--workers", 1, "--block-vertices", BLOCK, "--quiet",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert out.read_bytes() == expected["edit"]


def test_the_commands_errors_are_one_line(tmp_path):
    missing = tmp_path / "missing.ply"
    done = command("build", missing, "-o", tmp_path / "out.pyr", "--workers", 1)
    assert done.returncode != 0
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("error: "), done.stderr
    assert "missing.ply" in done.stderr
    assert not (tmp_path / "out.pyr").exists()
    done = command("filter", SCAN, "-o", tmp_path / "out.ply", "--enhance", "1:2=3")
    assert done.returncode != 0
    assert done.stderr == "error: give either --scheduler ADDRESS or --workers N\n"


class WorkersWithout:
    """A client whose workers declare no resources."""

    def scheduler_info(self, n_workers=-1):
        return {"workers": {"tcp://a": {"resources": {}}}}


def test_workers_without_the_memory_resource_are_refused():
    with pytest.raises(ValueError, match="--resources MEMORY="):
        meshpyr.dask.worker_memory(WorkersWithout())


def test_a_block_size_is_chosen_from_the_workers_memory():
    small, large = (meshpyr.dask.block_vertices_for(m) for m in (1e8, 3e9))
    assert 16 <= small < large


def test_a_task_larger_than_every_worker_is_refused_before_it_runs(tmp_path):
    """A worker would never accept a task declaring more MEMORY than it holds, so the run
    would wait for ever: it is refused with the task's estimate, and nothing is written."""
    small = 1_000_000  # below any block task's estimate
    out = tmp_path / "scan.pyr"
    with LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=True,
        memory_limit=MEMORY,
        resources={"MEMORY": small},
        dashboard_address=":0",
    ) as c, Client(c) as client:
        with pytest.raises(MemoryError, match="more than the largest worker's MEMORY"):
            meshpyr.dask.build(SCAN, out, client=client, block_vertices=BLOCK, quiet=True)
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []
