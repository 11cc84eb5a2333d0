"""meshpyr.Viewer: the editor of ``meshpyr view`` as a notebook widget (anywidget).

The page is the same as ``meshpyr view``'s and so are its handlers: the widget runs the page in a
sandboxed frame and carries its requests to the kernel as widget messages, where the editor
(in Rust) answers them; bodies travel as binary buffers. Nothing is loaded from a network.
"""

from __future__ import annotations

import json
import math
import os
import pathlib
import tempfile
import webbrowser
from typing import Any

import anywidget
import traitlets

from ._meshpyr import Pyramid, _Editor, _page_html, _Server, read

_HERE = pathlib.Path(__file__).parent

#: The largest answer a widget message carries: Jupyter drops messages over 10 MB. The display
#: budget keeps the page's answers below it (about 12 bytes per triangle shown); what would
#: exceed it (a budget set far higher, the export of a very large scan) is refused with a 413.
MAX_REPLY_BYTES = 8 * 1024 * 1024

#: The default display budget in triangles (as ``meshpyr view``'s).
DEFAULT_BUDGET = 400_000


def _pyramid_of(x: Any) -> tuple[Pyramid, str]:
    """A Pyramid and a name for what ``show`` accepts: a Pyramid, a ``(V, F)`` pair or a path."""
    if isinstance(x, Pyramid):
        return x, "mesh"
    if isinstance(x, (str, os.PathLike)):
        path = pathlib.Path(x)
        if path.suffix.lower() == ".pyr":
            return Pyramid.load(path), path.name
        v, f = read(path)
        return Pyramid(v, f), path.name
    if isinstance(x, tuple) and len(x) == 2:
        return Pyramid(x[0], x[1]), "mesh"
    raise TypeError(
        f"show() takes a meshpyr.Pyramid, a (V, F) pair or a mesh/.pyr path, not {type(x).__name__}"
    )


class _ValueErrors:
    """A trait whose wrong-typed values raise ValueError, as the rest of meshpyr's bad values
    do (traitlets' TraitError is no ValueError)."""

    def validate(self, obj: Any, value: Any) -> Any:
        try:
            return super().validate(obj, value)  # type: ignore[misc]
        except traitlets.TraitError as e:
            raise ValueError(str(e)) from None


class _List(_ValueErrors, traitlets.List):
    pass


class _Bool(_ValueErrors, traitlets.Bool):
    pass


