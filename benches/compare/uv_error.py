#!/usr/bin/env python3
"""Texture-space error of a simplified textured mesh (issue 46), and meshoptimizer's baseline.

    python3 uv_error.py measure INPUT.obj RESULT.obj [SAMPLES=200000] [SEED=1]
    python3 uv_error.py meshopt INPUT.obj OUT.obj FACES [UV_WEIGHT=1] [normals]

`measure` samples RESULT's surface area-uniformly; at each sample it compares the texture
coordinate interpolated in RESULT's triangle with the one interpolated at the nearest point of
INPUT's surface (exact point-to-triangle search, as distance.py), in texels of a 1024² image,
and prints the median, 90th percentile, mean and maximum; the share of samples whose nearest
input face has another material; and the geometric Hausdorff and RMS distances of distance.py
(relative to INPUT's bounding-box diagonal).

`meshopt` runs meshoptimizer's `meshopt_simplifyWithAttributes` on the seam-split mesh (one
vertex per distinct position, texture coordinate and material, as a renderer would hold it) with
the texture coordinates as attributes of weight UV_WEIGHT, stopping at FACES triangles
(target_error 1, so that only the count stops it), and writes the result as OBJ with `vt`
and `usemtl`. With `normals`, a vertex is also split by its corner normal (`f v/vt/vn`), as a
renderer holds a mesh with hard edges: meshoptimizer then keeps the hard edges as seams, as
meshpyr's wedges do (docs/seams.md); without it, it sees the texture seams and materials only.

Both read OBJ files with `v`, `vt`, `usemtl` and `f v/vt[/vn]` (polygons fanned from their first
corner); meshpyr converts a PLY scan (`meshpyr convert IN.ply OUT.obj`).
"""
import ctypes
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from distance import (  # noqa: E402
    TriangleIndex, compare_arrays, point_triangle_closest, sample_barycentric,
)

TEXELS = 1024


def read_obj(path):
    """Positions (n, 3), triangles (m, 3), per-corner uv (m, 3, 2) (NaN without), material per
    triangle (index into the list of names met)."""
    pos, uvs, tris, tuv, mats, names = [], [], [], [], [], {}
    mat = -1
    for line in open(path):
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            pos.append([float(x) for x in w[1:4]])
        elif w[0] == "vt":
            uvs.append([float(x) for x in w[1:3]])
        elif w[0] == "usemtl":
            mat = names.setdefault(w[1], len(names))
        elif w[0] == "f":
            corners = []
            for c in w[1:]:
                parts = c.split("/")
                vi = int(parts[0])
                vi = vi - 1 if vi > 0 else len(pos) + vi
                ti = int(parts[1]) if len(parts) > 1 and parts[1] else 0
                ti = ti - 1 if ti > 0 else (len(uvs) + ti if ti < 0 else -1)
                corners.append((vi, ti))
            for k in range(1, len(corners) - 1):
                tri = [corners[0], corners[k], corners[k + 1]]
                tris.append([c[0] for c in tri])
                tuv.append([c[1] for c in tri])
                mats.append(mat)
    pos = np.array(pos, dtype=np.float64)
    uvs = np.array(uvs + [[np.nan, np.nan]], dtype=np.float64)  # index -1: no vt
    return pos, np.array(tris, dtype=np.int64), uvs[np.array(tuv, dtype=np.int64)], np.array(mats), names


def corner_normal_indices(path):
    """The `vn` index of every corner of read_obj's triangles (-1 without), fanned as there."""
    out = []
    for line in open(path):
        w = line.split()
        if not w or w[0] != "f":
            continue
        corners = []
        for c in w[1:]:
            parts = c.split("/")
            corners.append(int(parts[2]) if len(parts) > 2 and parts[2] else -1)
        for k in range(1, len(corners) - 1):
            out.append([corners[0], corners[k], corners[k + 1]])
    return np.array(out, dtype=np.int64).reshape(-1, 3)


