"""The Python overhead of rmt_terrain.extract over the Rust extraction it runs, on a 64^3
float32 volume (a sphere's signed distance): the wall time of the Python call against the
extractor's own ``stats["t_total_s"]`` (Rust, ``Extractor::extract_borrowed`` plus gradient
normals), median of interleaved repetitions. The overhead is the argument checks, turning the
mesh into array order (z, y, x) where the extractor did not write it so
(``stats["t_reorder_s"]``; marching cubes and plain MT write their meshes in that order
themselves, so they need no such pass: plain MT turns its positions in one parallel pass inside
``t_total_s``, as it does for a Rust caller asking for array order), and wrapping the result (``stats["t_input_s"]``, the binding's
own input work, is about 0 here: the volume is read in place, not copied, and the extractor's
first pass refuses NaN and infinities as it classifies the values, for any Rust caller too, so
that check is inside ``t_total_s``).
``t_total_s`` is the time of the Rust call as a Rust program makes it: the extractor, called
from the caller's thread, hands its work to a pool of ``threads`` workers (the wake-up and the
hand-back are inside it, as they are for a Rust caller) and fills a fresh ``Mesh``; timed from
outside in a Rust program, that call takes ``t_total_s`` to within a few microseconds. The
binding's own work (the reordering of marching tetrahedra's mesh) runs on the calling thread, outside that call, so the Rust
call's pool wake-up is not counted as overhead, and none of the binding's work is inside
``t_total_s`` except gradient normals (Rust work the library does itself when it has a field).
Then the cost of ``extract_field``'s callable beyond the callable's own work, per lattice point
(64^3 cells, body-centred: 561,345 points).

    python python/examples/overhead.py [N] [REPS]
"""

import sys
import time

import numpy as np

import rmt_terrain


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 64
    reps = int(sys.argv[2]) if len(sys.argv) > 2 else 40
    g = np.linspace(-1, 1, n + 1)
    z, y, x = np.meshgrid(g, g, g, indexing="ij")
    volume = (np.sqrt(x * x + y * y + z * z) - 0.7).astype(np.float32)
    cases = [
        ("mt simple integrated, gradient normals", {}),
        ("mt simple integrated, area normals", {"normals": "area"}),
        ("mt simple none, area normals", {"clustering": "none", "normals": "area"}),
        ("mc, area normals", {"method": "mc", "normals": "area"}),
    ]
    for _, kw in cases:  # warm up: thread pools and buffers
        rmt_terrain.extract(volume, 0.0, spacing=(2 / n,) * 3, **kw)
    walls = {name: [] for name, _ in cases}
    rusts = {name: [] for name, _ in cases}
    inputs = {name: [] for name, _ in cases}
    for _ in range(reps):
        for name, kw in cases:
            m = None  # the previous mesh is freed outside the timed call
            t = time.perf_counter()
            m = rmt_terrain.extract(volume, 0.0, spacing=(2 / n,) * 3, **kw)
            walls[name].append(time.perf_counter() - t)
            rusts[name].append(m.stats["t_total_s"])
            inputs[name].append(m.stats["t_input_s"])
    print(f"{n}^3 float32 sphere, {reps} interleaved repetitions, medians")
    print(f"{'case':42} {'python ms':>10} {'rust ms':>9} {'input ms':>9} {'overhead':>9}")
    for name, _ in cases:
        w = float(np.median(walls[name]))
        r = float(np.median(rusts[name]))
        i = float(np.median(inputs[name]))
        # Per repetition, then the median: the two times of one call belong together.
        o = float(np.median([(a - b) / b for a, b in zip(walls[name], rusts[name])]))
        print(f"{name:42} {w * 1e3:10.3f} {r * 1e3:9.3f} {i * 1e3:9.3f} {o * 100:8.2f}%")

    inside = []

    def f(x, y, z):
        t = time.perf_counter()
        r = np.sqrt(x * x + y * y + z * z) - 0.7
        inside.append(time.perf_counter() - t)
        return r

    per_point = []
    for _ in range(max(3, reps // 8)):
        inside.clear()
        m = rmt_terrain.extract_field(f, resolution=n, normals="area")
        points = (n + 1) ** 3 + n ** 3 + 6 * n * n
        per_point.append((m.stats["t_sampling_s"] - sum(inside)) / points)
    print(f"extract_field, {n}^3 body-centred: {np.median(per_point) * 1e9:.1f} ns per point "
          f"beyond the callable's own time (median of {len(per_point)})")


if __name__ == "__main__":
    main()
