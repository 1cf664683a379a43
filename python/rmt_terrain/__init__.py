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
* :func:`extract` follows ``skimage.measure.marching_cubes``: ``volume[i, j, k]`` is a
  C-ordered array whose axes are, say, (z, y, x) (the last axis varies fastest); ``spacing``
  (and ``origin``) are given in the same array order ``(dz, dy, dx)``, and the returned
  ``vertices`` (and ``normals``) are in that array order too: vertex ``(a, b, c)`` lies at
  ``origin + (i, j, k) * spacing``, so ``a`` runs along axis 0 (z), ``c`` along axis 2 (x).
  Vertices from scikit-image and from us overlay directly. ``mesh.axes`` is ``"zyx"``.
* :func:`extract_field`, :func:`sample` and the command line work in world ``(x, y, z)``
  order: ``bounds`` and ``resolution`` are (x, y, z), ``f(x, y, z)`` gets world coordinates,
  and the mesh of :func:`extract_field` has ``(x, y, z)`` vertices (``mesh.axes == "xyz"``).
  :meth:`Mesh.with_axes` turns one order into the other (exactly: it only moves values), e.g.
  ``mesh.with_axes("xyz").write(path)`` writes the command line's file, byte for byte.
* Inside is ``volume < level``; ``volume == level`` counts as outside. Triangles are
  counter-clockwise seen from the side of increasing values *in the mesh's own frame* (the
  right-hand normal of each face points toward increasing values, outward for a signed
  distance field, negative inside). Swapping x and z mirrors the frame, so a ``"zyx"`` mesh has
  every triangle's last two corners swapped against its ``"xyz"`` twin; this is scikit-image's
  winding with its default ``gradient_direction="descent"`` (checked by the tests on a sphere).
  Our ``normals`` also point toward increasing values; scikit-image's point the other way.
* ``volume`` may be any floating-point array. A C-contiguous float32 array is used without a
  copy: on the simple lattice (and for ``method="mc"`` and ``"surface-nets"``) the extractor
  reads it in place and refuses non-finite values in its first pass over them, which reads
  every value anyway (no scan of its own; ``stats["input_copied"]`` is False). Other float arrays are converted to C-contiguous float32
  first (one copy, by numpy). The body-centred lattice interleaves corner and centre planes in
  its sample array, so there the values are copied into it (``stats["input_copied"]`` True).
  Do not write to the volume from another thread during the call.
