"""Type stubs of the extension module; the package ``meshpyr`` re-exports every name."""

from os import PathLike
from typing import Any, Callable, Dict, Iterable, List, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

Vertices = npt.NDArray[np.float64]
"""float64 array of shape (n, 3)."""
Faces = npt.NDArray[np.int64]
"""int64 array of shape (m, 3)."""
ArrayLike = npt.ArrayLike
Path = Union[str, "PathLike[str]"]
Level = Union[int, str]
"""A vertex count (int) or a feature size in model units ("0.02u")."""
Band = Tuple[Level, Level]
GainBand = Tuple[Level, Level, float]
Vec3 = Sequence[float]
Corners = Dict[str, Any]
"""What a textured mesh holds per triangle of F: ``texcoord`` (m, 3, 2), ``normal`` (m, 3, 3),
``material`` (m,) into ``materials``, ``material_libraries``, ``folder``, ``group`` (m,) into
``groups``; see :func:`read`."""

class FormatError(ValueError):
    """A mesh or .pyr file (or .pyr bytes) whose content is damaged, truncated or not in the
    format its name says."""

@overload
def read(path: Path, *, corners: Literal[False] = False) -> Tuple[Vertices, Faces]: ...
@overload
def read(path: Path, *, corners: Literal[True]) -> Tuple[Vertices, Faces, Corners]:
    """Reads a mesh file (.obj, .ply, .off, .stl, optionally .gz) as (V, F), with
    ``corners=True`` also its texture coordinates, corner normals, materials and groups."""

def write(
    path: Path,
    v: ArrayLike,
    f: ArrayLike,
    /,
    corners: Optional[Corners] = None,
    *,
    before: Optional[ArrayLike] = None,
) -> None:
    """Writes (V, F) (and the corners dict) to a mesh file, atomically; the extension chooses
    the format; ``before`` (the positions the normals were stored for) makes stored normals
    follow the moved surface."""

def info(v: ArrayLike, f: ArrayLike, /, corners: Optional[Corners] = None) -> Dict[str, object]:
    """Counts, topology and size, with the keys of ``meshpyr info --json``."""

@overload
def simplify(
    v: ArrayLike,
    f: ArrayLike,
    /,
    *,
    faces: Optional[int] = None,
    ratio: Optional[float] = None,
    error: Optional[float] = None,
    prune: Optional[float] = None,
    max_angle: float = 45.0,
    min_quality: float = 0.05,
    boundary_weight: float = 10.0,
    corners: None = None,
    uv_weight: float = 0.25,
) -> Tuple[Vertices, Faces, npt.NDArray[np.int64]]: ...
@overload
def simplify(
    v: ArrayLike,
    f: ArrayLike,
    /,
    *,
    faces: Optional[int] = None,
    ratio: Optional[float] = None,
    error: Optional[float] = None,
    prune: Optional[float] = None,
    max_angle: float = 45.0,
    min_quality: float = 0.05,
    boundary_weight: float = 10.0,
    corners: Corners,
    uv_weight: float = 0.25,
) -> Tuple[Vertices, Faces, npt.NDArray[np.int64], Corners]:
    """Quadric-error simplification to one target; returns (V2, F2, vertex_map), and the
    output's corners dict when ``corners`` is given (seams kept)."""

def subdivide(
    v: ArrayLike,
    f: ArrayLike,
    /,
    *,
    levels: int = 3,
    scheme: Literal["mcm", "loop"] = "mcm",
    refine: Literal["quad", "bisect"] = "quad",
    solver: Literal["auto", "exact", "cg", "jacobi"] = "auto",
    width: float = 0.25,
    local_width: bool = False,
    finest_steps: int = 2,
    beta: Optional[float] = None,
) -> Tuple[Vertices, Faces]:
    """Subdivides a coarse mesh (cascadic mean-curvature motion, or Loop)."""

def smooth(
    v: ArrayLike,
    f: ArrayLike,
    /,
    *,
    method: Literal["auto", "adaptive", "anisotropic", "taubin", "mcf"] = "auto",
    epsilon: Optional[float] = None,
    sigma_min: Optional[float] = None,
    sigma_max: Optional[float] = None,
    scales: Optional[int] = None,
    rho: Optional[float] = None,
    reach: Optional[float] = None,
    variance: Optional[Literal["unbiased", "biased"]] = None,
    scale: Optional[Literal["global", "local"]] = None,
    vertex_updates: Optional[int] = None,
    passes: Optional[int] = None,
    fit_iterations: Optional[int] = None,
    step_cap: Optional[float] = None,
    iterations: Optional[int] = None,
    weights: Optional[Literal["cotan", "uniform", "inverse-edge"]] = None,
    lambda_: Optional[float] = None,
    mu: Optional[float] = None,
    time_step: Optional[float] = None,
    boundary: Optional[Literal["fixed", "smooth"]] = None,
) -> Vertices:
    """Denoises (V, F) as ``meshpyr smooth``; returns the new positions in the input's vertex
    order."""

