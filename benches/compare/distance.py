"""Symmetric surface distance between two triangle meshes (Metro-style).

usage: python3 distance.py REFERENCE.ply RESULT.ply [SAMPLES=400000] [SEED=1]

Both surfaces are sampled area-uniformly (SAMPLES points each, fixed seed, plus all vertices).
For each sample the distance to the other surface is the exact point-to-triangle distance to
the nearest triangle: the K=32 triangles with the nearest centroids (scipy cKDTree) give an
upper bound, then every triangle whose bounding sphere (centroid, circumradius) comes within it
is checked. (The bound alone overstates distances where big triangles sit next to small ones,
as in a simplified CAD model: 40x on fandisk at 20 %.) Reports, relative
to the reference's bounding-box diagonal:
  hausdorff = max over both directions of the max distance
  rms       = sqrt((mean d^2 reference->result + mean d^2 result->reference) / 2)
"""
import sys
import numpy as np
from scipy.spatial import cKDTree
from plyio import read_ply

K = 32


def sample_barycentric(pos, tris, n, rng):
    """Area-uniform samples: points (n, 3), their triangles and barycentric weights (n, 3)."""
    a, b, c = pos[tris[:, 0]], pos[tris[:, 1]], pos[tris[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    idx = rng.choice(len(tris), size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    bary = np.stack([1 - s, s * (1 - r2), s * r2], 1)
    pts = bary[:, 0, None] * a[idx] + bary[:, 1, None] * b[idx] + bary[:, 2, None] * c[idx]
    return pts, idx, bary


def sample(pos, tris, n, rng):
    """Area-uniform samples plus every vertex a triangle uses."""
    pts, _, _ = sample_barycentric(pos, tris, n, rng)
    return np.concatenate([pts, pos[np.unique(tris)]])


def point_triangle_dist2(p, a, b, c):
    """Squared distance from points p to triangles (a, b, c); all (n, 3)."""
    return ((p - point_triangle_closest(p, a, b, c)) ** 2).sum(1)


def point_triangle_closest(p, a, b, c):
    """Closest point to each of p on triangles (a, b, c); all (n, 3). Ericson, RTCD 5.1.5."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    with np.errstate(divide="ignore", invalid="ignore"):
        v = vb / denom
        w = vc / denom
        q = a + v[:, None] * ab + w[:, None] * ac  # interior
        # edges
        t_ab = d1 / (d1 - d3)
        q_ab = a + t_ab[:, None] * ab
        t_ac = d2 / (d2 - d6)
        q_ac = a + t_ac[:, None] * ac
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        q_bc = b + t_bc[:, None] * (c - b)
    m_a = (d1 <= 0) & (d2 <= 0)
    m_b = (d3 >= 0) & (d4 <= d3)
    m_c = (d6 >= 0) & (d5 <= d6)
    m_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    m_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    m_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    out = q
    # Apply in reverse priority so that the first matching region wins.
    for m, r in [(m_bc, q_bc), (m_ac, q_ac), (m_ab, q_ab), (m_c, c), (m_b, b), (m_a, a)]:
        out = np.where(m[:, None], r, out)
    bad = ~np.isfinite(out).all(axis=1)  # degenerate triangles: nearest corner
    if bad.any():
        corners = np.stack([a[bad], b[bad], c[bad]], 1)
        dd = ((corners - p[bad][:, None, :]) ** 2).sum(-1)
        out[bad] = corners[np.arange(bad.sum()), dd.argmin(1)]
    return out


class TriangleIndex:
    """Triangles (pos, tris) behind a k-d tree of their centroids, with each one's bounding
    sphere (centroid, circumradius bound), for exact nearest-triangle searches."""

    def __init__(self, pos, tris):
        self.pos, self.tris = pos, tris
        self.cent = pos[tris].mean(axis=1)
        self.radius = np.linalg.norm(pos[tris] - self.cent[:, None, :], axis=2).max(1)
        self.tree = cKDTree(self.cent)

    def corners(self, t):
        """The corner positions (a, b, c) of triangles t."""
        tri = self.tris[t]
        return self.pos[tri[:, 0]], self.pos[tri[:, 1]], self.pos[tri[:, 2]]

    def upper_bound(self, points, chunk=20000):
        """Distance to the nearest of the K triangles with the nearest centroids: an upper
        bound of the distance to the surface."""
        out = np.empty(len(points))
        for s in range(0, len(points), chunk):
            p = points[s:s + chunk]
            _, nn = self.tree.query(p, k=min(K, len(self.tris)))
            nn = nn.reshape(len(p), -1)
            best = np.full(len(p), np.inf)
            for j in range(nn.shape[1]):
                best = np.minimum(best, point_triangle_dist2(p, *self.corners(nn[:, j])))
            out[s:s + chunk] = np.sqrt(best)
        return out

    def candidates(self, p, ub, slack=0.0):
        """Pairs (point i, triangle j) whose bounding sphere comes within each point's bound
        ub (times 1 + slack): every triangle that can be the nearest."""
        near = self.tree.query_ball_point(p, ub + self.radius.max())
        ii = np.repeat(np.arange(len(p)), [len(c) for c in near])
        jj = np.concatenate([np.asarray(c, dtype=np.int64) for c in near])
        keep = np.linalg.norm(p[ii] - self.cent[jj], axis=1) <= ub[ii] * (1 + slack) + self.radius[jj]
        return ii[keep], jj[keep]


def distances(points, pos, tris, chunk=5000, pairs=2_000_000):
    """Exact distance from each point to the triangle mesh (pos, tris)."""
    index = TriangleIndex(pos, tris)
    bound = index.upper_bound(points)
    out = bound.copy()
    for s in range(0, len(points), chunk):
        p, ub = points[s:s + chunk], bound[s:s + chunk]
        best = ub ** 2
        ii, jj = index.candidates(p, ub)
        for b in range(0, len(ii), pairs):
            i2 = ii[b:b + pairs]
            d = point_triangle_dist2(p[i2], *index.corners(jj[b:b + pairs]))
            np.minimum.at(best, i2, d)
        out[s:s + chunk] = np.sqrt(best)
    return out


def compare_arrays(rp, rt, sp, st, n=400000, seed=1):
    """compare() on meshes already read: reference (rp, rt), result (sp, st)."""
    h, rms, _, faces = compare_sides(rp, rt, sp, st, n, seed)
    return h, rms, faces


def compare_sides(rp, rt, sp, st, n=400000, seed=1):
    """compare_arrays() plus the one-sided Hausdorff from the result to the reference (does the
    result add surface where the reference has none?), all relative to the reference's
    diagonal: (hausdorff, rms, result_to_reference, result faces)."""
    diag = np.linalg.norm(rp.max(0) - rp.min(0))
    rng = np.random.default_rng(seed)
    d_rs = distances(sample(rp, rt, n, rng), sp, st)
    d_sr = distances(sample(sp, st, n, rng), rp, rt)
    h = max(d_rs.max(), d_sr.max()) / diag
    rms = np.sqrt(0.5 * ((d_rs ** 2).mean() + (d_sr ** 2).mean())) / diag
    return h, rms, d_sr.max() / diag, len(st)


def compare(ref_path, res_path, n=400000, seed=1):
    rp, rt = read_ply(ref_path)
    sp, st = read_ply(res_path)
    return compare_arrays(rp, rt, sp, st, n, seed)


if __name__ == "__main__":
    n = int(sys.argv[3]) if len(sys.argv) > 3 else 400000
    seed = int(sys.argv[4]) if len(sys.argv) > 4 else 1
    h, rms, f = compare(sys.argv[1], sys.argv[2], n, seed)
    print(f"{sys.argv[2]}: {f} triangles, hausdorff {h:.6e}, rms {rms:.6e} (relative to bbox diagonal)")
