"""Textured meshes through the bindings: the corners dict of ``read(path, corners=True)``
carries texture coordinates, materials and their files through ``write``, ``info`` and
``simplify`` (seams kept), as the command line does."""

import os
import re
import shutil

import numpy as np
import pytest
from conftest import assert_same_bits, data

import meshpyr

OBJ = data("textured/anchor_tex.obj")
PLY = data("textured/anchor_tex.ply")


def corner_values(v_map, f, uv):
    """The set of (input vertex, texture coordinate) pairs of every corner."""
    return {
        (int(v_map[f[t, k]]), tuple(uv[t, k].tolist()))
        for t in range(f.shape[0])
        for k in range(3)
    }


def material_names(c):
    """The material name of every triangle."""
    names = [x["name"] for x in c["materials"]]
    return [names[i] for i in c["material"]]


def test_read_with_corners_gives_texcoords_and_materials_per_triangle():
    v, f, c = meshpyr.read(OBJ, corners=True)
    m = f.shape[0]
    assert c["texcoord"].shape == (m, 3, 2)
    assert c["material"].shape == (m,)
    textures = {x["name"]: x["texture"] for x in c["materials"]}
    assert textures == {"left": "textures/left.png", "right": "textures/right.png"}
    assert c["material_libraries"] == ["anchor_tex.mtl"]
    assert os.path.samefile(c["folder"], OBJ.parent)
    assert set(np.unique(c["material"])) == {0, 1}
    assert not np.isnan(c["texcoord"]).any()


def test_the_obj_and_ply_layouts_of_one_scan_give_the_same_corners():
    _, f_obj, c_obj = meshpyr.read(OBJ, corners=True)
    _, f_ply, c_ply = meshpyr.read(PLY, corners=True)
    assert_same_bits(f_obj, f_ply)
    np.testing.assert_allclose(c_obj["texcoord"], c_ply["texcoord"], atol=1e-6)
    assert material_names(c_obj) == material_names(c_ply)


def test_read_without_corners_still_gives_a_pair():
    assert len(meshpyr.read(OBJ)) == 2


@pytest.mark.parametrize("suffix", [".obj", ".ply"])
def test_written_corners_read_back_bit_for_bit(tmp_path, suffix):
    v, f, c = meshpyr.read(OBJ, corners=True)
    out = tmp_path / f"out{suffix}"
    meshpyr.write(out, v, f, c)
    v2, f2, c2 = meshpyr.read(out, corners=True)
    assert_same_bits(v2, v)
    assert_same_bits(f2, f)
    assert c2["texcoord"].dtype == c["texcoord"].dtype
    assert_same_bits(c2["texcoord"], c["texcoord"])
    assert_same_bits(c2["material"], c["material"])
    assert [x["name"] for x in c2["materials"]] == [x["name"] for x in c["materials"]]


def test_a_copy_written_to_another_folder_still_reaches_its_material_and_images(tmp_path):
    v, f, c = meshpyr.read(OBJ, corners=True)
    out = tmp_path / "elsewhere" / "scan.obj"
    out.parent.mkdir()
    meshpyr.write(out, v, f, c)
    library = re.search(r"^mtllib (.+)$", out.read_text(), re.M).group(1)
    assert os.path.samefile(out.parent / library, OBJ.parent / "anchor_tex.mtl")
    texture = meshpyr.info(*meshpyr.read(out, corners=True))["texture"]
    assert sorted(texture["materials"]) == ["left", "right"]
    assert texture["files"] and all(found for _, found in texture["files"])


def test_info_with_corners_reports_seams_like_the_cli(cli):
    import json

    ours = meshpyr.info(*meshpyr.read(OBJ, corners=True))["texture"]
    theirs = json.loads(cli("info", OBJ, "--json"))["texture"]
    assert ours["seam_vertices"] == theirs["seam_vertices"] > 0
    assert ours["seam_edges"] == theirs["seam_edges"] > 0
    assert ours["materials"] == theirs["materials"]


def test_filtered_positions_keep_the_corners_valid(tmp_path):
    """Filters keep F, so the input's corners dict writes the filtered scan textured."""
    v, f, c = meshpyr.read(OBJ, corners=True)
    smooth = meshpyr.Pyramid(v, f).filter(lowpass=200)
    out = tmp_path / "smooth.obj"
    meshpyr.write(out, smooth, f, c)
    _, _, c2 = meshpyr.read(out, corners=True)
    assert_same_bits(c2["texcoord"], c["texcoord"])


