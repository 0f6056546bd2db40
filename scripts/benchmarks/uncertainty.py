"""--uncertainty: the jackknife (uncertainty='jackknife') and the placement band (uncertainty='placement')
against ground truth, and what they cost.

- Cost: the MeshSet filter as a user calls it (default checks), on the cow midpoint-subdivided to 46k
  vertices, bent and compressed by the paper's Figure 1 map, without uncertainty, with the jackknife, and with
  the placement band.
- Calibration: the exactly symmetric cow deformed by known maps; every landmark moved along the surface by a
  Gaussian step in its tangent plane of RMS length each of NOISES x the diagonal, then to the nearest vertex (known
  landmark noise; the placement band is given the RMS distance the landmarks actually moved, as repeated
  placements would measure it). The error the noise causes is the restoration from the noisy landmarks,
  fitted rigidly onto the one from the true landmarks, minus that one; the reported band is BAND x the
  per-vertex spread (for an isotropic Gaussian error in 3D whose RMS length is the spread, 90 % of the errors
  lie within it). Also the share within the band of the whole error, against the symmetric original aligned
  by a similarity (which adds the method's own bias).
- Detection: one right landmark moved 3 % (and 10 %) of the diagonal from its place among 20-100 pairs;
  how often it is the most influential pair, and how often a warning names it as probably misplaced; with
  none moved, how often a warning names a sound pair. `--quick`: 6 sets per cell instead of 12, 4 draws per
  calibration cell instead of 10.
"""

from __future__ import annotations

import time

import numpy as np
import pymeshlab
from scipy.spatial import cKDTree

from filter_symblend import symmetrize
from filter_symblend.core.geometry import rigid_fit, similarity_fit
from filter_symblend.core.mesh_quantities import vertex_normals
from filter_symblend.core.placement import tangent_steps
from filter_symblend.testing import synthetic

from .common import MESHES, load, measured, quiet

NOISES = (0.005, 0.01, 0.02)  # RMS landmark noise, x the diagonal (the jackknife: the middle one)
BAND = float(np.sqrt(6.2514 / 3))  # chi-square with 3 degrees of freedom, 90 %: 6.2514
DEFORMATIONS = {"bend 0.5 + compression 0.8 (affine)": ("affine", lambda p: synthetic.compress(
                    synthetic.bend(p, 0.5), [0, 0, 1], 0.8)),
                "Figure 1 map (affine)": ("affine", synthetic.figure_1_deformation),
                "bend 0.3 (standard)": ("standard", lambda p: synthetic.bend(p, 0.3))}


def _noisy(points: np.ndarray, faces: np.ndarray, vertices: np.ndarray, noise: float, rng) -> tuple[np.ndarray, float]:
    """Each of ``vertices`` moved by a Gaussian tangent step of RMS length ``noise`` on the surface (``points``
    (N, 3), ``faces``), then to the nearest vertex (drawn again where two land on one vertex); and the RMS
    distance they moved."""
    normals, tree = vertex_normals(points, faces)[0][vertices], cKDTree(points)
    moved = np.zeros(len(vertices), dtype=int)
    again = np.ones(len(vertices), dtype=bool)
    while again.any():
        moved[again] = tree.query(points[vertices[again]] + tangent_steps(normals[again], noise, rng))[1]
        again = np.ones(len(vertices), dtype=bool)
        again[np.unique(moved, return_index=True)[1]] = False  # all but the first landmark on each vertex
    return moved, float(np.sqrt(np.mean(np.sum((points[moved] - points[vertices])**2, axis=1))))


