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
    python scripts/benchmark.py --auto       # automatic pairs against 100 landmark pairs
"""

from __future__ import annotations

import argparse
import pathlib
import statistics
import time
import tracemalloc
import warnings

import numpy as np
import pymeshlab

from filter_symblend import SymblendWarning, symmetrize, synthetic
from filter_symblend.baseline import mirror_average
from filter_symblend.global_solve import global_solve
from filter_symblend.local_symmetries import local_symmetries
from filter_symblend.neighbourhoods import mean_nearest_spacing, pair_weights, require_connected

MESHES = {
    "cow": pathlib.Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "cow.obj",
    "spot": pathlib.Path(__file__).resolve().parents[2] / "shared" / "data" / "spot.obj",
}
IGEA = pathlib.Path(__file__).resolve().parents[2] / "shared" / "data" / "igea.ply"
# Table 1 of the paper: model, user-placed + automatic pairs, seconds (dual-core 2.4 GHz, 2010).
TABLE_1 = [("Bunny", 190, 6.61), ("Igea", 260, 7.6), ("Dragon", 944, 173.5), ("Hominid", 520, 38.5),
           ("Paradol", 722, 90.8), ("Vic", 243, 8.41), ("Ben", 935, 109.48), ("Armadillo", 606, 63.45),
           ("WoodDoll", 367, 18.4)]
DENSE_WARP_CENTRES = 4000  # the exact spline's dense system beyond this is out of reach here
MODES = ("standard", "affine", "articulated")
STAGES = ("local_transforms", "global_solve", "warp", "total")


def load(path: pathlib.Path):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    raw = ms.current_mesh().vertex_matrix()
    offset, partner = synthetic.mirror_partners(raw)
    points = synthetic.exactly_symmetric(raw, offset, partner)
    left = np.flatnonzero((partner >= 0) & (points[:, 0] > offset))
    return points, offset, partner, left, partner[left]


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
    """(result, seconds, peak MB of numpy/Python allocations) of one call."""
    tracemalloc.reset_peak()
    start = time.perf_counter()
    result = function(*args, **kwargs)
    return result, time.perf_counter() - start, tracemalloc.get_traced_memory()[1] / 1e6


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
    """Steps 1 + 2 per stage against the pair count, on one large mesh (affine mode)."""
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


def scale_meshes(cows, count):
    """The whole filter against the mesh size at ``count`` pairs, beside mirror averaging."""
    print(f"\nWhole filter against mesh size, {count} pairs, affine mode (the warp is scipy's dense "
          "RBFInterpolator for both)")
    print("| vertices | ours s | of which warp s | peak MB | mirror averaging s | ours / baseline |")
    print("|---|---|---|---|---|---|")
    for points, offset, partner in cows:
        left, right = synthetic.spread_pairs(points, offset, partner, count)
        deformed = synthetic.figure_1_deformation(points)
        result, ours, memory = measured(symmetrize, deformed, left, right, mode="affine")
        _, baseline, _ = measured(mirror_average, deformed, left, right)
        print(f"| {len(points):,} | {ours:.2f} | {result.report['seconds']['warp']:.2f} | {memory:.0f} | "
              f"{baseline:.2f} | {ours / baseline:.2f} |", flush=True)


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
    tracemalloc.start()
    cows = list(subdivided_cows(args.levels))
    largest = cows[-1]
    scale_steps(*largest, [c for c in args.scale_pairs if c <= (largest[2] >= 0).sum() // 2])
    scale_meshes(cows, args.mesh_pairs)
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


def auto_main(args) -> None:
    """Rows for pairs='auto' and 'landmarks+auto' (affine mode) beside 100 landmark pairs."""
    header = ["mesh", "scenario", "input", "100 landmarks", "auto", "landmarks+auto", "auto rounds",
              "s auto", "s landmarks+auto"]
    for mesh in _table_meshes("shape / sym error, % of the diagonal (lower is better); affine mode", header,
                              args.meshes):
        points, offset, partner, all_left, all_right = load(MESHES[mesh])
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(MESHES[mesh]))
        faces = ms.current_mesh().face_matrix()
        left, right = synthetic.farthest_point_pairs(points, offset, partner, 100)
        cases = [("symmetric", points, None), ("bend 0.2 rad", synthetic.bend(points, 0.2), None),
                 *scenarios(points, mesh)]
        for name, deformed, limb in cases:
            region = slice(None) if limb is None else np.concatenate([limb, partner[limb]])
            deformed = synthetic.random_rigid(deformed, seed=7)
            automatic = symmetrize(deformed, faces=faces, pairs="auto", mode="affine")
            hybrid = symmetrize(deformed, left, right, faces=faces, pairs="landmarks+auto", mode="affine")
            cells = [errors(out, points, all_left, all_right, region) for out in
                     (deformed, symmetrize(deformed, left, right, mode="affine").points, automatic.points,
                      hybrid.points)]
            rounds = automatic.report["auto_pairs"]
            cells += [f"{len(rounds['rounds'])}{'' if rounds['converged'] else ' (not converged)'}",
                      f"{automatic.report['seconds']['total']:.2f}", f"{hybrid.report['seconds']['total']:.2f}"]
            print(f"| {mesh} | {name} | " + " | ".join(cells) + " |", flush=True)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pairs", type=int, nargs="+", default=[100, 300, 1000])
    parser.add_argument("--repeat", type=int, default=3, help="runs per cell for the timings")
    parser.add_argument("--meshes", nargs="+", default=list(MESHES), choices=list(MESHES))
    parser.add_argument("--scale", action="store_true", help="speed and memory at scale, and Table 1")
    parser.add_argument("--auto", action="store_true", help="automatic pairs against 100 landmark pairs")
    parser.add_argument("--levels", type=int, default=4, help="--scale: subdivisions of the cow (4: 743k vertices)")
    parser.add_argument("--scale-pairs", type=int, nargs="+", default=[100, 1000, 10000, 100000])
    parser.add_argument("--mesh-pairs", type=int, default=1000, help="--scale: pairs for the mesh-size rows")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore", SymblendWarning)
    if args.scale:
        scale_main(args)
        return
    if args.auto:
        auto_main(args)
        return

    header = ["mesh", "scenario", "pairs", "input", "baseline", *MODES, "s local", "s solve", "s warp", "s total"]
    for mesh in _table_meshes("shape / sym error, % of the diagonal (lower is better); seconds: affine mode, "
                              "median", header, args.meshes):
        points, offset, partner, all_left, all_right = load(MESHES[mesh])
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