def nearest(points, pos, tris, chunk=5000, pairs=2_000_000):
    """For each point, the nearest triangle of (pos, tris) and the closest point on it (ties to
    the lower triangle)."""
    index = TriangleIndex(pos, tris)
    bound = index.upper_bound(points)
    best_t = np.empty(len(points), dtype=np.int64)
    best_q = np.empty_like(points)
    for s in range(0, len(points), chunk):
        p = points[s:s + chunk]
        ii, jj = index.candidates(p, bound[s:s + chunk], slack=1e-9)
        d_all, q_all = [], []
        for b in range(0, len(ii), pairs):
            i2 = ii[b:b + pairs]
            q = point_triangle_closest(p[i2], *index.corners(jj[b:b + pairs]))
            d_all.append(((p[i2] - q) ** 2).sum(1))
            q_all.append(q)
        d, q = np.concatenate(d_all), np.concatenate(q_all)
        order = np.lexsort((jj, d, ii))  # per point: smallest distance, then smallest triangle
        first = order[np.r_[True, ii[order][1:] != ii[order][:-1]]]
        best_t[s + ii[first]] = jj[first]
        best_q[s + ii[first]] = q[first]
    return best_t, best_q


def barycentric(q, a, b, c):
    v0, v1, v2 = b - a, c - a, q - a
    d00, d01, d11 = (v0 * v0).sum(1), (v0 * v1).sum(1), (v1 * v1).sum(1)
    d20, d21 = (v2 * v0).sum(1), (v2 * v1).sum(1)
    den = d00 * d11 - d01 * d01
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.where(den > 0, (d11 * d20 - d01 * d21) / den, 0.0)
        w = np.where(den > 0, (d00 * d21 - d01 * d20) / den, 0.0)
    return np.stack([1 - v - w, v, w], 1)


def measure(inp, res, n=200000, seed=1):
    ip, it, iuv, imat, inames = read_obj(inp)
    rp, rt, ruv, rmat, rnames = read_obj(res)
    rng = np.random.default_rng(seed)
    pts, ridx, rbary = sample_barycentric(rp, rt, n, rng)
    uv_out = (rbary[:, :, None] * ruv[ridx]).sum(1)
    tid, q = nearest(pts, ip, it)
    t = it[tid]
    ib = barycentric(q, ip[t[:, 0]], ip[t[:, 1]], ip[t[:, 2]])
    uv_in = (ib[:, :, None] * iuv[tid]).sum(1)
    err = np.linalg.norm(uv_out - uv_in, axis=1) * TEXELS
    err = np.where(np.isfinite(err), err, TEXELS * np.sqrt(2))  # a corner without uv
    names_in = {v: k for k, v in inames.items()}
    names_out = {v: k for k, v in rnames.items()}
    other = np.array([names_out.get(a) != names_in.get(b) for a, b in zip(rmat[ridx], imat[tid])])
    h, rms, faces = compare_arrays(ip, it, rp, rt)
    return {
        "faces": faces,
        "median": np.median(err),
        "p90": np.percentile(err, 90),
        "mean": err.mean(),
        "max": err.max(),
        "other_material": other.mean(),
        "hausdorff": h,
        "rms": rms,
    }


