"""The bindings give the very bits the command line writes, on the bundled meshes."""

import json

import numpy as np
import pytest
from conftest import assert_same_bits, data

import meshpyr

FILTERS = [
    ({"lowpass": 200}, ["--lowpass", "200"]),
    ({"stopband": [(100, 400)]}, ["--stopband", "100:400"]),
    ({"enhance": [(100, 600, 2.0)]}, ["--enhance", "100:600=2"]),
    (
        {"lowpass": 700, "gains": [(50, 300, 1.5), (200, 500, 0.5)], "normal_only": True},
        ["--lowpass", "700", "--gain", "50:300=1.5", "--gain", "200:500=0.5", "--normal-only"],
    ),
    ({"lowpass": "2.2u"}, ["--lowpass", "2.2u"]),
]


@pytest.mark.parametrize("keywords, flags", FILTERS, ids=[str(f[1]) for f in FILTERS])
def test_filter_matches_the_cli_bit_for_bit(cli, sphere, sphere_pyramid, double_ply, tmp_path, keywords, flags):
    source = double_ply(*sphere)
    out = tmp_path / "out.ply"
    cli("filter", source, "-o", out, *flags)
    cli_v, _ = meshpyr.read(out)
    assert_same_bits(sphere_pyramid.filter(**keywords), cli_v)


@pytest.mark.parametrize("relax", ["mcm", "normal"])
def test_filter_with_another_relaxation_matches_the_cli(cli, sphere, double_ply, tmp_path, relax):
    source = double_ply(*sphere)
    out = tmp_path / "out.obj"
    cli("filter", source, "-o", out, "--stopband", "50:500", "--relax", relax)
    pyramid = meshpyr.Pyramid(*sphere, relax=relax)
    assert pyramid.relax == relax
    assert_same_bits(pyramid.filter(stopband=[(50, 500)]), meshpyr.read(out)[0])


def test_filter_of_the_bundled_float32_scan_rounds_to_the_cli_output(cli, tmp_path):
    """On the file as shipped (float32 positions), the CLI writes float32: the bindings'
    float64 result rounds to exactly those values."""
    source = data("bunny.ply")
    out = tmp_path / "bunny-lowpass.ply"
    cli("filter", source, "-o", out, "--lowpass", "1000")
    v, f = meshpyr.read(source)
    smooth = meshpyr.Pyramid(v, f).filter(lowpass=1000)
    cli_v, cli_f = meshpyr.read(out)
    assert_same_bits(cli_f, f)
    assert_same_bits(smooth.astype(np.float32).astype(np.float64), cli_v)


def test_filter_of_a_quad_mesh_matches_the_cli_on_the_polygon_file(cli, tmp_path):
    source = data("mushroom_quad.ply")
    out = tmp_path / "out.obj"
    cli("filter", source, "-o", out, "--enhance", "30:200=1.5")
    v, f = meshpyr.read(source)
    ours = meshpyr.Pyramid(v, f).filter(enhance=[(30, 200, 1.5)])
    assert_same_bits(ours.astype(np.float32).astype(np.float64), meshpyr.read(out)[0])


def test_edit_matches_the_cli(cli, sphere, sphere_pyramid, double_ply, tmp_path):
    v, _ = sphere
    source = double_ply(*sphere)
    out = tmp_path / "edited.ply"
    at, by = v[0], np.array([0.0, 2.5, -1.0])
    move = ",".join(repr(float(x)) for x in at) + ":" + ",".join(repr(float(x)) for x in by)
    cli("edit", source, "-o", out, "--level", "100", "--move", move, "--radius", "8", "--lowpass", "600")
    ours = sphere_pyramid.edit(100, [(at, by)], 8.0, lowpass=600)
    assert_same_bits(ours, meshpyr.read(out)[0])


def test_a_pyr_file_of_the_cli_loads_and_filters_like_the_cli(cli, tmp_path):
    pyr = tmp_path / "joint.pyr"
    cli("build", data("joint.ply"), "-o", pyr)
    out = tmp_path / "out.ply"
    cli("filter", pyr, "-o", out, "--stopband", "40:150")
    loaded = meshpyr.Pyramid.load(pyr)
    assert_same_bits(loaded.filter(stopband=[(40, 150)]).astype(np.float32).astype(np.float64), meshpyr.read(out)[0])
    assert_same_bits(loaded.faces, meshpyr.read(data("joint.ply"))[1])


