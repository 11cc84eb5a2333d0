"""Minimal binary little-endian PLY reader/writer for triangle meshes (x,y,z + triangle list).

Used only by the comparison scripts in this directory (not by the crate or CI).
"""
import numpy as np

_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
          "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
          "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


def read_ply(path):
    """Returns (positions float64 (n,3), triangles int64 (m,3)). Polygons are fan-triangulated."""
    data = open(path, "rb").read()
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii").splitlines()
    assert "binary_little_endian" in header[1], "only binary little-endian PLY"
    elements = []
    for line in header:
        w = line.split()
        if w and w[0] == "element":
            elements.append([w[1], int(w[2]), []])
        elif w and w[0] == "property":
            elements[-1][2].append(w[1:])
    off = end
    pos = tris = None
    for name, count, props in elements:
        if all(p[0] != "list" for p in props):
            dt = np.dtype([(p[1], "<" + _TYPES[p[0]]) for p in props])
            arr = np.frombuffer(data, dtype=dt, count=count, offset=off)
            off += dt.itemsize * count
            if name == "vertex":
                pos = np.stack([arr["x"], arr["y"], arr["z"]], axis=1).astype(np.float64)
        else:
            assert name == "face" and len(props) == 1, "only a single list property on faces"
            ct, it = np.dtype("<" + _TYPES[props[0][1]]), np.dtype("<" + _TYPES[props[0][2]])
            # fast path: all triangles
            rec = np.dtype([("n", ct), ("i", it, (3,))])
            arr = np.frombuffer(data, dtype=rec, count=count, offset=off)
            if count and np.all(arr["n"] == 3):
                tris = arr["i"].astype(np.int64)
                off += rec.itemsize * count
            else:
                out = []
                for _ in range(count):
                    n = int(np.frombuffer(data, ct, 1, off)[0]); off += ct.itemsize
                    idx = np.frombuffer(data, it, n, off); off += it.itemsize * n
                    for k in range(1, n - 1):
                        out.append((idx[0], idx[k], idx[k + 1]))
                tris = np.array(out, dtype=np.int64).reshape(-1, 3)
    return pos, tris


def write_ply(path, pos, tris):
    """Writes float32 positions and uchar/int triangle lists."""
    pos = np.asarray(pos, dtype="<f4")
    tris = np.asarray(tris)
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement face %d\n"
            "property list uchar int vertex_indices\nend_header\n" % (len(pos), len(tris)))
    rec = np.zeros(len(tris), dtype=np.dtype([("n", "u1"), ("i", "<i4", (3,))]))
    rec["n"] = 3
    rec["i"] = tris
    with open(path, "wb") as f:
        f.write(head.encode("ascii"))
        f.write(pos.tobytes())
        f.write(rec.tobytes())
