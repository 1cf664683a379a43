"""Type stubs of the compiled module rmt_terrain._native (called by rmt_terrain)."""

from typing import Any, Callable, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

OBJECTS: List[str]

_Box = Tuple[Tuple[float, float, float], Tuple[float, float, float], Tuple[int, int, int]]
_Result = Tuple[
    npt.NDArray[np.float32],
    npt.NDArray[np.uint32],
    Optional[npt.NDArray[np.float32]],
    Dict[str, Any],
    _Box,
]

def extract_volume(
    volume: npt.NDArray[np.float32],
    centres: Optional[npt.NDArray[np.float32]],
    level: float,
    spacing: Tuple[float, float, float],
    origin: Tuple[float, float, float],
    lattice: str,
    method: str,
    clustering: str,
    normals: str,
    threads: Optional[int],
) -> _Result: ...
def extract_field(
    f: Callable[..., npt.NDArray[np.float32]],
    bounds: Tuple[float, ...],
    resolution: Tuple[int, int, int],
    level: float,
    lattice: str,
    method: str,
    clustering: str,
    normals: str,
    threads: Optional[int],
    batch: int,
) -> _Result: ...
def sample(
    object: str,
    resolution: Tuple[int, int, int],
    lattice: str,
    bounds: Tuple[float, ...],
    params: Dict[str, Any],
    threads: Optional[int],
) -> Tuple[
    npt.NDArray[np.float32],
    Optional[npt.NDArray[np.float32]],
    Tuple[float, float, float],
    Tuple[float, float, float],
]: ...
def validate(
    vertices: npt.NDArray[np.float32],
    faces: npt.NDArray[np.uint32],
    lo: Tuple[float, float, float],
    hi: Tuple[float, float, float],
    cells: Tuple[int, int, int],
) -> Dict[str, Any]: ...
def quality(vertices: npt.NDArray[np.float32], faces: npt.NDArray[np.uint32]) -> Dict[str, Any]: ...
def write(
    path: str,
    vertices: npt.NDArray[np.float32],
    faces: npt.NDArray[np.uint32],
    normals: Optional[npt.NDArray[np.float32]],
) -> None: ...
