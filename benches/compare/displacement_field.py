"""Pictures of a filter's displacement field, per vertex, for issue 47's spike criterion: the
one-process filter and the partitioned filter of a scan side by side, and their difference, each
vertex coloured by the length of its displacement (docs/partitioned.md, "How close it is to the
one-process hierarchy").

    python3 displacement_field.py SCAN.ply FOLDER OUT.png [--meshpyr BIN] [--view V] [--size WxH]

FOLDER holds `one_process.ply` and `partitioned.ply`, the two filtered meshes that
`partition_agreement.py SCAN --keep FOLDER` writes (the input's vertices in the input's order).
Writes three PLY files into FOLDER with a per-vertex float property `displacement`
(|one process - input|, |partitioned - input|, |partitioned - one process|, in model units) and
renders them with `meshpyr render --color-by displacement`, one colour range for the three
(0 to the largest |one process - input|), so that a spike at a block border would stand out as
the brightest spot and the difference panel shows where the two filters part.
"""
import argparse
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from plyio import read_ply  # noqa: E402

REPO = os.path.dirname(os.path.dirname(HERE))


def write_with_displacement(path, pos, tris, displacement):
    """A binary PLY of float32 positions, a float `displacement` per vertex, and triangles."""
    vert = np.zeros(len(pos), dtype=np.dtype([("p", "<f4", (3,)), ("d", "<f4")]))
    vert["p"] = pos
    vert["d"] = displacement
    face = np.zeros(len(tris), dtype=np.dtype([("n", "u1"), ("i", "<i4", (3,))]))
    face["n"] = 3
    face["i"] = tris
    head = (
        "ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
        "property float y\nproperty float z\nproperty float displacement\nelement face %d\n"
        "property list uchar int vertex_indices\nend_header\n" % (len(pos), len(tris))
    )
    with open(path, "wb") as f:
        f.write(head.encode("ascii"))
        f.write(vert.tobytes())
        f.write(face.tobytes())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scan")
    ap.add_argument("folder")
    ap.add_argument("out")
    ap.add_argument("--meshpyr", default=os.path.join(REPO, "target", "release", "meshpyr"))
    ap.add_argument("--view", default="front")
    ap.add_argument("--size", default="420x420", help="each panel's size in pixels")
    a = ap.parse_args()

    pos, tris = read_ply(a.scan)
    one, _ = read_ply(os.path.join(a.folder, "one_process.ply"))
    part, _ = read_ply(os.path.join(a.folder, "partitioned.ply"))
    if not (len(one) == len(part) == len(pos)):
        sys.exit("error: the filtered meshes do not have the scan's vertices")
    fields = {
        "one_process": np.linalg.norm(one - pos, axis=1),
        "partitioned": np.linalg.norm(part - pos, axis=1),
        "difference": np.linalg.norm(part - one, axis=1),
    }
    paths = []
    for name, d in fields.items():
        path = os.path.join(a.folder, f"{name}_displacement.ply")
        shown = part if name == "partitioned" else one
        write_with_displacement(path, shown, tris, d)
        paths.append(path)
        print(f"{name}: max {d.max():.4g}, p99 {np.percentile(d, 99):.4g}")
    top = float(fields["one_process"].max())
    subprocess.run(
        [a.meshpyr, "--quiet", "render", *paths, "-o", a.out, "--view", a.view,
         "--size", a.size, "--color-by", "displacement", "--range", f"0:{top!r}"],
        check=True,
    )  # fmt: skip
    print(f"wrote {a.out} (colour range 0 to {top:.4g}, the largest one-process displacement)")


if __name__ == "__main__":
    main()