class Viewer(anywidget.AnyWidget):
    """The editor of ``meshpyr view`` in a notebook cell: orbit, shading, the equalizer (one
    slider per octave of levels), normal-only, presets, the level scrubber, drag edits with undo.

    Make one with :func:`meshpyr.show`. Its state is shared both ways with the page and can be
    observed (``viewer.observe(callback, names=["gains"])``):

    * ``octaves`` (read-only): the ``(from, to)`` levels of each slider; the octave covers the
      levels (from, to].
    * ``gains``: one gain per octave, in ``0..=3``; setting it moves the sliders.
    * ``normal_only``: scale only the normal component of the details.
    * ``moves``: the drag edits as ``{"level", "center", "displacement", "radius"}`` dicts
      (an edit being dragged included).

    Bad values raise ValueError. :attr:`positions` is the exact full-resolution result of the
    current state; :meth:`save_html` saves it as a page that needs no server; :meth:`serve`
    serves the editor to a browser tab, as ``meshpyr view`` does.
    """

    _esm = _HERE / "_widget.js"
    _css = _HERE / "_widget.css"
    _page = traitlets.Unicode("").tag(sync=True)
    octaves = traitlets.List(read_only=True).tag(sync=True)
    gains = _List(traitlets.Float()).tag(sync=True)
    normal_only = _Bool(False).tag(sync=True)
    moves = _List(traitlets.Dict()).tag(sync=True)
    height = traitlets.Int(560, help="The widget's height in pixels.").tag(sync=True)

    def __init__(
        self,
        pyramid: Pyramid,
        *,
        name: str = "mesh",
        budget: int = DEFAULT_BUDGET,
        height: int = 560,
    ) -> None:
        self._server: _Server | None = None
        if not isinstance(pyramid, Pyramid):
            raise TypeError(f"Viewer takes a meshpyr.Pyramid, not {type(pyramid).__name__}")
        editor = _Editor(pyramid, name=name, budget=budget)
        octaves = [tuple(o) for o in editor.octaves]
        self._editor = editor
        self._pyramid = pyramid
        self._name = name
        self._budget = budget
        super().__init__(
            _page=_page_html((_HERE / "_frame.js").read_text(encoding="utf-8")),
            gains=[1.0] * len(octaves),
            height=height,
        )
        self.set_trait("octaves", octaves)
        self.on_msg(self._on_request)

    # ---- state ---------------------------------------------------------------------------
    def _state(self, **change: Any) -> bytes:
        state = {"gains": self.gains, "normal_only": self.normal_only, "moves": self.moves}
        state.update(change)
        return json.dumps(state).encode()

    @traitlets.validate("gains")
    def _check_gains(self, proposal: Any) -> list:
        value = [float(g) for g in proposal["value"]]
        if not all(math.isfinite(g) for g in value):
            raise ValueError(f"gains must be finite, got {value}")
        self._editor.check_state(self._state(gains=value))
        return value

    @traitlets.validate("moves")
    def _check_moves(self, proposal: Any) -> list:
        value = [dict(m) for m in proposal["value"]]
        self._editor.check_state(self._state(moves=value))
        return value

    @property
    def pyramid(self) -> Pyramid:
        """The pyramid being edited."""
        return self._pyramid

    @property
    def positions(self):
        """The exact result of the current state at full resolution: float64 (n, 3), the
        input's vertices in the input's order; the bits ``Pyramid.filter`` (or
        ``Pyramid.edit``) gives for the same gains and edits."""
        return self._editor.positions(self._state())

    def filter_bands(self) -> list[tuple[int, int, float]]:
        """The current gains as ``Pyramid.filter(gains=...)`` bands (octaves at gain 1 left out)."""
        return [(lo, hi, g) for (lo, hi), g in zip(self.octaves, self.gains) if g != 1.0]

    # ---- the page's requests -------------------------------------------------------------
    def _on_request(self, _widget: Any, content: Any, _buffers: Any) -> None:
        if not isinstance(content, dict) or content.get("kind") != "request":
            return
        status, content_type, headers, body = self.answer(
            str(content.get("method", "GET")),
            str(content.get("path", "")),
            str(content.get("body", "")).encode(),
        )
        reply_headers = dict(headers)
        reply_headers["Content-Type"] = content_type
        self.send(
            {"kind": "reply", "id": content.get("id"), "status": status, "headers": reply_headers},
            [body],
        )

    def answer(self, method: str, path: str, body: bytes) -> tuple[int, str, list, bytes]:
        """Answers one of the page's ``/api`` requests (docs/view-api.md) as
        ``(status, content_type, headers, body)``; answers over :data:`MAX_REPLY_BYTES`
        become a 413."""
        status, content_type, headers, data = self._editor.request(method, path, body)
        if len(data) > MAX_REPLY_BYTES:
            message = (
                f"the answer ({len(data):,} bytes) is over a notebook message's limit: lower the "
                "display budget, or use Viewer.positions and meshpyr.write for exports"
            )
            return 413, "application/json", [], json.dumps({"error": message}).encode()
        return status, content_type, list(headers), bytes(data)

    # ---- outputs -------------------------------------------------------------------------
    def save_html(self, path: str | os.PathLike) -> None:
        """Saves the current result as one self-contained HTML page (orbit, zoom, shading; no
        server, nothing loaded from a network), atomically: an existing file is replaced only
        by a complete one. A scan over the display budget is saved at the level the widget
        shows, with the exact result's positions there."""
        html = self._editor.snapshot_html(self._state())
        target = pathlib.Path(path)
        fd, temporary = tempfile.mkstemp(dir=target.parent or ".", prefix=".meshpyr-", suffix=".html")
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as out:
                out.write(html)
            os.replace(temporary, target)
        except BaseException:
            pathlib.Path(temporary).unlink(missing_ok=True)
            raise

    # Not `open`: ipywidgets' Widget.open opens the widget's comm.
    def serve(self, *, port: int = 0, browser: bool = True) -> str:
        """Serves the editor on 127.0.0.1 (``meshpyr view``'s server, with its Host check and
        token) on a background thread and opens it in the browser unless ``browser=False``;
        returns the page's URL. The served page starts from gains 1 and keeps its own state.
        :meth:`stop` stops it."""
        self.stop()
        self._server = _Server(self._pyramid, name=self._name, budget=self._budget, port=port)
        if browser:
            webbrowser.open(self._server.url)
        return self._server.url

    @property
    def url(self) -> str | None:
        """The served page's URL while :meth:`serve` serves it, else None."""
        return self._server.url if self._server is not None and self._server.running else None

    def stop(self) -> None:
        """Stops the server :meth:`serve` started, if any."""
        if self._server is not None:
            self._server.stop()
            self._server = None

    def close(self) -> None:
        """Closes the widget and stops the server :meth:`serve` started."""
        self.stop()
        super().close()


def show(
    x: Any,
    *,
    name: str | None = None,
    budget: int = DEFAULT_BUDGET,
    height: int = 560,
    open_browser: bool | None = None,
) -> Viewer:
    """See :func:`meshpyr.show`."""
    pyramid, default_name = _pyramid_of(x)
    viewer = Viewer(pyramid, name=name or default_name, budget=budget, height=height)
    if open_browser is None:
        open_browser = not _in_notebook()
    if open_browser:
        viewer.serve()
    return viewer


def _in_notebook() -> bool:
    """True inside a Jupyter kernel (JupyterLab, Notebook, VS Code), where widgets display."""
    try:
        from IPython import get_ipython
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and hasattr(shell, "kernel")
