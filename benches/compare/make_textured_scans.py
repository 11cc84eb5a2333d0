#!/usr/bin/env python3
"""Makes textured test scans the way photogrammetry and scanner software write them.

From an untextured PLY scan: a UV atlas by xatlas (charts with seams), two materials (the
faces left and right of the median x, each with its own generated PNG image), two OBJ groups
(below and above the median y), one object, and per-corner normals that keep the scan's hard
edges (corners of faces meeting at more than 30 degrees get separate normals). Written twice:

- OBJ + MTL + PNG: `NAME.obj` (`mtllib`, `o`, `g`, `usemtl`, `s`, `f v/vt/vn`), `NAME.mtl`
  and `textures/left.png`, `textures/right.png`;
- PLY as MeshLab writes it: ASCII, `comment TextureFile` per image, a per-face
  `list uchar float texcoord` and an `int texnumber`.

xatlas (pip) is a measuring tool only: the tests read the committed outputs of this script
(tests/data/textured/, made from anchor.ply) and never need it.

    python3 benches/compare/make_textured_scans.py tests/data/anchor.ply tests/data/textured anchor_tex
"""

import sys
import zlib
import struct
from pathlib import Path

import numpy as np
import xatlas

sys.path.insert(0, str(Path(__file__).parent))
from plyio import read_ply  # noqa: E402


def png(path, size, seed):
    """A checkerboard with a colour gradient: any texture-space error shows as broken squares."""
    y, x = np.mgrid[0:size, 0:size]
    check = ((x // 16 + y // 16) % 2).astype(np.uint8)
    r = (x * 255 // size).astype(np.uint8)
    g = (y * 255 // size).astype(np.uint8)
    b = np.full_like(r, 60 + 120 * seed)
    img = np.stack([r, g, b], axis=-1)
    img[check == 1] //= 2
    raw = b"".join(b"\0" + img[i].tobytes() for i in range(size))

    def chunk(kind, data):
        c = struct.pack(">I", len(data)) + kind + data
        return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    head = struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", head)
                     + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def corner_normals(v, f, angle_deg=30.0):
    """Per-corner normals: at each vertex, faces joined across edges whose dihedral angle is
    below `angle_deg` share one area-weighted normal. Returns (pool, per-corner index)."""
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    unit = fn / np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-300)
    cos_limit = np.cos(np.radians(angle_deg))
    edge_faces = {}
    for fi, tri in enumerate(f):
        for k in range(3):
            a, b = sorted((tri[k], tri[(k + 1) % 3]))
            edge_faces.setdefault((a, b), []).append(fi)
    around = {}
    for fi, tri in enumerate(f):
        for k in range(3):
            around.setdefault(tri[k], []).append(fi)
    pool, index = [], np.zeros(f.shape, dtype=np.int64)
    for vert, faces in around.items():
        parent = {fi: fi for fi in faces}

        def find(x):
            while parent[x] != x:
                parent[x] = parent[parent[x]]
                x = parent[x]
            return x
        for fi in faces:
            for k in range(3):
                a, b = f[fi][k], f[fi][(k + 1) % 3]
                if vert not in (a, b):
                    continue
                for fj in edge_faces[tuple(sorted((a, b)))]:
                    if fj in parent and fj != fi and unit[fi] @ unit[fj] > cos_limit:
                        parent[find(fi)] = find(fj)
        clusters = {}
        for fi in faces:
            clusters.setdefault(find(fi), []).append(fi)
        for members in clusters.values():
            n = fn[members].sum(axis=0)
            n /= max(np.linalg.norm(n), 1e-300)
            pool.append(n)
            for fi in members:
                index[fi][list(f[fi]).index(vert)] = len(pool) - 1
    return np.array(pool), index


def g(x):
    return f"{float(np.float32(x)):.9g}"


def main(src, out_dir, name):
    out_dir = Path(out_dir)
    (out_dir / "textures").mkdir(parents=True, exist_ok=True)
    v, f = read_ply(src)
    v = np.asarray(v, dtype=np.float64)
    f = np.asarray(f, dtype=np.int64)
    vmap, uv_faces, uvs = xatlas.parametrize(v.astype(np.float32), f.astype(np.uint32))
    assert (vmap[uv_faces] == f).all(), "xatlas keeps faces and their corner order"
    normals, n_index = corner_normals(v, f)
    centre = v[f].mean(axis=1)
    material = (centre[:, 0] > np.median(centre[:, 0])).astype(int)
    group = (centre[:, 1] > np.median(centre[:, 1])).astype(int)
    images = ["textures/left.png", "textures/right.png"]
    for i, img in enumerate(images):
        png(out_dir / img, 64, i)
    (out_dir / f"{name}.mtl").write_text(
        "".join(f"newmtl {m}\nKd 1 1 1\nmap_Kd {img}\n"
                for m, img in zip(["left", "right"], images)))
    lines = [f"# textured test scan made by make_textured_scans.py from {Path(src).name}",
             f"mtllib {name}.mtl", f"o {name}"]
    lines += [f"v {g(p[0])} {g(p[1])} {g(p[2])}" for p in v]
    lines += [f"vt {g(t[0])} {g(t[1])}" for t in uvs]
    lines += [f"vn {g(n[0])} {g(n[1])} {g(n[2])}" for n in normals]
    state = (None, None)
    for fi, tri in enumerate(f):
        if (group[fi], material[fi]) != state:
            lines += [f"g {['low', 'high'][group[fi]]}", f"usemtl {['left', 'right'][material[fi]]}",
                      "s 1"]
            state = (group[fi], material[fi])
        lines.append("f " + " ".join(f"{tri[k] + 1}/{uv_faces[fi][k] + 1}/{n_index[fi][k] + 1}"
                                     for k in range(3)))
    (out_dir / f"{name}.obj").write_text("\n".join(lines) + "\n")
    head = ["ply", "format ascii 1.0", "comment made by make_textured_scans.py"]
    head += [f"comment TextureFile {img}" for img in images]
    head += [f"element vertex {len(v)}", "property float x", "property float y", "property float z",
             f"element face {len(f)}", "property list uchar int vertex_indices",
             "property list uchar float texcoord", "property int texnumber", "end_header"]
    body = [f"{g(p[0])} {g(p[1])} {g(p[2])}" for p in v]
    for fi, tri in enumerate(f):
        tc = " ".join(f"{g(uvs[uv_faces[fi][k]][0])} {g(uvs[uv_faces[fi][k]][1])}" for k in range(3))
        body.append(f"3 {tri[0]} {tri[1]} {tri[2]} 6 {tc} {material[fi]}")
    (out_dir / f"{name}.ply").write_text("\n".join(head + body) + "\n")
    print(f"{name}: {len(v)} vertices, {len(f)} faces, {len(uvs)} vt ({len(uvs) - len(v)} "
          f"more than vertices: seams), {len(normals)} vn, 2 materials")


if __name__ == "__main__":
    main(*sys.argv[1:4])
