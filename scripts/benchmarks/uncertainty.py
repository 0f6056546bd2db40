"""--uncertainty: the jackknife (uncertainty='jackknife') against ground truth, and what it costs.

- Cost: the MeshSet filter as a user calls it (default checks), on the cow midpoint-subdivided to 46k
  vertices, bent and compressed by the paper's Figure 1 map, with and without the jackknife.
- Calibration: the exactly symmetric cow deformed by known maps; every landmark moved to a random vertex
  within NOISE of the diagonal of its true place (known landmark noise). The error the noise causes is the
  restoration from the noisy landmarks minus the one from the true landmarks; the reported band is
  BAND x the jackknife's standard error (for an isotropic Gaussian error in 3D whose RMS length is the
  standard error, 90 % of the errors lie within it). Also the share within the band of the whole error,
  against the symmetric original aligned by a similarity (which adds the method's own bias).
- Detection: one right landmark moved 3 % (and 10 %) of the diagonal from its place among 20-100 pairs;
  how often it is the most influential pair, and how often a warning names it as probably misplaced; with
  none moved, how often a warning names a sound pair. `--quick`: 6 sets per cell instead of 12.
"""

from __future__ import annotations

import time

import numpy as np
import pymeshlab

from filter_symblend import symmetrize
from filter_symblend.core.geometry import similarity_fit
from filter_symblend.testing import synthetic

from .common import MESHES, load, measured, quiet

NOISE = 0.01  # landmark noise: each landmark on a random vertex within this fraction of the diagonal
BAND = float(np.sqrt(6.2514 / 3))  # chi-square with 3 degrees of freedom, 90 %: 6.2514
DEFORMATIONS = {"bend 0.5 + compression 0.8 (affine)": ("affine", lambda p: synthetic.compress(
                    synthetic.bend(p, 0.5), [0, 0, 1], 0.8)),
                "Figure 1 map (affine)": ("affine", synthetic.figure_1_deformation),
                "bend 0.3 (standard)": ("standard", lambda p: synthetic.bend(p, 0.3))}


def _noisy(points: np.ndarray, vertices: np.ndarray, diagonal: float, rng) -> np.ndarray:
    """Each of ``vertices`` replaced by a random vertex of ``points`` within NOISE x ``diagonal`` of it."""
    out = vertices.copy()
    for index, vertex in enumerate(vertices):
        near = np.flatnonzero(np.linalg.norm(points - points[vertex], axis=1) <= NOISE * diagonal)
        out[index] = rng.choice(near)
    return out


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
    print("| pairs | without s | MB | with jackknife s | MB | ratio |")
    print("|---|---|---|---|---|---|")
    import filter_symblend  # noqa: F401  (binds the filter)
    for count in (20, 100):
        left, right = synthetic.farthest_point_pairs(points, offset, partner, count)
        labels = np.zeros(len(points))
        labels[left], labels[right] = np.arange(1, count + 1), -np.arange(1, count + 1)
        times = {}
        for choice in ("none", "jackknife"):
            def run():
                ms = pymeshlab.MeshSet()
                ms.add_mesh(pymeshlab.Mesh(deformed, faces))
                ms.current_mesh().add_vertex_custom_scalar_attribute(labels, "symblend_pair")
                return quiet(ms.generate_symmetrized_mesh, mode="affine", uncertainty=choice)
            quiet(run)  # warm
            seconds = []
            for _ in range(3):
                start = time.perf_counter()
                run()
                seconds.append(time.perf_counter() - start)
            _, _, peak = measured(run)
            times[choice] = (float(np.median(seconds)), peak)
        (plain, plain_mb), (jack, jack_mb) = times["none"], times["jackknife"]
        print(f"| {count} | {plain:.2f} | {plain_mb:.0f} | {jack:.2f} | {jack_mb:.0f} | {jack / plain:.1f}x |")
    print()


def _calibration(rng) -> None:
    points, offset, partner, *_ = load(MESHES["cow"])
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    print(f"Calibration: the cow, landmarks moved at random within {NOISE:.0%} of the diagonal; share of vertices "
          f"whose error lies within {BAND:.3f} x the jackknife's standard error (the 90 % band), 10 draws each\n")
    print("| deformation | pairs | noise error within band | median noise error / median s.e. | "
          "whole error within band |")
    print("|---|---|---|---|---|")
    for name, (mode, deform) in DEFORMATIONS.items():
        deformed = deform(points)
        for count in (20, 40, 100):
            left, right = synthetic.farthest_point_pairs(points, offset, partner, count)
            exact = quiet(symmetrize, deformed, left, right, mode=mode).points
            inside, ratio, whole = [], [], []
            for _ in range(10):
                noisy_left, noisy_right = _noisy(points, left, diagonal, rng), _noisy(points, right, diagonal, rng)
                if len(set(noisy_left) | set(noisy_right)) < 2 * count:
                    continue
                result = quiet(symmetrize, deformed, noisy_left, noisy_right, mode=mode, uncertainty="jackknife")
                error = np.linalg.norm(result.points - exact, axis=1)
                inside.append(np.mean(error <= BAND * result.uncertainty))
                ratio.append(np.median(error) / np.median(result.uncertainty))
                truth = np.linalg.norm(similarity_fit(result.points, points) - points, axis=1)
                whole.append(np.mean(truth <= BAND * result.uncertainty))
            print(f"| {name} | {count} | {np.mean(inside):.0%} | {np.median(ratio):.2f} | {np.mean(whole):.0%} |")
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
    print("## Uncertainty: the jackknife against ground truth\n")
    _cost()
    _calibration(rng)
    _detection(rng, 6 if args.quick else 12)
