"""Ours vs meshoptimizer at equal face counts: Hausdorff, RMS and time per mesh and ratio.

usage: python3 pm_table.py MESH [MESH ...] [--ratios 0.003 0.01 0.05 0.10] [--lowpass 0.005]
                           [--repeats 3] [--samples 200000] [--seed 1] [--json OUT.json]
                           [--workdir DIR] [--timeout 900] [--keep]

For each mesh and ratio R:
  ours  `$MESHPYR simplify MESH -o OUT.ply --ratio R -q` (MESHPYR defaults to
        target/release/meshpyr of this repository); the whole process is timed (wall clock,
        median of --repeats runs), so it includes start-up, reading and writing the PLY files;
  mo    meshoptimizer.simplify (meshopt_simplify.simplify: target_error=1.0, only the call
        timed, median of --repeats) with target_index_count = 3 x our output face count, i.e.
        at our face count, not at R; if ours failed it gets int(F x R) faces; where it cannot get
        down to our count, ours is cut again at its count (`--faces`, one untimed run) and that
        is what is measured (the row says so);
  both results are measured against the input with distance.compare_arrays (--samples
  area-uniform samples on each surface plus all vertices, --seed): symmetric Hausdorff and RMS
  relative to the input's bbox diagonal.
For each --lowpass fraction L (none with `--lowpass`): a row "lowpass L" where ours is
`$MESHPYR filter MESH -o OUT --lowpass n -q` with n = round(L x V) (the input's connectivity,
positions low-passed to the level of n vertices), and mo is meshoptimizer's simplification to 2n
faces (about n vertices); both distances are measured against the input as above, and the time
column is ours (process) against mo's call. The row also gives "to input / mo H": the one-sided
Hausdorff from our low-pass to the input over mo's Hausdorff, which is large when the low-pass
grows flaps or spikes (json: ours_to_input, flaps_ratio).
Prints a markdown table (ratios are ours / mo: < 1 means ours is smaller/faster); --json writes
every number, including each run's time and the distance seconds. Inputs that are not binary
little-endian PLY are converted once with trimesh into --workdir and both sides read that copy.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from plyio import read_ply, write_ply  # noqa: E402
import distance  # noqa: E402
import meshopt_simplify  # noqa: E402

DEFAULT_BIN = os.path.normpath(os.path.join(HERE, "..", "..", "target", "release", "meshpyr"))


def load_input(path, workdir):
    """(ply path both sides read, positions, triangles)."""
    try:
        pos, tris = read_ply(path)
        return path, pos, tris
    except Exception:  # not binary LE PLY: convert once
        import trimesh
        m = trimesh.load(path, process=False, force="mesh")
        pos, tris = np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)
        conv = os.path.join(workdir, os.path.splitext(os.path.basename(path))[0] + "_in.ply")
        write_ply(conv, pos, tris)
        return conv, *read_ply(conv)  # float32 as written


def run_ours(binary, src, dst, target, repeats, timeout):
    """`target` is the CLI target, e.g. ["--ratio", "0.01"] or ["--faces", "2456"]."""
    times = []
    for _ in range(repeats):
        if os.path.exists(dst):
            os.remove(dst)
        t0 = time.perf_counter()
        try:
            p = subprocess.run([binary, "simplify", src, "-o", dst, *target, "-q"],
                               capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return None, times, f"timeout after {timeout} s"
        except OSError as e:
            return None, times, f"cannot run {binary}: {e}"
        times.append(time.perf_counter() - t0)
        if p.returncode != 0:
            msg = (p.stderr.strip().splitlines() or ["(no message)"])[-1]
            return None, times, f"exit {p.returncode}: {msg}"
        if not os.path.exists(dst):
            return None, times, "exit 0 but no output file"
    try:
        return read_ply(dst), times, None
    except Exception as e:  # noqa: BLE001
        return None, times, f"unreadable output: {e}"


def run_lowpass(binary, src, dst, n, timeout):
    t0 = time.perf_counter()
    try:
        p = subprocess.run([binary, "filter", src, "-o", dst, "--lowpass", str(n), "-q"],
                           capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, None, f"timeout after {timeout} s"
    dt = time.perf_counter() - t0
    if p.returncode != 0:
        msg = (p.stderr.strip().splitlines() or ["(no message)"])[-1]
        return None, dt, f"exit {p.returncode}: {msg}"
    return read_ply(dst), dt, None


def lowpass_row(args, binary, workdir, mesh, name, stem, pos, tris, src, frac):
    n = max(4, int(round(frac * len(pos))))
    r = {"mesh": mesh, "V_in": len(pos), "F_in": len(tris), "lowpass": frac, "lowpass_vertices": n,
         "binary": binary, "samples": args.samples, "seed": args.seed}
    ours_out = os.path.join(workdir, f"{stem}_lowpass_{frac:g}.ply")
    mo_out = os.path.join(workdir, f"{stem}_mo_lowpass_{frac:g}.ply")
    res, dt, err = run_lowpass(binary, src, ours_out, n, args.timeout)
    r.update(ours_time=dt, ours_error=err, ours_faces=None if res is None else len(res[1]))
    if res is not None:
        r["ours_hausdorff"], r["ours_rms"], r["ours_to_input"], _ = distance.compare_sides(
            pos, tris, res[0], res[1], args.samples, args.seed)
    else:
        r["ours_hausdorff"] = r["ours_rms"] = r["ours_to_input"] = None
    try:
        mp, mt, mtimes, _ = meshopt_simplify.simplify(pos, tris, 3 * 2 * n, 1)
        write_ply(mo_out, mp, mt)
        r.update(mo_faces=len(mt), mo_time=float(np.median(mtimes)), mo_error=None)
        r["mo_hausdorff"], r["mo_rms"], _ = distance.compare_arrays(pos, tris, mp, mt, args.samples,
                                                                    args.seed)
    except Exception as e:  # noqa: BLE001
        r.update(mo_faces=None, mo_time=None, mo_hausdorff=None, mo_rms=None, mo_error=str(e))
    if not args.keep:
        for p in (ours_out, mo_out):
            if os.path.exists(p):
                os.remove(p)
    # Flaps: how far our low-pass strays from the input, against meshoptimizer's Hausdorff at
    # twice the faces (a low-pass may lose thin parts, it must not add surface).
    flaps = ratio_of(r["ours_to_input"], r["mo_hausdorff"])
    r["flaps_ratio"] = flaps
    ours = (f"filter --lowpass {n} (to input / mo H: {fmt(flaps, '.2f')})" if err is None
            else f"FAILED ({err})")
    print(f"| {name} | {len(pos)} | {len(tris)} | lowpass {frac:g} | {ours} | {fmt(r['mo_faces'], 'd')} | "
          f"{fmt(r['ours_hausdorff'], '.3e')} | {fmt(r['mo_hausdorff'], '.3e')} | "
          f"{fmt(ratio_of(r['ours_hausdorff'], r['mo_hausdorff']), '.2f')} | "
          f"{fmt(r['ours_rms'], '.3e')} | {fmt(r['mo_rms'], '.3e')} | "
          f"{fmt(ratio_of(r['ours_rms'], r['mo_rms']), '.2f')} | "
          f"{fmt(r['ours_time'], '.4g')} | {fmt(r['mo_time'], '.4g')} | "
          f"{fmt(ratio_of(r['ours_time'], r['mo_time']), '.1f')} |", flush=True)
    return r


def fmt(x, spec):
    return "-" if x is None else format(x, spec)


def ratio_of(a, b):
    return None if a is None or b is None or b == 0 else a / b


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--ratios", nargs="*", type=float, default=[0.003, 0.01, 0.05, 0.10])
    ap.add_argument("--lowpass", nargs="*", type=float, default=[0.005],
                    help="low-pass rows at these fractions of the input's vertices")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--samples", type=int, default=200000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", help="write all numbers here")
    ap.add_argument("--workdir", help="where the results go (default: a temporary directory)")
    ap.add_argument("--keep", action="store_true", help="keep the result meshes")
    ap.add_argument("--timeout", type=float, default=900, help="seconds per run of ours")
    args = ap.parse_args()
    binary = os.environ.get("MESHPYR", DEFAULT_BIN)
    workdir = args.workdir or tempfile.mkdtemp(prefix="pm_table_")
    os.makedirs(workdir, exist_ok=True)

    rows = []
    head = ("| mesh | V in | F in | ratio | our faces | mo faces | our Hausdorff | mo Hausdorff | H ours/mo "
            "| our RMS | mo RMS | RMS ours/mo | our time (process) | mo time (call) | time ours/mo |")
    print(f"binary: {binary}; repeats {args.repeats}; samples {args.samples}; seed {args.seed}; "
          f"distances relative to the input's bbox diagonal; times are medians in seconds", flush=True)
    print()
    print(head)
    print("|" + "---|" * head.count(" | ") + "---|", flush=True)
    for mesh in args.meshes:
        name = os.path.basename(mesh)
        stem = os.path.splitext(name)[0]
        try:
            src, pos, tris = load_input(mesh, workdir)
        except Exception as e:  # noqa: BLE001
            print(f"| {name} | - | - | - | cannot read: {e} |" + " - |" * 10, flush=True)
            rows.append({"mesh": mesh, "error": f"cannot read: {e}"})
            continue
        for ratio in args.ratios:
            r = {"mesh": mesh, "V_in": len(pos), "F_in": len(tris), "ratio": ratio, "binary": binary,
                 "repeats": args.repeats, "samples": args.samples, "seed": args.seed}
            ours_out = os.path.join(workdir, f"{stem}_ours_{ratio:g}.ply")
            mo_out = os.path.join(workdir, f"{stem}_mo_{ratio:g}.ply")
            res, times, err = run_ours(binary, src, ours_out, ["--ratio", repr(ratio)], args.repeats,
                                       args.timeout)
            r["ours_times"] = times
            r["ours_error"] = err
            r["ours_time"] = float(np.median(times)) if times and err is None else None
            r["ours_faces"] = len(res[1]) if res is not None else None
            target_faces = r["ours_faces"] if r["ours_faces"] is not None else int(len(tris) * ratio)
            r["mo_target_faces"] = target_faces
            try:
                mp, mt, mtimes, mcpu = meshopt_simplify.simplify(pos, tris, 3 * target_faces, args.repeats)
                write_ply(mo_out, mp, mt)
                r.update(mo_faces=len(mt), mo_times=mtimes, mo_cpu=mcpu, mo_time=float(np.median(mtimes)),
                         mo_error=None)
                t0 = time.perf_counter()
                r["mo_hausdorff"], r["mo_rms"], _ = distance.compare_arrays(
                    pos, tris, mp, mt, args.samples, args.seed)
                r["mo_distance_seconds"] = time.perf_counter() - t0
            except Exception as e:  # noqa: BLE001
                r.update(mo_faces=None, mo_time=None, mo_hausdorff=None, mo_rms=None, mo_error=str(e))
            # Where meshoptimizer stops above our count, equal face counts means ours cut at its
            # count (one untimed extra run).
            r["ours_recut"] = False
            if res is not None and r.get("mo_faces") and r["mo_faces"] > r["ours_faces"]:
                recut, _, recut_err = run_ours(binary, src, ours_out, ["--faces", str(r["mo_faces"])],
                                               1, args.timeout)
                if recut is not None:
                    res, r["ours_recut"] = recut, True
                    r["ours_recut_faces"] = len(recut[1])
            if res is not None:
                t0 = time.perf_counter()
                r["ours_hausdorff"], r["ours_rms"], _ = distance.compare_arrays(
                    pos, tris, res[0], res[1], args.samples, args.seed)
                r["ours_distance_seconds"] = time.perf_counter() - t0
            else:
                r["ours_hausdorff"] = r["ours_rms"] = None
            if not args.keep:
                for p in (ours_out, mo_out):
                    if os.path.exists(p):
                        os.remove(p)
            rows.append(r)
            our_faces = str(r["ours_faces"]) if err is None else f"FAILED ({err})"
            if r["ours_recut"]:
                our_faces += f" (measured at {r['ours_recut_faces']})"
            mo_faces = str(r["mo_faces"]) if r.get("mo_error") is None else f"FAILED ({r['mo_error']})"
            if r["mo_faces"] is not None and r["mo_faces"] != target_faces:
                mo_faces += f" (target {target_faces})"
            print(f"| {name} | {len(pos)} | {len(tris)} | {ratio:g} | {our_faces} | {mo_faces} | "
                  f"{fmt(r['ours_hausdorff'], '.3e')} | {fmt(r['mo_hausdorff'], '.3e')} | "
                  f"{fmt(ratio_of(r['ours_hausdorff'], r['mo_hausdorff']), '.2f')} | "
                  f"{fmt(r['ours_rms'], '.3e')} | {fmt(r['mo_rms'], '.3e')} | "
                  f"{fmt(ratio_of(r['ours_rms'], r['mo_rms']), '.2f')} | "
                  f"{fmt(r['ours_time'], '.4g')} | {fmt(r['mo_time'], '.4g')} | "
                  f"{fmt(ratio_of(r['ours_time'], r['mo_time']), '.1f')} |", flush=True)
            if args.json:  # rewritten after every row, so a long run leaves partial results
                with open(args.json, "w") as f:
                    json.dump(rows, f, indent=1)
        for frac in args.lowpass:
            rows.append(lowpass_row(args, binary, workdir, mesh, name, stem, pos, tris, src, frac))
            if args.json:
                with open(args.json, "w") as f:
                    json.dump(rows, f, indent=1)
    if not args.keep and not args.workdir:
        shutil.rmtree(workdir, ignore_errors=True)


if __name__ == "__main__":
    main()