def test_normals_written_with_the_positions_before_follow_the_moved_surface(tmp_path):
    """Each corner's written normal is the area-weighted normal of the new faces around its
    vertex on its own side of the input's hard edges (corners that shared a stored normal)."""
    v, f, c = meshpyr.read(OBJ, corners=True)
    smooth = meshpyr.Pyramid(v, f).filter(lowpass=100)
    out = tmp_path / "ours.obj"
    meshpyr.write(out, smooth, f, c, before=v)
    _, _, written = meshpyr.read(out, corners=True)
    p = smooth[f]
    area = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    sums = {}
    for t in range(f.shape[0]):
        for k in range(3):
            key = (int(f[t, k]), c["normal"][t, k].tobytes())
            sums[key] = sums.get(key, 0) + area[t]
    for t in range(f.shape[0]):
        for k in range(3):
            n = sums[(int(f[t, k]), c["normal"][t, k].tobytes())]
            np.testing.assert_allclose(written["normal"][t, k], n / np.linalg.norm(n), atol=1e-6)
    assert not np.array_equal(written["normal"], c["normal"])


def test_before_must_hold_the_same_vertices(tmp_path):
    v, f, c = meshpyr.read(OBJ, corners=True)
    with pytest.raises(ValueError, match="before has 3 rows"):
        meshpyr.write(tmp_path / "x.obj", v, f, c, before=v[:3])


def test_simplify_with_corners_keeps_every_corner_on_its_side_of_the_seams():
    v, f, c = meshpyr.read(OBJ, corners=True)
    v2, f2, v_map, c2 = meshpyr.simplify(v, f, ratio=0.3, corners=c)
    assert f2.shape[0] <= 0.3 * f.shape[0]
    assert c2["texcoord"].shape == (f2.shape[0], 3, 2)
    identity = np.arange(v.shape[0])
    kept = corner_values(v_map, f2, c2["texcoord"])
    assert kept <= corner_values(identity, f, c["texcoord"])
    # Each output triangle keeps the material of an input triangle on the same vertices'
    # side: both materials survive, and no corner value is invented.
    assert set(np.unique(c2["material"])) == {0, 1}


def test_simplify_with_corners_gives_the_cli_result(cli, tmp_path):
    out = tmp_path / "simple.obj"
    cli("simplify", OBJ, "-o", out, "--ratio", "0.3", "--uv-weight", "1")
    v, f, c = meshpyr.read(OBJ, corners=True)
    v2, f2, _, c2 = meshpyr.simplify(v, f, ratio=0.3, corners=c, uv_weight=1.0)
    cli_v, cli_f, cli_c = meshpyr.read(out, corners=True)
    assert_same_bits(cli_f, f2)
    assert_same_bits(cli_v, v2)
    assert_same_bits(cli_c["texcoord"], c2["texcoord"])
    assert_same_bits(cli_c["material"], c2["material"])


def test_the_uv_weight_changes_which_collapses_are_taken():
    v, f, c = meshpyr.read(OBJ, corners=True)
    _, f_geometry, _, _ = meshpyr.simplify(v, f, ratio=0.3, corners=c, uv_weight=0.0)
    _, f_texture, _, _ = meshpyr.simplify(v, f, ratio=0.3, corners=c, uv_weight=4.0)
    assert not np.array_equal(f_geometry, f_texture)


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda c, m: c.update(texcoord=np.zeros((m, 2))), r"shape \(\d+, 3, 2\)"),
        (lambda c, m: c.update(colour=np.zeros(m)), "unknown key \"colour\""),
        (lambda c, m: c.update(material=np.full(m, 5)), r"outside corners\[\"materials\"\]"),
        (lambda c, m: c["texcoord"].__setitem__((0, 0, 0), np.nan), "all finite or all NaN"),
        (lambda c, m: c.update(materials=[{"name": "two words"}]), "one word"),
    ],
    ids=["shape", "key", "index", "half-nan", "name"],
)
def test_bad_corners_are_a_value_error_naming_the_key(tmp_path, change, message):
    v, f, c = meshpyr.read(OBJ, corners=True)
    c["texcoord"] = c["texcoord"].copy()
    change(c, f.shape[0])
    with pytest.raises(ValueError, match=message):
        meshpyr.write(tmp_path / "bad.obj", v, f, c)
    assert not (tmp_path / "bad.obj").exists()


