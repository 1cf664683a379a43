"""Regularised marching tetrahedra (RMT) for numpy volumes, called like scikit-image's
``marching_cubes``.

>>> import numpy as np, rmt_terrain
>>> z, y, x = np.mgrid[-1:1:33j, -1:1:33j, -1:1:33j]
>>> volume = np.sqrt(x * x + y * y + z * z) - 0.7       # a sphere, indexed volume[z, y, x]
>>> mesh = rmt_terrain.extract(volume, 0.0, spacing=(2 / 32,) * 3)
>>> mesh.validate()["watertight_manifold"]
True

Conventions
-----------
* ``volume[i, j, k]`` is read the way ``skimage.measure.marching_cubes`` reads it: a C-ordered
  array whose axes are (z, y, x), so the last axis varies fastest, and ``spacing`` and
  ``origin`` are given in the same array order ``(dz, dy, dx)``. Point ``[i, j, k]`` lies at
  ``x = origin[2] + k * dx``, ``y = origin[1] + j * dy``, ``z = origin[0] + i * dz``.
* The returned ``vertices`` are ``(x, y, z)`` world coordinates, the order of every mesh file
  format and of the Rust library. scikit-image returns its vertices in array order
  ``(i, j, k)``, i.e. ``(z, y, x)``: ``mesh.vertices[:, ::-1]`` gives that order (the faces'
  winding then describes the mirrored orientation).
* Inside is ``volume < level``; ``volume == level`` counts as outside. Triangles are
  counter-clockwise seen from the side of increasing values, so normals point outward for a
  signed distance field (negative inside).
* ``volume`` may be any floating-point array. A C-contiguous float32 array is read in place (no
  conversion copy); other float arrays are converted to C-contiguous float32 first. The values
  are then copied once into the extractor's own sample array, with the finiteness check in the
  same pass (``stats["t_input_s"]`` is that time).
* The body-centred lattice (``lattice="bcdl"``) also samples the centre of every cube: pass
  ``centres`` (shape ``volume.shape - 1``), or a callable ``centres(x, y, z)``; without them it
  is refused, the values are never guessed. The centres of the cubes just outside the box
  ("ghosts", sampled on the box faces) matter only where the surface comes within half a cell
  of the box: with ``volume.shape - 1`` centres they are the mean of their face's four corners
  (the bilinear interpolant there); pass centres of shape ``volume.shape + 1`` (ghost layer
  included, as ``sample`` returns them) or a callable to give them exactly.
* The GIL is released while the extractor runs; ``threads`` defaults to the machine's cores.
  Errors are ``ValueError`` (with the library's message), ``TypeError`` for a non-float dtype,
  and ``MemoryError`` when the size estimate exceeds the available memory.
"""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native

__all__ = ["extract", "extract_field", "sample", "Mesh", "Sampled", "OBJECTS"]

#: The built-in objects of :func:`sample` (the command line's ``--object`` choices).
OBJECTS: Tuple[str, ...] = tuple(_native.OBJECTS)

_Triple = Tuple[float, float, float]


