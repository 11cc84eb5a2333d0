"""Bad input is a Python exception with a reason, never a crash: ValueError for arrays and
options, OSError for files, FormatError for damaged files."""

import gzip

import numpy as np
import pytest
from conftest import data

import meshpyr

TETRA_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
TETRA_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.int64)

# Every entry point that takes (V, F), called with its other arguments valid.
TAKERS = {
    "write": lambda v, f, tmp: meshpyr.write(tmp / "m.ply", v, f),
    "info": lambda v, f, tmp: meshpyr.info(v, f),
    "simplify": lambda v, f, tmp: meshpyr.simplify(v, f, faces=4),
    "subdivide": lambda v, f, tmp: meshpyr.subdivide(v, f, levels=1),
    "smooth": lambda v, f, tmp: meshpyr.smooth(v, f),
    "compare": lambda v, f, tmp: meshpyr.compare(v, f, TETRA_V, TETRA_F),
    "compare reference": lambda v, f, tmp: meshpyr.compare(TETRA_V, TETRA_F, v, f),
    "ProgressiveMesh": lambda v, f, tmp: meshpyr.ProgressiveMesh(v, f),
    "Pyramid": lambda v, f, tmp: meshpyr.Pyramid(v, f),
}

BAD_ARRAYS = {
    "V of shape (4, 2)": (TETRA_V[:, :2], TETRA_F, "shape (n, 3)"),
    "V of one dimension": (TETRA_V.ravel(), TETRA_F, "shape (n, 3)"),
    "V of integers": (TETRA_V.astype(np.int64), TETRA_F, "float"),
    "V of complex numbers": (TETRA_V.astype(np.complex128), TETRA_F, "float"),
    "V of strings": (TETRA_V.astype(str), TETRA_F, "float"),
    "V with a NaN": (np.where(np.arange(12).reshape(4, 3) == 4, np.nan, TETRA_V), TETRA_F, "not finite"),
    "V with an Inf": (np.where(np.arange(12).reshape(4, 3) == 7, np.inf, TETRA_V), TETRA_F, "not finite"),
    "F of shape (4, 4)": (TETRA_V, np.hstack([TETRA_F, TETRA_F[:, :1]]), "shape (n, 3)"),
    "F of floats": (TETRA_V, TETRA_F.astype(np.float64), "integer"),
    "F with index 4 of 4 vertices": (TETRA_V, np.where(TETRA_F == 3, 4, TETRA_F), "index 4"),
    "F with a negative index": (TETRA_V, np.where(TETRA_F == 3, -1, TETRA_F), "index -1"),
    "F of uint64 beyond int64": (TETRA_V, np.full((4, 3), 2**63 + 5, dtype=np.uint64), "outside"),
    "F that is not an array": (TETRA_V, object(), "F"),
}


@pytest.mark.parametrize("taker", TAKERS.values(), ids=TAKERS.keys())
@pytest.mark.parametrize("bad", BAD_ARRAYS.values(), ids=BAD_ARRAYS.keys())
def test_bad_arrays_raise_value_error_naming_the_problem(taker, bad, tmp_path):
    v, f, says = bad
    with pytest.raises(ValueError, match=None) as caught:
        taker(v, f, tmp_path)
    assert says in str(caught.value)
    assert not isinstance(caught.value, meshpyr.FormatError)


def test_acceptable_arrays_of_other_layouts_give_the_same_results():
    reference = meshpyr.info(TETRA_V, TETRA_F)
    for v, f in [
        (TETRA_V.astype(np.float32), TETRA_F.astype(np.int32)),
        (TETRA_V.tolist(), TETRA_F.tolist()),
        (np.asfortranarray(TETRA_V), TETRA_F.astype(np.uint16)),
        (np.hstack([TETRA_V, TETRA_V])[:, :3], TETRA_F[::-1][::-1]),
    ]:
        assert meshpyr.info(v, f) == reference


