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

* :func:`show` opens the editor of ``meshpyr view`` in a notebook cell (:class:`Viewer`, with
  the ``notebook`` extra: ``pip install "meshpyr[notebook]"``) or in a browser tab.

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

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._viewer import Viewer

_NOTEBOOK_HINT = (
    "meshpyr.show and meshpyr.Viewer need anywidget: pip install 'meshpyr[notebook]' "
    "(from a checkout: pip install './python[notebook]')"
)


def _viewer_module():
    try:
        from . import _viewer
    except ImportError as e:
        if e.name in ("anywidget", "traitlets", "ipywidgets"):
            raise ImportError(_NOTEBOOK_HINT, name=e.name) from e
        raise
    return _viewer


def show(x: Any, **options: Any) -> "Viewer":
    """The editor of ``meshpyr view`` on ``x`` (a :class:`Pyramid`, a ``(V, F)`` pair, or the
    path of a mesh or .pyr file), as a :class:`Viewer`: in a notebook (Jupyter, VS Code) it
    shows in the cell when displayed (the last expression of a cell, or ``display(viewer)``);
    elsewhere it also serves the page on 127.0.0.1 and opens the browser (``Viewer.serve``).

    Options: ``name`` (shown on the page), ``budget`` (display budget in triangles: larger
    scans are shown as a level of their progressive mesh), ``height`` (pixels),
    ``open_browser`` (True/False: serve and open a tab whatever the environment). Needs the
    ``notebook`` extra (anywidget); without it, raises ImportError saying so.
    """
    return _viewer_module().show(x, **options)


def __getattr__(name: str) -> Any:
    if name == "Viewer":
        return _viewer_module().Viewer
    raise AttributeError(f"module 'meshpyr' has no attribute {name!r}")


# Viewer stays out: `from meshpyr import *` must work without the notebook extra.
__all__ = [
    "show",
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
