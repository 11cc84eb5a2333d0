"""MeshLab's coordinate unsharp mask through pymeshlab (`pip install pymeshlab`), as a whole
process: load, filter, save. The peer of `meshpyr filter --enhance` in the scale table of
docs/performance.md; time it with GNU time (`/usr/bin/time -f "%e s %M KB"`).

usage: python3 meshlab_unsharp.py IN.ply OUT.ply [WEIGHT=0.3] [ITERATIONS=5]
"""
import sys
import pymeshlab


def main():
    src, dst = sys.argv[1], sys.argv[2]
    weight = float(sys.argv[3]) if len(sys.argv) > 3 else 0.3
    iterations = int(sys.argv[4]) if len(sys.argv) > 4 else 5
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(src)
    ms.apply_coord_unsharp_mask(weight=weight, weightorig=1.0, iterations=iterations)
    ms.save_current_mesh(dst, binary=True, save_vertex_normal=False, save_vertex_color=False)
    m = ms.current_mesh()
    print(f"{dst}: {m.vertex_number()} vertices, {m.face_number()} faces")


if __name__ == "__main__":
    main()
