"""MeshLab's TwoStep smoothing (Belyaev-Ohtake: iterated normal filtering + vertex fitting),
through pymeshlab, as an extra column of the README's denoising table.

    python3 twostep.py NOISY.ply OUT.ply [stepsmoothnum normalthr stepnormalnum stepfitnum]

Defaults are MeshLab's own (3, 60, 20, 20). Prints the wall time of the filter call only.
Needs `pip install pymeshlab` (not a dependency of the project).
"""
import sys
import time

import pymeshlab as ml


def main():
    src, dst = sys.argv[1], sys.argv[2]
    smooth, thr, normal, fit = 3, 60.0, 20, 20
    if len(sys.argv) > 3:
        smooth, thr, normal, fit = int(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6])
    ms = ml.MeshSet()
    ms.load_new_mesh(src)
    start = time.perf_counter()
    ms.apply_coord_two_steps_smoothing(
        stepsmoothnum=smooth, normalthr=thr, stepnormalnum=normal, stepfitnum=fit
    )
    elapsed = time.perf_counter() - start
    ms.save_current_mesh(dst, binary=True, save_vertex_color=False, save_face_color=False)
    print(f"{elapsed:.3f} s")


if __name__ == "__main__":
    main()