OPTIONS = {
    "simplify without a target": lambda: meshpyr.simplify(TETRA_V, TETRA_F),
    "simplify with two targets": lambda: meshpyr.simplify(TETRA_V, TETRA_F, faces=2, ratio=0.5),
    "simplify ratio 0": lambda: meshpyr.simplify(TETRA_V, TETRA_F, ratio=0.0),
    "simplify negative error": lambda: meshpyr.simplify(TETRA_V, TETRA_F, error=-1.0),
    "subdivide unknown scheme": lambda: meshpyr.subdivide(TETRA_V, TETRA_F, scheme="catmull"),
    "subdivide unknown solver": lambda: meshpyr.subdivide(TETRA_V, TETRA_F, solver="lu"),
    "subdivide negative width": lambda: meshpyr.subdivide(TETRA_V, TETRA_F, width=-0.25),
    "subdivide NaN width": lambda: meshpyr.subdivide(TETRA_V, TETRA_F, width=float("nan")),
    "subdivide too many levels": lambda: meshpyr.subdivide(TETRA_V, TETRA_F, levels=40),
    "subdivide negative levels": lambda: meshpyr.subdivide(TETRA_V, TETRA_F, levels=-1),
    "simplify negative faces": lambda: meshpyr.simplify(TETRA_V, TETRA_F, faces=-1),
    "level -1 of a progressive mesh": lambda: meshpyr.ProgressiveMesh(TETRA_V, TETRA_F).mesh(-1),
    "level 0 of a progressive mesh": lambda: meshpyr.ProgressiveMesh(TETRA_V, TETRA_F).mesh(0),
    "smooth unknown method": lambda: meshpyr.smooth(TETRA_V, TETRA_F, method="median"),
    "smooth 0 scales": lambda: meshpyr.smooth(TETRA_V, TETRA_F, scales=0),
    "smooth taubin with an adaptive option": lambda: meshpyr.smooth(TETRA_V, TETRA_F, method="taubin", epsilon=0.1),
    "smooth adaptive with a taubin option": lambda: meshpyr.smooth(TETRA_V, TETRA_F, lambda_=0.4),
    "smooth unknown scale": lambda: meshpyr.smooth(TETRA_V, TETRA_F, scale="medium"),
    "smooth mcf with passes": lambda: meshpyr.smooth(TETRA_V, TETRA_F, method="mcf", passes=2),
    "smooth unknown weights": lambda: meshpyr.smooth(TETRA_V, TETRA_F, method="taubin", weights="cot"),
    "smooth mcf negative time step": lambda: meshpyr.smooth(TETRA_V, TETRA_F, method="mcf", time_step=-1.0),
    "smooth pyramid negative strength": lambda: meshpyr.smooth(TETRA_V, TETRA_F, method="pyramid", strength=-1.0),
    "smooth auto with strength": lambda: meshpyr.smooth(TETRA_V, TETRA_F, strength=2.0),
    "Pyramid unknown relaxation": lambda: meshpyr.Pyramid(TETRA_V, TETRA_F, relax="laplace"),
    "compare against no surface": lambda: meshpyr.compare(TETRA_V, TETRA_F, TETRA_V, TETRA_F[:0]),
}


@pytest.mark.parametrize("call", OPTIONS.values(), ids=OPTIONS.keys())
def test_bad_options_raise_value_error(call):
    with pytest.raises(ValueError):
        call()


@pytest.mark.parametrize(
    "keywords",
    [
        {},
        {"lowpass": 0},
        {"lowpass": -5},
        {"lowpass": 1.5},
        {"lowpass": True},
        {"lowpass": "0.02"},
        {"lowpass": "-0.02u"},
        {"stopband": [(10,)]},
        {"stopband": 5},
        {"enhance": [(10, 20)]},
        {"enhance": [(10, 20, float("nan"))]},
        {"gains": [(10, 20, "x")]},
    ],
    ids=repr,
)
def test_bad_filters_raise_value_error(sphere_pyramid, keywords):
    with pytest.raises(ValueError):
        sphere_pyramid.filter(**keywords)


