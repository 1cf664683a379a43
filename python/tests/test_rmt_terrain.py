"""Tests of the rmt_terrain package: the command line's bytes, scikit-image's marching cubes
(vertices overlaid in array order, the same winding), topology on random volumes, conventions,
the body-centred lattice's ghosts, bad input, the GIL, the volume read without a copy, and
memory over many calls.

The byte-for-byte comparison runs the command line binary named by ``RMT_EXPERIMENTS`` (CI
passes target/release/experiments), else ``target/release/experiments`` of this checkout; it
is skipped, with a message saying so, only when no such binary exists.
"""

import inspect
import json
import os
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import rmt_terrain

ROOT = Path(__file__).resolve().parents[2]


def sphere_volume(n, radius=0.7, dtype=np.float32):
    g = np.linspace(-1, 1, n + 1)
    z, y, x = np.meshgrid(g, g, g, indexing="ij")
    return (np.sqrt(x * x + y * y + z * z) - radius).astype(dtype)


def random_volume(rng, shape):
    """A smooth random field: a sum of random plane waves plus a random offset."""
    z, y, x = np.meshgrid(*(np.linspace(0, 1, s) for s in shape), indexing="ij")
    v = np.zeros(shape)
    for _ in range(6):
        k = rng.normal(0, 6, 3)
        v += np.cos(k[0] * x + k[1] * y + k[2] * z + rng.uniform(0, 2 * np.pi))
    return (v + rng.uniform(-1, 1)).astype(np.float32)


# ---------------------------------------------------------------- the command line's bytes

def experiments_binary():
    given = os.environ.get("RMT_EXPERIMENTS")
    path = Path(given) if given else ROOT / "target" / "release" / "experiments"
    return path if path.is_file() else None


CLI_CASES = [
    # (object args, resolution, lattice, clustering or None, method, extension)
    (["--object", "sphere", "--radius", "0.8"], 24, "bcdl", None, "mt", "ply"),
    (["--object", "asteroid"], 32, "bcdl", "integrated", "mt", "obj"),
    (["--object", "torus"], 20, "simple", "none", "mt", "glb"),
    (["--object", "gyroid"], 16, "bcdl", "postprocessed", "mt", "ply"),
    (["--object", "random", "--seed", "3"], 20, "simple", None, "mc", "ply"),
    (["--object", "caves", "--octaves", "3"], 20, "bcdl", "integrated-unchecked", "mt", "ply"),
    (["--object", "bunny"], 24, "simple", None, "mt", "ply"),
]


@pytest.mark.parametrize("case", CLI_CASES, ids=lambda c: f"{c[0][1]}-{c[2]}-{c[4]}-{c[5]}")
def test_same_bytes_as_the_command_line(case, tmp_path):
    exe = experiments_binary()
    if exe is None:
        pytest.skip("no experiments binary (set RMT_EXPERIMENTS or build target/release/"
                    "experiments): the byte-for-byte comparison with the command line is skipped")
    args, n, lattice, clustering, method, ext = case
    cli_out = tmp_path / f"cli.{ext}"
    cmd = [str(exe), "extract", *args, "--resolution", str(n), "--lattice", lattice,
           "--method", method, "--threads", "2", "--out", str(cli_out)]
    if clustering:
        cmd += ["--clustering", clustering]
    subprocess.run(cmd, check=True, capture_output=True, cwd=ROOT)
    params = {}
    for flag, value in zip(args[2::2], args[3::2]):
        params[flag.lstrip("-")] = float(value) if "." in value else int(value)
    s = rmt_terrain.sample(args[1], n, lattice, **params)
    kw = {"method": method, "normals": "area", "threads": 1}
    if clustering:
        kw["clustering"] = clustering
    mesh = s.extract(**kw)
    # extract() answers in array order (z, y, x); the command line in world order.
    assert mesh.axes == "zyx"
    py_out = tmp_path / f"py.{ext}"
    mesh.with_axes("xyz").write(py_out)
    assert len(mesh.faces) > 0
    assert cli_out.read_bytes() == py_out.read_bytes()


# ------------------------------------------------------------------ scikit-image's marching cubes

def off_centre_ball(shape=(41, 49, 57), spacing=(0.05, 0.04, 0.035), centre=(1.1, 0.9, 1.0),
                    radius=0.6):
    """A ball off the volume's centre, on an anisotropic grid of unequal axes: any mix-up of the
    axes, of their spacing or of their order moves it."""
    axes = [np.arange(n) * d for n, d in zip(shape, spacing)]
    a0, a1, a2 = np.meshgrid(*axes, indexing="ij")
    d = np.sqrt((a0 - centre[0]) ** 2 + (a1 - centre[1]) ** 2 + (a2 - centre[2]) ** 2)
    return (d - radius).astype(np.float32)


def face_normals(vertices, faces):
    v = vertices.astype(np.float64)
    a, b, c = v[faces[:, 0]], v[faces[:, 1]], v[faces[:, 2]]
    return np.cross(b - a, c - a), (a + b + c) / 3


