"""How sure is a restoration: each landmark pair, and each midline landmark, left out in turn (the jackknife).

For each left-out unit j, Steps 1 and 2 are solved again without it (:func:`.symmetrize.landmark_targets`, at
the full solve's widths: only the data vary), the other landmarks' new targets are fitted rigidly onto the full
solve's (a rigid motion of the whole is not a change of shape), and the left-out landmarks take the value the
spline through the others gives them. The whole warp then needs no new solve: a thin-plate spline through
values that are themselves a thin-plate spline of fewer centres is that spline, so the result without j is
the full spline's warp plus the spline of the target changes ``delta_j`` at the same centres, and one spline
with all the ``delta_j`` as columns gives every vertex's change for every j in one evaluation.

Beyond ``JACKKNIFE_GROUPS`` units they are left out in that many random groups instead (the delete-a-group
jackknife; each unit's mirror error then comes from the restoration without its group, a k-fold cross-validation).
Per vertex, the jackknife standard error of its restored position (mesh units),
``sqrt((G - 1) / G * sum_g |d_g(x) - mean_g d_g(x)|^2)`` over the G groups (each unit alone: G = J); per
unit, its influence (the largest distance any vertex moves without it, or its group; the most influential of a
group is its unit with the largest mirror error) and its cross-validated mirror error: how far from mirror images the
restoration by the others leaves its two landmarks (a midline landmark: from its own mirror image), about
the full solve's plane. A landmark slipped by s lies about s from where the others put it; a sound one
lies as far as the others can predict it, which grows with the gap to its neighbours. So the error, over
the distance to the unit's fourth-nearest neighbour, is compared with the median of the same over all
units: a unit ``MISPLACED_RATIO`` times the median, and at least ``MISPLACED_ERROR`` of the diagonal from
mirroring, is named as probably misplaced (docs/uncertainty.md: chosen on one half of the draws, checked
on the other).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial import cKDTree

from ..errors import GeometryError, SymblendError
from .geometry import reflection_across_plane, rigid_fit
from .landmark_pairs import LandmarkPairs, midline_labels
from .report import UncertaintySummary
from .solve import LandmarkTargets, landmark_targets
from .warp import thin_plate_spline

EVALUATED_VALUES = 2**24  # vertices x columns per evaluation of the changes (128 MB of float64)
# A unit is probably misplaced when its cross-validated mirror error over its neighbour gap is this many times
# the median of the units (the 95th percentile of the largest in sound sets of 20-100 pairs on the cow under
# three deformations, one half of the draws; 4 % of sound sets warn on the other half; docs/uncertainty.md) ...
MISPLACED_RATIO = 25.0
MISPLACED_NEIGHBOUR = 4  # ... the gap: to the fourth-nearest unit (tried 1-4 and 6: the 2nd and 3rd warned as rarely
# but named fewer slips, the 1st named fewer still, the 6th warned more)
MISPLACED_ERROR = 0.01  # ... and the error is at least this share of the diagonal: a hand's placement precision
# Beyond this many units (pairs and midline landmarks) they are left out in this many random groups (the
# delete-a-group jackknife): each left-out solve costs more with more pairs, and one by one the cost grows as
# their square (600 pairs on the 2,904-vertex cow: 28 s one by one).
JACKKNIFE_GROUPS = 100
GROUPS_SEED = 0  # the groups are the same on every call: the same input gives the same output


@dataclasses.dataclass(frozen=True)
class Uncertainty:
    """``per_vertex`` (N,): jackknife standard error of each restored vertex, mesh units; ``influence``
    (J,): the largest distance a vertex moves when unit j is left out (with its group), mesh units;
    ``mirror_error`` (J,): its cross-validated mirror error, mesh units; ``positions`` (J, 3): where each unit
    is (a pair's midpoint); ``units`` (J >= 2,): their labels (pair ids, ``midline k``); ``kept_in``: units that
    cannot be left out, with why; ``groups``: how many groups they were left out in (J when one by one)."""

    per_vertex: np.ndarray
    influence: np.ndarray
    mirror_error: np.ndarray
    positions: np.ndarray
    units: list[str]
    kept_in: dict[str, str]
    groups: int

    def probably_misplaced(self, diagonal: float) -> int | None:
        """The index of the unit whose mirror error stands out (see the module doc), or None; needs more
        than ``MISPLACED_NEIGHBOUR`` units."""
        if len(self.units) <= MISPLACED_NEIGHBOUR:
            return None
        gap = cKDTree(self.positions).query(self.positions, MISPLACED_NEIGHBOUR + 1)[0][:, -1]  # itself first
        scaled = self.mirror_error / np.maximum(gap, np.finfo(float).tiny)
        worst = int(np.argmax(scaled))
        stands_out = scaled[worst] > MISPLACED_RATIO * np.median(scaled)
        return worst if stands_out and self.mirror_error[worst] >= MISPLACED_ERROR * diagonal else None

    def summary(self, diagonal: float, method: str = "jackknife",
                landmark_precision: float | None = None) -> UncertaintySummary:
        """The report's part: the spread's median, 90th percentile and max, each unit's influence and mirror
        error, relative to ``diagonal``, the most influential unit, and the probably misplaced one with its
        warning; ``method`` and ``landmark_precision`` say what ``per_vertex`` is (core/placement)."""
        p50, p90 = np.percentile(self.per_vertex, [50, 90])
        misplaced = self.probably_misplaced(diagonal)
        warnings = () if misplaced is None else (_misplaced_warning(self.units[misplaced],
                                                                    self.mirror_error[misplaced], diagonal),)
        return UncertaintySummary(len(self.units), float(p50 / diagonal), float(p90 / diagonal),
                                  float(self.per_vertex.max() / diagonal),
                                  {unit: float(value / diagonal) for unit, value in zip(self.units, self.influence)},
                                  self.units[int(np.lexsort((self.mirror_error, self.influence))[-1])],
                                  dict(self.kept_in),
                                  {unit: float(value / diagonal) for unit, value in zip(self.units, self.mirror_error)},
                                  None if misplaced is None else self.units[misplaced], warnings, method,
                                  landmark_precision, self.groups)


def _misplaced_warning(unit: str, error: float, diagonal: float) -> str:
    named = f"pair {unit}" if unit.isdigit() else unit
    what = "its two landmarks" if unit.isdigit() else "it"
    return (f"Landmark {named} is probably misplaced or mislabelled: the restoration by the other landmarks leaves "
            f"{what} {error:.4g} ({error / diagonal:.2%} of the diagonal) from mirroring, far more than the others "
            f"(report: uncertainty.mirror_error_relative). Check where it was placed, or leave it out.")


def _without(landmarks: LandmarkPairs, pairs: np.ndarray, midline: np.ndarray) -> LandmarkPairs:
    """``landmarks`` without the pairs at indices ``pairs`` and the midline landmarks at indices ``midline``."""
    keep = np.ones(len(landmarks.left), dtype=bool)
    keep[pairs] = False
    return LandmarkPairs(landmarks.ids[keep], landmarks.left[keep], landmarks.right[keep],
                         np.delete(landmarks.midline, midline), landmarks.left_weights[keep],
                         landmarks.right_weights[keep])


def left_out_groups(units: int) -> list[np.ndarray]:
    """The groups of unit indices (pairs first, then midline landmarks) left out together: each unit alone,
    or beyond ``JACKKNIFE_GROUPS`` units that many random groups (seeded: the same on every call)."""
    if units <= JACKKNIFE_GROUPS:
        return [np.array([unit]) for unit in range(units)]
    order = np.random.default_rng(GROUPS_SEED).permutation(units)
    return [np.sort(group) for group in np.array_split(order, JACKKNIFE_GROUPS)]


def _reduced_targets(points: np.ndarray, full: LandmarkTargets, reduced: LandmarkTargets) -> np.ndarray:
    """(k, 3): each of ``full``'s landmarks where ``reduced`` (fewer landmarks) puts it, its targets fitted
    rigidly onto the full ones and the missing landmarks given the reduced spline's values."""
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
    return changed


def _mirror_gap(full: LandmarkTargets, positions: np.ndarray, first: int, second: int) -> float:
    """How far the landmarks at rows ``first`` and ``second`` of ``positions`` (k, 3), in the input frame, are
    from mirror images about ``full``'s plane, mesh units."""
    return float(np.linalg.norm(reflection_across_plane(positions[[first]], *full.plane)[0] - positions[second]))


def jackknife(points: np.ndarray, landmarks: LandmarkPairs, options: dict, full: LandmarkTargets) -> Uncertainty:
    """The jackknife of the restoration of ``points`` (N, 3) from checked ``landmarks`` with core
    ``options``, whose full Steps 1 and 2 are ``full``; see the module doc."""
    pairs = len(landmarks.left)
    labels = [str(i) for i in landmarks.ids] + list(midline_labels(len(landmarks.midline)))
    fixed = {**options, "width_spacing": full.spacing}  # the widths of the full solve: only the data vary
    changes, group_of, mirror_error, positions, left_out, kept_in = [], [], [], [], [], {}
    for group in left_out_groups(len(labels)):
        try:
            reduced = landmark_targets(points, _without(landmarks, group[group < pairs], group[group >= pairs] - pairs),
                                       fixed, flat=full.flat)
        except SymblendError as error:  # e.g. the pairs fall apart without it
            kept_in.update({labels[unit]: str(error) for unit in group})
            continue
        targets = _reduced_targets(points, full, reduced)
        for unit in group:
            # full.vertices' order: left sides, right sides, midline
            rows = (unit, pairs + unit) if unit < pairs else (pairs + unit,) * 2
            mirror_error.append(_mirror_gap(full, targets, *rows))
            positions.append(points[full.vertices[list(rows)]].mean(axis=0))
            left_out.append(labels[unit])
            group_of.append(len(changes))
        changes.append(targets - full.target)
    count = len(changes)
    if count < 2:
        first, reason = next(iter(kept_in.items()))
        unit = f"pair {first}" if first in labels[:pairs] else first
        raise GeometryError(f"The jackknife needs two landmark pairs or midline landmarks that can be left out, and "
                            f"{count} can (without {unit}: {reason}). Add landmarks, or leave `uncertainty` at "
                            "'none'.")
    total, squares = np.zeros((len(points), 3)), np.zeros(len(points))
    influence = np.zeros(count)
    for start, moved in changes_everywhere(points, full.vertices, np.stack(changes, axis=1), full.flat):
        total += moved.sum(axis=1)
        distances = np.linalg.norm(moved, axis=2)
        squares += (distances**2).sum(axis=1)
        influence[start:start + moved.shape[1]] = distances.max(axis=0)
    spread = np.sqrt(np.maximum((count - 1) / count * (squares - (total**2).sum(axis=1) / count), 0.0))
    return Uncertainty(spread, influence[group_of], np.array(mirror_error), np.array(positions), left_out, kept_in,
                       count)


def changes_everywhere(points: np.ndarray, vertices: np.ndarray, changes: np.ndarray, flat: np.ndarray | None):
    """Yield ``(start, moved)``: ``moved`` (N, g, 3) the splines through columns ``start:start + g`` of
    ``changes`` (k, G, 3), the changes of the targets of the landmark ``vertices`` (k,), at all ``points``
    (N, 3) (at the landmarks their own changes, exactly); g columns at a time, ``EVALUATED_VALUES`` values."""
    group = max(1, EVALUATED_VALUES // (3 * len(points)))
    centres = points[vertices]
    for start in range(0, changes.shape[1], group):
        block = changes[:, start:start + group]
        moved = _spline_values(centres, block, flat, points)
        moved[vertices] = block
        yield start, moved


def _spline_values(centres: np.ndarray, changes: np.ndarray, flat: np.ndarray | None, points: np.ndarray) -> np.ndarray:
    """(N, g, 3): the splines through ``changes`` (k, g, 3) at ``centres`` (k, 3), at ``points`` (N, 3): one
    spline of 3g columns (one distance computation for all), or in the plane of a flat input one per change."""
    if flat is None:
        return thin_plate_spline(centres, changes.reshape(len(centres), -1))(points).reshape(len(points), -1, 3)
    return np.stack([thin_plate_spline(centres, change, flat)(points) for change in changes.transpose(1, 0, 2)], axis=1)
