"""Landmarks whose names do not pair (SlicerMorph's numbered "<template>-1", "<template>-2", ...)
paired by geometry: their mirror map, mutual mirror partners under a ratio test, and the
landmarks the map keeps in place as the midline.

The plane: every perpendicular bisector of two landmarks, and the planes normal to the
principal axes, are scored by how many landmarks they mirror onto a landmark (within half the
landmarks' median spacing); with a surface, planes that mirror as many landmarks are told apart
by how well they mirror the surface. The best is refined by the Procrustes mirror fit of the
pairs and midline landmarks it matches (core.landmark_asymmetry), until the matching is stable.
A bent or crushed specimen is mirrored by no plane, so the map is then the reflection plus a
smoothing thin-plate spline (scipy's RBFInterpolator) fitted to the confident matches, refitted
until they repeat. A landmark is paired with the one its mirror image lands nearest to, when
that one's image lands nearest to it too and each nearest is clearly nearer than the second
(``RATIO``); a landmark whose image lands on itself is a midline landmark; any other is
ambiguous. Each landmark's image is taken from the map fitted without it and its partner
(leave-one-out, up to ``LEAVE_ONE_OUT`` landmarks): a map fitted with a wrong match confirms it.

Measured on two exactly symmetric meshes (cow, spot) bent by 0, 0.3 and 0.6 rad, 24 landmark
sets each (5-30 pairs, 3-12 midline, 0.3-0.6 % of the diagonal off the surface): see
docs/landmarks.md.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.interpolate import RBFInterpolator
from scipy.spatial import cKDTree

from ..core.geometry import MirrorPlane, normalize, reflection_across_plane
from ..core.landmark_asymmetry import fit_mirror_plane

MATCH = 0.5  # a mirror image within this fraction of the landmarks' median spacing lands on a landmark
RATIO = 0.5  # a partner is unambiguous when its distance is below this fraction of the second nearest's
REFINEMENTS = 20  # at most, until the matching repeats
SURFACE_SAMPLES = 2000  # surface points that tell apart planes mirroring as many landmarks
CANDIDATE_PAIRS = 5000  # bisectors scored at most (an even random choice beyond: ~100 landmarks)
MIN_LANDMARKS = 3
SMOOTHING = 1.0  # of the spline, coordinates in units of the median spacing (0.3-3 measured alike)
MIN_SPLINE_MATCHES = 5  # below this many confident matches the map stays the reflection
LEAVE_ONE_OUT = 150  # landmarks up to which each image comes from a map fitted without it


@dataclasses.dataclass(frozen=True)
class GeometricPairing:
    """Index pairs (first, second), the first on the side ``plane.normal`` points to; midline and
    ambiguous landmark indices; the mirror plane."""

    pairs: list[tuple[int, int]]
    midline: list[int]
    ambiguous: list[int]
    plane: MirrorPlane


def _median_spacing(positions: np.ndarray) -> float:
    """Median distance from a landmark to its nearest other one, coincident landmarks left out (they
    pair ambiguously whatever the scale: each one's image lands as near the other)."""
    nearest = cKDTree(positions).query(positions, k=2)[0][:, 1]
    apart = nearest[nearest > 0]
    return float(np.median(apart)) if apart.size else 1.0


def _candidates(positions: np.ndarray) -> list[tuple[np.ndarray, float]]:
    """Perpendicular bisectors of every two landmarks and the principal planes, as (normal, offset)."""
    first, second = np.triu_indices(len(positions), k=1)
    if len(first) > CANDIDATE_PAIRS:
        chosen = np.random.default_rng(0).choice(len(first), CANDIDATE_PAIRS, replace=False)
        first, second = first[chosen], second[chosen]
    differences = positions[first] - positions[second]
    keep = np.linalg.norm(differences, axis=1) > 0
    normals = normalize(differences[keep])
    midpoints = 0.5 * (positions[first] + positions[second])[keep]
    centre = positions.mean(axis=0)
    _, _, axes = np.linalg.svd(positions - centre, full_matrices=False)
    planes = [(n, float(n @ m)) for n, m in zip(normals, midpoints)]
    return planes + [(axis, float(axis @ centre)) for axis in axes]


def _landed(positions: np.ndarray, tree: cKDTree, normal, offset, tolerance: float):
    """(how many mirror images land within ``tolerance`` of a landmark, their summed distance)."""
    distances, _ = tree.query(reflection_across_plane(positions, normal, offset))
    within = distances < tolerance
    return int(within.sum()), float(distances[within].sum())


def _surface_misfit(surface: np.ndarray, surface_tree: cKDTree, normal, offset) -> float:
    """Median distance from the mirrored surface sample to the surface."""
    return float(np.median(surface_tree.query(reflection_across_plane(surface, normal, offset))[0]))


def _matching(tree: cKDTree, images: np.ndarray, tolerance: float):
    """(confident (k,) bool, partner (k,)): each image's nearest landmark of ``tree``, and whether the
    two are mutual nearest mirror partners within ``tolerance`` (i == j: the midline), each clear of
    its second nearest (``RATIO``)."""
    distances, nearest = tree.query(images, k=2)
    partner = nearest[:, 0]
    mutual = (partner[partner] == np.arange(len(images))) & (distances[:, 0] < tolerance)
    clear = distances[:, 0] < RATIO * distances[:, 1]
    return mutual & clear & clear[partner], partner


class _MirrorMap:
    """x -> its reflection across ``plane`` plus a smoothing thin-plate spline fitted so that each
    ``sources[m]`` lands on ``targets[m]`` (the reflection alone with too few matches)."""

    def __init__(self, plane: MirrorPlane, sources: np.ndarray, targets: np.ndarray):
        self.plane = plane
        self.spline = None
        if len(sources) >= MIN_SPLINE_MATCHES:
            residual = targets - reflection_across_plane(sources, *plane)
            self.spline = RBFInterpolator(sources, residual, kernel="thin_plate_spline", smoothing=SMOOTHING)

    def __call__(self, points: np.ndarray) -> np.ndarray:
        images = reflection_across_plane(points, *self.plane)
        return images if self.spline is None else images + self.spline(points)


def _fitted_map(points: np.ndarray, plane: MirrorPlane, confident: np.ndarray, partner: np.ndarray,
                leave_out: int | None = None) -> _MirrorMap:
    """The mirror map through the ``confident`` matches (i -> partner[i]), without those of ``leave_out``."""
    chosen = confident.copy()
    if leave_out is not None:
        chosen[leave_out] = chosen[partner[leave_out]] = False
    chosen = np.flatnonzero(chosen)
    return _MirrorMap(plane, points[chosen], points[partner[chosen]])


def pair_by_geometry(positions: np.ndarray, surface: np.ndarray | None = None) -> GeometricPairing:
    """Pair landmarks ``positions`` (k, 3) by their mirror symmetry, with ``surface`` (N, 3) points
    (the mesh's vertices, in the same frame) to choose between planes the landmarks cannot."""
    positions = np.asarray(positions, dtype=float)
    if len(positions) < MIN_LANDMARKS:
        raise ValueError(f"pairing by geometry needs {MIN_LANDMARKS} landmarks or more, got {len(positions)}")
    spacing = _median_spacing(positions)
    tolerance = MATCH * spacing
    tree = cKDTree(positions)
    scored = [(_landed(positions, tree, n, d, tolerance), n, d) for n, d in _candidates(positions)]
    best_count = max(count for (count, _), _, _ in scored)
    tied = [(spread, n, d) for (count, spread), n, d in scored if count >= best_count - 1]
    if surface is not None and len(tied) > 1:
        sample = np.asarray(surface, dtype=float)[:: max(1, len(surface) // SURFACE_SAMPLES)]
        surface_tree = cKDTree(sample)
        _, normal, offset = min(tied, key=lambda t: _surface_misfit(sample, surface_tree, t[1], t[2]))
    else:
        _, normal, offset = max(scored, key=lambda s: (s[0][0], -s[0][1]))
    matched = None
    for _ in range(REFINEMENTS):
        confident, partner = _matching(tree, reflection_across_plane(positions, normal, offset), tolerance)
        now = frozenset((min(i, j), max(i, j)) for i, j in zip(np.flatnonzero(confident), partner[confident]))
        if now == matched or not now:
            break
        matched = now
        first, second = np.array(sorted(now)).T
        fit = fit_mirror_plane(positions[first], positions[second])
        normal, offset = fit.normal, fit.offset
    if normal[np.argmax(np.abs(normal))] < 0:  # one orientation for any run: the largest component positive
        normal, offset = -normal, -offset
    # The spline is fitted in units of the median spacing, where SMOOTHING means the same on any scale.
    units = positions / spacing
    plane = MirrorPlane(normal, float(offset) / spacing)
    unit_tree = cKDTree(units)
    images, matched = reflection_across_plane(units, *plane), None
    for _ in range(REFINEMENTS):
        confident, partner = _matching(unit_tree, images, MATCH)
        now = frozenset(zip(np.flatnonzero(confident), partner[confident]))
        if now == matched:
            break
        matched = now
        images = _fitted_map(units, plane, confident, partner)(units)
    confident, partner = _matching(unit_tree, images, MATCH)
    if len(units) <= LEAVE_ONE_OUT:
        images = np.array([_fitted_map(units, plane, confident, partner, i)(units[i:i + 1])[0]
                           for i in range(len(units))])
        confident, partner = _matching(unit_tree, images, MATCH)
    pairs, midline, ambiguous = [], [], []
    for i in range(len(positions)):
        j = int(partner[i])
        if not confident[i]:
            ambiguous.append(i)
        elif j == i:
            midline.append(i)
        elif i < j:
            pairs.append((i, j) if positions[i] @ normal >= positions[j] @ normal else (j, i))
    return GeometricPairing(pairs, midline, ambiguous, MirrorPlane(normal, float(offset)))
