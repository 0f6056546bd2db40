"""What every benchmark section shares: where the meshes are, loading them exactly symmetric, timing and
memory, scan pairs, table headers and child processes."""

from __future__ import annotations

import pathlib
import subprocess
import time
import tracemalloc
import warnings

import numpy as np
import pymeshlab

from filter_symblend import SymblendWarning
from filter_symblend.testing import synthetic

SAMPLES = pathlib.Path(pymeshlab.__file__).parent / "tests" / "sample_meshes"
SHARED = pathlib.Path(__file__).resolve().parents[3] / "shared" / "data"  # beside the repository
MESHES = {"cow": SAMPLES / "cow.obj", "spot": SHARED / "spot.obj"}
IGEA = SHARED / "igea.ply"
MESH_PAIR_TOLERANCE = 0.02  # mirror pairs on scans: reflections within 2 % of the diagonal (timing rows only)
# Timing rows on scans: approximate mirror pairs leave a few pairs isolated at the paper's phi width 5
# and a few affine neighbourhoods flat, so these rows use phi width 8 and the standard mode.
SCAN_OPTIONS = {"mode": "standard", "phi_width": 8.0}
EXACT = 1e-6  # sym error (/ diagonal) below which a result counts as exact: no ratio is printed


def load(path: pathlib.Path):
    """(exactly symmetric points (N, 3), mirror plane offset, partner (N,), left (n,), right (n,), faces (F, 3))."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    raw = ms.current_mesh().vertex_matrix()
    offset, partner = synthetic.mirror_partners(raw)
    points = synthetic.exactly_symmetric(raw, offset, partner)
    left = np.flatnonzero((partner >= 0) & (points[:, 0] > offset))
    return points, offset, partner, left, partner[left], ms.current_mesh().face_matrix()


def measured(function, *args, **kwargs):
    """(result, seconds, peak MB of numpy/Python allocations): timed in one call, memory traced in
    a second one (tracing every allocation slows numpy down, up to 1.8x measured here)."""
    start = time.perf_counter()
    result = function(*args, **kwargs)
    seconds = time.perf_counter() - start
    tracemalloc.start()
    try:
        function(*args, **kwargs)
        peak = tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()
    return result, seconds, peak


def subdivided_cows(levels: int):
    """The cow, exactly symmetrized, then midpoint-subdivided ``levels`` times (x4 vertices each)."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(MESHES["cow"]))
    for level in range(levels + 1):
        if level:
            ms.meshing_surface_subdivision_midpoint(iterations=1, threshold=pymeshlab.PercentageValue(0))
        raw = ms.current_mesh().vertex_matrix()
        offset, partner = synthetic.mirror_partners(raw)
        yield synthetic.exactly_symmetric(raw, offset, partner), offset, partner


def igea_meshes():
    """Igea decimated to about 10^4 vertices, as scanned (1.3 x 10^5), midpoint-subdivided (5.4 x 10^5) and
    subdivided again where edges exceed 0.18 % of the diagonal (1.02 x 10^6): (name, points, faces)."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(IGEA))
    ms.meshing_remove_unreferenced_vertices()
    scanned = pymeshlab.Mesh(vertex_matrix=ms.current_mesh().vertex_matrix(), face_matrix=ms.current_mesh().face_matrix())
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=20000)
    yield "igea decimated", ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    ms.add_mesh(scanned)
    yield "igea", ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    for name, threshold in (("igea subdivided", 0.0), ("igea subdivided twice", 0.18)):
        ms.meshing_surface_subdivision_midpoint(iterations=1, threshold=pymeshlab.PercentageValue(threshold))
        yield name, ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()


def scan_pairs(points, counts):
    """For each of ``counts``, about that many approximate mirror pairs of a scan, spread by a
    voxel grid (timing rows only); the mirror partners are found once."""
    offset, partner = synthetic.mirror_partners(points, tolerance=MESH_PAIR_TOLERANCE)
    for count in counts:
        left, right = synthetic.spread_pairs(points, offset, partner, count)
        distinct = left != right  # a vertex near the plane can be its own reflection's nearest vertex
        yield count, left[distinct], right[distinct]


def table_meshes(title: str, header: list[str], meshes: list[str]):
    """Print a table's title and header; yield the meshes present, a row for each absent one."""
    print(title)
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for mesh in meshes:
        if MESHES[mesh].exists():
            yield mesh
        else:
            print(f"| {mesh} | skipped: {MESHES[mesh]} is absent |")


def child(arguments: list[str]) -> tuple[str, float]:
    """Run a command; (its stdout, wall seconds)."""
    start = time.perf_counter()
    done = subprocess.run(arguments, capture_output=True, text=True, check=True)
    return done.stdout, time.perf_counter() - start


def quiet(function, *args, **kwargs):
    """``function`` called with its SymblendWarnings silenced (100 landmarks on a bent mesh warn by design)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        return function(*args, **kwargs)
