"""Makes the big benchmark mesh: midpoint (1-to-4, no smoothing) subdivision of a PLY mesh,
repeated K times, plus isotropic Gaussian noise of sigma = NOISE x the final mean edge length
(seeded), so that the result is not piecewise planar (which would make QEM ties everywhere).

usage: python3 make_big.py IN.ply OUT.ply [K=2] [NOISE=0.05]
"""
import sys
import numpy as np
from plyio import read_ply, write_ply


def midpoint_subdivide(pos, tris):
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    key = np.sort(e, axis=1)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    mid = 0.5 * (pos[uniq[:, 0]] + pos[uniq[:, 1]])
    n, m = len(pos), len(tris)
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    ab, bc, ca = n + inv[:m], n + inv[m:2 * m], n + inv[2 * m:]
    new = np.concatenate([np.stack([a, ab, ca], 1), np.stack([ab, b, bc], 1),
                          np.stack([ca, bc, c], 1), np.stack([ab, bc, ca], 1)])
    return np.concatenate([pos, mid]), new


def main():
    src, dst = sys.argv[1], sys.argv[2]
    k = int(sys.argv[3]) if len(sys.argv) > 3 else 2
    noise = float(sys.argv[4]) if len(sys.argv) > 4 else 0.05
    pos, tris = read_ply(src)
    for _ in range(k):
        pos, tris = midpoint_subdivide(pos, tris)
    e = pos[tris[:, 1]] - pos[tris[:, 0]]
    mean_edge = np.linalg.norm(e, axis=1).mean()
    rng = np.random.default_rng(12345)
    pos = pos + rng.normal(scale=noise * mean_edge, size=pos.shape)
    write_ply(dst, pos, tris)
    print(f"{dst}: {len(pos)} vertices, {len(tris)} triangles, noise sigma {noise * mean_edge:.4g}")


if __name__ == "__main__":
    main()
