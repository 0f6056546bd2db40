"""Accuracy and speed against ground truth, with the mirror-averaging baseline beside it.

Exactly symmetric meshes (pymeshlab's cow; spot from ../shared/data when present)
are deformed by known maps; pairs are farthest-point mirror pairs. For each
scenario x pair count, every mode and the baseline report:
  shape: RMS distance to the undeformed mesh after similarity alignment, % of
         the diagonal (for "articulated", on the two legs only: the symmetric
         pose of a limb is a choice, its shape is not);
  sym:   RMS over ALL ground-truth vertex pairs of |left - mirror(right)|,
         % of the diagonal.
Seconds are the filter's own stage timings (median of --repeat runs).

    python scripts/benchmark.py [--pairs 100 300 1000] [--repeat 3] [--meshes cow spot]
    python scripts/benchmark.py --scale      # speed and memory at scale, and the paper's Table 1
    python scripts/benchmark.py --auto       # automatic pairs against 100 landmark pairs, landmarks+auto with
                                             # 10-100 landmarks, automatic pairs on the Igea scan
    python scripts/benchmark.py --corpus     # pairs='auto' on every mesh of ../shared/data and pymeshlab's
                                             # samples, as given and deformed; synthetic meshes as they come
    python scripts/benchmark.py --filter     # what the user runs: the MeshSet filter against its core, and
                                             # `symblend report`, each in its own process (time, peak RSS)
    python scripts/benchmark.py --batch      # `symblend batch` on 16 specimens of about 30k vertices: 1 and 2
                                             # local workers, and a local Dask cluster
    python scripts/benchmark_dense.py        # dense pairs: the stages, the warp against the dense spline
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
import warnings

import numpy as np
import pymeshlab

from filter_symblend import GeometryError, SymblendError, SymblendWarning, symmetrize, synthetic
from filter_symblend.core import splines, warp
from filter_symblend.core.baseline import mirror_average
from filter_symblend.core.global_solve import global_solve
from filter_symblend.core.local_symmetries import local_symmetries
from filter_symblend.core.neighbourhoods import mean_nearest_spacing, pair_weights, require_connected
from filter_symblend.meshlab.ground_truth import remeshed

SAMPLES = pathlib.Path(pymeshlab.__file__).parent / "tests" / "sample_meshes"
SHARED = pathlib.Path(__file__).resolve().parents[2] / "shared" / "data"
MESHES = {"cow": SAMPLES / "cow.obj", "spot": SHARED / "spot.obj"}
IGEA = SHARED / "igea.ply"
# Table 1 of the paper: model, user-placed + automatic pairs, seconds (dual-core 2.4 GHz, 2010).
TABLE_1 = [("Bunny", 190, 6.61), ("Igea", 260, 7.6), ("Dragon", 944, 173.5), ("Hominid", 520, 38.5),
           ("Paradol", 722, 90.8), ("Vic", 243, 8.41), ("Ben", 935, 109.48), ("Armadillo", 606, 63.45),
           ("WoodDoll", 367, 18.4)]
MESH_PAIR_TOLERANCE = 0.02  # mirror pairs on scans: reflections within 2 % of the diagonal (timing rows only)
# Timing rows on scans: approximate mirror pairs leave a few pairs isolated at the paper's phi width 5
# and a few affine neighbourhoods flat, so these rows use phi width 8 and the standard mode.
SCAN_OPTIONS = {"mode": "standard", "phi_width": 8.0}
BASELINE_CENTRES = 10_000  # scipy's dense RBFInterpolator beyond this: 0.8 GB and a k^3 solve, out of reach
MODES = ("standard", "affine", "articulated")
# Strengths of the --auto deformations: bend angles (rad), (bend angle, compression factor along (1, 1, 0),
# shear) with the paper's Figure 1 last, and limb swings (rad).
AUTO_BENDS = (0.2, 0.4, 0.6, 1.2)
AUTO_BENDS_AND_COMPRESSIONS = ((0.2, 0.9, 0.05), (0.4, 0.85, 0.05), (1.2, 0.65, 0.15))
AUTO_SWINGS = (0.15, 0.3, 0.6)
AUTO_LANDMARK_COUNTS = (10, 20, 50, 100)  # landmark pairs placed for the landmarks+auto table
EXACT = 1e-6  # sym error (/ diagonal) below which a result counts as exact: no ratio is printed
STAGES = ("local_transforms", "global_solve", "warp", "total")


def load(path: pathlib.Path):
    """(exactly symmetric points (N, 3), mirror plane offset, partner (N,), left (n,), right (n,), faces (F, 3))."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    raw = ms.current_mesh().vertex_matrix()
    offset, partner = synthetic.mirror_partners(raw)
    points = synthetic.exactly_symmetric(raw, offset, partner)
    left = np.flatnonzero((partner >= 0) & (points[:, 0] > offset))
    return points, offset, partner, left, partner[left], ms.current_mesh().face_matrix()


def scenarios(points: np.ndarray, mesh: str):
    limb = synthetic.limb_weights(points, **synthetic.LIMBS[mesh])
    yield "bend", synthetic.bend(points, 1.2), None
    yield "bend+compression", synthetic.figure_1_deformation(points), None
    yield "articulated", synthetic.articulate_limb(points, limb, 0.6), np.flatnonzero(limb > 0.99)
    yield "global affine", synthetic.compress(points, [1, 1, 0], 0.6, shear=0.2), None