def test_a_pyr_file_saved_by_the_bindings_filters_like_the_bindings_in_the_cli(cli, sphere_pyramid, tmp_path):
    pyr = tmp_path / "sphere.pyr"
    sphere_pyramid.save(pyr)
    out = tmp_path / "out.ply"
    cli("filter", pyr, "-o", out, "--lowpass", "300")
    # Both open the file's stored details: the same bits.
    assert_same_bits(meshpyr.Pyramid.load(pyr).filter(lowpass=300), meshpyr.read(out)[0])
    # Without details both recompute them: the bits of the pyramid that was saved.
    sphere_pyramid.save(pyr, details=False)
    cli("filter", pyr, "-o", out, "--lowpass", "300")
    assert_same_bits(sphere_pyramid.filter(lowpass=300), meshpyr.read(out)[0])


def test_simplify_matches_the_cli(cli, sphere, double_ply, tmp_path):
    source = double_ply(*sphere)
    out = tmp_path / "coarse.ply"
    cli("simplify", source, "-o", out, "--faces", "300")
    v2, f2, vertex_map = meshpyr.simplify(*sphere, faces=300)
    cli_v, cli_f = meshpyr.read(out)
    assert_same_bits(v2, cli_v)
    assert_same_bits(f2, cli_f)
    assert_same_bits(v2, sphere[0][vertex_map])


def test_subdivide_matches_the_cli(cli, double_ply, tmp_path):
    coarse = meshpyr.read(data("cross.ply"))
    source = double_ply(*coarse)
    for flags, keywords in [((), {}), (("--scheme", "loop"), {"scheme": "loop"}), (("--solver", "cg", "--levels", "2"), {"solver": "cg", "levels": 2})]:
        out = tmp_path / "fine.ply"
        cli("subdivide", source, "-o", out, *flags)
        v2, f2 = meshpyr.subdivide(*coarse, **keywords)
        cli_v, cli_f = meshpyr.read(out)
        assert_same_bits(v2, cli_v)
        assert_same_bits(f2, cli_f)


SMOOTHINGS = [
    ({}, []),
    ({"method": "auto", "passes": 1, "scale": "global"}, ["--method", "auto", "--passes", "1", "--scale", "global"]),
    ({"method": "adaptive"}, ["--method", "adaptive"]),
    ({"method": "adaptive", "vertex_updates": 3}, ["--method", "adaptive", "--vertex-updates", "3"]),
    ({"method": "anisotropic", "epsilon": 0.05}, ["--method", "anisotropic", "--epsilon", "0.05"]),
    ({"method": "taubin"}, ["--method", "taubin"]),
    (
        {"method": "taubin", "iterations": 4, "lambda_": 0.6, "mu": -0.65, "weights": "uniform", "boundary": "smooth"},
        ["--method", "taubin", "--iterations", "4", "--lambda", "0.6", "--mu", "-0.65", "--weights", "uniform", "--boundary", "smooth"],
    ),
    ({"method": "mcf", "time_step": 0.5}, ["--method", "mcf", "--time-step", "0.5"]),
    ({"method": "pyramid", "strength": 1.5}, ["--method", "pyramid", "--strength", "1.5"]),
]


@pytest.mark.parametrize("keywords, flags", SMOOTHINGS, ids=[" ".join(f[1]) or "default" for f in SMOOTHINGS])
def test_smooth_matches_the_cli(cli, double_ply, tmp_path, keywords, flags):
    noisy = meshpyr.read(data("nefertiti.ply"))
    source = double_ply(*noisy)
    out = tmp_path / "smooth.ply"
    cli("smooth", source, "-o", out, *flags)
    assert_same_bits(meshpyr.smooth(*noisy, **keywords), meshpyr.read(out)[0])


def test_info_and_compare_give_the_cli_json(cli, sphere, double_ply, tmp_path):
    source = double_ply(*sphere)
    assert meshpyr.info(*sphere) == json.loads(cli("info", source, "--json"))
    smooth = sphere[0] + 0.01
    result = double_ply(smooth, sphere[1], name="result.ply")
    assert meshpyr.compare(smooth, sphere[1], *sphere) == json.loads(cli("compare", result, source, "--json"))


def test_compare_per_vertex_gives_the_cli_field(cli, sphere, double_ply, tmp_path):
    source = double_ply(*sphere)
    moved = sphere[0] * 1.01
    result = double_ply(moved, sphere[1], name="result.ply")
    expected = json.loads(cli("compare", result, source, "--json", "--per-vertex", tmp_path / "field.ply"))
    got = meshpyr.compare(moved, sphere[1], *sphere, per_vertex=True)
    distance = got.pop("distance")
    assert got == expected
    assert distance.dtype == np.float64 and distance.shape == (len(moved),)
    # Every vertex of a sphere scaled by 1.01 lies outside the original polyhedron.
    assert np.all(distance > 0)
    assert distance.max() == expected["per_vertex_distance"]["max"]
    assert "distance" not in meshpyr.compare(moved, sphere[1], *sphere)
