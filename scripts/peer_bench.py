#!/usr/bin/env python3
"""Times VTK's Flying Edges and scikit-image's marching cubes on sampled values dumped by Rust.

Usage: peer_bench.py DIR [--reps N] [--methods vtk_flying_edges,skimage_mc] [--only NAME]

Needs numpy, vtk and scikit-image (`pip install vtk scikit-image numpy`). Prints CSV on stdout,
one row per (values file, method), with a header row:

    field,n,method,threads,median_ms,min_ms,reps,triangles

`median_ms` is the median wall time of `reps` repetitions of the extraction alone (the input
arrays are built once, outside the timing; the repetitions of the methods are interleaved), on
one thread (VTK's SMP backend set to Sequential, scikit-image is single-threaded).
`triangles` is the output's triangle count. Progress and versions go to stderr.

Input format (what `cargo run --release -p rmt-extract --example dump_values -- DIR` writes,
and what any other writer, such as `experiments bench --dump DIR`, should write): for every
volume NAME, two files in DIR,

- `NAME.json`, a JSON object:
    {"format": "rmt-values-1", "field": "sphere", "cells": 64,
     "dims": [65, 65, 65], "origin": [-1.0, -1.0, -1.0], "spacing": [0.03125, 0.03125, 0.03125],
     "level": 0.0, "values": "NAME.f32"}
  `dims` are the grid points per axis (x, y, z), `origin` the position of point (0, 0, 0),
  `spacing` the distance between neighbouring points per axis, `level` the isovalue (inside is
  below it), `values` the name of the values file in DIR, `field` and `cells` the labels of the
  CSV rows (`cells` is `n`);
- `NAME.f32`: `dims[0] * dims[1] * dims[2]` raw little-endian 32-bit floats, x fastest: the
  value of point (x, y, z) is at index `x + dims[0] * (y + dims[1] * z)`.

Every `*.json` in DIR with `"format": "rmt-values-1"` is read, in name order; with `--only NAME`,
only `NAME.json` (an error if it is missing).
"""

import argparse
import json
import pathlib
import statistics
import sys
import time

import numpy as np

FORMAT = "rmt-values-1"


def load(header_path):
    """The header and the values (a float32 array shaped (z, y, x)) of one dumped volume."""
    header = json.loads(header_path.read_text())
    if header.get("format") != FORMAT:
        return None
    dims = [int(d) for d in header["dims"]]
    values = np.fromfile(header_path.parent / header["values"], dtype="<f4")
    if values.size != dims[0] * dims[1] * dims[2]:
        raise SystemExit(
            f"{header_path}: {values.size} values, dims {dims} need {dims[0] * dims[1] * dims[2]}"
        )
    return header, values.reshape(dims[2], dims[1], dims[0])


class FlyingEdges:
    """vtkFlyingEdges3D on one thread: no normals, gradients or scalars computed."""

    name = "vtk_flying_edges"

    def __init__(self, header, values):
        import vtk
        from vtk.util import numpy_support

        vtk.vtkSMPTools.SetBackend("Sequential")
        image = vtk.vtkImageData()
        image.SetDimensions(*header["dims"])
        image.SetOrigin(*header["origin"])
        image.SetSpacing(*header["spacing"])
        flat = np.ascontiguousarray(values).ravel()  # x fastest, as VTK stores points
        self.array = numpy_support.numpy_to_vtk(flat, deep=True, array_type=vtk.VTK_FLOAT)
        self.array.SetName("f")
        image.GetPointData().SetScalars(self.array)
        fe = vtk.vtkFlyingEdges3D()
        fe.SetInputData(image)
        fe.SetValue(0, float(header["level"]))
        fe.ComputeNormalsOff()
        fe.ComputeGradientsOff()
        fe.ComputeScalarsOff()
        fe.InterpolateAttributesOff()
        self.image = image
        self.fe = fe

    def run(self):
        self.fe.Modified()
        self.fe.Update()
        return self.fe.GetOutput().GetNumberOfPolys()


class SkimageMc:
    """skimage.measure.marching_cubes (Lewiner, its default), no step skipping."""

    name = "skimage_mc"

    def __init__(self, header, values):
        from skimage.measure import marching_cubes

        self.marching_cubes = marching_cubes
        # skimage indexes volume[i, j, k] with spacing per index: pass (z, y, x) as is.
        self.values = np.ascontiguousarray(values)
        self.level = float(header["level"])
        self.spacing = tuple(float(s) for s in reversed(header["spacing"]))

    def run(self):
        _, faces, _, _ = self.marching_cubes(
            self.values, level=self.level, spacing=self.spacing, allow_degenerate=True
        )
        return len(faces)


METHODS = {m.name: m for m in (FlyingEdges, SkimageMc)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dir", type=pathlib.Path)
    parser.add_argument("--reps", type=int, default=10)
    parser.add_argument("--methods", default=",".join(METHODS))
    parser.add_argument("--only", help="time only the volume NAME (NAME.json in DIR)")
    args = parser.parse_args()
    methods = [m for m in args.methods.split(",") if m]
    unknown = [m for m in methods if m not in METHODS]
    if unknown or args.reps < 1:
        raise SystemExit(f"unknown methods {unknown} (known: {list(METHODS)}) or reps < 1")
    import vtk
    import skimage

    print(
        f"peer_bench: VTK {vtk.vtkVersion.GetVTKVersion()}, scikit-image {skimage.__version__}, "
        f"numpy {np.__version__}",
        file=sys.stderr,
    )
    print("field,n,method,threads,median_ms,min_ms,reps,triangles")
    if args.only is not None:
        headers = [args.dir / f"{args.only}.json"]
        if not headers[0].is_file():
            raise SystemExit(f"--only {args.only}: no {headers[0]}")
    else:
        headers = sorted(args.dir.glob("*.json"))
    if not headers:
        raise SystemExit(f"no *.json headers in {args.dir}")
    for header_path in headers:
        loaded = load(header_path)
        if loaded is None:
            continue
        header, values = loaded
        runners = [METHODS[m](header, values) for m in methods]
        times = {r.name: [] for r in runners}
        triangles = {}
        for r in runners:  # warm-up, not timed
            triangles[r.name] = r.run()
        for _ in range(args.reps):
            for r in runners:
                t = time.perf_counter()
                count = r.run()
                times[r.name].append(time.perf_counter() - t)
                triangles[r.name] = count
        for r in runners:
            ts = times[r.name]
            print(
                f"{header['field']},{header['cells']},{r.name},1,"
                f"{statistics.median(ts) * 1e3:.3f},{min(ts) * 1e3:.3f},{len(ts)},"
                f"{triangles[r.name]}",
                flush=True,
            )
        print(f"peer_bench: {header_path.name} done", file=sys.stderr)


if __name__ == "__main__":
    main()
