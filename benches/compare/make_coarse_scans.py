"""Scanner-output test scans for the coarse levels (docs/coarse-levels.md): vrip-like
reconstructions with many components and holes, marching cubes at several grid sizes, and Poisson
reconstructions of sampled point clouds cropped by density.

usage: python3 make_coarse_scans.py OUTDIR [--meshes DIR] [--only NAME ...]

Deterministic (fixed seeds, no network). Needs numpy, scipy, scikit-image and trimesh; the
Poisson kind also needs open3d (`pip install open3d`; on Debian it wants `libusb-1.0-0`), which is
a measuring tool here, not a dependency. Kinds:

  vrip     a blurred voxelisation of a shared scan (marching cubes at 0.5) cropped at the bottom,
           with HOLES seeded occlusion holes, plus DEBRIS small floating pieces near the surface
           (seeded ellipsoids of 1-3 voxels, some of them cut open by the hole mask) and a little
           seeded normal noise on every vertex: the many components and hole rims of range-scan
           merges
  mc       the closed blurred voxelisation at grid size N (make_mc_scans.py's "vox")
  poisson  open3d screened Poisson (depth D) of POINTS area-uniform samples of a shared scan with
           its normals and seeded noise; the vertices of the lowest-density 8 % are removed, which
           opens holes along the thin parts and leaves non-manifold corners and small islands
Statistics as make_mc_scans.py prints them.
"""
import argparse
import os
import sys
import time

import numpy as np
from scipy import ndimage

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from plyio import read_ply, write_ply  # noqa: E402
import make_mc_scans as mc  # noqa: E402

# (name, kind, source, N or depth, parameters)
SCANS = [
    ("vrip_armadillo_n256", "vrip", "armadillo", 256, {"holes": 50, "debris": 80, "seed": 7}),
    ("vrip_bunny_n224", "vrip", "bunny", 224, {"holes": 70, "debris": 100, "seed": 11}),
    ("mc_armadillo_vox96", "mc", "armadillo", 96, {}),
    ("mc_armadillo_vox160", "mc", "armadillo", 160, {}),
    ("mc_bunny_vox128", "mc", "bunny", 128, {}),
    ("poisson_armadillo_d8", "poisson", "armadillo", 8, {"points": 200000, "seed": 3}),
    ("poisson_bunny_d8", "poisson", "bunny", 8, {"points": 200000, "seed": 5}),
]


def make_vrip(mesh_path, n, holes, debris, seed, crop=0.12):
    occ, origin, pitch = mc.voxel_occupancy(mesh_path, n, pad=6)
    vol = ndimage.gaussian_filter(occ, 1.0)
    ys = np.nonzero(occ.any(axis=(0, 2)))[0]
    cut = int(ys[0] + crop * (ys[-1] - ys[0]))
    vol = np.ascontiguousarray(vol[:, cut:, :])
    origin = origin + np.array([0.0, cut * pitch, 0.0])
    rng = np.random.default_rng(seed)
    # Debris: small ellipsoids a few voxels outside the surface (stray range samples merged into
    # separate pieces).
    outside = np.argwhere((vol > 0.01) & (vol < 0.05))
    outside = outside[outside[:, 1] > 6]
    for c in outside[rng.choice(len(outside), size=debris, replace=False)]:
        ax = rng.uniform(1.0, 3.0, 3)
        lo = np.maximum(c - 5, 0)
        hi = np.minimum(c + 6, vol.shape)
        sl = tuple(slice(a, b) for a, b in zip(lo, hi))
        og = np.ogrid[sl]
        d2 = sum(((g - ci) / a) ** 2 for g, ci, a in zip(og, c, ax))
        vol[sl] = np.maximum(vol[sl], np.exp(-d2) * 0.9)
    near = np.argwhere((vol > 0.3) & (vol < 0.7))
    near = near[near[:, 1] > 6]
    mask = np.ones(vol.shape, dtype=bool)
    for c in near[rng.choice(len(near), size=holes, replace=False)]:
        r = rng.uniform(1.5, 4.0) * n / 64.0
        lo = np.maximum(c - int(r) - 1, 0)
        hi = np.minimum(c + int(r) + 2, vol.shape)
        sl = tuple(slice(a, b) for a, b in zip(lo, hi))
        og = np.ogrid[sl]
        d2 = sum((g - ci) ** 2 for g, ci in zip(og, c))
        mask[sl] &= d2 > r * r
    v, f = mc._marching_cubes(vol, 0.5, mask=mask)
    pos = origin + v * pitch
    # Range noise: a fraction of the voxel size along random directions.
    pos += rng.normal(0.0, 0.05 * pitch, pos.shape)
    return pos, f


def make_poisson(mesh_path, depth, points, seed, crop=0.08):
    import open3d as o3d
    import trimesh
    pos, tris = read_ply(mesh_path)
    m = trimesh.Trimesh(pos, tris, process=False)
    rng = np.random.default_rng(seed)
    pts, fid = trimesh.sample.sample_surface(m, points, seed=int(rng.integers(1 << 31)))
    nrm = m.face_normals[fid]
    diag = float(np.linalg.norm(m.extents))
    pts = pts + rng.normal(0.0, 5e-4 * diag, pts.shape)
    # Real scans see some parts from fewer views: thin out a band so the density crop opens it.
    keep = rng.uniform(size=len(pts)) > np.clip((pts[:, 1] - pts[:, 1].min()) / (np.ptp(pts[:, 1])) - 0.7,
                                                 0, 1) * 2.5
    pts, nrm = pts[keep], nrm[keep]
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
    pcd.normals = o3d.utility.Vector3dVector(nrm)
    mesh, dens = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(pcd, depth=depth, n_threads=1)
    dens = np.asarray(dens)
    mesh.remove_vertices_by_mask(dens < np.quantile(dens, crop))
    mesh.remove_unreferenced_vertices()
    return np.asarray(mesh.vertices), np.asarray(mesh.triangles, dtype=np.int64)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--meshes", default=mc.DEFAULT_MESHES)
    ap.add_argument("--only", nargs="+")
    args = ap.parse_args()
    os.makedirs(args.outdir, exist_ok=True)
    print(mc.HEADER)
    for name, kind, src, n, kw in SCANS:
        if args.only and name not in args.only:
            continue
        path = os.path.join(args.meshes, src + ".ply")
        t0 = time.perf_counter()
        if kind == "vrip":
            pos, tris = make_vrip(path, n, **kw)
        elif kind == "mc":
            pos, tris = mc.make_vox(path, n)
        else:
            pos, tris = make_poisson(path, n, **kw)
        if kind != "poisson" and mc.signed_volume(pos, tris) < 0:
            tris = tris[:, ::-1].copy()
        out = os.path.join(args.outdir, name + ".ply")
        write_ply(out, pos, tris)
        s = mc.mesh_stats(pos, tris)
        print(mc.row(name + ".ply", kind, n, s, os.path.getsize(out)), flush=True)
        print(f"  ({name}: {time.perf_counter() - t0:.1f} s, source: {mc.SOURCES[src]})", file=sys.stderr,
              flush=True)


if __name__ == "__main__":
    main()
