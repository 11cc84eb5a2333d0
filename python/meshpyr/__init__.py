"""meshpyr: multiresolution editing of triangle meshes on numpy arrays.

Meshes are ``(V, F)`` pairs: V float64 (n, 3) vertex positions, F integer (m, 3) triangles.

* Files: :func:`read`, :func:`write`; counts and topology: :func:`info`.
* :func:`simplify` cuts the progressive mesh at a face count, ratio or error;
  :class:`ProgressiveMesh` gives every level.
* :class:`Pyramid` is the Burt-Adelson detail pyramid: band filters (low-pass, stop-band,
  enhancement), multiresolution edits, detail spectra, and the ``.pyr`` file (also as bytes
  and pickles).
* :func:`smooth` denoises, :func:`subdivide` refines coarse meshes, :func:`compare` measures
  a result against a reference.

Bad arrays or options raise ValueError, files OSError, damaged files :class:`FormatError`
(a ValueError). Every heavy call releases the GIL, so threads run in parallel.
"""

from ._meshpyr import (
    FormatError,
    ProgressiveMesh,
    Pyramid,
    __version__,
    compare,
    info,
    read,
    simplify,
    smooth,
    subdivide,
    write,
)

__all__ = [
    "FormatError",
    "ProgressiveMesh",
    "Pyramid",
    "__version__",
    "compare",
    "info",
    "read",
    "simplify",
    "smooth",
    "subdivide",
    "write",
]
