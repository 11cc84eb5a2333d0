"""Files, counts, simplification, progressive meshes, subdivision, smoothing, comparison, and
a round trip through trimesh."""

import re

import numpy as np
import pytest
from conftest import REPO, assert_same_bits, data

import meshpyr


def test_version_is_the_crates_version():
    cargo = (REPO / "Cargo.toml").read_text()
    version = re.search(r'^version = "([^"]+)"', cargo, re.M).group(1)
    assert meshpyr.__version__ == version


def test_every_public_name_has_a_docstring():
    for name in meshpyr.__all__:
        if name != "__version__":
            assert len(getattr(meshpyr, name).__doc__ or "") > 40, name
    for method in ["filter", "edit", "spectrum", "to_bytes", "from_bytes", "save", "load"]:
        assert len(getattr(meshpyr.Pyramid, method).__doc__ or "") > 40, method
    assert "levels" in meshpyr.ProgressiveMesh.mesh.__doc__


@pytest.mark.parametrize("extension", ["ply", "obj", "off", "ply.gz", "obj.gz"])
def test_write_then_read_gives_back_the_same_float64_arrays(sphere, tmp_path, extension):
    v = sphere[0] + np.pi  # every bit of a float64 counts
    path = tmp_path / f"sphere.{extension}"
    meshpyr.write(path, v, sphere[1])
    v2, f2 = meshpyr.read(path)
    assert_same_bits(v2, v)
    assert_same_bits(f2, sphere[1])


def test_polygons_are_fan_triangulated_like_the_mesh_builder():
    v, f = meshpyr.read(data("cube_quad.off"))
    assert f.shape == (12, 3) and v.shape == (8, 3)
    assert meshpyr.info(v, f)["polygons"] == 12
    assert meshpyr.info(v, f)["faces"] == 12


def test_info_reports_topology(sphere):
    info = meshpyr.info(*sphere)
    assert (info["vertices"], info["faces"], info["genus"], info["manifold"]) == (926, 1848, 0, True)
    assert info["components"] == 1 and info["boundary_loops"] == 0
    holes = meshpyr.info(*meshpyr.read(data("nefertiti.ply")))
    assert holes["boundary_loops"] == 1


@pytest.mark.parametrize("target", [{"faces": 500}, {"ratio": 0.25}, {"error": 0.001}], ids=repr)
def test_simplify_keeps_vertices_where_they_were(sphere, target):
    v, f = sphere
    v2, f2, vertex_map = meshpyr.simplify(v, f, **target)
    assert len(f2) < len(f) and f2.max() < len(v2)
    assert vertex_map.dtype == np.int64 and len(np.unique(vertex_map)) == len(v2)
    assert_same_bits(v2, v[vertex_map])
    if "faces" in target:
        assert len(f2) <= 500


def test_simplify_warns_when_the_topology_stops_it(sphere):
    with pytest.warns(UserWarning, match="floor of its topology"):
        _, f2, _ = meshpyr.simplify(*meshpyr.read(data("joint.ply")), faces=4)
    assert len(f2) > 4


def test_progressive_mesh_levels_are_simplifications_and_the_finest_is_the_input(sphere):
    v, f = sphere
    pm = meshpyr.ProgressiveMesh(v, f)
    assert pm.levels.stop == len(v) + 1
    vertex_map = pm.vertex_map
    assert sorted(vertex_map) == list(range(len(v)))
    finest_v, finest_f = pm.mesh(pm.levels.stop - 1)
    assert_same_bits(finest_v, v[vertex_map])
    # The same triangles as the input, in the same order, renumbered.
    assert_same_bits(vertex_map[finest_f], f)
    previous = len(finest_f)
    for n in [500, 200, 50, pm.levels.start]:
        vn, fn = pm.mesh(n)
        assert len(vn) == n and fn.max() < n and len(fn) < previous
        assert_same_bits(vn, v[vertex_map[:n]])
        previous = len(fn)
    with pytest.raises(ValueError, match="outside"):
        pm.mesh(len(v) + 1)


def test_the_base_level_is_where_simplify_stops(sphere):
    pm = meshpyr.ProgressiveMesh(*sphere)
    base_v, base_f = pm.mesh(pm.levels.start)
    with pytest.warns(UserWarning, match="stopped at 4 triangles"):
        v2, f2, _ = meshpyr.simplify(*sphere, faces=0)
    assert len(v2) == len(base_v) and len(f2) == len(base_f)


def test_subdivide_keeps_the_input_vertices_first():
    v, f = meshpyr.read(data("tetrahedron.ply"))
    for scheme, factor in [("mcm", 4), ("loop", 4)]:
        v2, f2 = meshpyr.subdivide(v, f, levels=2, scheme=scheme)
        assert len(f2) == len(f) * factor**2
    v2, f2 = meshpyr.subdivide(v, f, levels=2, refine="bisect")
    assert len(f2) == len(f) * 4


def test_smooth_reduces_the_error_of_a_noisy_scan():
    clean = meshpyr.read(data("fandisk.ply"))
    noisy = meshpyr.read(data("fandisk_noise_n020.ply"))
    smoothed = meshpyr.smooth(*noisy)
    assert smoothed.shape == noisy[0].shape
    before = meshpyr.compare(*noisy, *clean)["e_v"]
    after = meshpyr.compare(smoothed, noisy[1], *clean)["e_v"]
    assert after < 0.7 * before


def test_compare_of_a_mesh_with_itself_is_zero(sphere):
    result = meshpyr.compare(*sphere, *sphere)
    # Sample points off the vertices are interpolated, so they are exact only to rounding.
    assert result["e_v"] == 0 and result["hausdorff"] < 1e-12
    moved = meshpyr.compare(sphere[0] + [0.0, 0.0, 0.1], sphere[1], *sphere)
    assert 0 < moved["e_v"] <= 0.1 + 1e-12


def test_a_trimesh_round_trip_keeps_every_vertex_and_face(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    v, f = meshpyr.read(data("bunny.ply"))
    # trimesh reads the bundled file to the same arrays.
    loaded = trimesh.load(data("bunny.ply"), process=False)
    assert_same_bits(np.asarray(loaded.vertices, dtype=np.float64), v)
    assert_same_bits(np.asarray(loaded.faces, dtype=np.int64), f)
    # Its arrays go straight in; the filtered mesh comes back as a trimesh with the same faces.
    mesh = trimesh.Trimesh(vertices=v, faces=f, process=False)
    smooth = meshpyr.Pyramid(mesh.vertices, mesh.faces).filter(lowpass=2000)
    out = trimesh.Trimesh(vertices=smooth, faces=mesh.faces, process=False)
    assert out.is_watertight and abs(out.volume - mesh.volume) < 0.05 * mesh.volume
    # trimesh's export is a file meshpyr reads back exactly, and the other way round.
    out.export(tmp_path / "smooth.ply")
    exported = meshpyr.read(tmp_path / "smooth.ply")[0]
    # trimesh exports float32 PLY positions: the same values to float32 rounding.
    assert_same_bits(exported.astype(np.float32), smooth.astype(np.float32))
    meshpyr.write(tmp_path / "ours.obj", smooth, f)
    again = trimesh.load(tmp_path / "ours.obj", process=False)
    assert np.allclose(again.vertices, smooth, rtol=0, atol=1e-12)
    assert_same_bits(np.asarray(again.faces, dtype=np.int64), f)
