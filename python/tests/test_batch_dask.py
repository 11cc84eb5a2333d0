"""examples/batch_dask.py on a LocalCluster with two worker processes gives the CLI's bits."""

import importlib.util

import numpy as np
import pytest
from conftest import REPO, assert_same_bits, data

import meshpyr

pytest.importorskip("dask.distributed", reason="the Dask example needs dask[distributed]")


def load_example():
    spec = importlib.util.spec_from_file_location("batch_dask", REPO / "examples" / "batch_dask.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture()
def scans(tmp_path):
    """A folder of three bundled meshes with double positions, so the CLI reads the very
    float64 values the workers get."""
    folder = tmp_path / "scans"
    folder.mkdir()
    for name in ["cross.ply", "tripod.ply", "sphere_highval.ply"]:
        meshpyr.write(folder / name, *meshpyr.read(data(name)))
    return folder


def test_the_dask_example_filters_a_folder_like_the_cli(cli, scans, tmp_path, capsys):
    example = load_example()
    out = tmp_path / "out"
    flags = ["--stopband", "10:500", "--enhance", "5:30=1.5", "--normal-only"]
    assert example.main([str(scans), str(out), *flags, "--local-workers", "2"]) == 0
    printed = capsys.readouterr().out.split()
    assert len(printed) == 3
    for source in sorted(scans.iterdir()):
        expected = tmp_path / f"cli-{source.name}"
        cli("filter", source, "-o", expected, *flags)
        ours = meshpyr.read(out / source.name)
        theirs = meshpyr.read(expected)
        assert_same_bits(ours[0], theirs[0])
        assert_same_bits(ours[1], theirs[1])


def test_the_dask_example_writes_pyr_files_that_hold_the_inputs(scans, tmp_path):
    example = load_example()
    out = tmp_path / "pyr"
    assert example.main([str(scans), str(out), "--pyr"]) == 0
    for source in sorted(scans.iterdir()):
        v, f = meshpyr.read(source)
        pyramid = meshpyr.Pyramid.load(out / (source.stem + ".pyr"))
        assert_same_bits(pyramid.vertices, v)
        assert_same_bits(pyramid.faces, f)
        # From the stored details: within their bound of the mesh's filter.
        diagonal = np.linalg.norm(v.max(axis=0) - v.min(axis=0))
        off = np.max(np.abs(pyramid.filter(lowpass=8) - meshpyr.Pyramid(v, f).filter(lowpass=8)))
        assert off < 1e-9 * diagonal
