"""The bindings and the command line share one options layer (the library's): the same bad
value gets the same message from both."""

import pytest
from conftest import data

import meshpyr

CROSS = data("cross.ply")

# (what the bindings are called with, the command line's arguments)
BAD_OPTIONS = [
    (
        lambda v, f: meshpyr.smooth(v, f, method="taubin", epsilon=0.1),
        ["smooth", CROSS, "-o", "{out}.ply", "--method", "taubin", "--epsilon", "0.1"],
    ),
    (
        lambda v, f: meshpyr.smooth(v, f, method="adaptive", scales=0),
        ["smooth", CROSS, "-o", "{out}.ply", "--method", "adaptive", "--scales", "0"],
    ),
    (
        lambda v, f: meshpyr.smooth(v, f, method="median"),
        ["smooth", CROSS, "-o", "{out}.ply", "--method", "median"],
    ),
    (
        lambda v, f: meshpyr.subdivide(v, f, scheme="catmull"),
        ["subdivide", CROSS, "-o", "{out}.ply", "--scheme", "catmull"],
    ),
    (
        lambda v, f: meshpyr.subdivide(v, f, solver="lu"),
        ["subdivide", CROSS, "-o", "{out}.ply", "--solver", "lu"],
    ),
    (
        lambda v, f: meshpyr.simplify(v, f, faces=10, prune=1.5),
        ["simplify", CROSS, "-o", "{out}.ply", "--faces", "10", "--prune", "1.5"],
    ),
    (
        lambda v, f: meshpyr.Pyramid(v, f).filter(lowpass=0),
        ["filter", CROSS, "-o", "{out}.ply", "--lowpass", "0"],
    ),
    (
        lambda v, f: meshpyr.Pyramid(v, f, relax="laplace"),
        ["filter", CROSS, "-o", "{out}.ply", "--lowpass", "10", "--relax", "laplace"],
    ),
]


@pytest.mark.parametrize("call, args", BAD_OPTIONS, ids=[" ".join(map(str, a[3:])) for _, a in BAD_OPTIONS])
def test_a_bad_option_gets_the_same_message_from_the_bindings_and_the_cli(cli_error, tmp_path, call, args):
    v, f = meshpyr.read(CROSS)
    with pytest.raises(ValueError) as caught:
        call(v, f)
    stderr = cli_error(*[str(a).format(out=tmp_path / "out") for a in args])
    assert str(caught.value) in stderr, (str(caught.value), stderr)