def test_marching_cubes_matches_scikit_image_on_a_sphere():
    skimage_measure = pytest.importorskip("skimage.measure")
    spatial = pytest.importorskip("scipy.spatial")
    spacing, centre = (0.05, 0.04, 0.035), (1.1, 0.9, 1.0)
    volume = off_centre_ball(spacing=spacing, centre=centre)
    mesh = rmt_terrain.extract(volume, 0.0, spacing=spacing, method="mc")
    verts, faces, normals, _ = skimage_measure.marching_cubes(volume, 0.0, spacing=spacing)
    assert mesh.axes == "zyx"
    # Same triangles, same vertices, overlaid as they come (both in array order z, y, x).
    assert len(mesh.faces) == len(faces)
    assert len(mesh.vertices) == len(verts)
    d, match = spatial.cKDTree(verts.astype(np.float64)).query(mesh.vertices.astype(np.float64))
    assert d.max() < 1e-5 * min(spacing) and len(np.unique(match)) == len(verts)
    # The same triangles with the same winding: each of ours, in scikit-image's vertex ids, is
    # one of scikit-image's faces up to a rotation of its corners (a rotation keeps the
    # winding; a reflection would not).
    def rotated_to_least(f):
        k = np.argmin(f, axis=1)
        return np.stack([f[np.arange(len(f)), (k + i) % 3] for i in range(3)], axis=1)
    ours = {tuple(t) for t in rotated_to_least(match[mesh.faces.astype(np.int64)])}
    theirs = {tuple(t) for t in rotated_to_least(faces.astype(np.int64))}
    assert ours == theirs
    # Outward in this frame, like scikit-image's default (gradient_direction="descent").
    n, c = face_normals(mesh.vertices, mesh.faces)
    assert np.all(np.sum(n * (c - centre), axis=1) > 0)
    # Normals in array order too: ours point toward increasing values, scikit-image's the
    # other way.
    cos = np.sum(mesh.normals * normals[match], axis=1)
    assert np.min(cos) < -0.0 and np.median(cos) < -0.99
    assert mesh.validate()["watertight_manifold"]


def test_rmt_overlays_scikit_image_on_a_sphere():
    skimage_measure = pytest.importorskip("skimage.measure")
    spatial = pytest.importorskip("scipy.spatial")
    spacing, centre, radius = (0.05, 0.04, 0.035), (1.1, 0.9, 1.0), 0.6
    volume = off_centre_ball(spacing=spacing, centre=centre, radius=radius)
    verts, faces, _, _ = skimage_measure.marching_cubes(volume, 0.0, spacing=spacing)
    for kw in [{}, {"clustering": "none"}]:
        mesh = rmt_terrain.extract(volume, 0.0, spacing=spacing, **kw)
        v = mesh.vertices.astype(np.float64)
        # Both on the same sphere, in the same frame: every vertex of one is within a cell of
        # the other's surface, and every face of both points outward.
        for a, b in [(v, verts), (verts, v)]:
            d, _ = spatial.cKDTree(b).query(a)
            assert d.max() < max(spacing), kw
        r = np.linalg.norm(v - centre, axis=1)
        assert np.abs(r - radius).max() < 0.3 * max(spacing), kw
        for vv, ff in [(mesh.vertices, mesh.faces), (verts, faces)]:
            n, c = face_normals(vv, ff)
            assert np.all(np.sum(n * (c - centre), axis=1) > 0), kw
        n, c = face_normals(mesh.vertices, mesh.faces)
        # In world order (x, y, z) the same mesh is outward too, with the centre reversed.
        xyz = mesh.with_axes("xyz")
        n2, c2 = face_normals(xyz.vertices, xyz.faces)
        assert np.all(np.sum(n2 * (c2 - centre[::-1]), axis=1) > 0), kw
        np.testing.assert_array_equal(xyz.with_axes("zyx").vertices, mesh.vertices)
        np.testing.assert_array_equal(xyz.with_axes("zyx").faces, mesh.faces)


def test_rmt_has_far_fewer_triangles_than_marching_cubes():
    volume = sphere_volume(48)
    rmt = rmt_terrain.extract(volume, 0.0, lattice="simple")
    mc = rmt_terrain.extract(volume, 0.0, method="mc")
    assert len(rmt.faces) < 0.8 * len(mc.faces)
    assert rmt.quality()["ar_mean"] < mc.quality()["ar_mean"]


# ---------------------------------------------------------------------- topology on random volumes

@pytest.mark.parametrize("seed", range(6))
def test_random_volumes_are_closed_and_manifold(seed):
    rng = np.random.default_rng(seed)
    shape = tuple(int(s) for s in rng.integers(9, 26, 3))
    volume = random_volume(rng, shape)
    centres = random_volume(np.random.default_rng(seed), tuple(s - 1 for s in shape))
    configs = [
        {"lattice": "simple"},
        {"lattice": "simple", "clustering": "none"},
        {"lattice": "bcdl", "centres": (volume[1:, 1:, 1:] + volume[:-1, :-1, :-1]) / 2,
         "ghosts": 0.25},
        {"lattice": "bcdl", "centres": centres, "clustering": "postprocessed",
         "ghosts": lambda x, y, z: np.cos(3 * x) - np.sin(2 * z)},
        {"lattice": "bcdl", "centres": random_volume(np.random.default_rng(seed + 50),
                                                     tuple(s + 1 for s in shape))},
        {"method": "mc"},
    ]
    for kw in configs:
        mesh = rmt_terrain.extract(volume, 0.1, spacing=(0.5, 1.0, 2.0), **kw)
        report = mesh.validate()
        label = {k: v for k, v in kw.items() if k not in ("centres", "ghosts")}
        assert report["closed"] and report["manifold"] and report["oriented"], (label, report)
        assert report["watertight_manifold"], (label, report)