def errors(out, reference, all_left, all_right, region):
    shape = synthetic.shape_error(out[region], reference[region])
    return f"{100 * shape:.2f} / {100 * synthetic.symmetry_error(out, all_left, all_right):.3f}"


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


def scale_steps(points, offset, partner, counts):
    """Steps 1 + 2 per stage against the pair count, on one large mesh (standard mode)."""
    deformed = synthetic.figure_1_deformation(points)
    print(f"\nSteps 1 + 2 on a bent, compressed cow of {len(points):,} vertices (standard mode; seconds, "
          "peak MB of numpy allocations)")
    print("| pairs | neighbourhoods s | MB | local s | MB | solve s | MB | steps 1+2 s |")
    print("|---|---|---|---|---|---|---|---|")
    for count in counts:
        left, right = synthetic.spread_pairs(points, offset, partner, count)
        p, q = deformed[left], deformed[right]
        ids = np.arange(1, len(left) + 1)

        def neighbourhoods():
            spacing = mean_nearest_spacing(np.vstack([p, q]))
            weights = pair_weights(p, q, 5 * spacing)
            require_connected(weights, p, q, ids, spacing, "phi_width", 5.0)
            return weights

        weights, t1, m1 = measured(neighbourhoods)
        local, t2, m2 = measured(local_symmetries, "standard", weights, p, q, ids)
        _, t3, m3 = measured(global_solve, weights, p, q, local, 0.01)
        print(f"| {len(left):,} | {t1:.2f} | {m1:.0f} | {t2:.2f} | {m2:.0f} | {t3:.2f} | {m3:.0f} | {t1 + t2 + t3:.2f} |",
              flush=True)


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


def scale_meshes(meshes, counts):
    """The whole filter against mesh size and pair count, beside mirror averaging with scipy's dense
    RBFInterpolator warp (out of reach beyond BASELINE_CENTRES landmarks)."""
    print("\nWhole filter against mesh size, standard mode, phi width 8; bent and compressed (Figure 1 map); "
          "approximate mirror pairs (within 2 % of the diagonal); ours: the hand-written warp, baseline: mirror averaging + scipy's dense RBFInterpolator")
    print("| mesh | vertices | pairs | warp | ours s | of which warp s | peak MB | landmark pairs: asymmetry "
          "/ diagonal | mirror averaging s | baseline / ours |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, points, _ in meshes:
        deformed = synthetic.figure_1_deformation(points)
        for count, left, right in scan_pairs(points, counts):
            if len(left) < 0.9 * count:
                continue
            result, ours, memory = measured(symmetrize, deformed, left, right, **SCAN_OPTIONS)
            report = result.report
            method = "approximate" if "patches" in report["warp"] else "exact"
            baseline = "out of reach"
            ratio = ""
            if 2 * len(left) <= BASELINE_CENTRES:
                start = time.perf_counter()
                mirror_average(deformed, left, right)
                seconds = time.perf_counter() - start
                baseline, ratio = f"{seconds:.2f}", f"{seconds / ours:.1f}x"
            print(f"| {name} | {len(points):,} | {len(left):,} | {method} | {ours:.2f} | "
                  f"{report['seconds']['warp']:.2f} | {memory:.0f} | "
                  f"{report['landmark_asymmetry_after']['max_relative']:.1e} | {baseline} | {ratio} |", flush=True)


def approximation_against_exact(points, faces, count):
    """The approximate warp forced where the exact one can still be computed: how far apart they are."""
    [(_, left, right)] = scan_pairs(points, [count])
    deformed = synthetic.figure_1_deformation(points)
    limits = splines.EXACT_CENTRES, splines.ITERATIVE_CENTRES
    try:
        splines.EXACT_CENTRES = 2 * len(left)
        exact = symmetrize(deformed, left, right, **SCAN_OPTIONS)
        splines.EXACT_CENTRES = splines.ITERATIVE_CENTRES = 2 * len(left) - 1
        approximate = symmetrize(deformed, left, right, **SCAN_OPTIONS)
    finally:
        splines.EXACT_CENTRES, splines.ITERATIVE_CENTRES = limits
    edges = np.unique(np.sort(np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1), axis=0)
    lengths = [np.linalg.norm(out[edges[:, 0]] - out[edges[:, 1]], axis=1) for out in (exact.points, approximate.points)]
    change = np.abs(lengths[1] - lengths[0]) / lengths[0]
    diagonal = exact.report["diagonal"]
    print(f"\nApproximate warp ({warp.SUBSET_CENTRES:,} landmarks exact + local splines on patches) against the exact "
          f"spline, {len(points):,} vertices, {len(left):,} pairs ({2 * len(left):,} landmarks), as above")
    print("| warp s exact | warp s approximate | max distance / diagonal | edge length change: worst | 99.9 % | median |")
    print("|---|---|---|---|---|---|")
    print(f"| {exact.report['seconds']['warp']:.2f} | {approximate.report['seconds']['warp']:.2f} | "
          f"{np.abs(approximate.points - exact.points).max() / diagonal:.1e} | {change.max():.1%} | "
          f"{np.quantile(change, 0.999):.2%} | {np.median(change):.3%} |", flush=True)


def table_1():
    """The paper's Table 1 workloads (same pair counts) on Igea, 134k vertices."""
    if not IGEA.exists():
        print(f"\nTable 1: skipped, {IGEA} is absent")
        return
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(IGEA))
    ms.meshing_remove_unreferenced_vertices()
    points = ms.current_mesh().vertex_matrix()
    offset, partner = synthetic.mirror_partners(points, tolerance=5e-3)
    print(f"\nThe paper's Table 1 workloads on Igea ({len(points):,} vertices; approximate mirror pairs), "
          "whole filter, affine mode")
    print("| model | pairs | paper s (2010) | ours s | speed-up |")
    print("|---|---|---|---|---|")
    for model, count, paper in TABLE_1:
        left, right = synthetic.farthest_point_pairs(points, offset, partner, count)
        report = symmetrize(points, left, right, mode="affine").report
        total = report["seconds"]["total"]
        print(f"| {model} | {count} | {paper} | {total:.2f} | {paper / total:.0f}x |", flush=True)


