"""How often numbered landmarks pair correctly by geometry (filter_symblend.landmarks.geometric_pairing).

On exactly symmetric meshes (pymeshlab's cow; spot from ../shared/data when present) in a random pose,
bent by 0, 0.3 and 0.6 rad: 24 landmark sets per cell (5, 14 or 30 pairs x 3 or 12 midline landmarks x
4 seeds), each landmark 0.3-0.6 % of the diagonal off its vertex in a random direction. A set is
"exact" when every landmark gets its true role; "accepted wrong" when none is named ambiguous (so the
pairing would be used) yet one is paired or put on the midline wrongly, the outcome that must not
happen; otherwise it is refused (some named ambiguous), "refused, rest right" when the pairs found
(written as a table to complete) are right, "refused, rest wrong" when one of them is wrong. Prints a
table.

    python scripts/pairing_accuracy.py
"""

import itertools
import pathlib
import time

import numpy as np
import pymeshlab

from filter_symblend.core.mesh_quantities import farthest_point_order
from filter_symblend.landmarks.geometric_pairing import pair_by_geometry
from filter_symblend.testing import synthetic

SHARED = pathlib.Path(__file__).resolve().parents[2] / "shared" / "data"
MESHES = {"cow": pathlib.Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "cow.obj",
          "spot": SHARED / "spot.obj"}


def _outcome(points, offset, partner, diagonal, pairs, midline, bend, seed):
    rng = np.random.default_rng(seed)
    left, right = synthetic.farthest_point_pairs(points, offset, partner, pairs + seed)
    left, right = left[seed:], right[seed:]
    near_plane = np.flatnonzero(np.abs(points[:, 0] - offset) < 0.002 * diagonal)
    candidates = rng.permutation(near_plane)
    centre = candidates[farthest_point_order(points[candidates], midline, start=0)]
    shape = synthetic.bend(points, bend) if bend else points
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shape = shape @ rotation.T
    positions = shape[np.concatenate([left, right, centre])]
    directions = rng.normal(size=positions.shape)
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    positions = positions + directions * rng.uniform(0.003, 0.006, len(positions))[:, None] * diagonal
    found = pair_by_geometry(positions, shape)
    truth_pairs = {frozenset((k, k + pairs)) for k in range(pairs)}
    truth_midline = set(range(2 * pairs, 2 * pairs + midline))
    wrong = ({frozenset(p) for p in found.pairs} - truth_pairs) or (set(found.midline) - truth_midline)
    if not found.ambiguous:
        return "accepted wrong" if wrong else "exact"
    return "refused, rest wrong" if wrong else "refused, rest right"


def main() -> None:
    kinds = ("exact", "accepted wrong", "refused, rest right", "refused, rest wrong")
    print(f"{'mesh':<6} {'bend rad':>8} " + " ".join(f"{kind:>19}" for kind in kinds) + f" {'ms per set':>11}")
    for name, path in MESHES.items():
        if not path.is_file():
            print(f"{name:<6} (not found: {path})")
            continue
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(path))
        ms.meshing_remove_duplicate_vertices()
        points = ms.current_mesh().vertex_matrix()
        offset, partner = synthetic.mirror_partners(points)
        diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
        for bend in (0.0, 0.3, 0.6):
            start = time.perf_counter()
            outcomes = [_outcome(points, offset, partner, diagonal, pairs, midline, bend, seed)
                        for pairs, midline, seed in itertools.product((5, 14, 30), (3, 12), range(4))]
            per_set = 1000 * (time.perf_counter() - start) / len(outcomes)
            print(f"{name:<6} {bend:>8.1f} " + " ".join(f"{outcomes.count(kind):>19}" for kind in kinds)
                  + f" {per_set:>11.0f}")


if __name__ == "__main__":
    main()