def test_integrated_clustering_keeps_the_topology_of_plain_mt():
    rng = np.random.default_rng(11)
    volume = random_volume(rng, (30, 28, 26))
    plain = rmt_terrain.extract(volume, 0.0, clustering="none").validate()
    rmt = rmt_terrain.extract(volume, 0.0, clustering="integrated").validate()
    assert (rmt["euler"], rmt["components"]) == (plain["euler"], plain["components"])


# ------------------------------------------------------------------------------- conventions

def test_volume_is_indexed_z_y_x_and_vertices_come_back_in_that_order():
    # A plane x = 1.3 in a volume whose axes have different lengths and spacings.
    nz, ny, nx = 5, 7, 9
    dz, dy, dx = 0.5, 0.25, 0.5
    x = np.arange(nx) * dx
    volume = np.broadcast_to(x - 1.3, (nz, ny, nx)).astype(np.float32)
    for method in ["mt", "mc", "surface-nets"]:
        mesh = rmt_terrain.extract(volume, 0.0, spacing=(dz, dy, dx), clustering="none",
                                   method=method)
        v = mesh.vertices
        assert mesh.axes == "zyx"
        # Column 2 is x (the last array axis), column 0 is z.
        np.testing.assert_allclose(v[:, 2], 1.3, atol=1e-5 if method != "surface-nets" else dx)
        # Surface nets puts its vertices inside cells: they stop half a cell from the box.
        inset = 0.5 if method == "surface-nets" else 0.0
        assert v[:, 1].min() == pytest.approx(inset * dy)
        assert v[:, 1].max() == pytest.approx((ny - 1 - inset) * dy)
        assert v[:, 0].min() == pytest.approx(inset * dz)
        assert v[:, 0].max() == pytest.approx((nz - 1 - inset) * dz)
        # Normals point toward increasing values, +x: their last component.
        assert np.all(mesh.normals[:, 2] > 0.99), method
        # Faces wound toward increasing values in this frame.
        n, _ = face_normals(v, mesh.faces)
        assert np.all(n[:, 2] > 0) and np.allclose(n[:, :2], 0, atol=1e-6), method
        # World order: x first.
        w = mesh.with_axes("xyz")
        np.testing.assert_allclose(w.vertices[:, 0], 1.3, atol=1e-5)
        assert np.all(w.normals[:, 0] > 0.99)
        n, _ = face_normals(w.vertices, w.faces)
        assert np.all(n[:, 0] > 0), method


def test_origin_shifts_the_mesh():
    volume = sphere_volume(16)
    # Plain MT: clustering decisions read positions, so they may differ in the last bits.
    a = rmt_terrain.extract(volume, spacing=(0.125,) * 3, clustering="none")
    b = rmt_terrain.extract(volume, spacing=(0.125,) * 3, origin=(-1.0, -1.0, -1.0),
                            clustering="none")
    np.testing.assert_allclose(b.vertices, a.vertices - 1.0, atol=1e-6)
    np.testing.assert_array_equal(a.faces, b.faces)


def test_outputs_are_owned_arrays_of_the_promised_types():
    mesh = rmt_terrain.extract(sphere_volume(24), 0.0)
    assert mesh.vertices.dtype == np.float32 and mesh.vertices.shape[1] == 3
    assert mesh.faces.dtype == np.uint32 and mesh.faces.shape[1] == 3
    assert mesh.normals.shape == mesh.vertices.shape
    # Rust's buffers, handed over: the arrays are views of a Rust-owned container.
    assert not mesh.vertices.flags.owndata and mesh.vertices.base is not None
    assert mesh.faces.max() < len(mesh.vertices)
    assert mesh.stats["triangles"] == len(mesh.faces)
    assert mesh.stats["vertices"] == len(mesh.vertices)
    assert mesh.stats["t_total_s"] > 0


def test_stats_have_the_command_lines_fields_and_types():
    # The stats dict is built from the library's Stats directly (no JSON in between): every
    # field the command line's --json prints, in its order, with its type, on every call.
    exe = experiments_binary()
    if exe is None:
        pytest.skip("no experiments binary (set RMT_EXPERIMENTS or build target/release/"
                    "experiments): the comparison with the command line's --json is skipped")
    out = subprocess.run([str(exe), "extract", "--object", "sphere", "--radius", "0.7",
                          "--resolution", "16", "--lattice", "simple", "--method", "mc",
                          "--threads", "1", "--json"],
                         check=True, capture_output=True, cwd=ROOT, text=True).stdout
    cli = json.loads(out)
    keys = list(cli)
    fields = keys[keys.index("vertices"):keys.index("bytes_indices") + 1]
    assert len(fields) > 30
    for _ in range(3):
        mesh = rmt_terrain.extract(sphere_volume(16), 0.0, method="mc", normals="area")
        assert list(mesh.stats)[:len(fields)] == fields
        for k in fields:
            assert type(mesh.stats[k]) is type(cli[k]), k
        assert mesh.stats["triangles"] == len(mesh.faces)
        assert mesh.stats["vertices"] == len(mesh.vertices)
        assert mesh.stats["input_copied"] is False and mesh.stats["axes"] == "zyx"
        assert 0 < mesh.stats["t_total_s"] < mesh.stats["t_call_s"]


