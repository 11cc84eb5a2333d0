"""Marching-cubes test scans: the meshes that voxel scanners and reconstruction pipelines emit.

usage: python3 make_mc_scans.py OUTDIR (--small | --big) [--meshes DIR] [--only NAME ...]
       python3 make_mc_scans.py --stats FILE.ply [FILE.ply ...]

Deterministic (fixed seeds, no network); needs numpy, scipy, scikit-image and trimesh. Writes
binary PLY (plyio.write_ply: float32 x/y/z, uchar/int triangles) and prints one markdown row of
statistics per file (also for --stats). Kinds:

  vox     a closed shared scan voxelised with trimesh (pitch = longest bbox side / N), filled,
          padded, occupancy blurred with a Gaussian (sigma 1 voxel), skimage marching cubes at
          0.5, scaled back to world units: the classic "voxelised scan"
  raw     the same without the blur: binary occupancy, every vertex at an edge midpoint, a pure
          staircase (large coplanar patches)
  quant   the blurred occupancy quantised to Q levels (as an integer CT/density volume) and
          marching cubes at an integer level with allow_degenerate=True: grid samples exactly on
          the level give coincident vertices (distinct indices, same position) and zero-area
          triangles - the degenerate class
  open    "vrip-like" open scan: blurred voxelisation cropped on one side (the unseen bottom)
          and with seeded ball-shaped occlusion holes (marching cubes' mask), so the surface has
          boundary loops
  implicit analytic: bumpy sphere, union a torus handle, minus a tunnel, union 30 seeded small
          floating blobs, sampled on an N^3 grid over [-1.5, 1.5]^3, marching cubes at 0:
          many components (blobs below the grid spacing vanish or become tiny), genus 2

Statistics: V, F, components (edge-connected through shared vertices), boundary loops
(components of the boundary-edge graph), manifold (no edge with > 2 faces, no vertex whose faces
form more than one fan, no face repeating a vertex), genus (sum over components of
(2 - chi - loops) / 2, only if manifold), zero-area faces (area <= 1e-12 x bbox diagonal^2, from
the float32 positions as written) and faces of quality 4 sqrt(3) A / (l0^2 + l1^2 + l2^2) < 0.05.
"""
import argparse
import os
import sys
import time

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plyio import read_ply, write_ply  # noqa: E402

DEFAULT_MESHES = "/work/shared/data/meshes"
SOURCES = {  # provenance, as in the shared data README
    "bunny": "shared `meshes/bunny.ply`: Stanford bunny (closed, 37.7k V), libcgal-demo 5.5.1-2, CC0-1.0; "
             "originally Stanford 3D Scanning Repository",
    "armadillo": "shared `meshes/armadillo.ply`: Stanford Armadillo (closed, 26k V), libcgal-demo 5.5.1-2, "
                 "CC0-1.0; originally Stanford 3D Scanning Repository",
    "fandisk": "shared `meshes/fandisk.ply`: fandisk CAD part (closed, 6.5k V), libcgal-demo 5.5.1-2, CC0-1.0",
    None: "analytic, generated",
}

# (name, kind, source mesh or None, grid size N, extra parameters)
SMALL = [
    ("mc_bunny_vox40", "vox", "bunny", 40, {}),
    ("mc_armadillo_vox52", "vox", "armadillo", 52, {}),
    ("mc_fandisk_raw40", "raw", "fandisk", 40, {}),
    ("mc_bunny_quant36", "quant", "bunny", 36, {"levels": 16}),
    ("mc_armadillo_open52", "open", "armadillo", 52, {"holes": 6, "crop": 0.15}),
    ("mc_implicit_n40", "implicit", None, 40, {}),
    ("mc_implicit_n56", "implicit", None, 56, {}),
]
BIG = [
    ("mc_bunny_vox96", "vox", "bunny", 96, {}),
    ("mc_bunny_vox186", "vox", "bunny", 186, {}),          # ~120k vertices
    ("mc_armadillo_vox192", "vox", "armadillo", 192, {}),
    ("mc_bunny_vox336", "vox", "bunny", 336, {}),          # ~800k faces
    ("mc_fandisk_raw192", "raw", "fandisk", 192, {}),
    ("mc_bunny_quant192", "quant", "bunny", 192, {"levels": 16}),
    ("mc_armadillo_open192", "open", "armadillo", 192, {"holes": 12, "crop": 0.15}),
    ("mc_implicit_n64", "implicit", None, 64, {}),
    ("mc_implicit_n100", "implicit", None, 100, {}),
    ("mc_implicit_n200", "implicit", None, 200, {}),
    ("mc_implicit_n430", "implicit", None, 430, {}),       # ~800k faces
]


# ----------------------------------------------------------------------------------------------
# generators