def meshopt(inp, out, faces, uv_weight=1.0, split_normals=False):
    from meshoptimizer._loader import lib

    ip, it, iuv, imat, inames = read_obj(inp)
    columns = [it.reshape(-1, 1).astype(np.float64), iuv.reshape(-1, 2),
               np.repeat(imat, 3).reshape(-1, 1).astype(np.float64)]
    if split_normals:
        columns.append(corner_normal_indices(inp).reshape(-1, 1).astype(np.float64))
    keys = np.concatenate(columns, 1)
    keys = np.nan_to_num(keys, nan=-1e30)
    uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    vpos = np.ascontiguousarray(ip[uniq[:, 0].astype(np.int64)], dtype=np.float32)
    vuv = np.ascontiguousarray(np.where(uniq[:, 1:3] < -1e29, 0.0, uniq[:, 1:3]), dtype=np.float32)
    idx = np.ascontiguousarray(inverse, dtype=np.uint32)
    f = lib.meshopt_simplifyWithAttributes
    f.restype = ctypes.c_size_t
    f.argtypes = [ctypes.POINTER(ctypes.c_uint), ctypes.POINTER(ctypes.c_uint), ctypes.c_size_t,
                  ctypes.POINTER(ctypes.c_float), ctypes.c_size_t, ctypes.c_size_t,
                  ctypes.POINTER(ctypes.c_float), ctypes.c_size_t,
                  ctypes.POINTER(ctypes.c_float), ctypes.c_size_t,
                  ctypes.POINTER(ctypes.c_ubyte), ctypes.c_size_t, ctypes.c_float, ctypes.c_uint,
                  ctypes.POINTER(ctypes.c_float)]
    dest = np.zeros_like(idx)
    weights = np.array([uv_weight, uv_weight], dtype=np.float32)
    err = ctypes.c_float(0.0)
    fp = ctypes.POINTER(ctypes.c_float)
    up = ctypes.POINTER(ctypes.c_uint)
    n = f(dest.ctypes.data_as(up), idx.ctypes.data_as(up), len(idx),
          vpos.ctypes.data_as(fp), len(vpos), 12, vuv.ctypes.data_as(fp), 8,
          weights.ctypes.data_as(fp), 2, ctypes.POINTER(ctypes.c_ubyte)(), 3 * faces, 1.0, 0,
          ctypes.byref(err))
    res = dest[:n].reshape(-1, 3)
    mat_of = {}
    for tri, m in zip(inverse.reshape(-1, 3), imat):
        for v in tri:
            mat_of[int(v)] = int(m)
    names = {v: k for k, v in inames.items()}
    used = np.unique(res)
    new = {int(v): i + 1 for i, v in enumerate(used)}
    with open(out, "w") as o:
        split = ", split by corner normals" if split_normals else ""
        o.write(f"# meshoptimizer (python 0.2.30a0) simplifyWithAttributes, uv weight {uv_weight}{split}\n")
        for v in used:
            o.write("v %.9g %.9g %.9g\n" % tuple(vpos[v]))
        for v in used:
            o.write("vt %.9g %.9g\n" % tuple(vuv[v]))
        cur = None
        for tri in res:
            m = mat_of[int(tri[0])]
            if m != cur and m in names:
                o.write(f"usemtl {names[m]}\n")
                cur = m
            a, b, c = (new[int(x)] for x in tri)
            o.write(f"f {a}/{a} {b}/{b} {c}/{c}\n")
    print(f"meshoptimizer simplifyWithAttributes: {len(it)} -> {len(res)} triangles "
          f"({len(vpos)} split vertices), error {err.value:.3g}")


if __name__ == "__main__":
    if sys.argv[1] == "measure":
        n = int(sys.argv[4]) if len(sys.argv) > 4 else 200000
        seed = int(sys.argv[5]) if len(sys.argv) > 5 else 1
        r = measure(sys.argv[2], sys.argv[3], n, seed)
        print(f"{sys.argv[3]}: {r['faces']} triangles, texels (1024²) median {r['median']:.3f} "
              f"p90 {r['p90']:.3f} mean {r['mean']:.3f} max {r['max']:.1f}, "
              f"other material {100 * r['other_material']:.2f} %, "
              f"hausdorff {r['hausdorff']:.4e} rms {r['rms']:.4e}")
    elif sys.argv[1] == "meshopt":
        w = float(sys.argv[5]) if len(sys.argv) > 5 else 1.0
        split = len(sys.argv) > 6 and sys.argv[6] == "normals"
        if len(sys.argv) > 6 and not split:
            sys.exit(__doc__)
        meshopt(sys.argv[2], sys.argv[3], int(sys.argv[4]), w, split)
    else:
        sys.exit(__doc__)
