"""How sure is a restoration: each landmark pair, and each midline landmark, left out in turn (the jackknife).

For each left-out unit j, Steps 1 and 2 are solved again without it (:func:`.symmetrize.landmark_targets`, at
the full solve's widths: only the data vary), the other landmarks' new targets are fitted rigidly onto the full
solve's (a rigid motion of the whole is not a change of shape), and the left-out landmarks take the value the
spline through the others gives them. The whole warp then needs no new solve: a thin-plate spline through
values that are themselves a thin-plate spline of fewer centres is that spline, so the result without j is
the full spline's warp plus the spline of the target changes ``delta_j`` at the same centres, and one spline
with all the ``delta_j`` as columns gives every vertex's change for every j in one evaluation.

Per vertex, the jackknife standard error of its restored position (mesh units),
``sqrt((J - 1) / J * sum_j |d_j(x) - mean_j d_j(x)|^2)``; per unit, its influence: the largest
distance any vertex moves without it. The most influential unit is named; no warning says that it is
misplaced, because no rule tried told a landmark moved 3 % of the diagonal from the natural spread of
influences (docs/uncertainty.md: Tukey's fences and robust z-scores either missed it or fired on
most sound sets).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import GeometryError, SymblendError
from .geometry import rigid_fit
from .landmark_pairs import LandmarkPairs, midline_labels
from .report import UncertaintySummary
from .solve import LandmarkTargets, landmark_targets
from .warp import thin_plate_spline

EVALUATED_VALUES = 2**24  # vertices x columns per evaluation of the changes (128 MB of float64)


@dataclasses.dataclass(frozen=True)
class Uncertainty:
    """``per_vertex`` (N,): jackknife standard error of each restored vertex, mesh units; ``influence``
    (J,): the largest distance a vertex moves when unit j is left out, mesh units; ``units`` (J >= 2,):
    their labels (pair ids, ``midline k``); ``kept_in``: units that cannot be left out, with why."""

    per_vertex: np.ndarray
    influence: np.ndarray
    units: list[str]
    kept_in: dict[str, str]

    def summary(self, diagonal: float) -> UncertaintySummary:
        """The report's part: the spread's median, 90th percentile and max, and each unit's influence,
        relative to ``diagonal``, and the most influential unit."""
        p50, p90 = np.percentile(self.per_vertex, [50, 90])
        return UncertaintySummary(len(self.units), float(p50 / diagonal), float(p90 / diagonal),
                                  float(self.per_vertex.max() / diagonal),
                                  {unit: float(value / diagonal) for unit, value in zip(self.units, self.influence)},
                                  self.units[int(np.argmax(self.influence))], dict(self.kept_in))


def _without(landmarks: LandmarkPairs, pair: int | None, midline: int | None) -> LandmarkPairs:
    keep = np.arange(len(landmarks.left)) != pair
    return LandmarkPairs(landmarks.ids[keep], landmarks.left[keep], landmarks.right[keep],
                         np.delete(landmarks.midline, [] if midline is None else [midline]),
                         landmarks.left_weights[keep], landmarks.right_weights[keep])


def _target_change(points: np.ndarray, full: LandmarkTargets, reduced: LandmarkTargets) -> np.ndarray:
    """(k, 3): how each landmark's target moves from ``full`` to ``reduced`` (fewer landmarks), the reduced
    targets fitted rigidly onto the full ones and the missing landmarks given the reduced spline's values."""
    row = {vertex: index for index, vertex in enumerate(full.vertices)}
    common = np.array([row[vertex] for vertex in reduced.vertices])
    rotation, translation = rigid_fit(reduced.target, full.target[common])
    target = reduced.target @ rotation.T + translation
    changed = np.empty_like(full.target)
    changed[common] = target
    missing = np.setdiff1d(np.arange(len(full.vertices)), common)
    centres = points[reduced.vertices]
    spline = thin_plate_spline(centres, target - centres, full.flat)
    changed[missing] = points[full.vertices[missing]] + spline(points[full.vertices[missing]])
    return changed - full.target


def jackknife(points: np.ndarray, landmarks: LandmarkPairs, options: dict, full: LandmarkTargets) -> Uncertainty:
    """The jackknife of the restoration of ``points`` (N, 3) from checked ``landmarks`` with core
    ``options``, whose full Steps 1 and 2 are ``full``; see the module doc."""
    labels = [str(i) for i in landmarks.ids] + list(midline_labels(len(landmarks.midline)))
    units = [(index, None) for index in range(len(landmarks.left))]
    units += [(None, index) for index in range(len(landmarks.midline))]
    fixed = {**options, "width_spacing": full.spacing}  # the widths of the full solve: only the data vary
    changes, left_out, kept_in = [], [], {}
    for label, (pair, midline) in zip(labels, units):
        try:
            reduced = landmark_targets(points, _without(landmarks, pair, midline), fixed)
        except SymblendError as error:  # e.g. the pairs fall apart without it
            kept_in[label] = str(error)
            continue
        changes.append(_target_change(points, full, reduced))
        left_out.append(label)
    count = len(changes)
    if count < 2:
        first, reason = next(iter(kept_in.items()))
        unit = f"pair {first}" if first in labels[:len(landmarks.left)] else first
        raise GeometryError(f"The jackknife needs two landmark pairs or midline landmarks that can be left out, and "
                            f"{count} can (without {unit}: {reason}). Add landmarks, or leave `uncertainty` at "
                            "'none'.")
    total, squares = np.zeros((len(points), 3)), np.zeros(len(points))
    influence = np.zeros(count)
    centres = points[full.vertices]
    group = max(1, EVALUATED_VALUES // (3 * len(points)))
    for start in range(0, count, group):
        block = np.stack(changes[start:start + group], axis=1)  # (k, g, 3)
        moved = _spline_values(centres, block, full.flat, points)
        moved[full.vertices] = block  # the landmarks' own changes, exactly
        total += moved.sum(axis=1)
        distances = np.linalg.norm(moved, axis=2)
        squares += (distances**2).sum(axis=1)
        influence[start:start + group] = distances.max(axis=0)
    spread = np.sqrt(np.maximum((count - 1) / count * (squares - (total**2).sum(axis=1) / count), 0.0))
    return Uncertainty(spread, influence, left_out, kept_in)


def _spline_values(centres: np.ndarray, changes: np.ndarray, flat: np.ndarray | None, points: np.ndarray) -> np.ndarray:
    """(N, g, 3): the splines through ``changes`` (k, g, 3) at ``centres`` (k, 3), at ``points`` (N, 3): one
    spline of 3g columns (one distance computation for all), or in the plane of a flat input one per change."""
    if flat is None:
        return thin_plate_spline(centres, changes.reshape(len(centres), -1))(points).reshape(len(points), -1, 3)
    return np.stack([thin_plate_spline(centres, change, flat)(points) for change in changes.transpose(1, 0, 2)], axis=1)
