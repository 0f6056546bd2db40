"""The default section: landmark pairs on exactly symmetric meshes deformed by known maps, every mode and the
mirror-averaging baseline, shape and symmetry error, and the stages' seconds."""

from __future__ import annotations

import statistics

import numpy as np

from filter_symblend import symmetrize
from filter_symblend.core.baseline import mirror_average
from filter_symblend.testing import synthetic

from .common import MESHES, load, table_meshes

MODES = ("standard", "affine", "articulated")
STAGES = ("local_transforms", "global_solve", "warp", "total")


def scenarios(points: np.ndarray, mesh: str):
    limb = synthetic.limb_weights(points, **synthetic.LIMBS[mesh])
    yield "bend", synthetic.bend(points, 1.2), None
    yield "bend+compression", synthetic.figure_1_deformation(points), None
    yield "articulated", synthetic.articulate_limb(points, limb, 0.6), np.flatnonzero(limb > 0.99)
    yield "global affine", synthetic.compress(points, [1, 1, 0], 0.6, shear=0.2), None


def errors(out, reference, all_left, all_right, region):
    shape = synthetic.shape_error(out[region], reference[region])
    return f"{100 * shape:.2f} / {100 * synthetic.symmetry_error(out, all_left, all_right):.3f}"


def accuracy_main(args) -> None:
    """Shape / sym error of every mode and the baseline per mesh, scenario and pair count; median stage seconds."""
    header = ["mesh", "scenario", "pairs", "input", "baseline", *MODES, "s local", "s solve", "s warp", "s total"]
    for mesh in table_meshes("shape / sym error, % of the diagonal (lower is better); seconds: affine mode, "
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
                seconds = [symmetrize(deformed, left, right, mode="affine").report.seconds.to_dict()
                           for _ in range(args.repeat)]
                cells += [f"{statistics.median(s[stage] for s in seconds):.3f}" for stage in STAGES]
                print(f"| {mesh} | {name} | {count} | " + " | ".join(cells) + " |", flush=True)