def scale_main(args) -> None:
    largest = list(subdivided_cows(args.levels))[-1]
    scale_steps(*largest, [c for c in args.scale_pairs if c <= (largest[2] >= 0).sum() // 2])
    if IGEA.exists():
        meshes = list(igea_meshes())
        scale_meshes(meshes, args.warp_pairs)
        approximation_against_exact(*meshes[1][1:], 5000)
    else:
        print(f"\nMesh sizes and the approximate warp: skipped, {IGEA} is absent")
    table_1()


def _table_meshes(title: str, header: list[str], meshes: list[str]):
    """Print a table's title and header; yield the meshes present, a row for each absent one."""
    print(title)
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for mesh in meshes:
        if MESHES[mesh].exists():
            yield mesh
        else:
            print(f"| {mesh} | skipped: {MESHES[mesh]} is absent |")


def auto_cases(points: np.ndarray, mesh: str):
    """(name, deformed points, limb vertices or None, mode) for the automatic-pairs table: each kind of
    deformation at increasing strength, in the mode a user would choose for it."""
    limb = synthetic.limb_weights(points, **synthetic.LIMBS[mesh])
    legs = np.flatnonzero(limb > 0.99)
    yield "exactly symmetric", points, None, "affine"
    for angle in AUTO_BENDS:
        yield f"bend {angle} rad", synthetic.bend(points, angle), None, "affine"
    for angle, factor, shear in AUTO_BENDS_AND_COMPRESSIONS:
        name = "Figure 1" if (angle, factor, shear) == (1.2, 0.65, 0.15) else f"bend {angle} + compression {factor}"
        yield name, synthetic.compress(synthetic.bend(points, angle), [1, 1, 0], factor, shear=shear), None, "affine"
    for angle in AUTO_SWINGS:
        yield f"limb swung {angle} rad", synthetic.articulate_limb(points, limb, angle), legs, "articulated"
    yield "compression 0.6 + shear 0.2", synthetic.compress(points, [1, 1, 0], 0.6, shear=0.2), None, "affine"


def auto_main(args) -> None:
    """pairs='auto' and 'landmarks+auto' beside 100 landmark pairs, deformations of rising strength."""
    header = ["mesh", "deformation", "mode", "input", "100 landmarks", "auto", "landmarks / auto", "landmarks+auto",
              "auto pairs (twins are)", "auto rounds", "s auto", "s landmarks+auto"]
    for mesh in _table_meshes("shape / sym error, % of the diagonal (lower is better); landmarks / auto: ratio of "
                              "their sym errors (the target is 5 or more)", header, args.meshes):
        points, offset, partner, all_left, all_right, faces = load(MESHES[mesh])
        left, right = synthetic.farthest_point_pairs(points, offset, partner, 100)
        for name, deformed, limb, mode in auto_cases(points, mesh):
            region = slice(None) if limb is None else np.concatenate([limb, partner[limb]])
            deformed = synthetic.random_rigid(deformed, seed=7)
            try:
                automatic = symmetrize(deformed, faces=faces, pairs="auto", mode=mode)
            except GeometryError:
                automatic = None  # refused: no candidate's pairs are locally mirror-symmetric
            hybrid = symmetrize(deformed, left, right, faces=faces, pairs="landmarks+auto", mode=mode)
            landmarks = symmetrize(deformed, left, right, mode=mode)
            cells = [mode] + [errors(out, points, all_left, all_right, region) if out is not None else "refused"
                              for out in (deformed, landmarks.points, automatic and automatic.points)]
            landmark_error = synthetic.symmetry_error(landmarks.points, all_left, all_right)
            auto_error = None if automatic is None else synthetic.symmetry_error(automatic.points, all_left, all_right)
            if automatic is None or landmark_error < EXACT:
                cells.append("-")  # refused, or the landmarks are exact already
            elif auto_error < EXACT:
                cells.append("auto exact")  # every vertex paired with its true twin: no finite ratio
            else:
                cells.append(f"{landmark_error / auto_error:.1f}")
            cells.append(errors(hybrid.points, points, all_left, all_right, region))
            if automatic is None:
                cells += ["-", "-", "-"]
            else:
                rounds = automatic.report["auto_pairs"]
                cells += [f"{rounds['pair_count']} ({rounds['twins_are']})",
                          f"{len(rounds['rounds'])} ({rounds['stopped']})",
                          f"{automatic.report['seconds']['total']:.2f}"]
            cells.append(f"{hybrid.report['seconds']['total']:.2f}")
            print(f"| {mesh} | {name} | " + " | ".join(cells) + " |", flush=True)


def auto_landmark_counts(args) -> None:
    """Sym error of a few landmark pairs alone and with automatic pairs added (landmarks+auto): how many
    landmarks a deformed specimen needs."""
    header = ["mesh", "deformation", "mode", *(f"{count} landmarks / +auto" for count in AUTO_LANDMARK_COUNTS)]
    for mesh in _table_meshes("\nsym error, % of the diagonal: landmark pairs alone / the same pairs with "
                              "pairs='landmarks+auto'", header, args.meshes):
        points, offset, partner, all_left, all_right, faces = load(MESHES[mesh])
        for name, deformed, _, mode in auto_cases(points, mesh):
            deformed = synthetic.random_rigid(deformed, seed=7)
            cells = [mode]
            for count in AUTO_LANDMARK_COUNTS:
                left, right = synthetic.farthest_point_pairs(points, offset, partner, count)
                alone = symmetrize(deformed, left, right, mode=mode).points
                hybrid = symmetrize(deformed, left, right, faces=faces, pairs="landmarks+auto", mode=mode).points
                cells.append(" / ".join(f"{100 * synthetic.symmetry_error(out, all_left, all_right):.3f}"
                                        for out in (alone, hybrid)))
            print(f"| {mesh} | {name} | " + " | ".join(cells) + " |", flush=True)


def auto_scans() -> None:
    """pairs='auto' on the Igea scan at three sizes, through the MeshSet filter as a user runs it: time, pair
    count, mirror asymmetry before/after, two-way Hausdorff (MeshLab) between input and output."""
    if not IGEA.exists():
        print(f"\npairs='auto' on a scan: skipped, {IGEA} is absent")
        return
    print("\npairs='auto' on the Igea scan: mirror asymmetry RMS / max and two-way Hausdorff input<->output "
          "max / mean, % of the diagonal")
    print("| mesh | vertices | seconds | pairs (twins are) | rounds | asymmetry before | asymmetry after | Hausdorff in<->out |")
    print("|---|---|---|---|---|---|---|---|")
    for name, points, faces in igea_meshes():
        if name == "igea subdivided":
            continue
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=points, face_matrix=faces))
        report = ms.generate_symmetrized_mesh(pairs="auto")
        automatic, diagonal = report["auto_pairs"], report["diagonal"]
        before, after = report["mirror_asymmetry_before"], report["mirror_asymmetry_after"]
        hausdorff = report["hausdorff_input_output"]
        print(f"| {name} | {len(points):,} | {report['seconds']['total']:.0f} | "
              f"{automatic['pair_count']} ({automatic['twins_are']}) | {len(automatic['rounds'])} ({automatic['stopped']}) | "
              f"{100 * before['rms_relative']:.2f} / {100 * before['max_relative']:.1f} | "
              f"{100 * after['rms_relative']:.2f} / {100 * after['max_relative']:.1f} | "
              f"{100 * hausdorff['max'] / diagonal:.2f} / {100 * hausdorff['mean'] / diagonal:.3f} |", flush=True)


