"""RMT against scikit-image's marching cubes on the same volume.

Samples the asteroid (the dissertation's noisy sphere) on a 64^3 grid, extracts it with
scikit-image's ``marching_cubes``, our marching cubes, plain marching tetrahedra and RMT
(integrated clustering), and prints triangle counts, radius ratios (circumradius over twice
the inradius: 1 for an equilateral triangle) and times. Saves a matplotlib figure.
scikit-image and matplotlib are not dependencies of rmt_terrain: without them the script
prints our rows only and says what to install.

    python python/examples/compare.py [--resolution 64] [--object asteroid] [--out compare.png]
"""

import argparse
import time

import numpy as np

import rmt_terrain


def radius_ratios(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Per triangle: circumradius / (2 inradius) = abc / (8 (s - a)(s - b)(s - c))."""
    p = vertices[faces.astype(np.int64)].astype(np.float64)
    a = np.linalg.norm(p[:, 1] - p[:, 2], axis=1)
    b = np.linalg.norm(p[:, 2] - p[:, 0], axis=1)
    c = np.linalg.norm(p[:, 0] - p[:, 1], axis=1)
    s = (a + b + c) / 2
    den = 8 * (s - a) * (s - b) * (s - c)
    ok = den > 1e-30
    return a[ok] * b[ok] * c[ok] / den[ok]


def timed(f, reps=3):
    """The best of `reps` calls and the last result."""
    best, out = float("inf"), None
    for _ in range(reps):
        t = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--resolution", type=int, default=64)
    ap.add_argument("--object", default="asteroid", choices=rmt_terrain.OBJECTS)
    ap.add_argument("--out", default="compare.png", help="the figure (PNG)")
    args = ap.parse_args()

    s = rmt_terrain.sample(args.object, args.resolution, "simple")
    volume, spacing = s.volume, s.spacing
    print(f"{args.object}, {volume.shape[2] - 1}^3 cells, volume {volume.shape} {volume.dtype}")

    rows = []
    try:
        from skimage.measure import marching_cubes

        t, (verts, faces, _, _) = timed(lambda: marching_cubes(volume, 0.0, spacing=spacing))
        # Both in array order (z, y, x); scikit-image's from 0, ours from the volume's origin.
        verts = verts + np.array(s.origin)
        rows.append(("scikit-image marching_cubes", verts, faces, t))
    except ImportError:
        print("scikit-image is not installed (pip install scikit-image matplotlib): its row is "
              "left out")
    for label, kw in [
        ("rmt_terrain marching cubes", {"method": "mc"}),
        ("rmt_terrain plain MT (simple)", {"clustering": "none"}),
        ("rmt_terrain RMT (simple, integrated)", {}),
    ]:
        t, mesh = timed(lambda: s.extract(normals="area", **kw))
        assert mesh.validate()["closed"], label
        rows.append((label, mesh.vertices, mesh.faces, t))

    print(f"{'':38} {'triangles':>10} {'radius ratio mean':>18} {'max':>9} {'time ms':>9}")
    ratios = {}
    for label, v, f, t in rows:
        r = radius_ratios(v, f)
        ratios[label] = r
        print(f"{label:38} {len(f):10d} {r.mean():18.3f} {r.max():9.1f} {t * 1e3:9.2f}")
    if rows and rows[0][0].startswith("scikit"):
        rmt = len(rows[-1][2]) / len(rows[0][2])
        print(f"RMT has {100 * (1 - rmt):.1f}% fewer triangles than scikit-image's marching cubes")

    try:
        import matplotlib
    except ImportError:
        print("matplotlib is not installed (pip install matplotlib): no figure saved")
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    bins = np.logspace(0, 1.5, 60)
    for label, r in ratios.items():
        # scikit-image's curve lies under our marching cubes' (the same triangles): dashed.
        style = "--" if label.startswith("scikit") else "-"
        ax1.hist(np.clip(r, 1, bins[-1]), bins=bins, histtype="step", label=label,
                 linewidth=1.4, linestyle=style)
    ax1.set_xscale("log")
    ax1.set_xlabel("radius ratio (1 = equilateral)")
    ax1.set_ylabel("triangles")
    ax1.set_title("triangle quality")
    ax1.legend(fontsize=8)
    labels = [label.replace("rmt_terrain ", "").replace(" ", "\n", 1) for label, *_ in rows]
    counts = [len(f) for _, _, f, _ in rows]
    bars = ax2.bar(range(len(rows)), counts, color=["#999", "#69c", "#c96", "#3a7"][: len(rows)])
    for bar, (_, _, _, t) in zip(bars, rows):
        ax2.annotate(f"{t * 1e3:.1f} ms", (bar.get_x() + bar.get_width() / 2, bar.get_height()),
                     ha="center", va="bottom", fontsize=8)
    ax2.set_xticks(range(len(rows)), labels, fontsize=7)
    ax2.set_ylabel("triangles")
    ax2.set_title(f"{args.object}, {args.resolution}^3 cells (time above each bar)")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"figure saved to {args.out}")


if __name__ == "__main__":
    main()