class Mesh:
    """A triangle mesh from :func:`extract`, :func:`extract_field` or :meth:`Sampled.extract`.

    Attributes
    ----------
    vertices : ndarray, (N, 3) float32
        Vertex positions, (x, y, z). The array owns the extractor's buffer (no copy).
    faces : ndarray, (M, 3) uint32
        Vertex indices, counter-clockwise seen from increasing values.
    normals : ndarray, (N, 3) float32, or None
        Unit vertex normals (``normals="none"`` gives None).
    stats : dict
        Counters and stage times of the extraction (the command line's ``--json`` keys:
        ``vertices``, ``triangles``, ``crossings``, ``clusters_committed``, ``t_total_s``,
        ``t_sampling_s``, ``t_vertex_s``, ``t_geometry_s``, ``t_normals_s``, ...).
        ``t_total_s`` is the Rust extraction (with gradient normals), ``t_input_s`` the copy
        and check of the input before it, ``t_call_s`` the whole compiled call (input, extraction
        and conversion of the result; the rest of a call's time is the Python wrapper).
    """

    __slots__ = ("vertices", "faces", "normals", "stats", "_box")

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, normals: Optional[np.ndarray],
                 stats: Dict[str, Any], box: Any = None) -> None:
        self.vertices = vertices
        self.faces = faces
        self.normals = normals
        self.stats = stats
        self._box = box

    def __repr__(self) -> str:
        return f"Mesh({len(self.vertices)} vertices, {len(self.faces)} faces)"

    def _arrays(self) -> Tuple[np.ndarray, np.ndarray]:
        v = np.ascontiguousarray(self.vertices, dtype=np.float32)
        f = np.ascontiguousarray(self.faces, dtype=np.uint32)
        return v, f

    def validate(self) -> Dict[str, Any]:
        """Topology of the mesh: ``closed`` (no hole inside the sampled box; edges on the box
        faces are ``boundary_edges_on_box``), ``manifold``, ``oriented``, ``euler`` (the Euler
        characteristic V - E + F), ``components``, ``watertight_manifold`` (all of these and no
        duplicate or non-finite data), and the counts behind them."""
        v, f = self._arrays()
        if self._box is None:
            # Not from an extraction: no box, so every open edge counts as a hole.
            lo, hi, cells = (float("nan"),) * 3, (float("nan"),) * 3, (1, 1, 1)
        else:
            lo, hi, cells = self._box
        return _native.validate(v, f, tuple(lo), tuple(hi), tuple(cells))

    def quality(self) -> Dict[str, Any]:
        """Triangle quality: radius ratio (circumradius over twice the inradius, 1 for an
        equilateral triangle; ``ar_mean``, ``ar_sd``, ``ar_median``, ``ar_max``, ...), minimum
        angles and areas."""
        v, f = self._arrays()
        return _native.quality(v, f)

    def to_trimesh(self):
        """The mesh as a ``trimesh.Trimesh`` (needs ``pip install trimesh``), unprocessed."""
        try:
            import trimesh
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Mesh.to_trimesh needs trimesh: pip install trimesh") from e
        kwargs = {}
        if self.normals is not None:
            kwargs["vertex_normals"] = self.normals
        return trimesh.Trimesh(vertices=self.vertices, faces=self.faces, process=False, **kwargs)

    def write(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the mesh as binary PLY (``.ply``), OBJ (``.obj``) or binary glTF (``.glb``),
        by the extension: the command line's writers, so the same mesh gives the same bytes."""
        v, f = self._arrays()
        n = None if self.normals is None else np.ascontiguousarray(self.normals, dtype=np.float32)
        _native.write(os.fspath(path), v, f, n)


def _triple(value: Any, name: str) -> _Triple:
    try:
        t = tuple(float(v) for v in value)
    except TypeError:
        t = (float(value),) * 3
    if len(t) != 3:
        raise ValueError(f"{name} must have 3 values (array order z, y, x), got {len(t)}")
    return t  # type: ignore[return-value]


def _as_float32(array: Any, name: str) -> np.ndarray:
    """`array` as a C-contiguous float32 3-D array (no copy when it already is one)."""
    a = array if isinstance(array, np.ndarray) else np.asarray(array)
    if a.dtype.kind != "f":
        raise TypeError(f"{name} must be a floating-point array, got dtype {a.dtype}")
    if a.ndim != 3:
        raise ValueError(f"{name} must be 3-D, indexed [z, y, x]; got shape {a.shape}")
    if a.size == 0:
        raise ValueError(f"{name} is empty: shape {a.shape}")
    if a.dtype == np.float32 and a.flags.c_contiguous:
        return a
    with np.errstate(over="ignore"):
        return np.ascontiguousarray(a, dtype=np.float32)


def _grid_axes(shape: Tuple[int, int, int], spacing: _Triple, origin: _Triple):
    """Per array axis: (origin, half spacing, cells) as the library computes them in float32."""
    axes = []
    for a in range(3):
        cells = shape[a] - 1
        lo = np.float32(origin[a])
        hi = np.float32(origin[a] + spacing[a] * cells)
        h = np.float32((hi - lo) / np.float32(cells))
        axes.append((lo, np.float32(h * np.float32(0.5)), cells))
    return axes


def _centre_positions(shape, spacing, origin):
    """World coordinates (x, y, z) of the cube centres with their ghost layer, shape
    ``shape + 1``, computed as the library computes its body-centred points."""
    coords = []
    for lo, half, cells in _grid_axes(shape, spacing, origin):
        lattice = np.clip(np.arange(-1, 2 * cells + 2, 2), 0, 2 * cells).astype(np.float32)
        coords.append(lo + lattice * half)
    zz, yy, xx = np.meshgrid(*coords, indexing="ij")
    return xx, yy, zz


def _as_field(f: Callable[..., Any]) -> Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
    def call(x, y, z):
        r = np.asarray(f(x, y, z))
        if r.dtype.kind not in "fiu":
            raise TypeError(f"the field callable must return real numbers, got dtype {r.dtype}")
        with np.errstate(over="ignore"):
            return np.ascontiguousarray(np.broadcast_to(r, x.shape), dtype=np.float32)
    return call


def _mesh(result) -> Mesh:
    vertices, faces, normals, stats, box = result
    return Mesh(vertices, faces, normals, stats, box)


def extract(volume: Any, level: float = 0.0, *, spacing: Sequence[float] = (1.0, 1.0, 1.0),
            lattice: str = "simple", clustering: Optional[str] = None, method: str = "mt",
            normals: str = "gradient", threads: Optional[int] = None,
            centres: Any = None, origin: Sequence[float] = (0.0, 0.0, 0.0)) -> Mesh:
    """Extracts the isosurface ``volume == level`` of a sampled volume.

    Parameters
    ----------
    volume : (nz + 1, ny + 1, nx + 1) float array
        Values at the grid points, indexed ``volume[z, y, x]`` as scikit-image reads it.
    level : float
        The isovalue; inside is ``volume < level``.
    spacing : 3 floats
        Grid spacing in array order ``(dz, dy, dx)``, as in scikit-image.
    lattice : "simple" or "bcdl"
        Marching tetrahedra on the simple cubic lattice (six tetrahedra per cube) or on the
        body-centred lattice (needs ``centres``). Ignored by ``method="mc"``.
    clustering : None, "integrated", "integrated-unchecked", "none", "postprocessed", "meshopt"
        Vertex clustering; None takes the method's default: ``"integrated"`` (RMT) for
        marching tetrahedra, ``"none"`` for marching cubes and surface nets (which take no
        other).
    method : "mt", "mc" or "surface-nets"
        Marching tetrahedra, marching cubes, or surface nets (the peer).
    normals : "gradient", "area" or "none"
        Vertex normals: the gradient of the volume (central differences, interpolated
        trilinearly), the area-weighted face normals, or none.
    threads : int or None
        Worker threads (None: the machine's cores). The mesh does not depend on it.
    centres : (nz, ny, nx) or (nz + 2, ny + 2, nx + 2) float array, callable, or None
        Values at the cube centres, for ``lattice="bcdl"``: the cube centres, or the cube
        centres with the ghost layer (see the module doc), or ``centres(x, y, z)``, a
        vectorised callable evaluated once at every centre and ghost.
    origin : 3 floats
        World position of ``volume[0, 0, 0]``, array order ``(z, y, x)``. Not in scikit-image
        (which starts at 0, the default).

    Returns
    -------
    Mesh
        ``vertices`` (N, 3) float32 in (x, y, z) order, ``faces`` (M, 3) uint32, ``normals``,
        ``stats``; ``validate()``, ``quality()``, ``to_trimesh()``, ``write(path)``.
    """
    volume = _as_float32(volume, "volume")
    spacing = _triple(spacing, "spacing")
    origin = _triple(origin, "origin")
    if centres is not None:
        if callable(centres):
            xx, yy, zz = _centre_positions(volume.shape, spacing, origin)
            centres = _as_field(centres)(xx.ravel().astype(np.float64), yy.ravel().astype(np.float64),
                                         zz.ravel().astype(np.float64)).reshape(xx.shape)
            # Points that do not exist (outside two faces) are never read.
            centres = np.ascontiguousarray(centres)
        else:
            centres = _as_float32(centres, "centres")
    return _mesh(_native.extract_volume(volume, centres, float(level), spacing, origin, lattice,
                                        method, clustering, normals, threads))


def _cells(resolution: Any) -> Tuple[int, int, int]:
    if isinstance(resolution, (int, np.integer)):
        r = (int(resolution),) * 3
    else:
        r = tuple(int(v) for v in resolution)
    if len(r) != 3 or min(r) < 1:
        raise ValueError(f"resolution must be N or (nx, ny, nz) cells, each >= 1; got {resolution!r}")
    return r  # type: ignore[return-value]


def _bounds(bounds: Any) -> Tuple[float, ...]:
    b = tuple(float(v) for v in bounds)
    if len(b) != 6:
        raise ValueError(f"bounds must be (xmin, ymin, zmin, xmax, ymax, zmax), got {bounds!r}")
    return b


def extract_field(f: Callable[[np.ndarray, np.ndarray, np.ndarray], Any],
                  bounds: Sequence[float] = (-1.0, -1.0, -1.0, 1.0, 1.0, 1.0),
                  resolution: Union[int, Sequence[int]] = 64, *, lattice: str = "bcdl",
                  level: float = 0.0, clustering: Optional[str] = None, method: str = "mt",
                  normals: str = "gradient", threads: Optional[int] = None,
                  batch: int = 1 << 16) -> Mesh:
    """Samples a vectorised callable and extracts its isosurface ``f == level``.

    ``f(x, y, z)`` receives three float64 arrays of equal length (one batch of lattice points,
    up to ``batch`` points, world coordinates) and returns one value per point (any real
    dtype, converted to float32). It is called once per batch, never once per point: a 64^3
    body-centred grid (561,345 points) is 9 calls of 65,536 points. The overhead beyond ``f``'s
    own numpy work (listing the points, the coordinate arrays, the conversion and copy of the
    answers) was 14-45 ns per point on a busy 2-vCPU VM (``python/examples/overhead.py``),
    about as much as ``np.sqrt(x*x + y*y + z*z)`` itself; batches much larger than the default
    cost more (fresh memory for every batch). Sampling runs on the calling thread, with the
    GIL; the extraction after it runs on ``threads`` workers without the GIL. Gradient normals
    call ``f`` again on six points per vertex.

    ``bounds`` is ``(xmin, ymin, zmin, xmax, ymax, zmax)`` and ``resolution`` the cells per
    axis, ``N`` or ``(nx, ny, nz)``, in the command line's (x, y, z) order. The body-centred
    lattice (the default here) samples the cube corners, the cube centres and the ghosts on
    the box faces, exactly the library's points. Other arguments as in :func:`extract`.
    """
    if not callable(f):
        raise TypeError("f must be a callable f(x, y, z) over numpy arrays")
    return _mesh(_native.extract_field(_as_field(f), _bounds(bounds), _cells(resolution),
                                       float(level), lattice, method, clustering, normals,
                                       threads, int(batch)))


class Sampled:
    """A built-in object sampled on a lattice (from :func:`sample`).

    Attributes
    ----------
    volume : (nz + 1, ny + 1, nx + 1) float32 array
        The values at the grid points, ``volume[z, y, x]``.
    centres : (nz + 2, ny + 2, nx + 2) float32 array or None
        Body-centred lattice only: the cube centres with the ghost layer (NaN where no point
        exists).
    spacing, origin : 3 floats, array order (z, y, x)
    lattice, object : str
    """

    __slots__ = ("volume", "centres", "spacing", "origin", "lattice", "object")

    def __init__(self, volume, centres, spacing, origin, lattice, object):  # noqa: A002
        self.volume = volume
        self.centres = centres
        self.spacing = spacing
        self.origin = origin
        self.lattice = lattice
        self.object = object

    def __repr__(self) -> str:
        return f"Sampled({self.object!r}, lattice={self.lattice!r}, shape={self.volume.shape})"

    def extract(self, level: float = 0.0, **kwargs: Any) -> Mesh:
        """:func:`extract` on these values, lattice, spacing and origin (keyword arguments as
        there). The same object, box and resolution give the command line's mesh, byte for
        byte (``experiments extract --object ... --out``)."""
        kwargs.setdefault("lattice", self.lattice)
        return extract(self.volume, level, spacing=self.spacing, origin=self.origin,
                       centres=self.centres if kwargs["lattice"] == "bcdl" else None, **kwargs)


def sample(object: str, resolution: Union[int, Sequence[int]] = 50,  # noqa: A002
           lattice: str = "bcdl", seed: Optional[int] = None, *,
           bounds: Sequence[float] = (-1.0, -1.0, -1.0, 1.0, 1.0, 1.0),
           threads: Optional[int] = None, **params: Any) -> Sampled:
    """Samples a built-in object (one of :data:`OBJECTS`) as the command line does
    (``experiments extract --object OBJECT --resolution R --lattice L --bounds B``), to
    reproduce the dissertation's configurations in a notebook.

    ``params`` are the object's own parameters, as on the command line (``radius`` for the
    sphere and asteroid; ``octaves``, ``frequency``, ``amplitude`` for the noise objects;
    ``major``, ``minor`` for the torus; ``thickness`` for the gyroid; ``base``,
    ``cave_frequency``, ``cave_radius``, ``cave_ceiling`` for the terrains; ``mesh``,
    ``margin``, ``band`` for the bunny). ``seed`` applies to the noise objects and
    ``random``. Every point is evaluated (dense sampling).
    """
    if seed is not None:
        params["seed"] = int(seed)
    volume, centres, spacing, origin = _native.sample(str(object), _cells(resolution), lattice,
                                                      _bounds(bounds), params, threads)
    return Sampled(volume, centres, spacing, origin, lattice, str(object))