CORPUS_FILES = [SHARED / name for name in ("spot.obj", "woody.obj", "homer.obj", "cheburashka.obj", "fandisk.obj",
                                            "rocker-arm.obj", "stanford-bunny.obj", "igea.ply")] + \
    [SAMPLES / name for name in ("cow.obj", "bone.ply", "bunny.obj", "airplane.obj", "cube.obj")]
# Known deformations of the exactly symmetric meshes: name, map, mode a user would choose.
REMESHED_EDGE = 2.0  # % of the diagonal: the remeshed ground truth's edges (no vertex keeps an exact twin)
CORPUS_DEFORMATIONS = [
    ("random pose", lambda p: p, "affine"),
    ("bend 0.2 rad", lambda p: synthetic.bend(p, 0.2), "affine"),
    ("bend 0.6 rad", lambda p: synthetic.bend(p, 0.6), "affine"),
    ("bend 1.2 rad", lambda p: synthetic.bend(p, 1.2), "affine"),
    ("bend 0.4 + compression 0.85", lambda p: synthetic.compress(synthetic.bend(p, 0.4), [1, 1, 0], 0.85, shear=0.05),
     "affine"),
    ("Figure 1", synthetic.figure_1_deformation, "affine"),
]


def _referenced(faces: np.ndarray, count: int) -> np.ndarray:
    used = np.zeros(count, dtype=bool)
    used[faces.ravel()] = True
    return used if len(faces) else np.ones(count, dtype=bool)


def _pieces(faces: np.ndarray, count: int) -> int:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    if not len(faces):
        return count
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]]])
    labels = connected_components(coo_matrix((np.ones(len(edges)), edges.T), shape=(count, count)), directed=False)[1]
    return len(np.unique(labels[_referenced(faces, count)]))


