"""--icp: the reflection ICP that refines a surface's mirror plane (core/mirror_planes), plain against
Anderson-accelerated, from a start 3 degrees off each mesh's best plane: the trimmed RMS reached (/ the
diagonal, lower is better), the seconds and the steps; the plain ICP also run to 200 steps at a 1e-6 gain, as
the converged reference."""

from __future__ import annotations

import time

import numpy as np
import pymeshlab
from scipy.spatial import cKDTree

from filter_symblend.core import mirror_planes
from filter_symblend.core.geometry import normalize
from filter_symblend.core.mesh_quantities import evenly
from filter_symblend.testing import synthetic

from .common import IGEA, SAMPLES, SHARED

CHECKS_GAIN = 1e-4  # the checks' stopping gain (measures/surface_asymmetry.CHECK_CONVERGED)


def _meshes():
    """(name, points) of the corpus meshes present: Igea (32k) as scanned and under Figure 1's map, four
    meshes of ../shared/data, the cow bent and under Figure 1's map."""
    if IGEA.exists():
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(IGEA))
        ms.meshing_remove_unreferenced_vertices()
        ms.meshing_decimation_quadric_edge_collapse(targetfacenum=64000)
        points = ms.current_mesh().vertex_matrix()
        yield "igea 32k, Figure 1 map", synthetic.figure_1_deformation(points)
        yield "igea 32k", points
    for name in ("homer.obj", "woody.obj", "stanford-bunny.obj", "cheburashka.obj"):
        if (SHARED / name).exists():
            ms = pymeshlab.MeshSet()
            ms.load_new_mesh(str(SHARED / name))
            yield name, ms.current_mesh().vertex_matrix()
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(SAMPLES / "cow.obj"))
    cow = ms.current_mesh().vertex_matrix()
    yield "cow bent 1.0 rad", synthetic.bend(cow, 1.0)
    yield "cow, Figure 1 map", synthetic.figure_1_deformation(cow)


def _refined(sample, start, memory: int, iterations: int, gain: float):
    """(trimmed RMS, seconds, steps) of the ICP from ``start`` with ``memory`` steps of acceleration (1: plain)."""
    saved = mirror_planes.ANDERSON_MEMORY, mirror_planes.ICP_ITERATIONS
    mirror_planes.ANDERSON_MEMORY, mirror_planes.ICP_ITERATIONS = memory, iterations
    tree = cKDTree(sample)
    steps = []
    query = tree.query

    class Counted:  # the tree, counting the ICP's steps
        def query(self, *args, **kwargs):
            steps.append(1)
            return query(*args, **kwargs)

    try:
        clock = time.perf_counter()
        _, _, rms = mirror_planes._refine_plane(sample, Counted(), *start, None, gain)
        return rms, time.perf_counter() - clock, len(steps)
    finally:
        mirror_planes.ANDERSON_MEMORY, mirror_planes.ICP_ITERATIONS = saved


def icp_main() -> None:
    print("Reflection ICP on ICP_SAMPLES vertices from a plane 3 degrees off the best: trimmed RMS / diagonal, "
          "seconds, steps")
    print("| mesh | plain, 40 steps at most, gain 1e-4 | plain, 200 steps, gain 1e-6 | accelerated, gain 1e-4 |")
    print("|---|---|---|---|")
    for name, points in _meshes():
        sample = evenly(points, mirror_planes.ICP_SAMPLES)
        normal, offset = mirror_planes.surface_mirror_planes(points, converged=CHECKS_GAIN, polish=False)[0]
        axis = normalize(np.cross(normal, [0.3, 0.5, 0.8]))
        angle = np.radians(3.0)
        start = (normal * np.cos(angle) + np.cross(axis, normal) * np.sin(angle), float(offset))
        diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
        cells = []
        for memory, iterations, gain in ((1, 40, CHECKS_GAIN), (1, 200, 1e-6),
                                         (mirror_planes.ANDERSON_MEMORY, mirror_planes.ICP_ITERATIONS, CHECKS_GAIN)):
            rms, seconds, steps = _refined(sample, start, memory, iterations, gain)
            cells.append(f"{rms / diagonal:.5e}, {seconds:.2f} s, {steps}")
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
