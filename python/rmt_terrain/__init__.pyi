"""Type stubs of rmt_terrain (signatures for IDEs; the docstrings are in __init__.py)."""

import os
from typing import Any, Callable, Dict, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

OBJECTS: Tuple[str, ...]

_Clustering = Literal["integrated", "none", "integrated-unchecked", "postprocessed", "meshopt"]
_Field = Callable[[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]], Any]

class Mesh:
    """A triangle mesh: vertices (N, 3) float32 in the order `axes` ("zyx", array order, from
    extract; "xyz", world order, from extract_field), faces (M, 3) uint32, normals, stats."""

    vertices: npt.NDArray[np.float32]
    faces: npt.NDArray[np.uint32]
    normals: Optional[npt.NDArray[np.float32]]
    stats: Dict[str, Any]
    axes: Literal["xyz", "zyx"]
    def __init__(
        self,
        vertices: npt.NDArray[np.float32],
        faces: npt.NDArray[np.uint32],
        normals: Optional[npt.NDArray[np.float32]],
        stats: Dict[str, Any],
        box: Any = ...,
        axes: Literal["xyz", "zyx"] = ...,
    ) -> None: ...
    def with_axes(self, axes: Literal["xyz", "zyx"]) -> Mesh:
        """This mesh in the order axes (coordinates swapped, faces rewound; exact)."""
    def validate(self) -> Dict[str, Any]:
        """closed, manifold, oriented, euler, components, watertight_manifold and counts."""
    def quality(self) -> Dict[str, Any]:
        """Radius ratio statistics (ar_mean, ar_sd, ar_median, ar_max, ...), angles, areas."""
    def to_trimesh(self) -> Any:
        """A trimesh.Trimesh (needs trimesh)."""
    def write(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Binary PLY, OBJ or binary glTF by the extension (.ply, .obj, .glb), vertices as they
        are (the command line's files: with_axes("xyz").write(path))."""

class Sampled:
    """A built-in object sampled on a lattice (from sample())."""

    volume: npt.NDArray[np.float32]
    centres: Optional[npt.NDArray[np.float32]]
    spacing: Tuple[float, float, float]
    origin: Tuple[float, float, float]
    lattice: str
    object: str
    def __init__(
        self,
        volume: npt.NDArray[np.float32],
        centres: Optional[npt.NDArray[np.float32]],
        spacing: Tuple[float, float, float],
        origin: Tuple[float, float, float],
        lattice: str,
        object: str,
    ) -> None: ...
    def extract(self, level: float = 0.0, **kwargs: Any) -> Mesh:
        """extract() on these values (array order); .with_axes("xyz") is the command line's
        mesh, byte for byte."""

def extract(
    volume: npt.ArrayLike,
    level: float = 0.0,
    *,
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    lattice: Literal["simple", "bcdl"] = "simple",
    clustering: _Clustering = "integrated",
    method: Literal["mt", "mc", "surface-nets"] = "mt",
    normals: Literal["gradient", "area", "none"] = "gradient",
    threads: Optional[int] = None,
    centres: Union[npt.ArrayLike, _Field, None] = None,
    ghosts: Union[float, _Field, None] = None,
    origin: Sequence[float] = (0.0, 0.0, 0.0),
) -> Mesh:
    """The isosurface volume == level of volume[z, y, x], as scikit-image's marching_cubes reads
    and returns it: spacing, origin, vertices and normals in array order (z, y, x); no copy of
    a C-contiguous float32 volume (simple lattice, mc, surface-nets). lattice bcdl needs
    centres: shape - 1 (the box faces closed by pyramids, no ghost), shape + 1 (ghost layer
    included), shape - 1 with ghosts (a number or callable), or a callable. clustering applies
    to mt (mc and surface-nets: the default or none)."""

def extract_field(
    f: _Field,
    bounds: Sequence[float] = (-1.0, -1.0, -1.0, 1.0, 1.0, 1.0),
    resolution: Union[int, Sequence[int]] = 64,
    *,
    lattice: Literal["simple", "bcdl"] = "bcdl",
    level: float = 0.0,
    clustering: _Clustering = "integrated",
    method: Literal["mt", "mc", "surface-nets"] = "mt",
    normals: Literal["gradient", "area", "none"] = "gradient",
    threads: Optional[int] = None,
    batch: int = 65536,
) -> Mesh:
    """The isosurface f == level of a vectorised f(x, y, z), called once per batch of points;
    bounds, resolution and the mesh in world order (x, y, z)."""

def sample(
    object: str,
    resolution: Union[int, Sequence[int]] = 50,
    lattice: str = "bcdl",
    seed: Optional[int] = None,
    *,
    bounds: Sequence[float] = (-1.0, -1.0, -1.0, 1.0, 1.0, 1.0),
    threads: Optional[int] = None,
    **params: Any,
) -> Sampled:
    """A built-in object (OBJECTS) sampled as the command line samples it."""