def _cost() -> None:
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(MESHES["cow"]))
    for _ in range(2):
        ms.meshing_surface_subdivision_midpoint(iterations=1, threshold=pymeshlab.PercentageValue(0))
    raw, faces = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    offset, partner = synthetic.mirror_partners(raw)
    points = synthetic.exactly_symmetric(raw, offset, partner)
    deformed = synthetic.figure_1_deformation(points)
    print(f"Cost: the MeshSet filter (checks 'mirror'), the cow subdivided to {len(points):,} vertices, Figure 1 map\n")
    print("| pairs | without s | MB | jackknife s | MB | ratio | placement s | MB | ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    import filter_symblend  # noqa: F401  (binds the filter)
    for count in (20, 100):
        left, right = synthetic.farthest_point_pairs(points, offset, partner, count)
        labels = np.zeros(len(points))
        labels[left], labels[right] = np.arange(1, count + 1), -np.arange(1, count + 1)
        times = {}
        precision = 0.01 * float(np.linalg.norm(np.ptp(points, axis=0)))
        for choice in ("none", "jackknife", "placement"):
            def run():
                ms = pymeshlab.MeshSet()
                ms.add_mesh(pymeshlab.Mesh(deformed, faces))
                ms.current_mesh().add_vertex_custom_scalar_attribute(labels, "symblend_pair")
                return quiet(ms.generate_symmetrized_mesh, mode="affine", uncertainty=choice,
                             landmark_precision=precision if choice == "placement" else 0.0)
            quiet(run)  # warm
            seconds = []
            for _ in range(3):
                start = time.perf_counter()
                run()
                seconds.append(time.perf_counter() - start)
            _, _, peak = measured(run)
            times[choice] = (float(np.median(seconds)), peak)
        (plain, plain_mb), (jack, jack_mb), (place, place_mb) = times["none"], times["jackknife"], times["placement"]
        print(f"| {count} | {plain:.2f} | {plain_mb:.0f} | {jack:.2f} | {jack_mb:.0f} | {jack / plain:.1f}x | "
              f"{place:.2f} | {place_mb:.0f} | {place / plain:.1f}x |")
    print()


def _calibration(rng, draws: int) -> None:
    points, offset, partner, _, _, faces = load(MESHES["cow"])
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    print(f"Calibration: the cow, landmarks moved at random along the surface (RMS, x the diagonal); share of "
          f"vertices whose error lies within {BAND:.3f} x the spread (the 90 % band), {draws} draws each\n")
    print("| deformation | pairs | noise | band | noise error within band | median noise error / median spread | "
          "whole error within band |")
    print("|---|---|---|---|---|---|---|")
    cells = [(0.01, "jackknife")] + [(noise, "placement") for noise in NOISES]
    for name, (mode, deform) in DEFORMATIONS.items():
        deformed = deform(points)
        for count in (20, 40, 100):
            left, right = synthetic.farthest_point_pairs(points, offset, partner, count)
            exact = quiet(symmetrize, deformed, left, right, mode=mode).points
            for noise, band in cells:
                inside, ratio, whole = [], [], []
                for _ in range(draws):
                    noisy, moved = _noisy(deformed, faces, np.concatenate([left, right]), noise * diagonal, rng)
                    precision = {"landmark_precision": moved} if band == "placement" else {}
                    result = quiet(symmetrize, deformed, noisy[:count], noisy[count:], faces=faces, mode=mode,
                                   uncertainty=band, **precision)
                    rotation, translation = rigid_fit(result.points, exact)
                    error = np.linalg.norm(result.points @ rotation.T + translation - exact, axis=1)
                    inside.append(np.mean(error <= BAND * result.uncertainty))
                    ratio.append(np.median(error) / np.median(result.uncertainty))
                    truth = np.linalg.norm(similarity_fit(result.points, points) - points, axis=1)
                    whole.append(np.mean(truth <= BAND * result.uncertainty))
                print(f"| {name} | {count} | {noise:.1%} | {band} | {np.mean(inside):.0%} | {np.median(ratio):.2f} | "
                      f"{np.mean(whole):.0%} |", flush=True)
    print()


def _detection(rng, trials: int) -> None:
    points, offset, partner, *_ = load(MESHES["cow"])
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    print(f"Detection: one right landmark moved along the surface ({trials} random sets of pairs per cell): how often "
          "it is the most influential pair / named as probably misplaced (a warning); with none moved, how often a "
          "warning names a sound pair\n")
    print("| deformation | moved | 20 pairs | 40 | 60 | 100 |")
    print("|---|---|---|---|---|---|")
    for name, (mode, deform) in DEFORMATIONS.items():
        deformed = deform(points)
        for moved in (0.0, 0.03, 0.10):
            cells = []
            for count in (20, 40, 60, 100):
                pool_left, pool_right = synthetic.farthest_point_pairs(points, offset, partner, 2 * count)
                influential = named = tried = 0
                for _ in range(trials):
                    pick = rng.choice(2 * count, count, replace=False)
                    left, right = pool_left[pick], pool_right[pick].copy()
                    j = int(rng.integers(count))
                    if moved:
                        distance = np.linalg.norm(points - points[right[j]], axis=1)
                        right[j] = int(np.argmin(np.abs(distance - moved * diagonal)))
                        if right[j] in set(left) | set(np.delete(right, j)):
                            continue
                    report = quiet(symmetrize, deformed, left, right, mode=mode, uncertainty="jackknife").report
                    influential += report.uncertainty.most_influential_pair == str(j + 1)
                    named += report.uncertainty.probably_misplaced == (str(j + 1) if moved else None)
                    tried += 1
                cells.append(f"{influential}/{named}/{tried}" if moved else f"{tried - named}/{tried}")
            print(f"| {name} | {moved:.0%} | " + " | ".join(cells) + " |")
    print("\n(moved: most influential / named as probably misplaced / sets; none moved: sets that warn / sets)\n")


def uncertainty_main(args) -> None:
    rng = np.random.default_rng(2026)
    print("## Uncertainty: the jackknife and the placement band against ground truth\n")
    _cost()
    _calibration(rng, 4 if args.quick else 10)
    _detection(rng, 6 if args.quick else 12)
