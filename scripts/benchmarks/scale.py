"""--scale: steps 1 + 2 against the pair count on a large cow, the whole filter against mesh size beside mirror
averaging with scipy's dense spline, the approximate warp against the exact one, and the paper's Table 1."""

from __future__ import annotations

import time

import numpy as np
import pymeshlab

from filter_symblend import symmetrize
from filter_symblend.core.warp import choice, splines
from filter_symblend.core.baseline import mirror_average
from filter_symblend.core.global_solve import global_solve
from filter_symblend.core.local_symmetries import local_symmetries
from filter_symblend.core.neighbourhoods import mean_nearest_spacing, pair_weights, require_connected
from filter_symblend.testing import synthetic

from .common import IGEA, SCAN_OPTIONS, igea_meshes, measured, scan_pairs, subdivided_cows

# Table 1 of the paper: model, user-placed + automatic pairs, seconds (dual-core 2.4 GHz, 2010).
TABLE_1 = [("Bunny", 190, 6.61), ("Igea", 260, 7.6), ("Dragon", 944, 173.5), ("Hominid", 520, 38.5),
           ("Paradol", 722, 90.8), ("Vic", 243, 8.41), ("Ben", 935, 109.48), ("Armadillo", 606, 63.45),
           ("WoodDoll", 367, 18.4)]
BASELINE_CENTRES = 10_000  # scipy's dense RBFInterpolator beyond this: 0.8 GB and a k^3 solve, out of reach


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
            method = "approximate" if "patches" in report.warp else "exact"
            baseline = "out of reach"
            ratio = ""
            if 2 * len(left) <= BASELINE_CENTRES:
                start = time.perf_counter()
                mirror_average(deformed, left, right)
                seconds = time.perf_counter() - start
                baseline, ratio = f"{seconds:.2f}", f"{seconds / ours:.1f}x"
            print(f"| {name} | {len(points):,} | {len(left):,} | {method} | {ours:.2f} | "
                  f"{report.seconds.stages['warp']:.2f} | {memory:.0f} | "
                  f"{report.landmark_asymmetry_after.max_relative:.1e} | {baseline} | {ratio} |", flush=True)


def approximation_against_exact(points, faces, count):
    """The approximate warp forced where the exact one can still be computed: how far apart they are."""
    [(_, left, right)] = scan_pairs(points, [count])
    deformed = synthetic.figure_1_deformation(points)
    limits = choice.EXACT_CENTRES, choice.ITERATIVE_CENTRES
    try:
        choice.EXACT_CENTRES = 2 * len(left)
        exact = symmetrize(deformed, left, right, **SCAN_OPTIONS)
        choice.EXACT_CENTRES = choice.ITERATIVE_CENTRES = 2 * len(left) - 1
        approximate = symmetrize(deformed, left, right, **SCAN_OPTIONS)
    finally:
        choice.EXACT_CENTRES, choice.ITERATIVE_CENTRES = limits
    edges = np.unique(np.sort(np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1), axis=0)
    lengths = [np.linalg.norm(out[edges[:, 0]] - out[edges[:, 1]], axis=1) for out in (exact.points, approximate.points)]
    change = np.abs(lengths[1] - lengths[0]) / lengths[0]
    diagonal = exact.report.diagonal
    print(f"\nApproximate warp ({splines.SUBSET_CENTRES:,} landmarks exact + local splines on patches) against the exact "
          f"spline, {len(points):,} vertices, {len(left):,} pairs ({2 * len(left):,} landmarks), as above")
    print("| warp s exact | warp s approximate | max distance / diagonal | edge length change: worst | 99.9 % | median |")
    print("|---|---|---|---|---|---|")
    print(f"| {exact.report.seconds.stages['warp']:.2f} | {approximate.report.seconds.stages['warp']:.2f} | "
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
        total = report.seconds.total
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
