"""Dense landmark pairs: where the time goes, and the warp against the dense spline.

A mesh of about 32k vertices (Igea decimated when ../shared/data is present, else pymeshlab's cow
subdivided twice) bent and compressed by the paper's Figure 1 map, with approximate mirror pairs
spread by a voxel grid. For each pair count: the core's stages, the warp's fit and evaluation timed
apart, the MeshSet filter as a user calls it (checks off and on; layer building = filter - core), and
scipy's RBFInterpolator(kernel="linear", degree=1) fitted and evaluated through the same landmarks
(the plain-scipy way to do the dominant step). With --accuracy, the chosen warp against the dense LU's
at every vertex (the dense solve takes about 30 s at 13,000 landmarks).

    python scripts/benchmark_dense.py [--pairs 1000 10000] [--accuracy] [--mesh igea|cow|cow32k|cow742k]
"""

from __future__ import annotations

import argparse
import os
import pathlib
import time
import warnings

import numpy as np
import pymeshlab
from scipy.interpolate import RBFInterpolator

import filter_symblend  # noqa: F401  (binds the filter)
from filter_symblend import SymblendWarning, symmetrize
from filter_symblend.core.warp import choice, splines
from filter_symblend.testing import synthetic

SHARED = pathlib.Path(__file__).resolve().parents[2] / "shared" / "data"
COW = pathlib.Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "cow.obj"
OPTIONS = {"mode": "standard", "phi_width": 8.0}  # as the scan rows of scripts/benchmark.py
PAIR_TOLERANCE = 0.02  # approximate mirror pairs: reflections within 2 % of the diagonal
RBF_CENTRES = 10_000  # scipy's dense RBFInterpolator beyond this: out of reach


def mesh(name: str) -> tuple[str, np.ndarray, np.ndarray]:
    """(name, points, faces) of the benchmark mesh: Igea decimated to 32k vertices (``name`` 'igea', when
    ../shared is present: 6,496 approximate pairs at most), pymeshlab's exactly symmetric cow subdivided
    twice (``cow``: 19k vertices, a pair for every vertex off the plane), or subdivided to 46k vertices and
    decimated to 32k (``cow32k``: the issue's mesh size with 10^4 approximate pairs and more), or subdivided
    four times (``cow742k``: 742,914 vertices, exactly symmetric: 10^5 pairs)."""
    ms = pymeshlab.MeshSet()
    if name == "cow742k":
        ms.load_new_mesh(str(COW))
        ms.meshing_surface_subdivision_midpoint(iterations=4, threshold=pymeshlab.PercentageValue(0))
        name = "cow subdivided four times"
    elif name == "cow32k":
        ms.load_new_mesh(str(COW))
        ms.meshing_surface_subdivision_midpoint(iterations=2, threshold=pymeshlab.PercentageValue(0))
        ms.meshing_decimation_quadric_edge_collapse(targetfacenum=64_000)
        name = "cow subdivided and decimated"
    elif name == "igea" and (SHARED / "igea.ply").exists():
        ms.load_new_mesh(str(SHARED / "igea.ply"))
        ms.meshing_remove_unreferenced_vertices()
        ms.meshing_decimation_quadric_edge_collapse(targetfacenum=64_000)
        name = "igea"
    else:
        ms.load_new_mesh(str(COW))
        ms.meshing_surface_subdivision_midpoint(iterations=2)
        name = "cow subdivided"
    return name, ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()


def filter_seconds(points, faces, left, right, checks: str) -> tuple[float, float]:
    """(filter seconds, its core's seconds) of the MeshSet filter with ``checks``."""
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=points, face_matrix=faces))
    labels = np.zeros(len(points))
    labels[left], labels[right] = np.arange(1, len(left) + 1), -np.arange(1, len(left) + 1)
    ms.current_mesh().add_vertex_custom_scalar_attribute(labels, "symblend_pair")
    start = time.perf_counter()
    report = ms.generate_symmetrized_mesh(**OPTIONS, **({} if checks == "default" else {"checks": checks}))
    return time.perf_counter() - start, report["seconds"]["total"]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pairs", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--accuracy", action="store_true", help="the warp against the dense LU's at every vertex")
    parser.add_argument("--mesh", choices=["igea", "cow", "cow32k", "cow742k"], default="igea",
                        help="igea (32k vertices, at most 6,496 pairs; the cow without ../shared), cow (19k, "
                             "exactly symmetric: 10^4 pairs and more), cow32k (32k, 10^4 approximate pairs) or "
                             "cow742k (742k, exactly symmetric: 10^5 pairs; about 5 minutes)")
    args = parser.parse_args(argv)
    name, points, faces = mesh(args.mesh)
    deformed = synthetic.figure_1_deformation(points)
    offset, partner = synthetic.mirror_partners(points, tolerance=PAIR_TOLERANCE)
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    print(f"\nDense pairs ({time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores): {name}, {len(points):,} vertices, "
          "Figure 1 map; seconds")
    print("| pairs | neighbourhoods | local | solve | warp fit | warp evaluation | core | layer building | "
          "filter, checks none | filter, default checks | RBFInterpolator fit + evaluation | warp | "
          "deviation from the dense spline / diagonal |")
    print("|" + "---|" * 13)
    for count in args.pairs:
        left, right = synthetic.spread_pairs(points, offset, partner, count)
        left, right = left[left != right], right[left != right]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SymblendWarning)
            result = symmetrize(deformed, left, right, **OPTIONS)
            landmarks = np.concatenate([left, right])
            others = np.setdiff1d(np.arange(len(points)), landmarks)
            values = result.points[landmarks] - deformed[landmarks]
            start = time.perf_counter()
            spline = choice.thin_plate_spline(deformed[landmarks], values)
            fitted = time.perf_counter()
            moved = spline(deformed[others])
            evaluated = time.perf_counter()
            none, core = filter_seconds(deformed, faces, left, right, "none")
            default, _ = filter_seconds(deformed, faces, left, right, "default")
        rbf = "out of reach"
        if len(landmarks) <= RBF_CENTRES:
            start_rbf = time.perf_counter()
            RBFInterpolator(deformed[landmarks], values, kernel="linear", degree=1)(deformed[others])
            rbf = f"{time.perf_counter() - start_rbf:.2f}"
        deviation = ""
        if args.accuracy:
            dense = splines.ThinPlateSpline(deformed[landmarks], values)(deformed[others])
            deviation = f"{np.abs(moved - dense).max() / diagonal:.1e}"
        seconds = result.report.seconds.to_dict()
        print(f"| {len(left):,} | {seconds['neighbourhoods']:.2f} | {seconds['local_transforms']:.3f} | "
              f"{seconds['global_solve']:.2f} | {fitted - start:.2f} | {evaluated - fitted:.2f} | {core:.2f} | "
              f"{none - core:.2f} | {none:.2f} | {default:.2f} | {rbf} | {spline.description} | {deviation} |",
              flush=True)


if __name__ == "__main__":
    main()