def _outline_distances(points: np.ndarray, faces: np.ndarray, normal, offset) -> np.ndarray:
    """A flat mesh's asymmetry is its outline's: distance from each boundary vertex to the reflected
    boundary (edges used by one triangle), by closest points on the edges as thin triangles."""
    from filter_symblend.core.geometry import reflection_across_plane
    from filter_symblend.core.mirror_fill import distances_to_surface
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    boundary = unique[counts == 1]
    mirrored = reflection_across_plane(points, np.asarray(normal), offset)
    segments = np.column_stack([boundary, boundary[:, 1]])  # degenerate triangles: the edges themselves
    vertices = np.unique(boundary)
    return distances_to_surface(mirrored, segments, points[vertices])


def mirror_statistics(points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """RMS, median and 90th percentile (% of the diagonal) of the distance from each referenced vertex to
    the surface reflected across its best mirror plane, fitted afresh (an independent measure); for a flat
    mesh, from each vertex of its outline to the reflected outline."""
    from filter_symblend.core.geometry import flat_normal
    from filter_symblend.checks.surface_asymmetry import mirror_distances
    from filter_symblend.core.mirror_planes import fit_surface_mirror_plane
    used = _referenced(faces, len(points))
    plane = fit_surface_mirror_plane(points[used])
    if len(faces) and flat_normal(points[used]) is not None:
        distance = _outline_distances(points, faces, *plane)
    else:
        distance = mirror_distances(points, faces, *plane)[used]
    diagonal = np.linalg.norm(np.ptp(points[used], axis=0))
    return 100 * np.array([np.sqrt(np.mean(distance**2)), np.median(distance), np.quantile(distance, 0.9)]) / diagonal


def surface_hausdorff(before: np.ndarray, after: np.ndarray, faces: np.ndarray) -> float:
    """Two-way Hausdorff distance between two embeddings of one mesh, sampled at the referenced vertices,
    % of the diagonal."""
    from filter_symblend.core.mirror_fill import distances_to_surface
    used = _referenced(faces, len(before))
    if not len(faces):
        return 100 * float(np.abs(before - after).max()) / np.linalg.norm(np.ptp(before, axis=0))
    one = distances_to_surface(after, faces, before[used]).max()
    other = distances_to_surface(before, faces, after[used]).max()
    return 100 * max(one, other) / np.linalg.norm(np.ptp(before[used], axis=0))


def corpus_cases():
    """(mesh, case, points, faces, mode, ground truth or None): every corpus file as given, the exactly
    symmetric ones deformed, and synthetic meshes as real ones come (pieces, a cropped side, seams)."""
    for path in CORPUS_FILES:
        if not path.exists():
            yield path.name, f"skipped: {path} is absent", None, None, None, None
            continue
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(path))
        mesh = ms.current_mesh()
        yield path.name, "as given", mesh.vertex_matrix(), mesh.face_matrix(), "standard", None
    truths = []
    for name in ("cow", "spot"):
        if MESHES[name].exists():
            points, offset, _, left, right, faces = load(MESHES[name])
            truths += [(name, synthetic.vertex_truth(points, faces, left, right)),
                       (f"{name} remeshed", remeshed(points, faces, offset, REMESHED_EDGE))]
    pieces_points, pieces_faces = synthetic.several_pieces(3)
    offset, partner = synthetic.mirror_partners(pieces_points)
    left = np.flatnonzero((partner >= 0) & (pieces_points[:, 0] > offset))
    truths.append(("several pieces", synthetic.vertex_truth(pieces_points, pieces_faces, left, partner[left])))
    for name, truth in truths:
        deformations = list(CORPUS_DEFORMATIONS)
        mesh = name.split()[0]
        if mesh in synthetic.LIMBS:
            limb = synthetic.limb_weights(truth.points, **synthetic.LIMBS[mesh])
            deformations += [(f"limb swung {angle} rad", lambda p, a=angle: synthetic.articulate_limb(p, limb, a),
                              "articulated") for angle in (0.3, 0.6)]
        for case, deform, mode in deformations:
            yield name, case, synthetic.random_rigid(deform(truth.points), 7), truth.faces, mode, truth
    if MESHES["spot"].exists():
        points, offset, partner, _, _, faces = load(MESHES["spot"])
        keep = points[:, 0] > offset - 0.6 * (points[:, 0].max() - offset)
        cut, cut_faces, _ = synthetic.cropped(points, faces, keep)
        yield "spot, 60 % of one side cut away", "bend 0.4 rad", synthetic.random_rigid(synthetic.bend(cut, 0.4), 7), \
            cut_faces, "affine", None
        seamed, seamed_faces = synthetic.with_seams(points, faces, points[faces].mean(axis=1)[:, 1] > np.median(points[:, 1]))
        yield "spot with seams (duplicated vertices)", "bend 0.4 rad", \
            synthetic.random_rigid(synthetic.bend(seamed, 0.4), 7), seamed_faces, "affine", None


def core_seconds(points: np.ndarray, faces: np.ndarray, mode: str) -> float:
    """Seconds of the paper's method with 2,000 landmark pairs (fewer if the mesh has fewer): the vertices'
    approximate mirror partners across the mesh's best plane, spread by a voxel grid."""
    from filter_symblend.core.geometry import reflection_across_plane
    from filter_symblend.core.mirror_planes import fit_surface_mirror_plane
    from scipy.spatial import cKDTree
    used = np.flatnonzero(_referenced(faces, len(points)))
    normal, offset = fit_surface_mirror_plane(points[used])
    partner = used[cKDTree(points[used]).query(reflection_across_plane(points[used], normal, offset))[1]]
    left = used[(points[used] @ normal > offset) & (partner != used)]
    right = partner[np.searchsorted(used, left)]
    _, first = np.unique(right, return_index=True)  # one pair per vertex
    left, right = left[first], right[first]
    left, right = left[~np.isin(left, right)], right[~np.isin(left, right)]
    if len(left) > 2000:
        from filter_symblend.core.geometry import voxel_grid
        _, chosen = np.unique(voxel_grid(points[left], 2000), return_index=True)
        left, right = left[chosen], right[chosen]
    start = time.perf_counter()
    symmetrize(points, left, right, mode=mode, phi_width=8.0)
    return time.perf_counter() - start