def compare(
    v: ArrayLike, f: ArrayLike, v_ref: ArrayLike, f_ref: ArrayLike, /, *, per_vertex: bool = False
) -> Dict[str, Any]:
    """E_v, E_n and the sampled Hausdorff distance of (V, F) against (Vref, Fref); with
    per_vertex=True also ``distance`` (each vertex's distance to the reference surface, float64
    array) and its percentiles ``per_vertex_distance``."""

class ProgressiveMesh:
    """The hierarchy of quadric-error half-edge collapses; level n is the mesh on the first n
    vertices."""

    def __init__(self, v: ArrayLike, f: ArrayLike, /) -> None: ...
    @property
    def levels(self) -> range:
        """The valid levels, range(base, finest + 1), as vertex counts."""
    @property
    def vertex_map(self) -> npt.NDArray[np.int64]:
        """Index in V of each vertex of the hierarchy."""
    def mesh(self, n: int) -> Tuple[Vertices, Faces]:
        """Level n as (V_n, F_n)."""

class Pyramid:
    """A mesh with its progressive mesh and Burt-Adelson detail pyramid. Immutable; pickles as
    its .pyr bytes."""

    def __init__(
        self,
        v: ArrayLike,
        f: ArrayLike,
        /,
        *,
        relax: Literal["second-difference", "mcm", "normal"] = "second-difference",
    ) -> None: ...
    @property
    def levels(self) -> range:
        """The levels, range(base, finest + 1), as vertex counts."""
    @property
    def vertices(self) -> Vertices:
        """The input's vertex positions."""
    @property
    def faces(self) -> Faces:
        """The input's triangles."""
    @property
    def relax(self) -> str:
        """The relaxation operator's name."""
    def filter(
        self,
        *,
        lowpass: Optional[Level] = None,
        stopband: Optional[Iterable[Band]] = None,
        enhance: Optional[Iterable[GainBand]] = None,
        gains: Optional[Iterable[GainBand]] = None,
        normal_only: bool = False,
    ) -> Vertices:
        """The input with its details scaled per level; the same bits as ``meshpyr filter``."""
    def edit(
        self,
        level: int,
        moves: Iterable[Tuple[Vec3, Vec3]],
        radius: float,
        *,
        lowpass: Optional[Level] = None,
        stopband: Optional[Iterable[Band]] = None,
        enhance: Optional[Iterable[GainBand]] = None,
        gains: Optional[Iterable[GainBand]] = None,
        normal_only: bool = False,
    ) -> Vertices:
        """A multiresolution edit: move level `level` near each point, resynthesise."""
    def spectrum(self) -> Dict[str, npt.NDArray[np.generic]]:
        """Detail energy per band of levels: lo, hi, levels, details, energy, rms, feature_size."""
    def to_bytes(self, *, details: bool = True) -> bytes:
        """The .pyr file's bytes, with the quantised details unless details=False."""
    @classmethod
    def from_bytes(cls, data: bytes) -> "Pyramid":
        """Opens .pyr bytes (with their stored details, if any)."""
    def save(self, path: Path, *, details: bool = True) -> None:
        """Saves the .pyr file at path, atomically (with details unless details=False)."""
    @classmethod
    def load(cls, path: Path) -> "Pyramid":
        """Opens the .pyr file at path (with its stored details, if any)."""
    def __reduce__(self) -> Tuple[object, Tuple[bytes]]: ...

# The editor of `meshpyr view`, wrapped by meshpyr.Viewer (meshpyr/_viewer.py); states are the
# JSON bodies of POST /api/edit (docs/view-api.md).
class _Editor:
    def __init__(self, pyramid: Pyramid, /, *, name: str = "mesh", budget: int = 400000) -> None: ...
    @property
    def octaves(self) -> List[Tuple[int, int]]: ...
    def request(
        self, method: str, target: str, body: bytes
    ) -> Tuple[int, str, List[Tuple[str, str]], bytes]: ...
    def check_state(self, state: bytes) -> None: ...
    def positions(self, state: bytes) -> Vertices: ...
    def snapshot_html(self, state: bytes) -> str: ...

class _Server:
    def __init__(
        self, pyramid: Pyramid, /, *, name: str = "mesh", budget: int = 400000, port: int = 0
    ) -> None: ...
    @property
    def url(self) -> str: ...
    @property
    def running(self) -> bool: ...
    def stop(self) -> None: ...

def _page_html(script: str) -> str: ...

# meshpyr.dask's task layer: a block task as a dict of str, int and float values.
def _run_task(task: Dict[str, Any]) -> Union[None, int, bytes]: ...
def _run_command(
    args: List[str], round: Callable[[List[Dict[str, Any]]], List[Union[None, int, bytes]]]
) -> None: ...
def _block_vertices_for(memory: int) -> int: ...
