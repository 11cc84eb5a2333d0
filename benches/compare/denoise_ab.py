"""E_n and E_v of `meshpyr smooth` (default method) for several binaries or `--reach` values on
the cases of denoise_table.py (same meshes, same seeded noises), one Markdown row per case:

    python3 denoise_ab.py [--meshes bunny fandisk ...] [--] LABEL=BINARY[@REACH] ...

The first configuration's binary also measures (`meshpyr compare OUT CLEAN --json`). Meshes come
from $MESHPYR_MESHES (default /work/shared/data/meshes), as in denoise_table.py.
"""
import os
import subprocess
import sys
import tempfile
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from denoise_table import MESHES, NOISES, add_noise, errors  # noqa: E402
from plyio import read_ply, write_ply  # noqa: E402


def main():
    args = sys.argv[1:]
    meshes = MESHES
    if args and args[0] == "--meshes":
        end = args.index("--") if "--" in args else len(args)
        meshes, args = args[1:end], args[end:]
    configs = []
    for a in (a for a in args if a != "--"):
        label, rest = a.split("=", 1)
        binary, _, reach = rest.partition("@")
        configs.append((label, binary, reach))
    if not configs:
        sys.exit(__doc__)
    measure = configs[0][1]
    meshes_dir = os.environ.get("MESHPYR_MESHES", "/work/shared/data/meshes")
    workdir = tempfile.mkdtemp()
    print("| mesh | noise | noisy E_n · E_v | "
          + " | ".join(f"{c[0]} E_n · E_v" for c in configs) + " |")
    print("|---|---|---|" + "---|" * len(configs))
    for mesh in meshes:
        clean = os.path.join(meshes_dir, mesh + ".ply")
        pos, tris = read_ply(clean)
        for noise in NOISES:
            seed = zlib.crc32(f"{mesh}/{noise}".encode())
            noisy = os.path.join(workdir, "noisy.ply")
            write_ply(noisy, add_noise(pos, tris, noise, seed), tris)
            row = [errors(measure, noisy, clean)]
            for _, binary, reach in configs:
                out = os.path.join(workdir, "out.ply")
                extra = ["--reach", reach] if reach else []
                subprocess.run([binary, "-q", "smooth", noisy, "-o", out] + extra, check=True)
                row.append(errors(measure, out, clean))
            print(f"| {mesh} | {noise} | "
                  + " | ".join(f"{a:.4f} · {b:.4f}" for a, b in row) + " |", flush=True)


if __name__ == "__main__":
    main()
