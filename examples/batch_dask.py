"""Filter (or build the .pyr of) every mesh in a folder on a Dask cluster.

Batch processing many scans is what outgrows one machine. Each mesh becomes two tasks: one
builds its pyramid on a worker, the next filters it there (the pyramid never travels; only the
new positions come back) and the client writes the result. With ``--pyr`` the pyramids
themselves come back, pickled as their .pyr bytes, and are saved as .pyr files.

On one machine (a LocalCluster with two worker processes)::

    python examples/batch_dask.py scans/ out/ --lowpass 2000
    python examples/batch_dask.py scans/ out/ --stopband 1000:15000 --normal-only
    python examples/batch_dask.py scans/ out/ --pyr

On a real cluster, start a scheduler and workers where meshpyr is installed
(``pip install ./python`` on each node, or a shared environment)::

    dask scheduler                          # on the head node; prints tcp://HEAD:8786
    dask worker tcp://HEAD:8786 --nworkers 1 --nthreads 4   # on each node

and point the script at it; the client reads the inputs and writes the outputs, so only the
machine running the script needs the folders::

    python examples/batch_dask.py scans/ out/ --lowpass 2000 --scheduler tcp://HEAD:8786

A worker thread per core is right: every meshpyr call releases the GIL. Outputs are PLY files
with double positions, the same bits as ``meshpyr filter`` writes for the same input.
Requires ``dask[distributed]`` (not a dependency of meshpyr).
"""

import argparse
import sys
from pathlib import Path

import meshpyr

MESH_SUFFIXES = (".ply", ".obj", ".off", ".stl", ".ply.gz", ".obj.gz", ".off.gz", ".stl.gz")


def mesh_files(folder):
    """The mesh files directly in `folder`, sorted by name."""
    return sorted(
        p for p in Path(folder).iterdir() if p.is_file() and p.name.lower().endswith(MESH_SUFFIXES)
    )


def stem(path):
    """The name without its mesh suffix (``scan.ply.gz`` -> ``scan``)."""
    name = path.name
    for suffix in MESH_SUFFIXES:
        if name.lower().endswith(suffix):
            return name[: -len(suffix)]
    return path.stem


def parse_band(text, with_gain):
    """``A:B`` or ``A:B=G`` as the command line writes them; levels stay strings ("0.02u")
    unless they are plain vertex counts."""

    def level(s):
        return int(s) if s.strip().isdigit() else s.strip()

    band, _, gain = text.partition("=")
    a, _, b = band.partition(":")
    if not b or (with_gain and not gain):
        raise argparse.ArgumentTypeError(f"{text!r}: expected A:B{'=G' if with_gain else ''}")
    return (level(a), level(b), float(gain)) if with_gain else (level(a), level(b))


def filter_keywords(args):
    """The keywords of ``Pyramid.filter`` the arguments describe."""
    lowpass = None
    if args.lowpass is not None:
        lowpass = int(args.lowpass) if args.lowpass.isdigit() else args.lowpass
    return {
        "lowpass": lowpass,
        "stopband": args.stopband,
        "enhance": args.enhance,
        "gains": args.gain,
        "normal_only": args.normal_only,
    }


def run(client, inputs, output, keywords=None, pyr=False):
    """Processes `inputs` on `client`'s cluster into the folder `output`; returns the paths
    written, in input order."""
    output.mkdir(parents=True, exist_ok=True)
    meshes = [meshpyr.read(p) for p in inputs]
    # pure=False: two scans with identical arrays still get a task each, and a pyramid is not
    # hashed for a key.
    pyramids = [client.submit(meshpyr.Pyramid, v, f, pure=False) for v, f in meshes]
    written = []
    if pyr:
        for path, future in zip(inputs, pyramids):
            target = output / f"{stem(path)}.pyr"
            future.result().save(target)
            written.append(target)
        return written
    # The method goes by reference, so the workers need nothing but meshpyr.
    positions = [client.submit(meshpyr.Pyramid.filter, p, pure=False, **keywords) for p in pyramids]
    for path, (_, faces), future in zip(inputs, meshes, positions):
        target = output / f"{stem(path)}.ply"
        meshpyr.write(target, future.result(), faces)
        written.append(target)
    return written


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("input", type=Path, help="folder of meshes (.ply .obj .off .stl, optionally .gz)")
    parser.add_argument("output", type=Path, help="folder for the results")
    parser.add_argument("--lowpass", metavar="N", help="zero the details above level N (or a size such as 0.02u)")
    parser.add_argument("--stopband", metavar="A:B", action="append", default=[], type=lambda s: parse_band(s, False))
    parser.add_argument("--enhance", metavar="A:B=G", action="append", default=[], type=lambda s: parse_band(s, True))
    parser.add_argument("--gain", metavar="A:B=G", action="append", default=[], type=lambda s: parse_band(s, True))
    parser.add_argument("--normal-only", action="store_true")
    parser.add_argument("--pyr", action="store_true", help="write each mesh's .pyr file instead of filtering")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="a running cluster's scheduler (tcp://host:8786)")
    parser.add_argument("--local-workers", type=int, default=2, help="worker processes of the local cluster (default 2)")
    args = parser.parse_args(argv)
    keywords = filter_keywords(args)
    if not args.pyr and keywords["lowpass"] is None and not (args.stopband or args.enhance or args.gain):
        parser.error("give a filter (--lowpass, --stopband, --enhance, --gain) or --pyr")
    inputs = mesh_files(args.input)
    if not inputs:
        parser.error(f"no mesh files in {args.input}")

    from dask.distributed import Client, LocalCluster

    cluster = None
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        cluster = LocalCluster(n_workers=args.local_workers, threads_per_worker=1, processes=True)
        client = Client(cluster)
    try:
        for path in run(client, inputs, args.output, keywords, args.pyr):
            print(path)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