@pytest.mark.parametrize(
    "args",
    [
        (0, [((0, 0, 0), (0, 0, 1))], 1.0),
        (-1, [((0, 0, 0), (0, 0, 1))], 1.0),
        (10**9, [((0, 0, 0), (0, 0, 1))], 1.0),
        (100, [], 1.0),
        (100, [((0, 0), (0, 0, 1))], 1.0),
        (100, [((0, 0, float("inf")), (0, 0, 1))], 1.0),
        (100, [((0, 0, 0), (0, 0, 1))], 0.0),
        (100, [((0, 0, 0), (0, 0, 1))], float("nan")),
    ],
    ids=repr,
)
def test_bad_edits_raise_value_error(sphere_pyramid, args):
    with pytest.raises(ValueError):
        sphere_pyramid.edit(*args)


def test_missing_files_raise_file_not_found_with_the_name(tmp_path):
    missing = tmp_path / "nowhere.ply"
    with pytest.raises(FileNotFoundError) as caught:
        meshpyr.read(missing)
    assert caught.value.filename == str(missing)
    with pytest.raises(FileNotFoundError):
        meshpyr.Pyramid.load(tmp_path / "nowhere.pyr")


def test_unwritable_places_raise_os_error(tmp_path):
    with pytest.raises(OSError):
        meshpyr.write(tmp_path / "no" / "such" / "dir.ply", TETRA_V, TETRA_F)
    pyramid = meshpyr.Pyramid(*meshpyr.read(data("cross.ply")))
    with pytest.raises(OSError):
        pyramid.save(tmp_path / "no" / "such.pyr")


def test_unknown_extensions_raise_value_error(tmp_path):
    with pytest.raises(ValueError, match="unknown mesh format"):
        meshpyr.write(tmp_path / "m.xyz", TETRA_V, TETRA_F)
    (tmp_path / "m.xyz").write_text("hello")
    with pytest.raises(ValueError, match="unknown mesh format"):
        meshpyr.read(tmp_path / "m.xyz")


def test_damaged_mesh_files_raise_format_error(tmp_path):
    cases = {
        "truncated.ply": data("cross.ply").read_bytes()[:-100],
        "garbage.obj": b"v 1 2 3\nf 1 2 banana\n",
        "broken.off": b"OFF\n3 1 0\n0 0 0\n",
        "bad.ply.gz": b"not gzip at all",
    }
    for name, content in cases.items():
        (tmp_path / name).write_bytes(content)
        with pytest.raises(meshpyr.FormatError):
            meshpyr.read(tmp_path / name)


def test_damaged_pyr_files_and_bytes_raise_format_error(tmp_path):
    good = meshpyr.Pyramid(*meshpyr.read(data("cross.ply"))).to_bytes()
    flipped = bytearray(good)
    flipped[len(good) // 2] ^= 0xFF
    for damaged in [b"", b"hello world", good[:-10], good[: len(good) // 2], bytes(flipped)]:
        with pytest.raises(meshpyr.FormatError):
            meshpyr.Pyramid.from_bytes(damaged)
        (tmp_path / "d.pyr").write_bytes(damaged)
        with pytest.raises(meshpyr.FormatError):
            meshpyr.Pyramid.load(tmp_path / "d.pyr")
    # A mesh file is not a .pyr file.
    with pytest.raises(meshpyr.FormatError):
        meshpyr.Pyramid.load(data("cross.ply"))


def test_format_error_is_a_value_error_of_the_package():
    assert issubclass(meshpyr.FormatError, ValueError)
    assert meshpyr.FormatError.__module__ == "meshpyr"


def test_random_bytes_never_crash_the_pyr_reader():
    rng = np.random.default_rng(7)
    good = meshpyr.Pyramid(TETRA_V, TETRA_F).to_bytes()
    for _ in range(200):
        damaged = bytearray(good)
        for i in rng.integers(0, len(good), size=3):
            damaged[i] = rng.integers(0, 256)
        try:
            meshpyr.Pyramid.from_bytes(bytes(damaged))
        except meshpyr.FormatError:
            pass