def test_a_mesh_without_texture_reads_an_empty_corners_dict(tmp_path):
    source = tmp_path / "plain.obj"
    shutil.copy(data("bunny.ply"), tmp_path / "bunny.ply")
    v, f = meshpyr.read(tmp_path / "bunny.ply")
    meshpyr.write(source, v, f)
    assert meshpyr.read(source, corners=True)[2] == {}


def as_float32(v):
    """Positions rounded as the command line writes a float32 file's (anchor_tex.obj)."""
    return v.astype(np.float32).astype(np.float64)


def test_a_pyramid_with_corners_filters_like_the_cli_on_the_textured_file(cli, tmp_path):
    """The command line builds a seam-keeping hierarchy for a textured file; so does
    Pyramid(V, F, corners=C): the bindings' float64 result rounds to the very positions the
    command line writes (float32, as the file stores them)."""
    theirs = tmp_path / "cli.obj"
    cli("filter", OBJ, "-o", theirs, "--lowpass", "200")
    v, f, c = meshpyr.read(OBJ, corners=True)
    filtered = meshpyr.Pyramid(v, f, corners=c).filter(lowpass=200)
    cli_v, cli_f, cli_c = meshpyr.read(theirs, corners=True)
    assert_same_bits(cli_f, f)
    assert_same_bits(as_float32(filtered), cli_v)
    assert_same_bits(cli_c["texcoord"], c["texcoord"])
    # Without the corners the hierarchy ignores the seams, and the result differs.
    plain = meshpyr.Pyramid(v, f).filter(lowpass=200)
    assert not np.array_equal(as_float32(plain), cli_v)


def test_a_level_of_a_pyramid_with_corners_is_the_level_the_cli_extracts(cli, tmp_path):
    pyr, theirs = tmp_path / "scan.pyr", tmp_path / "level.obj"
    cli("build", OBJ, "-o", pyr)
    cli("extract", pyr, "-o", theirs, "--level", "200")
    v, f, c = meshpyr.read(OBJ, corners=True)
    pyramid = meshpyr.Pyramid(v, f, corners=c)
    assert pyramid.corners["materials"] == c["materials"]
    v2, f2, c2 = pyramid.level(200, corners=True)
    cli_v, cli_f, cli_c = meshpyr.read(theirs, corners=True)
    assert_same_bits(cli_v, v2)
    assert_same_bits(cli_f, f2)
    assert_same_bits(cli_c["texcoord"], c2["texcoord"])
    assert_same_bits(cli_c["material"], c2["material"])
    assert f2.shape[0] < f.shape[0]
    assert len(pyramid.level(200)) == 2


def test_a_progressive_mesh_with_corners_keeps_every_corner_on_its_side_of_the_seams():
    v, f, c = meshpyr.read(OBJ, corners=True)
    pm = meshpyr.ProgressiveMesh(v, f, corners=c)
    identity = np.arange(v.shape[0])
    for n in (pm.levels[0], 200, pm.levels[-1]):
        v_n, f_n, c_n = pm.mesh(n, corners=True)
        assert_same_bits(v_n, v[pm.vertex_map[:n]])
        assert_same_bits(f_n, pm.mesh(n)[1])
        assert c_n["texcoord"].shape == (f_n.shape[0], 3, 2)
        kept = corner_values(pm.vertex_map, f_n, c_n["texcoord"])
        assert kept <= corner_values(identity, f, c["texcoord"])
        assert set(np.unique(c_n["material"])) == {0, 1}
    # The same hierarchy as the pyramid's: its levels are the pyramid's.
    v_p, f_p, c_p = meshpyr.Pyramid(v, f, corners=c).level(200, corners=True)
    v_n, f_n, c_n = pm.mesh(200, corners=True)
    assert_same_bits(v_p, v_n)
    assert_same_bits(f_p, f_n)
    assert_same_bits(c_p["texcoord"], c_n["texcoord"])
    # Built without corners, a level has none, and the seams were not kept.
    plain = meshpyr.ProgressiveMesh(v, f)
    assert plain.mesh(200, corners=True)[2] == {}
    assert not np.array_equal(plain.vertex_map, pm.vertex_map)