def _marching_cubes(vol, level, **kw):
    from skimage import measure
    verts, faces, _, _ = measure.marching_cubes(vol, level, **kw)
    return verts.astype(np.float64), faces.astype(np.int64)


def voxel_occupancy(mesh_path, n, pad=3):
    """Filled occupancy (float32, padded) and the index -> world map (origin, pitch)."""
    import trimesh
    pos, tris = read_ply(mesh_path)
    mesh = trimesh.Trimesh(pos, tris, process=False)
    pitch = float(mesh.extents.max()) / n
    vg = trimesh.voxel.creation.voxelize(mesh, pitch).fill()
    occ = np.pad(vg.matrix.astype(np.float32), pad)
    scale = vg.transform[:3, :3].diagonal()
    assert np.allclose(scale, pitch) and np.allclose(vg.transform[:3, :3], np.diag(scale))
    origin = vg.transform[:3, 3] - pad * pitch  # world position of index (0, 0, 0)
    return occ, origin, pitch


def make_vox(mesh_path, n, raw=False):
    occ, origin, pitch = voxel_occupancy(mesh_path, n)
    vol = occ if raw else ndimage.gaussian_filter(occ, 1.0)
    v, f = _marching_cubes(vol, 0.5)
    return origin + v * pitch, f


def make_quant(mesh_path, n, levels=16):
    occ, origin, pitch = voxel_occupancy(mesh_path, n)
    vol = np.round(ndimage.gaussian_filter(occ, 1.0) * levels).astype(np.float32)
    v, f = _marching_cubes(vol, float(levels // 2), allow_degenerate=True)
    return origin + v * pitch, f


def make_open(mesh_path, n, holes=6, crop=0.15, seed=4242):
    """Blurred voxelisation, bottom (lowest `crop` of the object's y extent, y = up for the
    armadillo and bunny) cut off, plus `holes` occlusion holes: balls of radius 2-4 voxels around
    seeded near-surface voxels are masked out of marching cubes."""
    occ, origin, pitch = voxel_occupancy(mesh_path, n)
    vol = ndimage.gaussian_filter(occ, 1.0)
    ys = np.nonzero(occ.any(axis=(0, 2)))[0]
    cut = int(ys[0] + crop * (ys[-1] - ys[0]))
    vol = np.ascontiguousarray(vol[:, cut:, :])
    origin = origin + np.array([0.0, cut * pitch, 0.0])
    rng = np.random.default_rng(seed)
    near = np.argwhere((vol > 0.3) & (vol < 0.7))
    near = near[near[:, 1] > 6]  # not on the cut
    mask = np.ones(vol.shape, dtype=bool)
    grid = np.indices(vol.shape, sparse=True)
    for c in near[rng.choice(len(near), size=holes, replace=False)]:
        r = rng.uniform(2.0, 4.0) * n / 56.0 if n > 56 else rng.uniform(2.0, 4.0)
        d2 = sum((g - ci) ** 2 for g, ci in zip(grid, c))
        mask[d2 <= r * r] = False
    v, f = _marching_cubes(vol, 0.5, mask=mask)
    return origin + v * pitch, f


def implicit_field(n, seed=2024, lim=1.5):
    """Inside-positive float32 field on an n^3 grid over [-lim, lim]^3, and the grid spacing."""
    t = np.linspace(-lim, lim, n, dtype=np.float32)
    x, y, z = np.meshgrid(t, t, t, indexing="ij", sparse=True)
    r = np.sqrt(x * x + y * y + z * z)
    d = r - (0.8 + 0.06 * np.sin(7 * x) * np.sin(7 * y) * np.sin(7 * z))  # bumpy sphere
    del r
    tx = np.sqrt((x - 0.85) ** 2 + z * z) - 0.42  # torus around the y axis through x = 0.85
    np.minimum(d, np.sqrt(tx * tx + y * y) - 0.11, out=d)  # union the handle
    del tx
    np.maximum(d, 0.16 - np.sqrt((x + 0.3) ** 2 + (y - 0.15) ** 2), out=d)  # minus a z tunnel
    rng = np.random.default_rng(seed)
    blobs = 0
    while blobs < 30:
        c = rng.uniform(-1.3, 1.3, 3)
        rad = rng.uniform(0.03, 0.12)
        if np.linalg.norm(c) < 1.0 + rad or np.hypot(np.hypot(c[0] - 0.85, c[2]) - 0.42, c[1]) < 0.2 + rad:
            continue  # keep the blobs off the body and the handle: floating
        ax = rng.uniform(0.7, 1.4, 3)  # ellipsoids
        # evaluated within +-0.5 of the centre only: beyond, the blob's value (> 0.23) is above
        # any value that matters near a crossing on grids of N >= 40
        sl = tuple(slice(np.searchsorted(t, ci - 0.5), np.searchsorted(t, ci + 0.5)) for ci in c)
        xs, ys, zs = x[sl[0], :, :], y[:, sl[1], :], z[:, :, sl[2]]
        e = np.sqrt(((xs - c[0]) / ax[0]) ** 2 + ((ys - c[1]) / ax[1]) ** 2 + ((zs - c[2]) / ax[2]) ** 2) - rad
        np.minimum(d[sl], e, out=d[sl])
        blobs += 1
    np.negative(d, out=d)
    return d, float(t[1] - t[0]), -lim


def make_implicit(n):
    vol, h, lo = implicit_field(n)
    v, f = _marching_cubes(vol, 0.0)
    return lo + v * h, f


# ----------------------------------------------------------------------------------------------
# statistics

def _cc(n, a, b):
    g = coo_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(n, n))
    return connected_components(g, directed=False)


def mesh_stats(pos, tris):
    pos = np.asarray(pos, dtype=np.float32).astype(np.float64)  # as written
    tris = np.asarray(tris, dtype=np.int64)
    nv, nf = len(pos), len(tris)
    out = {"V": nv, "F": nf}
    p = pos[tris]
    e0, e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2]
    area = 0.5 * np.linalg.norm(np.cross(e0, -e2), axis=1)
    l2 = (e0 ** 2).sum(1) + (e1 ** 2).sum(1) + (e2 ** 2).sum(1)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(l2 > 0, 4 * np.sqrt(3) * area / l2, 0.0)
    used = np.unique(tris)
    diag = float(np.linalg.norm(pos[used].max(0) - pos[used].min(0))) if nf else 0.0
    out["zero_area"] = int((area <= 1e-12 * diag * diag).sum())
    out["q_lt_0.05"] = int((q < 0.05).sum())
    out["min_q"] = float(q.min()) if nf else 0.0
    out["coincident_verts"] = int(len(used) - len(np.unique(pos[used], axis=0)))
    rep = (tris[:, 0] == tris[:, 1]) | (tris[:, 1] == tris[:, 2]) | (tris[:, 2] == tris[:, 0])
    out["repeated_index_faces"] = int(rep.sum())
    out["unused_verts"] = int(nv - len(used))

    # half-edges (face f, corner k -> k+1) and undirected edge keys
    a = tris.reshape(-1)
    b = tris[:, [1, 2, 0]].reshape(-1)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    key = lo * nv + hi
    order = np.argsort(key, kind="stable")
    ks = key[order]
    start = np.r_[True, ks[1:] != ks[:-1]]
    gid = np.cumsum(start) - 1
    counts = np.bincount(gid)
    edge_count = counts[gid]  # per sorted half-edge
    ne = len(counts)
    uniq_lo, uniq_hi = lo[order][start], hi[order][start]
    bnd = counts == 1
    out["E"] = int(ne)
    out["boundary_edges"] = int(bnd.sum())
    out["nonmanifold_edges"] = int((counts > 2).sum())
    # orientation: the two half-edges of a manifold edge should run opposite ways
    same_dir = (a[order][1:] == a[order][:-1]) & (ks[1:] == ks[:-1]) & (edge_count[1:] == 2)
    out["misoriented_edges"] = int(same_dir.sum())

    # components over vertices (only used ones count)
    ncomp_all, vlab = _cc(nv, uniq_lo, uniq_hi)
    comp_ids, vcomp = np.unique(vlab[used], return_inverse=True)
    remap = np.full(ncomp_all, -1)
    remap[comp_ids] = np.arange(len(comp_ids))
    c_of_v = remap[vlab]
    nc = len(comp_ids)
    out["components"] = int(nc)
    Vc = np.bincount(c_of_v[used], minlength=nc)
    Ec = np.bincount(c_of_v[uniq_lo], minlength=nc)
    Fc = np.bincount(c_of_v[tris[:, 0]], minlength=nc)
    chi = Vc - Ec + Fc

    # boundary loops: components of the boundary-edge graph
    bl, bh = uniq_lo[bnd], uniq_hi[bnd]
    if len(bl):
        bverts = np.unique(np.r_[bl, bh])
        idx = np.searchsorted(bverts, np.r_[bl, bh])
        nloops, llab = _cc(len(bverts), idx[:len(bl)], idx[len(bl):])
        first = np.zeros(nloops, dtype=np.int64)
        first[llab] = bverts  # any vertex of each loop
        loops_c = np.bincount(c_of_v[first], minlength=nc)
    else:
        nloops, loops_c = 0, np.zeros(nc, dtype=np.int64)
    out["boundary_loops"] = int(nloops)

    # non-manifold vertices: corners (f, k) of one vertex joined across each shared edge; more
    # than one group of corners around a vertex = more than one fan
    # half-edge h = 3f + k starts at corner 3f + k and ends at corner 3f + (k+1)%3
    same = ks[1:] == ks[:-1]
    h0, h1 = order[:-1][same], order[1:][same]
    ca0, cb0 = h0, (h0 // 3) * 3 + (h0 % 3 + 1) % 3
    ca1, cb1 = h1, (h1 // 3) * 3 + (h1 % 3 + 1) % 3
    # pair corners of the same vertex
    u0 = np.where(a[ca0] == a[ca1], ca1, cb1)  # corner of h1 at vertex a[ca0]
    w0 = np.where(a[ca0] == a[ca1], cb1, ca1)
    nco = 3 * nf
    _, clab = _cc(nco, np.r_[ca0, cb0], np.r_[u0, w0])
    fans = np.unique(a * nco + clab)  # (vertex, corner group) pairs; a[c] = vertex of corner c
    fans_per_v = np.bincount(fans // nco, minlength=nv)
    out["nonmanifold_verts"] = int((fans_per_v > 1).sum())

    manifold = out["nonmanifold_edges"] == 0 and out["nonmanifold_verts"] == 0 and rep.sum() == 0
    out["manifold"] = bool(manifold)
    if manifold:
        g2 = 2 - chi - loops_c
        out["genus"] = int(g2.sum() // 2) if np.all(g2 % 2 == 0) else None
    else:
        out["genus"] = None
    out["bbox_diag"] = diag
    return out


HEADER = ("| file | kind | N | V | F | components | boundary loops | manifold | genus | zero-area | "
          "q < 0.05 | coincident V | bytes |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|")


def row(name, kind, n, s, nbytes):
    g = "-" if s["genus"] is None else str(s["genus"])
    man = "yes" if s["manifold"] else "no (nm edges %d, nm verts %d)" % (s["nonmanifold_edges"], s["nonmanifold_verts"])
    return (f"| {name} | {kind} | {n} | {s['V']} | {s['F']} | {s['components']} | {s['boundary_loops']} | "
            f"{man} | {g} | {s['zero_area']} | {s['q_lt_0.05']} | {s['coincident_verts']} | {nbytes} |")


def signed_volume(pos, tris):
    p = pos[tris]
    return np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0


def generate(spec, outdir, meshes):
    name, kind, src, n, kw = spec
    path = os.path.join(meshes, src + ".ply") if src else None
    t0 = time.perf_counter()
    if kind == "vox":
        pos, tris = make_vox(path, n)
    elif kind == "raw":
        pos, tris = make_vox(path, n, raw=True)
    elif kind == "quant":
        pos, tris = make_quant(path, n, **kw)
    elif kind == "open":
        pos, tris = make_open(path, n, **kw)
    elif kind == "implicit":
        pos, tris = make_implicit(n)
    else:
        raise ValueError(kind)
    # marching cubes' winding is inward for these volumes in some skimage versions: make the
    # closed surfaces outward (positive signed volume); open ones follow the same rule
    if signed_volume(pos, tris) < 0:
        tris = tris[:, ::-1].copy()
    out = os.path.join(outdir, name + ".ply")
    write_ply(out, pos, tris)
    dt = time.perf_counter() - t0
    s = mesh_stats(pos, tris)
    return out, s, dt


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir", nargs="?")
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--small", action="store_true", help="the test-data set (each file < 300 KB)")
    mode.add_argument("--big", action="store_true", help="medium and ~800k-face meshes for benchmarks")
    mode.add_argument("--stats", nargs="+", metavar="PLY", help="only print the statistics of these files")
    ap.add_argument("--meshes", default=DEFAULT_MESHES, help="directory of the shared meshes")
    ap.add_argument("--only", nargs="+", help="generate only these names")
    ap.add_argument("--json", help="also write the statistics here")
    args = ap.parse_args()
    results = []
    if args.stats:
        print(HEADER)
        for p in args.stats:
            pos, tris = read_ply(p)
            s = mesh_stats(pos, tris)
            print(row(os.path.basename(p), "-", "-", s, os.path.getsize(p)), flush=True)
            results.append({"file": p, **s})
    else:
        if not args.outdir:
            ap.error("OUTDIR is required")
        os.makedirs(args.outdir, exist_ok=True)
        specs = SMALL if args.small else BIG
        if args.only:
            specs = [s for s in specs if s[0] in args.only]
        print(HEADER)
        for spec in specs:
            out, s, dt = generate(spec, args.outdir, args.meshes)
            print(row(spec[0] + ".ply", spec[1], spec[3], s, os.path.getsize(out)), flush=True)
            print(f"  ({spec[0]}: {dt:.1f} s, source: {SOURCES[spec[2]]})", file=sys.stderr, flush=True)
            results.append({"file": out, "kind": spec[1], "source": spec[2], "N": spec[3],
                            "params": spec[4], "seconds": dt, **s})
    if args.json:
        import json
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