def _quiet(function, *args, **kwargs):
    """``function`` called with its SymblendWarnings silenced (100 landmarks on a bent mesh warn by design)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        return function(*args, **kwargs)


def corpus_main() -> None:
    """pairs='auto' over the corpus: status, time (and against the paper's method with 2,000 landmark pairs),
    mirror distance before/after, shape kept, and for the exactly symmetric meshes the symmetry error over
    every true pair against 100 landmark pairs."""
    import platform
    print(f"pairs='auto' over the corpus ({time.strftime('%Y-%m-%d')}, {platform.machine()}, {os.cpu_count()} cores): "
          "mirror distance to the reflected surface (RMS / median / 90th percentile, % of the diagonal; a flat "
          "mesh: its outline), two-way Hausdorff input<->output (% of the diagonal), symmetry error over all "
          "true pairs: auto / 100 landmark pairs (%) and their ratio (target <= 0.2). x core: the automatic "
          "pairs' time over that of the paper's method with 2,000 landmark pairs on the same mesh.")
    print("| mesh | case | vertices | pieces | mode | s | x core | status | before | after | Hausdorff | auto / 100 landmarks |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for mesh, case, points, faces, mode, truth in corpus_cases():
        if points is None:
            print(f"| {mesh} | {case} |")
            continue
        cells = [mesh, case, f"{len(points):,}", str(_pieces(faces, len(points))), mode]
        start = time.perf_counter()
        try:
            result = symmetrize(points, faces=faces, pairs="auto", mode=mode)
            output = result.points
            status = "ok" if np.isfinite(output).all() else "NON-FINITE"
        except SymblendError as error:
            output, status = None, "refused: " + " ".join(str(error).split())
        except Exception as error:  # noqa: BLE001  (the corpus counts crashes; it must not stop at one)
            output, status = None, f"CRASH {type(error).__name__}: {error}"
        seconds = time.perf_counter() - start
        try:
            ratio = f"{seconds / core_seconds(points, faces, mode):.1f}"
        except SymblendError:
            ratio = "-"
        cells += [f"{seconds:.1f}", ratio, status, "/".join(f"{v:.3f}" for v in mirror_statistics(points, faces))]
        if output is None or status != "ok":
            cells += ["-", "-", "-"]
        else:
            cells += ["/".join(f"{v:.3f}" for v in mirror_statistics(output, faces)), f"{surface_hausdorff(points, output, faces):.3f}"]
            if truth is None:
                cells.append("")
            else:
                landmarks = _quiet(symmetrize, points, *truth.landmarks(100), mode=mode).points
                auto_error, landmark_error = truth.symmetry_error(output), truth.symmetry_error(landmarks)
                moved = np.abs(output - points).max() / np.linalg.norm(np.ptp(points, axis=0))
                ratio = f"{auto_error / landmark_error:.3f}" if landmark_error > EXACT else f"output moved {moved:.1e}"
                cells.append(f"{100 * auto_error:.4f} / {100 * landmark_error:.4f} ({ratio})")
        print("| " + " | ".join(cells) + " |", flush=True)


# --filter rows: (name, Igea faces after decimation or None for subdivided twice, landmark pairs, checks)
# 'none' first: with checks on, the input's check runs beside the warp and slows the core it shares the CPU
# with, so each row is set against the core of the mesh's 'none' row.
FILTER_ROWS = (("igea 32k", 64_000, 1000, "none"), ("igea 32k", 64_000, 1000, "mirror"),
               ("igea 32k", 64_000, 1000, "full"), ("igea 1M", None, 2000, "none"), ("igea 1M", None, 2000, "mirror"))
REPORT_ROWS = (("igea 61k", 122_000), ("igea 1M", None))


def _filter_mesh(path: pathlib.Path, faces: int | None) -> None:
    """Igea decimated to ``faces`` faces (None: subdivided twice, 1.02 x 10^6 vertices): a PLY at ``path``."""
    if faces is None:
        *_, (_, points, triangles) = igea_meshes()
    else:
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(IGEA))
        ms.meshing_remove_unreferenced_vertices()
        ms.meshing_decimation_quadric_edge_collapse(targetfacenum=faces)
        points, triangles = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=points, face_matrix=triangles))
    ms.save_current_mesh(str(path))


def filter_row(mesh: str, pairs: int, checks: str) -> None:
    """One --filter row in this process, on ``mesh`` bent and compressed (the paper's Figure 1 map) with
    ``pairs`` approximate mirror pairs found before the deformation: print JSON {vertices, pairs, core and
    total seconds, peak RSS MB}; the deformed input and the output are saved beside ``mesh`` (_in, _out)."""
    import filter_symblend  # noqa: F401  (binds the filter)

    loaded = pymeshlab.MeshSet()
    loaded.load_new_mesh(mesh)
    points, faces = loaded.current_mesh().vertex_matrix(), loaded.current_mesh().face_matrix()
    [(_, left, right)] = scan_pairs(points, [pairs])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=synthetic.figure_1_deformation(points), face_matrix=faces))
    ms.save_current_mesh(mesh.replace(".ply", "_in.ply"))
    labels = np.zeros(len(points))
    labels[left], labels[right] = np.arange(1, len(left) + 1), -np.arange(1, len(left) + 1)
    ms.current_mesh().add_vertex_custom_scalar_attribute(labels, "symblend_pair")
    options = {**SCAN_OPTIONS, **({} if checks == "default" else {"checks": checks})}
    start = time.perf_counter()
    report = ms.generate_symmetrized_mesh(**options)
    total = time.perf_counter() - start
    ms.save_current_mesh(mesh.replace(".ply", "_out.ply"))
    print(json.dumps({"vertices": len(points), "pairs": len(left), "core": report["seconds"]["total"],
                      "total": total, "rss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))


def _child(arguments: list[str]) -> tuple[str, float]:
    """Run a command; (its stdout, wall seconds)."""
    start = time.perf_counter()
    done = subprocess.run(arguments, capture_output=True, text=True, check=True)
    return done.stdout, time.perf_counter() - start


# `symblend report` as the console script runs it, then the process's own peak RSS (MB) on the last line.
REPORT_PROCESS = ("import resource, sys; from filter_symblend.commands.main import main; code = main(sys.argv[1:]); "
                  "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024); sys.exit(code)")


def filter_main() -> None:
    """The MeshSet filter as a user calls it, against its core (report seconds.total), and `symblend report`
    on its output; every row in a fresh process, so its peak RSS is its own."""
    if not IGEA.exists():
        print(f"--filter: skipped, {IGEA} is absent")
        return
    print(f"\nThe whole filter against its core ({time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores): Igea, "
          "Figure 1 map, approximate mirror pairs; standard mode, phi width 8; peak RSS of the process")
    print("| mesh | vertices | pairs | checks | core s | filter s | filter / core of 'none' | peak RSS MB |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        made, core = {}, {}
        for name, faces, pairs, checks in FILTER_ROWS:
            path = made.setdefault(name, str(pathlib.Path(folder) / f"{name.replace(' ', '_')}.ply"))
            if not pathlib.Path(path).exists():
                _filter_mesh(pathlib.Path(path), faces)
            out, _ = _child([sys.executable, __file__, "--filter-row", path, str(pairs), checks])
            row = json.loads(out.strip().splitlines()[-1])
            core.setdefault(name, row["core"])
            print(f"| {name} | {row['vertices']:,} | {row['pairs']:,} | {checks} | {row['core']:.2f} | "
                  f"{row['total']:.2f} | {row['total'] / core[name]:.2f} | {row['rss']:.0f} |", flush=True)
        print("\n`symblend report BEFORE AFTER` (the process as a whole, start-up included)")
        print("| mesh | vertices | s | peak RSS MB |")
        print("|---|---|---|---|")
        for name, faces in REPORT_ROWS:
            path = made.get(name) or str(pathlib.Path(folder) / f"{name.replace(' ', '_')}.ply")
            if not pathlib.Path(path).exists():
                _filter_mesh(pathlib.Path(path), faces)
            before, after = path.replace(".ply", "_in.ply"), path.replace(".ply", "_out.ply")
            if not pathlib.Path(after).exists():
                _child([sys.executable, __file__, "--filter-row", path, "2000", "none"])
            out, seconds = _child([sys.executable, "-c", REPORT_PROCESS, "report", before, after])
            rss = float(out.strip().splitlines()[-1])
            vertices = pymeshlab.MeshSet()
            vertices.load_new_mesh(path)
            print(f"| {name} | {vertices.current_mesh().vertex_number():,} | {seconds:.1f} | {rss:.0f} |", flush=True)


BATCH_SPECIMENS = 16
BATCH_PAIRS = 100


def _batch_study(folder: pathlib.Path) -> pathlib.Path:
    """16 copies of the cow midpoint-subdivided twice (46k vertices), each bent by its own angle and posed, with 100
    landmark pairs: the manifest."""
    from filter_symblend.landmarks.files import Landmark, LandmarkSet, write_landmarks

    *_, (points, offset, partner) = subdivided_cows(2)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(MESHES["cow"]))
    ms.meshing_surface_subdivision_midpoint(iterations=2, threshold=pymeshlab.PercentageValue(0))
    faces = ms.current_mesh().face_matrix()
    left, right = synthetic.spread_pairs(points, offset, partner, BATCH_PAIRS)
    rows = []
    for index in range(BATCH_SPECIMENS):
        bent = synthetic.random_rigid(synthetic.bend(points, 0.1 + 0.05 * index), seed=index)
        specimen = pymeshlab.MeshSet()
        specimen.add_mesh(pymeshlab.Mesh(vertex_matrix=bent, face_matrix=faces))
        specimen.save_current_mesh(str(folder / f"cow_{index:02d}.ply"))
        write_landmarks(folder / f"cow_{index:02d}.pp", LandmarkSet([
            Landmark(f"{side}_{k}", tuple(bent[v])) for k, (a, b) in enumerate(zip(left, right))
            for side, v in (("L", a), ("R", b))]))
        rows.append(f"cow_{index:02d}.ply,cow_{index:02d}.pp")
    manifest = folder / "manifest.csv"
    manifest.write_text("mesh,landmarks\n" + "\n".join(rows) + "\n")
    return manifest


# `symblend batch` in a process of its own; its peak RSS and its workers' largest, MB, on the last line.
BATCH_PROCESS = ("import resource, sys; from filter_symblend.commands.main import main; code = main(sys.argv[1:]); "
                 "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "
                 "resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)")


def batch_main() -> None:
    """`symblend batch` over 16 specimens: wall time with 1 and 2 local workers and on a local Dask cluster."""
    print(f"\n`symblend batch`, {BATCH_SPECIMENS} bent cows of {len(list(subdivided_cows(2))[-1][0]):,} vertices, "
          f"{BATCH_PAIRS} landmark pairs each ({time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores)")
    print("| run | workers | wall s | s per specimen | speed-up | peak RSS MB: main / largest worker |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        manifest = _batch_study(pathlib.Path(folder))
        first = None
        for name, workers in (("local pool", 1), ("local pool", 2)):
            out, seconds = _child([sys.executable, "-c", BATCH_PROCESS, "batch", str(manifest), "-o",
                                   str(pathlib.Path(folder) / f"out_{workers}"), "--workers", str(workers)])
            main_rss, worker_rss = out.strip().splitlines()[-1].split()
            first = first or seconds
            print(f"| {name} | {workers} | {seconds:.1f} | {seconds / BATCH_SPECIMENS:.2f} | {first / seconds:.2f}x | "
                  f"{float(main_rss):.0f} / {float(worker_rss):.0f} |", flush=True)
        from dask.distributed import LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address=None) as cluster:
            out, seconds = _child([sys.executable, "-c", BATCH_PROCESS, "batch", str(manifest), "-o",
                                   str(pathlib.Path(folder) / "out_dask"), "--scheduler", cluster.scheduler_address])
        print(f"| local Dask cluster | 2 | {seconds:.1f} | {seconds / BATCH_SPECIMENS:.2f} | {first / seconds:.2f}x | "
              f"{float(out.strip().splitlines()[-1].split()[0]):.0f} / - (Dask's workers are not its children) |",
              flush=True)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pairs", type=int, nargs="+", default=[100, 300, 1000])
    parser.add_argument("--repeat", type=int, default=3, help="runs per cell for the timings")
    parser.add_argument("--meshes", nargs="+", default=list(MESHES), choices=list(MESHES))
    parser.add_argument("--scale", action="store_true", help="speed and memory at scale, and Table 1")
    parser.add_argument("--auto", action="store_true", help="automatic pairs against 100 landmark pairs")
    parser.add_argument("--corpus", action="store_true", help="automatic pairs over every corpus mesh")
    parser.add_argument("--filter", action="store_true", help="the MeshSet filter against its core; symblend report")
    parser.add_argument("--batch", action="store_true", help="symblend batch: 1 and 2 workers, a local Dask cluster")
    parser.add_argument("--filter-row", nargs=3, metavar=("MESH", "PAIRS", "CHECKS"), help=argparse.SUPPRESS)
    parser.add_argument("--levels", type=int, default=4, help="--scale: subdivisions of the cow (4: 743k vertices)")
    parser.add_argument("--scale-pairs", type=int, nargs="+", default=[100, 1000, 10000, 100000])
    parser.add_argument("--warp-pairs", type=int, nargs="+", default=[2000, 20000],
                        help="--scale: pair counts of the mesh-size rows")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore", SymblendWarning)
    if args.scale:
        scale_main(args)
        return
    if args.corpus:
        corpus_main()
        return
    if args.filter_row:
        filter_row(args.filter_row[0], int(args.filter_row[1]), args.filter_row[2])
        return
    if args.filter:
        filter_main()
        return
    if args.batch:
        batch_main()
        return
    if args.auto:
        auto_main(args)
        auto_landmark_counts(args)
        auto_scans()
        return

    header = ["mesh", "scenario", "pairs", "input", "baseline", *MODES, "s local", "s solve", "s warp", "s total"]
    for mesh in _table_meshes("shape / sym error, % of the diagonal (lower is better); seconds: affine mode, "
                              "median", header, args.meshes):
        points, offset, partner, all_left, all_right, _ = load(MESHES[mesh])
        for name, deformed, limb in scenarios(points, mesh):
            region = slice(None) if limb is None else np.concatenate([limb, partner[limb]])
            deformed = synthetic.random_rigid(deformed, seed=7)
            for count in args.pairs:
                left, right = synthetic.farthest_point_pairs(points, offset, partner, count)
                cells = [errors(deformed, points, all_left, all_right, region),
                         errors(mirror_average(deformed, left, right), points, all_left, all_right, region)]
                for mode in MODES:
                    cells.append(errors(symmetrize(deformed, left, right, mode=mode).points, points,
                                        all_left, all_right, region))
                seconds = [symmetrize(deformed, left, right, mode="affine").report["seconds"]
                           for _ in range(args.repeat)]
                cells += [f"{statistics.median(s[stage] for s in seconds):.3f}" for stage in STAGES]
                print(f"| {mesh} | {name} | {count} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