def test_any_float_dtype_and_layout_give_the_same_mesh():
    v32 = sphere_volume(20)
    ref = rmt_terrain.extract(v32, 0.0)
    for v in [v32.astype(np.float64), np.asfortranarray(v32), v32[:, :, ::-1][:, :, ::-1]]:
        m = rmt_terrain.extract(v, 0.0)
        np.testing.assert_array_equal(m.vertices, ref.vertices)
        np.testing.assert_array_equal(m.faces, ref.faces)


def test_thread_counts_give_identical_meshes():
    volume = random_volume(np.random.default_rng(5), (33, 33, 33))
    one = rmt_terrain.extract(volume, 0.0, threads=1)
    two = rmt_terrain.extract(volume, 0.0, threads=2)
    np.testing.assert_array_equal(one.vertices, two.vertices)
    np.testing.assert_array_equal(one.faces, two.faces)


def test_gradient_normals_of_a_sphere_point_outward():
    n = 32
    mesh = rmt_terrain.extract(sphere_volume(n), 0.0, spacing=(2 / n,) * 3, origin=(-1, -1, -1))
    radial = mesh.vertices / np.linalg.norm(mesh.vertices, axis=1, keepdims=True)
    assert np.min(np.sum(radial * mesh.normals, axis=1)) > 0.99


def test_clustering_defaults_to_integrated():
    assert inspect.signature(rmt_terrain.extract).parameters["clustering"].default == "integrated"
    assert inspect.signature(rmt_terrain.extract_field).parameters["clustering"].default == \
        "integrated"
    volume = random_volume(np.random.default_rng(4), (25, 27, 29))
    default = rmt_terrain.extract(volume, 0.0)
    integrated = rmt_terrain.extract(volume, 0.0, clustering="integrated")
    plain = rmt_terrain.extract(volume, 0.0, clustering="none")
    np.testing.assert_array_equal(default.faces, integrated.faces)
    assert default.stats["clusters_committed"] > 0 and plain.stats["clusters_committed"] == 0
    assert len(default.faces) < len(plain.faces)
    # Marching cubes has no clustering: the default runs it as 'none' does.
    mc = rmt_terrain.extract(volume, 0.0, method="mc")
    mc_none = rmt_terrain.extract(volume, 0.0, method="mc", clustering="none")
    np.testing.assert_array_equal(mc.faces, mc_none.faces)


# ------------------------------------------------------------------ body-centred lattice, ghosts

def ghost_case(n=16):
    """A ball that crosses the box's z = max face, so the ghosts on that face shape the mesh."""
    def f(x, y, z):
        return np.sqrt(x * x + y * y + (z - 0.8) ** 2) - 0.5

    h = np.float32(2.0) / np.float32(n)
    g = (np.float32(-1) + np.arange(0, 2 * n + 1, 2, dtype=np.float32) * (h * np.float32(0.5)))
    z, y, x = np.meshgrid(g.astype(np.float64), g, g, indexing="ij")
    return f, f(x, y, z).astype(np.float32), dict(spacing=(2 / n,) * 3, origin=(-1, -1, -1),
                                                  lattice="bcdl", normals="area")


def test_ghosts_are_given_never_guessed():
    f, volume, kw = ghost_case()
    # The exact ghosts three ways: a callable for all centres, the (n + 2) centres with the
    # ghost layer (as sample() returns them), the (n) centres with a callable for the ghosts.
    by_callable = rmt_terrain.extract(volume, 0.0, centres=f, **kw)
    with_layer = rmt_terrain.sample("sphere", 16, "bcdl", radius=0.5)  # shape check below
    assert with_layer.centres.shape == tuple(s + 1 for s in volume.shape)
    n = volume.shape[0] - 1
    from rmt_terrain import _centre_positions  # the library's centre and ghost positions
    xx, yy, zz = _centre_positions(volume.shape, kw["spacing"], kw["origin"])
    layer = f(xx.astype(np.float64), yy.astype(np.float64), zz.astype(np.float64))
    by_layer = rmt_terrain.extract(volume, 0.0, centres=layer.astype(np.float32), **kw)
    inner = layer[1:-1, 1:-1, 1:-1].astype(np.float32)
    assert inner.shape == (n, n, n)
    by_ghosts = rmt_terrain.extract(volume, 0.0, centres=inner, ghosts=f, **kw)
    for m in [by_layer, by_ghosts]:
        np.testing.assert_array_equal(m.vertices, by_callable.vertices)
        np.testing.assert_array_equal(m.faces, by_callable.faces)
    # The mesh reaches the box face z = 1 (array column 0), and the ghosts shape it there:
    # other ghost values give another mesh, so they are read, not made up.
    assert by_callable.vertices[:, 0].max() == pytest.approx(1.0)
    outside = rmt_terrain.extract(volume, 0.0, centres=inner, ghosts=1.0, **kw)
    assert not np.array_equal(outside.vertices, by_callable.vertices)
    assert outside.validate()["closed"] and by_callable.validate()["closed"]
    # Without centres, the body-centred lattice is refused, with the reason.
    with pytest.raises(ValueError, match="not guessed by interpolation"):
        rmt_terrain.extract(volume, 0.0, **kw)
    with pytest.raises(ValueError, match="ghosts= completes"):
        rmt_terrain.extract(volume, 0.0, centres=f, ghosts=1.0, **kw)
    with pytest.raises(ValueError, match="ghosts= completes"):
        rmt_terrain.extract(volume, 0.0, centres=layer.astype(np.float32), ghosts=1.0, **kw)
    with pytest.raises(ValueError, match="finite"):
        rmt_terrain.extract(volume, 0.0, centres=inner, ghosts=float("inf"), **kw)
    with pytest.raises(TypeError, match="ghosts must be"):
        rmt_terrain.extract(volume, 0.0, centres=inner, ghosts="outside", **kw)


