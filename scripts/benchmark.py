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
"""

from __future__ import annotations

import argparse
import pathlib
import statistics
import warnings

import numpy as np
import pymeshlab

from filter_symblend import SymblendWarning, symmetrize, synthetic
from filter_symblend.baseline import mirror_average

MESHES = {
    "cow": pathlib.Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "cow.obj",
    "spot": pathlib.Path(__file__).resolve().parents[2] / "shared" / "data" / "spot.obj",
}
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
    yield "bend+compression", synthetic.compress(synthetic.bend(points, 1.2), [1, 1, 0], 0.65, shear=0.15), None
    yield "articulated", synthetic.articulate_limb(points, limb, 0.6), np.flatnonzero(limb > 0.99)
    yield "global affine", synthetic.compress(points, [1, 1, 0], 0.6, shear=0.2), None


def errors(out, reference, all_left, all_right, region):
    shape = synthetic.shape_error(out[region], reference[region])
    return f"{100 * shape:.2f} / {100 * synthetic.symmetry_error(out, all_left, all_right):.3f}"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pairs", type=int, nargs="+", default=[100, 300, 1000])
    parser.add_argument("--repeat", type=int, default=3, help="runs per cell for the timings")
    parser.add_argument("--meshes", nargs="+", default=list(MESHES), choices=list(MESHES))
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore", SymblendWarning)

    header = ["mesh", "scenario", "pairs", "input", "baseline", *MODES, "s local", "s solve", "s warp", "s total"]
    print("shape / sym error, % of the diagonal (lower is better); seconds: affine mode, median")
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for mesh in args.meshes:
        if not MESHES[mesh].exists():
            print(f"| {mesh} | skipped: {MESHES[mesh]} is absent |")
            continue
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