* The body-centred lattice (``lattice="bcdl"``) also samples the centre of every cube: pass
  ``centres`` of shape ``volume.shape - 1`` (``centres[k, j, i]`` at the centre of cube
  ``[k, j, i]``). Between each cube face on the box and the centre inside lies half an
  octahedron, a pyramid; it is split into two tetrahedra along the face diagonal through the
  face's lowest corner, whose crossing is a vertex of its own, so no value outside the box is
  needed and the mesh is closed wherever the surface stays inside the box. Integrated
  clustering leaves the crossings within one and a half cells of the box faces alone there
  (no cluster's triangles touch a pyramid), so its guarantee holds. The library's own
  lattice closes the pyramids instead with the centres of the cubes just outside the box
  ("ghosts", sampled on the face, at its centre): pass ``centres`` of shape
  ``volume.shape + 1`` (the ghost layer included, as :func:`sample` returns them; entries
  outside two or three faces are not read), or a callable ``centres(x, y, z)``, or
  ``centres`` of shape ``volume.shape - 1`` together with ``ghosts``: a number (every ghost has
  that value) or a callable ``ghosts(x, y, z)`` evaluated at the ghosts. The two meshes are the
  same more than a cell inside the box. Centres are never guessed: without them
  ``lattice="bcdl"`` is refused.
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
        Vertex positions in the order ``axes``: the volume's array order (z, y, x) from
        :func:`extract`, world (x, y, z) from :func:`extract_field`. The array owns the
        extractor's buffer (no copy).
    faces : ndarray, (M, 3) uint32
        Vertex indices, counter-clockwise seen from increasing values in that frame.
    normals : ndarray, (N, 3) float32, or None
        Unit vertex normals, toward increasing values, in the order ``axes``
        (``normals="none"`` gives None).
    axes : str
        ``"zyx"`` (array order, :func:`extract`) or ``"xyz"`` (world order); see
        :meth:`with_axes`.
    stats : dict
        Counters and stage times of the extraction (the command line's ``--json`` keys:
        ``vertices``, ``triangles``, ``crossings``, ``clusters_committed``, ``t_total_s``,
        ``t_sampling_s``, ``t_vertex_s``, ``t_geometry_s``, ``t_normals_s``, ...).
        ``t_total_s`` is the Rust extraction (with gradient normals; on the simple lattice
        its first pass also checks the values for NaN and infinities), ``t_input_s`` the copy
        and check of the input before it (body-centred lattice; about 0 otherwise),
        ``t_reorder_s`` turning the mesh into array order after it (0 for marching cubes and
        plain MT, which write it in that order), ``t_call_s`` the whole compiled call (input, extraction
        and conversion of the result; the rest of a call's time is the Python wrapper).
        ``input_copied`` (from :func:`extract`) says whether the volume was copied into the
        extractor's sample array (body-centred lattice) or read in place.
    """

    __slots__ = ("vertices", "faces", "normals", "stats", "axes", "_box")

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, normals: Optional[np.ndarray],
                 stats: Dict[str, Any], box: Any = None, axes: str = "xyz") -> None:
        if axes not in ("xyz", "zyx"):
            raise ValueError(f"axes must be 'xyz' or 'zyx', got {axes!r}")
        self.vertices = vertices
        self.faces = faces
        self.normals = normals
        self.stats = stats
        self.axes = axes
        self._box = box

    def __repr__(self) -> str:
        return f"Mesh({len(self.vertices)} vertices, {len(self.faces)} faces, axes={self.axes!r})"

    def with_axes(self, axes: str) -> "Mesh":
        """This mesh in the coordinate order ``axes`` (``"xyz"`` or ``"zyx"``): itself when it
        is already in that order, else a copy with the first and last coordinates of every
        vertex and normal swapped and every face's last two corners swapped, so that its faces
        stay counter-clockwise seen from increasing values in the mirrored frame. Exact: only
        values move, and converting back gives the same arrays."""
        if axes not in ("xyz", "zyx"):
            raise ValueError(f"axes must be 'xyz' or 'zyx', got {axes!r}")
        if axes == self.axes:
            return self
        vertices = np.ascontiguousarray(self.vertices[:, ::-1])
        faces = np.ascontiguousarray(self.faces[:, [0, 2, 1]])
        normals = None if self.normals is None else np.ascontiguousarray(self.normals[:, ::-1])
        box = None
        if self._box is not None:
            lo, hi, cells = self._box
            box = (tuple(lo)[::-1], tuple(hi)[::-1], tuple(cells)[::-1])
        stats = dict(self.stats, axes=axes)
        return Mesh(vertices, faces, normals, stats, box, axes)

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
        by the extension: the command line's writers, so the same mesh gives the same bytes.
        The file holds ``vertices`` as they are, in the order ``axes``; the command line's
        files are (x, y, z): ``mesh.with_axes("xyz").write(path)``."""
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
    return Mesh(vertices, faces, normals, stats, box, stats["axes"])


def _ghost_mask(shape: Tuple[int, int, int]) -> np.ndarray:
    """The ghosts of a centre array of ``shape`` (ghost layer included): the entries outside
    exactly one face of the box."""
    outside = [np.zeros(n, dtype=np.int8) for n in shape]
    for o in outside:
        o[0] = o[-1] = 1
    count = outside[0][:, None, None] + outside[1][None, :, None] + outside[2][None, None, :]
    return count == 1


def _centres_with_ghosts(centres: np.ndarray, ghosts: Any, shape, spacing, origin) -> np.ndarray:
    """The centres of shape ``shape - 1`` and the user's ``ghosts`` (a number or a callable)
    as one array of shape ``shape + 1`` (NaN at the entries that are never read)."""
    finite = np.isfinite(centres)
    if not finite.all():
        at = np.unravel_index(int(np.argmin(finite.ravel())), centres.shape)
        raise ValueError(f"centres is not finite at index [{at[0]}, {at[1]}, {at[2]}] (z, y, x): "
                         f"got {centres[at]}; the first such value in C order")
    full = np.full(tuple(s + 1 for s in shape), np.nan, dtype=np.float32)
    full[1:-1, 1:-1, 1:-1] = centres
    mask = _ghost_mask(full.shape)
    if callable(ghosts):
        xx, yy, zz = _centre_positions(shape, spacing, origin)
        x, y, z = (c[mask].astype(np.float64) for c in (xx, yy, zz))
        values = _as_field(ghosts)(x, y, z)
        bad = np.flatnonzero(~np.isfinite(values))
        if len(bad):
            k = bad[0]
            raise ValueError(f"ghosts(x, y, z) is not finite at ({x[k]}, {y[k]}, {z[k]}): got "
                             f"{values[k]}")
        full[mask] = values
    else:
        if isinstance(ghosts, (bool, np.bool_)):
            raise TypeError("ghosts must be a number or a callable ghosts(x, y, z), got a bool")
        try:
            value = float(ghosts)
        except (TypeError, ValueError):
            raise TypeError("ghosts must be a number or a callable ghosts(x, y, z), got "
                            f"{type(ghosts).__name__}") from None
        if not np.isfinite(np.float32(value)):
            raise ValueError(f"ghosts must be finite in float32, got {value}")
        full[mask] = np.float32(value)
    return full


def extract(volume: Any, level: float = 0.0, *, spacing: Sequence[float] = (1.0, 1.0, 1.0),
            lattice: str = "simple", clustering: str = "integrated", method: str = "mt",
            normals: str = "gradient", threads: Optional[int] = None,
            centres: Any = None, ghosts: Any = None,
            origin: Sequence[float] = (0.0, 0.0, 0.0)) -> Mesh:
    """Extracts the isosurface ``volume == level`` of a sampled volume, in the shape of
    ``skimage.measure.marching_cubes(volume, level, spacing=...)``.

    Parameters
    ----------
    volume : (nz + 1, ny + 1, nx + 1) float array
        Values at the grid points, indexed ``volume[z, y, x]`` (C order) as scikit-image reads
        it. Used without a copy when it is C-contiguous float32 (simple lattice, marching
        cubes, surface nets; the body-centred lattice copies it into its interleaved sample
        array).
    level : float
        The isovalue; inside is ``volume < level``.
    spacing : 3 floats
        Grid spacing in array order ``(dz, dy, dx)``, as in scikit-image.
    lattice : "simple" or "bcdl"
        Marching tetrahedra on the simple cubic lattice (six tetrahedra per cube) or on the
        body-centred lattice (needs ``centres``, see below). Ignored by ``method="mc"`` and
        ``"surface-nets"``.
    clustering : "integrated", "none", "integrated-unchecked", "postprocessed", "meshopt"
        Vertex clustering of marching tetrahedra: ``"integrated"`` is RMT (clusters checked
        as they are made), ``"none"`` plain marching tetrahedra. Marching cubes and surface
        nets have no clustering: they run without it under the default or ``"none"``, and
        refuse the other modes.
    method : "mt", "mc" or "surface-nets"
        Marching tetrahedra, marching cubes, or surface nets (the peer).
    normals : "gradient", "area" or "none"
        Vertex normals: the gradient of the volume (central differences, interpolated
        trilinearly), the area-weighted face normals, or none. They point toward increasing
        values.
    threads : int or None
        Worker threads (None: the machine's cores). The mesh does not depend on it.
    centres : (nz + 2, ny + 2, nx + 2) or (nz, ny, nx) float array, callable, or None
        Values at the cube centres, for ``lattice="bcdl"``: with the ghost layer (entry
        ``[k + 1, j + 1, i + 1]`` is the centre of cube ``[k, j, i]``; the first and last
        entries along an axis are the ghosts on that box face, as :func:`sample` returns
        them), or without it (the box faces are then closed by pyramids, see the module doc,
        unless ``ghosts`` is given), or ``centres(x, y, z)``, a vectorised callable of world
        coordinates evaluated once at every centre and ghost.
    ghosts : number, callable, or None
        With ``(nz, ny, nx)`` centres only, optional: the values of the ghosts (the centres of
        the cubes just outside the box, sampled at the centre of their box face): one number
        for all, or ``ghosts(x, y, z)`` evaluated at them. Never guessed; see the module doc.
    origin : 3 floats
        World position of ``volume[0, 0, 0]``, array order ``(z, y, x)``. Not in scikit-image
        (which starts at 0, the default).

    Returns
    -------
    Mesh
        ``vertices`` (N, 3) float32 and ``normals`` in array order (z, y, x) like
        scikit-image's, ``faces`` (M, 3) uint32 (counter-clockwise seen from increasing values
        in that frame), ``stats``, ``axes == "zyx"``; ``validate()``, ``quality()``,
        ``to_trimesh()``, ``write(path)``, ``with_axes("xyz")``.
    """
    volume = _as_float32(volume, "volume")
    spacing = _triple(spacing, "spacing")
    origin = _triple(origin, "origin")
    if centres is not None and (lattice != "bcdl" or method != "mt"):
        raise ValueError("centres are read only on the body-centred lattice (lattice='bcdl' "
                         f"with method='mt'), got lattice={lattice!r}, method={method!r}")
    if ghosts is not None and (centres is None or callable(centres)):
        raise ValueError("ghosts= completes centres of shape volume.shape - 1; a callable "
                         "centres gives the ghosts itself")
    if centres is not None:
        if callable(centres):
            xx, yy, zz = _centre_positions(volume.shape, spacing, origin)
            centres = _as_field(centres)(xx.ravel().astype(np.float64), yy.ravel().astype(np.float64),
                                         zz.ravel().astype(np.float64)).reshape(xx.shape)
            # Points that do not exist (outside two faces) are never read.
            centres = np.ascontiguousarray(centres)
        else:
            centres = _as_float32(centres, "centres")
            inner = tuple(s - 1 for s in volume.shape)
            if centres.shape == inner:
                # Without ghosts= the box faces are closed by pyramids (no ghost needed).
                if ghosts is not None:
                    centres = _centres_with_ghosts(centres, ghosts, volume.shape, spacing,
                                                   origin)
            elif ghosts is not None:
                raise ValueError(f"ghosts= completes centres of shape {inner}; got centres of "
                                 f"shape {centres.shape}")
    return _mesh(_native.extract_volume(volume, centres, float(level), spacing, origin, lattice,
                                        method, str(clustering), normals, threads))


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
                  level: float = 0.0, clustering: str = "integrated", method: str = "mt",
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
    axis, ``N`` or ``(nx, ny, nz)``, in the command line's (x, y, z) order, and the mesh is in
    world order too: ``(x, y, z)`` vertices and normals, ``mesh.axes == "xyz"`` (the command
    line's mesh; :meth:`Mesh.with_axes` gives the array order of :func:`extract`). The
    body-centred lattice (the default here) samples the cube corners, the cube centres and the
    ghosts on the box faces, exactly the library's points. Other arguments as in
    :func:`extract`.
    """
    if not callable(f):
        raise TypeError("f must be a callable f(x, y, z) over numpy arrays")
    return _mesh(_native.extract_field(_as_field(f), _bounds(bounds), _cells(resolution),
                                       float(level), lattice, method, str(clustering),
                                       normals, threads, int(batch)))


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
        there): a mesh in array order (z, y, x), like every :func:`extract`. In world order,
        ``.with_axes("xyz")``, it is the command line's mesh for the same object, box and
        resolution, byte for byte (``experiments extract --object ... --out``)."""
        kwargs.setdefault("lattice", self.lattice)
        bcdl = kwargs["lattice"] == "bcdl" and kwargs.get("method", "mt") == "mt"
        return extract(self.volume, level, spacing=self.spacing, origin=self.origin,
                       centres=self.centres if bcdl else None, **kwargs)


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