def _inner_triangles(mesh, lo, hi, margin):
    """The triangles with every corner more than ``margin`` inside the box, as sorted tuples of
    their corners' coordinates (each rotated to start at its smallest corner: orientation
    kept), so that two meshes compare without their vertex numbering."""
    v = mesh.vertices
    inside = np.all((v > lo + margin) & (v < hi - margin), axis=1)
    out = []
    for t in mesh.faces[inside[mesh.faces].all(axis=1)]:
        c = [tuple(v[i].tolist()) for i in t]
        k = min(range(3), key=lambda i: c[i])
        out.append((c[k], c[(k + 1) % 3], c[(k + 2) % 3]))
    return sorted(out)


def test_centres_without_ghosts_close_the_box_with_pyramids():
    # Centres of the volume's shape minus 1 alone: each half-octahedron between a box face and
    # the centre inside is split into two tetrahedra. On random smooth fields that cross the
    # box faces: closed inside the box, manifold, oriented; and more than a cell inside the
    # box the mesh is the one the exact ghosts give.
    rng = np.random.default_rng(5)
    n = 14
    h = 2.0 / n
    for trial in range(4):
        waves = [(rng.normal(0, 5, 3), rng.uniform(0, 2 * np.pi)) for _ in range(5)]
        offset = rng.uniform(-1, 1)

        def f(x, y, z, waves=waves, offset=offset):
            v = np.full(np.shape(x), offset)
            for k, ph in waves:
                v = v + np.cos(k[0] * x + k[1] * y + k[2] * z + ph)
            return v

        g = -1.0 + h * np.arange(n + 1)
        z, y, x = np.meshgrid(g, g, g, indexing="ij")
        volume = f(x, y, z).astype(np.float32)
        c = -1.0 + h * (np.arange(n) + 0.5)
        cz, cy, cx = np.meshgrid(c, c, c, indexing="ij")
        centres = f(cx, cy, cz).astype(np.float32)
        for clustering in ["none", "integrated"]:
            kw = dict(spacing=(h,) * 3, origin=(-1, -1, -1), lattice="bcdl", normals="area",
                      clustering=clustering)
            mesh = rmt_terrain.extract(volume, 0.0, centres=centres, **kw)
            report = mesh.validate()
            what = f"trial {trial} {clustering}: {report}"
            assert report["closed"] and report["manifold"] and report["oriented"], what
            assert report["boundary_edges_on_box"] > 0, what  # it does meet the box faces
            ghosts = rmt_terrain.extract(volume, 0.0, centres=centres, ghosts=f, **kw)
            if clustering == "none":
                a = _inner_triangles(mesh, -1.0, 1.0, h * 1.01)
                b = _inner_triangles(ghosts, -1.0, 1.0, h * 1.01)
                assert len(a) > 100 and a == b, what
                assert len(mesh.faces) != len(ghosts.faces) or not np.array_equal(
                    mesh.vertices, ghosts.vertices), what


# ----------------------------------------------------------------------- the volume, not copied

def peak_rss_reset():
    """Resets the peak resident set size of this process (Linux: clear_refs 5); skips the test
    where the system does not allow it."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError as e:
        pytest.skip(f"cannot reset the peak resident set size: {e}")


def peak_rss():
    with open("/proc/self/status") as f:
        return next(int(l.split()[1]) * 1024 for l in f if l.startswith("VmHWM:"))


def test_a_c_contiguous_float32_volume_is_read_in_place():
    volume = sphere_volume(24)
    for kw in [{}, {"method": "mc"}, {"method": "surface-nets"}, {"clustering": "none"}]:
        assert rmt_terrain.extract(volume, 0.0, **kw).stats["input_copied"] is False, kw
    # Other layouts and dtypes are converted first (by numpy), then read in place too; the
    # body-centred lattice copies into its interleaved sample array.
    assert rmt_terrain.extract(np.asfortranarray(volume), 0.0).stats["input_copied"] is False
    bcdl = rmt_terrain.extract(volume, 0.0, lattice="bcdl", centres=sphere_volume(23),
                               ghosts=1.0)
    assert bcdl.stats["input_copied"] is True


@pytest.mark.skipif(not Path("/proc/self/clear_refs").exists(), reason="needs /proc (Linux)")
def test_no_copy_of_a_large_volume_in_peak_memory():
    # A 321^3 float32 volume (132 MB). Marching cubes' own working memory is small (rows and
    # planes of the volume), so the peak resident memory of the call shows whether the volume
    # was copied: the float64 twin of the same values is converted by numpy (one float32 copy)
    # and must show that copy; the float32 volume must not.
    n = 320
    g = np.linspace(-1, 1, n + 1, dtype=np.float32)
    volume = np.sqrt(g[:, None, None] ** 2 + g[None, :, None] ** 2 + g[None, None, :] ** 2)
    volume -= np.float32(0.7)
    as_f64 = volume.astype(np.float64)
    size = volume.nbytes
    rmt_terrain.extract(sphere_volume(16), 0.0, method="mc", normals="none")

    def growth(v):
        peak_rss_reset()
        before = peak_rss()
        mesh = rmt_terrain.extract(v, 0.0, method="mc", normals="none")
        grown = peak_rss() - before
        assert mesh.stats["input_copied"] is False and len(mesh.faces) > 0
        return grown, mesh

    copied, m64 = growth(as_f64)
    in_place, m32 = growth(volume)
    np.testing.assert_array_equal(m32.faces, m64.faces)
    print(f"volume {size / 2**20:.0f} MiB: peak growth {in_place / 2**20:.1f} MiB in place, "
          f"{copied / 2**20:.1f} MiB through a float32 copy")
    assert copied > 0.9 * size, (copied, size)
    assert in_place < 0.25 * size, (in_place, size)


def test_extract_field_equals_extract_on_the_same_values():
    def f(x, y, z):
        return np.sqrt(x * x + y * y + z * z) - 0.6 + 0.1 * np.sin(5 * x)

    n = 20
    for lattice in ["simple", "bcdl"]:
        field_mesh = rmt_terrain.extract_field(f, (-1, -1, -1, 1, 1, 1), n, lattice=lattice,
                                               normals="area")
        # The corner values at the float32 positions the library samples on each lattice:
        # min + x h (simple), min + (2 x) (h / 2) (body-centred).
        h = np.float32(2.0) / np.float32(n)
        if lattice == "simple":
            g = np.float32(-1) + np.arange(n + 1, dtype=np.float32) * h
        else:
            g = np.float32(-1) + np.arange(0, 2 * n + 1, 2, dtype=np.float32) * (h * np.float32(0.5))
        g = g.astype(np.float64)
        z, y, x = np.meshgrid(g, g, g, indexing="ij")
        volume = f(x, y, z).astype(np.float32)
        kw = {"centres": f} if lattice == "bcdl" else {}
        vol_mesh = rmt_terrain.extract(volume, 0.0, spacing=(2 / n,) * 3, origin=(-1, -1, -1),
                                       lattice=lattice, normals="area", **kw)
        assert len(field_mesh.faces) > 0
        assert (field_mesh.axes, vol_mesh.axes) == ("xyz", "zyx")
        world = vol_mesh.with_axes("xyz")
        np.testing.assert_array_equal(field_mesh.vertices, world.vertices)
        np.testing.assert_array_equal(field_mesh.faces, world.faces)
        np.testing.assert_array_equal(field_mesh.normals, world.normals)
        assert field_mesh.validate()["watertight_manifold"]


def test_extract_field_calls_the_callable_in_batches():
    calls = []

    def f(x, y, z):
        calls.append(len(x))
        return x * x + y * y + z * z - 0.5

    mesh = rmt_terrain.extract_field(f, resolution=24, batch=10_000, normals="gradient")
    points = 25 ** 3 + 24 ** 3 + 6 * 24 * 24  # corners, centres, ghosts
    assert sum(calls[:-1]) >= points and max(calls) <= 10_000
    # Sampling calls plus one call per batch of gradient points.
    assert len(calls) == -(-points // 10_000) + -(-len(mesh.vertices) // (10_000 // 6))


def test_sample_gives_every_object():
    for name in rmt_terrain.OBJECTS:
        s = rmt_terrain.sample(name, 12, "bcdl")
        assert s.volume.shape == (13, 13, 13) and s.centres.shape == (14, 14, 14)
        assert np.all(np.isfinite(s.volume))
        mesh = s.extract()
        assert mesh.validate()["closed"], name
    simple = rmt_terrain.sample("asteroid", (10, 12, 14), "simple", seed=3)
    assert simple.volume.shape == (15, 13, 11) and simple.centres is None
    other = rmt_terrain.sample("asteroid", (10, 12, 14), "simple", seed=4)
    assert not np.array_equal(simple.volume, other.volume)


def test_write_formats_and_to_trimesh(tmp_path):
    mesh = rmt_terrain.extract(sphere_volume(16), 0.0)
    for ext in ["ply", "obj", "glb"]:
        mesh.write(tmp_path / f"m.{ext}")
        assert (tmp_path / f"m.{ext}").stat().st_size > 0
    with pytest.raises(ValueError):
        mesh.write(tmp_path / "m.stl")
    trimesh = pytest.importorskip("trimesh")
    t = mesh.to_trimesh()
    assert isinstance(t, trimesh.Trimesh) and t.is_watertight
    assert len(t.faces) == len(mesh.faces)
    loaded = trimesh.load(tmp_path / "m.ply", process=False)
    assert len(loaded.faces) == len(mesh.faces)


# ------------------------------------------------------------------------------- bad input

def test_non_finite_values_are_found_anywhere():
    # The extractor's first pass (marching cubes and plain MT classify 64 values at a time,
    # rows or chunks in parallel, with a partial last word; surface nets scans in 32 lanes and
    # a remainder) finds NaN and both infinities at any position, for every method; the error
    # names the first in C order.
    for shape in [(5, 6, 7), (162, 162, 163)]:
        volume = np.ones(shape, np.float32)
        n = volume.size
        for at in (0, (n * 5) // 9, n - 1):
            i, j, k = np.unravel_index(at, shape)
            for bad in (np.nan, np.inf, -np.inf):
                volume.flat[at] = bad
                volume.flat[-1] = volume.flat[-1] if at == n - 1 else np.nan  # a later one
                for method in ("mt", "mc", "surface-nets"):
                    with pytest.raises(ValueError,
                                       match=rf"volume is not finite at index \[{i}, {j}, {k}\]"):
                        rmt_terrain.extract(volume, method=method, normals="area")
                volume.flat[at] = volume.flat[-1] = 1.0
        assert len(rmt_terrain.extract(volume, 0.5).faces) == 0  # all finite again


def test_nan_names_the_first_index():
    volume = sphere_volume(10)
    volume[3, 4, 5] = np.nan
    volume[7, 0, 0] = np.nan
    with pytest.raises(ValueError, match=r"volume is not finite at index \[3, 4, 5\]"):
        rmt_terrain.extract(volume)
    centres = np.zeros((10, 10, 10), np.float32)
    centres[1, 2, 3] = np.inf
    with pytest.raises(ValueError, match=r"centres is not finite at index \[1, 2, 3\]"):
        rmt_terrain.extract(sphere_volume(10), lattice="bcdl", centres=centres, ghosts=1.0)
    full = np.zeros((12, 12, 12), np.float32)
    full[0, 2, 3] = np.nan  # a ghost (outside the z = 0 face)
    with pytest.raises(ValueError, match=r"centres is not finite at index \[0, 2, 3\]"):
        rmt_terrain.extract(sphere_volume(10), lattice="bcdl", centres=full)
    full[0, 0, 3] = np.nan  # outside two faces: never read
    full[0, 2, 3] = 1.0
    rmt_terrain.extract(sphere_volume(10), lattice="bcdl", centres=full)
    with pytest.raises(ValueError, match=r"ghosts\(x, y, z\) is not finite"):
        rmt_terrain.extract(sphere_volume(10), lattice="bcdl", centres=np.zeros_like(centres),
                            ghosts=lambda x, y, z: np.where(z > 0.5, np.nan, 1.0))


@pytest.mark.parametrize("bad, error", [
    (np.zeros(10, np.float32), ValueError),                 # 1-D
    (np.zeros((4, 4), np.float32), ValueError),             # 2-D
    (np.zeros((0, 4, 4), np.float32), ValueError),          # zero-sized
    (np.zeros((1, 4, 4), np.float32), ValueError),          # one point along an axis
    (np.zeros((4, 4, 4), np.int32), TypeError),             # integer dtype
    (np.zeros((4, 4, 4), np.complex64), TypeError),         # complex dtype
    (np.array([["a"]]), TypeError),                         # strings
    ([[[1.0, 2.0], [3.0, 4.0]]], ValueError),               # a list with one point along z
])
def test_bad_volumes_raise(bad, error):
    with pytest.raises(error):
        rmt_terrain.extract(bad)


def test_bad_arguments_raise_with_the_reason():
    v = sphere_volume(8)
    with pytest.raises(ValueError, match="needs the values at the cube centres"):
        rmt_terrain.extract(v, lattice="bcdl")
    with pytest.raises(ValueError, match="centres must have shape"):
        rmt_terrain.extract(v, lattice="bcdl", centres=np.zeros((8, 8, 7), np.float32))
    with pytest.raises(ValueError, match="only on the body-centred lattice"):
        rmt_terrain.extract(v, centres=np.zeros((8, 8, 8), np.float32))
    with pytest.raises(ValueError, match="lattice"):
        rmt_terrain.extract(v, lattice="hex")
    with pytest.raises(ValueError, match="has no clustering"):
        rmt_terrain.extract(v, method="mc", clustering="postprocessed")
    with pytest.raises(ValueError, match="has no clustering"):
        rmt_terrain.extract(v, method="surface-nets", clustering="meshopt")
    with pytest.raises(ValueError, match="clustering must be"):
        rmt_terrain.extract(v, clustering="fast")
    with pytest.raises(ValueError, match="threads"):
        rmt_terrain.extract(v, threads=0)
    with pytest.raises(ValueError, match="spacing"):
        rmt_terrain.extract(v, spacing=(1, -1, 1))
    with pytest.raises(ValueError, match="level"):
        rmt_terrain.extract(v, level=float("nan"))
    with pytest.raises(ValueError, match="unknown object"):
        rmt_terrain.sample("teapot", 8)
    with pytest.raises(ValueError, match="takes no parameter"):
        rmt_terrain.sample("gyroid", 8, radius=2.0)
    with pytest.raises(ValueError, match="octaves"):
        rmt_terrain.sample("asteroid", 8, octaves=40)
    with pytest.raises(ValueError, match="not finite"):
        rmt_terrain.extract_field(lambda x, y, z: np.where(x > 0.5, np.nan, x), resolution=8)
    with pytest.raises(ValueError):
        rmt_terrain.extract_field(lambda x, y, z: np.zeros(3), resolution=8)
    with pytest.raises(ZeroDivisionError):
        rmt_terrain.extract_field(lambda x, y, z: 1 / 0, resolution=8)


@pytest.mark.skipif(not Path("/proc/meminfo").exists(), reason="needs /proc (Linux)")
def test_huge_sizes_are_refused_before_allocating():
    with pytest.raises((MemoryError, ValueError)):
        rmt_terrain.extract_field(lambda x, y, z: x, resolution=200_000)
    with pytest.raises(ValueError, match="too large"):
        rmt_terrain.sample("sphere", 20_000)
    # Below the library's point limit, above the memory available (1281^3 points, 24 bytes
    # each in the estimate: 50 GB).
    with open("/proc/meminfo") as f:
        available = next(int(l.split()[1]) * 1024 for l in f if l.startswith("MemAvailable:"))
    if available < 50e9:
        with pytest.raises(MemoryError, match="needs an estimated"):
            rmt_terrain.sample("sphere", 1280, "simple")
    # A volume whose index arithmetic would overflow a float32 box is refused too.
    with pytest.raises(ValueError):
        rmt_terrain.extract(sphere_volume(8), spacing=(1e38, 1e38, 1e38))


# ------------------------------------------------------------------------------- GIL and memory

def test_the_gil_is_released_during_extraction():
    volume = random_volume(np.random.default_rng(1), (97, 97, 97))
    count = [0]
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            count[0] += 1

    t = threading.Thread(target=spin)
    t.start()
    try:
        time.sleep(0.05)
        rates = []
        for _ in range(3):
            before, t0 = count[0], time.perf_counter()
            time.sleep(0.1)
            rates.append((count[0] - before) / (time.perf_counter() - t0))
        rate = float(np.median(rates))
        ratios = []
        for _ in range(3):
            before, t0 = count[0], time.perf_counter()
            rmt_terrain.extract(volume, 0.0, threads=1, normals="area")
            elapsed = time.perf_counter() - t0
            ratios.append((count[0] - before) / (rate * elapsed))
    finally:
        stop.set()
        t.join()
    # With the GIL held during the call the other thread would not run at all (ratio near 0);
    # released, it runs about as fast as alone (on a second core, or time-shared with the
    # extraction's one thread on a busy machine).
    assert max(ratios) > 0.3, ratios


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


@pytest.mark.skipif(not Path("/proc/self/statm").exists(), reason="needs /proc (Linux)")
def test_no_leak_over_a_thousand_calls():
    volume = sphere_volume(24)
    centres = sphere_volume(23)  # the volume's shape minus 1: with ghosts
    for _ in range(50):
        rmt_terrain.extract(volume).validate()
    before = rss_bytes()
    for i in range(1000):
        m = rmt_terrain.extract(volume, lattice="bcdl" if i % 2 else "simple",
                                centres=centres if i % 2 else None,
                                ghosts=1.0 if i % 2 else None)
        m.quality()
        del m
    grown = rss_bytes() - before
    # One 24^3 mesh is about 150 KB; 1000 leaked meshes would be 150 MB.
    assert grown < 8 << 20, f"RSS grew by {grown / 2**20:.1f} MiB over 1000 calls"


@pytest.mark.skipif(not Path("/proc/self/statm").exists(), reason="needs /proc (Linux)")
def test_memory_of_a_large_extraction_is_given_back():
    volume = random_volume(np.random.default_rng(2), (257, 257, 257))  # 68 MB of float32
    rmt_terrain.extract(sphere_volume(16))
    before = rss_bytes()
    mesh = rmt_terrain.extract(volume, 0.0, clustering="none", normals="none")
    assert len(mesh.faces) > 0
    del mesh
    grown = rss_bytes() - before
    # The extraction's sample array alone is 68 MB; kept extractors would hold it and more.
    assert grown < 32 << 20, f"RSS grew by {grown / 2**20:.1f} MiB after the call"


def test_concurrent_calls_from_python_threads_give_the_serial_meshes():
    volumes = [random_volume(np.random.default_rng(s), (33, 30, 27)) for s in range(4)]
    serial = [rmt_terrain.extract(v, 0.0) for v in volumes]
    results = [None] * len(volumes)

    def run(i):
        results[i] = rmt_terrain.extract(volumes[i], 0.0)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(len(volumes))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(serial, results):
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_array_equal(a.faces, b.faces)
